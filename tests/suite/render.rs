//! End-to-end renders: the brute-force tracer against the CPU on the Cornell box, the
//! image's orientation, determinism, scenes past one storage binding and the device's
//! real limit.

use crate::common;

use glam::Vec3;
use splitray::bench::workloads::primary_rays;
use splitray::integrator::IntegratorKind;
use splitray::render::{render, RenderOptions};
use splitray::scene::{self, Scene, Triangle};
use splitray::trace::{cpu, BruteForceTracer, GpuTriangle, Hit, Query, Ray, Tracer};

/// The scene's settings at `width` × `height`, `spp` samples, seed 1 and `integrator`.
pub(crate) fn options(
    scene: &Scene,
    width: u32,
    height: u32,
    spp: u32,
    integrator: IntegratorKind,
) -> RenderOptions {
    RenderOptions::resolve(
        scene,
        Some(width),
        Some(height),
        Some(spp),
        Some(1),
        Some(integrator),
        None,
    )
    .unwrap()
}

#[test]
fn brute_force_matches_cpu_on_the_cornell_box() {
    let gpu = common::gpu();
    let scene = scene::load("cornell-box").unwrap();
    let triangles = scene.gpu_triangles();
    let rays = primary_rays(&scene, 256, 256);
    let mut tracer = BruteForceTracer::new(&gpu, &triangles).unwrap();
    let ray_buf = gpu.upload("rays", &rays).unwrap();
    let hit_buf = gpu.zeroed::<Hit>("hits", rays.len()).unwrap();
    let done = tracer
        .trace(
            &ray_buf,
            &hit_buf,
            rays.len() as u32,
            Query::ClosestHit,
            &[],
        )
        .unwrap();
    gpu.wait(&done).unwrap();
    let hits = hit_buf.read::<Hit>().unwrap();
    let expected = cpu::closest_hits(&rays, &triangles);
    let bad = hits
        .iter()
        .zip(&expected)
        .filter(|(g, c)| !cpu::same_hit(g, c, 1e-5, false))
        .count();
    assert_eq!(bad, 0, "{bad} of {} Cornell-box rays differ", rays.len());
    // The box is open towards the camera: the image corners miss, the rest hits.
    let hit_count = hits.iter().filter(|h| h.is_hit()).count();
    assert!(
        hit_count > rays.len() * 9 / 10 && hit_count < rays.len(),
        "{hit_count} hits"
    );
    common::assert_clean(&gpu);
}

#[test]
fn rendered_triangle_ids_and_depth_match_cpu_camera_rays() {
    let gpu = common::gpu();
    let scene = scene::load("cornell-box").unwrap();
    let (w, h) = (96, 64);
    let out = render(
        &gpu,
        &scene,
        &options(&scene, w, h, 1, IntegratorKind::Primary),
        &mut |_| {},
    )
    .unwrap();
    let expected = cpu::closest_hits(&primary_rays(&scene, w, h), &scene.gpu_triangles());
    let ids = out.film.triangle_id.as_ref().unwrap();
    let depth = out.film.depth.as_ref().unwrap();
    // The GPU builds the same rays in its own kernel; rounding of the direction may
    // flip a ray that grazes a shared edge to the neighbouring triangle, never more.
    let mut differing = 0;
    for (i, e) in expected.iter().enumerate() {
        if ids[i] != e.triangle {
            differing += 1;
            continue;
        }
        if !e.is_hit() {
            assert_eq!(depth[i], f32::INFINITY);
            continue;
        }
        assert!(
            (depth[i] - e.t).abs() <= 1e-4 * e.t,
            "pixel {i}: depth {} vs {}",
            depth[i],
            e.t
        );
    }
    assert!(
        differing * 1000 <= expected.len(),
        "{differing} pixels differ"
    );
    common::assert_clean(&gpu);
}

fn mean_rgb(film: &splitray::film::Film, x0: u32, x1: u32) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let mut n = 0.0;
    for y in 0..film.height() {
        for x in x0..x1 {
            sum += Vec3::from(film.mean_rgb(film.index(x, y)));
            n += 1.0;
        }
    }
    sum / n
}

#[test]
fn cornell_box_has_the_red_wall_on_the_left() {
    let gpu = common::gpu();
    let scene = scene::load("cornell-box").unwrap();
    let out = render(
        &gpu,
        &scene,
        &options(&scene, 64, 64, 1, IntegratorKind::Primary),
        &mut |_| {},
    )
    .unwrap();
    let left = mean_rgb(&out.film, 0, 8);
    let right = mean_rgb(&out.film, 56, 64);
    assert!(
        left.x > 2.0 * left.y && left.x > 2.0 * left.z,
        "left strip {left}"
    );
    assert!(right.y > 2.0 * right.x, "right strip {right}");
    common::assert_clean(&gpu);
}

#[test]
fn same_seed_same_image_and_seeds_matter() {
    let gpu = common::gpu();
    let scene = scene::load("cornell-box").unwrap();
    let mut opts = options(&scene, 48, 48, 3, IntegratorKind::Ao);
    let a = render(&gpu, &scene, &opts, &mut |_| {})
        .unwrap()
        .film
        .mean_rgb_buffer();
    let b = render(&gpu, &scene, &opts, &mut |_| {})
        .unwrap()
        .film
        .mean_rgb_buffer();
    assert_eq!(a, b);
    opts.seed = 2;
    let c = render(&gpu, &scene, &opts, &mut |_| {})
        .unwrap()
        .film
        .mean_rgb_buffer();
    assert_ne!(a, c);
    common::assert_clean(&gpu);
}

#[test]
fn ambient_occlusion_of_an_open_plane_is_one() {
    // Nothing above a lone plane can occlude it: every hit pixel sees the whole sky.
    // One sample per pixel keeps the (unjittered) AOV and the AO value on the same ray.
    let gpu = common::gpu();
    let mut scene = scene::load("cornell-box").unwrap();
    let floor = scene.triangles[..2].to_vec();
    scene.triangles = floor;
    let out = render(
        &gpu,
        &scene,
        &options(&scene, 32, 32, 1, IntegratorKind::Ao),
        &mut |_| {},
    )
    .unwrap();
    let ids = out.film.triangle_id.as_ref().unwrap();
    let mut hit_pixels = 0;
    for (i, id) in ids.iter().enumerate() {
        let v = out.film.mean_rgb(i)[0];
        if *id == u32::MAX {
            assert_eq!(v, 0.0);
        } else {
            hit_pixels += 1;
            assert_eq!(v, 1.0, "pixel {i}");
        }
    }
    assert!(
        hit_pixels > 100,
        "the plane must be in view ({hit_pixels} pixels)"
    );
    common::assert_clean(&gpu);
}

#[test]
fn a_scene_past_one_storage_binding_renders() {
    let gpu = common::gpu();
    let mut scene = scene::load("cornell-box").unwrap();
    // Filler behind the camera first, so that every triangle the camera sees lies past
    // the first storage binding's worth of the triangle buffers (the kernels take them by
    // address). Each filler triangle still passes through every filter.
    let binding = gpu.info().limits.max_storage_buffer_range;
    let filler = (binding / size_of::<GpuTriangle>() as u64 + 1) as usize;
    let behind = scene.camera.position - 10.0 * (scene.camera.look_at - scene.camera.position);
    let t = Triangle::new(behind, behind + Vec3::X, behind + Vec3::Y, 0);
    let bytes = ((filler + scene.triangles.len()) * size_of::<GpuTriangle>()) as u64;
    if !common::holds_past_one_binding(&gpu, bytes, "the scene's triangles") {
        return;
    }
    let visible = std::mem::replace(&mut scene.triangles, vec![t; filler]);
    scene.triangles.extend(visible);
    let (w, h) = (8, 8);
    let out = render(
        &gpu,
        &scene,
        &options(&scene, w, h, 1, IntegratorKind::Primary),
        &mut |_| {},
    )
    .unwrap();
    let ids = out.film.triangle_id.as_ref().unwrap();
    let expected = cpu::closest_hits(&primary_rays(&scene, w, h), &scene.gpu_triangles());
    let past = expected
        .iter()
        .filter(|e| e.triangle as usize >= filler)
        .count();
    assert_eq!(past, expected.len(), "every pixel sees the box");
    let same = ids
        .iter()
        .zip(&expected)
        .filter(|(i, e)| **i == e.triangle)
        .count();
    // As in rendered_triangle_ids_and_depth_match_cpu_camera_rays: an edge may flip.
    assert!(
        same + 1 >= expected.len(),
        "{same} of {} ids match",
        expected.len()
    );
    let rgb = out.film.mean_rgb_buffer();
    assert!(rgb
        .iter()
        .all(|c| c.iter().all(|v| v.is_finite() && *v >= 0.0)));
    assert!(rgb.iter().any(|c| c[0] > 0.1), "the box is lit");
    common::assert_clean(&gpu);
}

#[test]
fn a_film_past_the_largest_buffer_is_refused_before_any_work() {
    let gpu = common::gpu();
    let scene = scene::load("cornell-box").unwrap();
    let (limit, which) = gpu.max_buffer_bytes();
    let side = splitray::scene::validate::MAX_FILM_DIM;
    let accum = side as u64 * side as u64 * 16;
    if accum <= limit {
        println!("a {side}x{side} film fits this device's largest buffer ({limit} bytes)");
        return;
    }
    let before = gpu.memory_bytes().0;
    let err = render(
        &gpu,
        &scene,
        &options(&scene, side, side, 1, IntegratorKind::Pt),
        &mut |_| {},
    )
    .err()
    .expect("must be refused")
    .to_string();
    for part in [
        "cornell-box".to_string(),
        format!("{side}x{side}"),
        "'pt-accum'".to_string(),
        accum.to_string(),
        limit.to_string(),
        which.to_string(),
    ] {
        assert!(err.contains(&part), "missing {part:?} in: {err}");
    }
    assert_eq!(gpu.memory_bytes().0, before, "nothing was allocated");
    common::assert_clean(&gpu);
}

/// A closed cube [0, 1]³ of 12 triangles, all of material 0.
fn closed_cube() -> Vec<Triangle> {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let quads = [
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        [v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
        [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
        [v(1., 0., 0.), v(1., 0., 1.), v(1., 1., 1.), v(1., 1., 0.)],
        [v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)],
        [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
    ];
    quads
        .iter()
        .flat_map(|q| {
            [
                Triangle::new(q[0], q[1], q[2], 0),
                Triangle::new(q[0], q[2], q[3], 0),
            ]
        })
        .collect()
}

#[test]
fn path_integrator_in_a_glowing_closed_box_sums_the_bounces_exactly() {
    // Every surface emits Le and reflects albedo a: a path gathers Le at its camera hit
    // and at each of its 7 diffuse bounces, its throughput falling by a each time. Every
    // ray hits, so each sample is exactly Le · Σ_{k=0..7} a^k (the 7-bounce truncation of
    // Le / (1 − a)), with no noise at all.
    let gpu = common::gpu();
    let mut scene = scene::load("cornell-box").unwrap();
    scene.triangles = closed_cube();
    scene.materials.truncate(1);
    let (le, a) = (Vec3::new(0.5, 1.0, 2.0), 0.6f32);
    scene.materials[0].emission = le;
    scene.materials[0].diffuse = Vec3::splat(a);
    scene.camera.position = Vec3::new(0.5, 0.5, 0.3);
    scene.camera.look_at = Vec3::new(0.6, 0.4, 1.0);
    scene.camera.up = Vec3::Y;
    let out = render(
        &gpu,
        &scene,
        &options(&scene, 24, 16, 2, IntegratorKind::Path),
        &mut |_| {},
    )
    .unwrap();
    let expected = le * (0..=7).map(|k| a.powi(k)).sum::<f32>();
    for i in 0..24 * 16 {
        let got = Vec3::from(out.film.mean_rgb(i));
        assert!(
            (got - expected).abs().max_element() <= 1e-4 * expected.max_element(),
            "pixel {i}: {got} vs {expected}"
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn shadow_integrator_matches_the_inverse_square_law_on_an_open_plane() {
    // A lone floor under a point light: radiance = albedo/π · I · cos θ / d², nothing
    // in the way. The expected value comes from the first-hit AOVs (depth, normal).
    let gpu = common::gpu();
    let mut scene = scene::load("cornell-box").unwrap();
    scene.triangles.truncate(2); // the floor
    let light = Vec3::new(278.0, 300.0, 280.0);
    let intensity = 5.0e4;
    scene.point_lights = vec![splitray::scene::PointLight {
        position: light,
        intensity: Vec3::splat(intensity),
    }];
    let (w, h) = (32u32, 32u32);
    let out = render(
        &gpu,
        &scene,
        &options(&scene, w, h, 1, IntegratorKind::Shadow),
        &mut |_| {},
    )
    .unwrap();
    let frame = scene.camera.frame(w, h);
    let albedo = scene.materials[scene.triangles[0].material as usize].diffuse;
    let depth = out.film.depth.as_ref().unwrap();
    let mut lit = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let got = Vec3::from(out.film.mean_rgb(i));
            if !depth[i].is_finite() {
                assert_eq!(got, Vec3::ZERO);
                continue;
            }
            let p = frame.origin + depth[i] * frame.pixel_center_direction(x, y);
            let to = light - p;
            let cos = Vec3::Y.dot(to.normalize());
            let expected = albedo / std::f32::consts::PI * intensity * cos / to.length_squared();
            assert!(
                (got - expected).abs().max_element() <= 2e-3 * expected.max_element(),
                "pixel {x},{y}: {got} vs {expected}"
            );
            lit += 1;
        }
    }
    assert!(lit > 100, "{lit} lit pixels");
    common::assert_clean(&gpu);
}

#[test]
fn reflection_integrator_shows_what_the_cpu_sees_in_the_mirror() {
    let gpu = common::gpu();
    let scene = scene::load("cornell-box").unwrap();
    let (w, h) = (48u32, 48u32);
    let out = render(
        &gpu,
        &scene,
        &options(&scene, w, h, 1, IntegratorKind::Reflection),
        &mut |_| {},
    )
    .unwrap();
    let tris = scene.gpu_triangles();
    let primary = primary_rays(&scene, w, h);
    let hits = cpu::closest_hits(&primary, &tris);
    let eps = scene.bounds().ray_epsilon([scene.camera.position]);
    let mut agree = 0;
    let mut compared = 0;
    for (i, (r, hit)) in primary.iter().zip(&hits).enumerate() {
        let got = Vec3::from(out.film.mean_rgb(i));
        if !hit.is_hit() {
            assert_eq!(got, Vec3::ZERO);
            continue;
        }
        let d = Vec3::from(r.dir);
        let mut n = tris[hit.triangle as usize].normal().normalize();
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let p = Vec3::from(r.origin) + hit.t * d + eps * n;
        let m = Ray::new(p, (d - 2.0 * d.dot(n) * n).normalize(), 0.0, f32::INFINITY);
        let second = cpu::closest_hit(&m, &tris);
        let expected = if second.is_hit() {
            let t = &scene.triangles[second.triangle as usize];
            let mat = &scene.materials[t.material as usize];
            mat.emission
                + mat.diffuse
                    * tris[second.triangle as usize]
                        .normal()
                        .normalize()
                        .dot(Vec3::from(m.dir))
                        .abs()
        } else {
            Vec3::ZERO
        };
        compared += 1;
        if (got - expected).abs().max_element() <= 1e-3 {
            agree += 1;
        }
    }
    // Rays that graze an edge on the way may land on the neighbouring triangle.
    assert!(
        agree * 100 >= compared * 99,
        "{agree} of {compared} pixels agree"
    );
    common::assert_clean(&gpu);
}

#[test]
fn frame_params_layout_matches_glsl() {
    use splitray::integrator::FrameParams;
    use splitray::vk::{ComputePipeline, PipelineDesc, StreamKind};
    let gpu = common::gpu();
    let words: Vec<u32> = (0..32u32).map(|k| 0x3F80_0000 + k * 7919).collect();
    let params: FrameParams = bytemuck::cast_slice::<u32, FrameParams>(&words)[0];
    let pipeline = ComputePipeline::new(
        &gpu,
        &PipelineDesc {
            kernel: splitray::shaders::TEST_FRAME_ECHO,
            bindings: 1,
            push_constant_bytes: 128,
            spec: &[],
        },
    )
    .unwrap();
    let out = gpu.zeroed::<u32>("echo", 32).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch(&pipeline, &[(&out).into()], &params, [1, 1, 1])
        .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let echoed = out.read::<u32>().unwrap();
    // Word 27 is padding on both sides; every other word must come back where it went.
    for k in (0..32).filter(|k| *k != 27) {
        assert_eq!(echoed[k], words[k], "word {k}");
    }
    common::assert_clean(&gpu);
}
