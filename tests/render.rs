//! End-to-end renders: the brute-force tracer against the CPU on the Cornell box, the
//! image's orientation, determinism, and the storage-binding limit.

mod common;

use glam::Vec3;
use splitray::integrator::IntegratorKind;
use splitray::render::{render, RenderOptions};
use splitray::scene::{self, Scene, Triangle};
use splitray::trace::{cpu, BruteForceTracer, GpuTriangle, Hit, Query, Ray, Tracer};

fn options(
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

fn gpu_triangles(scene: &Scene) -> Vec<GpuTriangle> {
    scene
        .triangles
        .iter()
        .map(|t| GpuTriangle::new(t.p))
        .collect()
}

/// Primary rays through pixel centres, made on the CPU with the camera convention.
fn pixel_centre_rays(scene: &Scene, width: u32, height: u32) -> Vec<Ray> {
    let frame = scene.camera.frame(width, height);
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            Ray::new(
                frame.origin,
                frame.pixel_center_direction(x, y),
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

#[test]
fn brute_force_matches_cpu_on_the_cornell_box() {
    let gpu = common::gpu();
    let scene = scene::load("cornell-box").unwrap();
    let triangles = gpu_triangles(&scene);
    let rays = pixel_centre_rays(&scene, 256, 256);
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
    let expected = cpu::closest_hits(&pixel_centre_rays(&scene, w, h), &gpu_triangles(&scene));
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
fn a_scene_beyond_one_storage_binding_is_refused_by_name() {
    let gpu = common::gpu();
    let mut scene = scene::load("cornell-box").unwrap();
    let limit = gpu.info().limits.max_storage_buffer_range;
    let needed = (limit / size_of::<GpuTriangle>() as u64 + 1) as usize;
    let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
    scene.triangles = vec![t; needed];
    let err = render(
        &gpu,
        &scene,
        &options(&scene, 8, 8, 1, IntegratorKind::Primary),
        &mut |_| {},
    )
    .err()
    .expect("must fail")
    .to_string();
    assert!(
        err.contains("maxStorageBufferRange") && err.contains("cornell-box"),
        "{err}"
    );
    common::assert_clean(&gpu);
}
