//! Scenes and films larger than one storage binding (maxStorageBufferRange: 128 MiB on
//! lavapipe): PDACRT equals brute force on a scene whose triangle buffer is past it, and
//! a film whose buffers are past it renders what the CPU computes and round-trips through
//! EXR. The kernels take such buffers by address (glsl/common/address.glsl); lavapipe
//! runs the descriptor twins wherever the buffers fit, so these tests mix both forms.
//! The light-vertex-cache integrators render the same image of a scene padded past one
//! binding with hidden triangles as of the scene itself.

use crate::common;

use glam::{Vec2, Vec3};
use splitray::film::{read_exr, write_exr, Film};
use splitray::integrator::IntegratorKind;
use splitray::render::{render, RenderOptions};
use splitray::scene::{self, Scene, Triangle};
use splitray::trace::{
    cpu, BruteForceTracer, GpuTriangle, Hit, PdacrtTracer, Query, Ray, TracerKind,
};
use splitray::vk::{BufferAccess, Gpu};

/// Cells per side of a height field whose triangle buffer is past one binding.
fn cells_past_one_binding(gpu: &Gpu) -> usize {
    let binding_triangles = gpu.info().limits.max_storage_buffer_range / 48;
    ((binding_triangles as f64 / 2.0).sqrt() as usize + 8).max(16)
}

/// A bumpy height field over [0, 1]² of `n` × `n` cells, two triangles each, in rows
/// of increasing y: triangle 2(row · n + column) and the next.
fn height_field(n: usize) -> Vec<GpuTriangle> {
    let z = |x: f32, y: f32| 0.05 * (20.0 * x).sin() * (17.0 * y).cos();
    let p = |i: usize, j: usize| {
        let (x, y) = (j as f32 / n as f32, i as f32 / n as f32);
        Vec3::new(x, y, z(x, y))
    };
    let mut out = Vec::with_capacity(2 * n * n);
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (p(i, j), p(i, j + 1), p(i + 1, j + 1), p(i + 1, j));
            out.push(GpuTriangle::new([a, b, c]));
            out.push(GpuTriangle::new([a, c, d]));
        }
    }
    out
}

/// `n` rays from nearly straight above the field toward random points on it; those with
/// even index aim at its last rows `y >= last_rows_from`, whose triangles lie past the
/// first binding.
fn rays_onto_the_field(n: usize, last_rows_from: f32) -> Vec<Ray> {
    let r = common::uniforms(n * 4, 77);
    (0..n)
        .map(|i| {
            let c = &r[i * 4..];
            let y0 = if i % 2 == 0 { last_rows_from } else { 0.0 };
            let target = Vec2::new(c[0], y0 + (1.0 - y0) * c[1]);
            let tilt = 0.01 * Vec2::new(c[2] - 0.5, c[3] - 0.5);
            let origin = (target + tilt).extend(2.0);
            let dir = (target.extend(0.0) - origin).normalize();
            Ray::new(origin, dir, 0.0, f32::INFINITY)
        })
        .collect()
}

#[test]
fn pdacrt_equals_brute_force_on_a_scene_past_one_binding() {
    let gpu = common::gpu();
    let n = cells_past_one_binding(&gpu);
    let bytes = (2 * n * n * size_of::<GpuTriangle>()) as u64;
    if !common::holds_past_one_binding(&gpu, bytes, "the height field's triangles") {
        return;
    }
    let triangles = height_field(n);
    assert_eq!(triangles.len(), 2 * n * n);
    let binding_triangles = (gpu.info().limits.max_storage_buffer_range / 48) as usize;
    let last_rows_from = (binding_triangles / (2 * n)) as f32 / n as f32;
    let rays = rays_onto_the_field(512, last_rows_from);

    let mut pdacrt = PdacrtTracer::new(&gpu, &triangles).unwrap();
    let hits = common::trace_hits(&gpu, &mut pdacrt, &rays, Query::ClosestHit);
    let occluded = common::trace_hits(&gpu, &mut pdacrt, &rays, Query::Occlusion);
    drop(pdacrt);
    let mut brute = BruteForceTracer::new(&gpu, &triangles).unwrap();
    let expected = common::trace_hits(&gpu, &mut brute, &rays, Query::ClosestHit);
    drop(brute);
    common::assert_same_hits(&hits, &expected, "past one binding");
    assert!(occluded
        .iter()
        .zip(&expected)
        .all(|(o, e)| o.is_hit() == e.is_hit()));

    // Every ray lands on the field, about half of them past the first binding's
    // triangles.
    assert!(expected.iter().all(Hit::is_hit), "every ray hits the field");
    let past = expected
        .iter()
        .filter(|h| h.triangle as usize >= binding_triangles)
        .count();
    assert!(past >= rays.len() / 3, "{past} hits past the binding");
    // The CPU twin agrees on a sample (a CPU brute force over millions of triangles).
    let sample: Vec<Ray> = rays.iter().step_by(32).copied().collect();
    let on_cpu = cpu::closest_hits(&sample, &triangles);
    let on_gpu: Vec<Hit> = hits.iter().step_by(32).copied().collect();
    common::assert_same_hits(&on_gpu, &on_cpu, "CPU sample");
    common::assert_clean(&gpu);
}

/// Renders the Cornell box `width` pixels wide and two rows taller than one binding holds
/// (vec4s) with the `primary` integrator at 1 spp (pixel centres), checks sampled pixels
/// (the last row among them) against the CPU, and writes and reads back the film as EXR.
fn render_film_past_one_binding(width: u32) {
    let gpu = common::gpu();
    let binding = gpu.info().limits.max_storage_buffer_range;
    let height = u32::try_from(binding / 16 / u64::from(width) + 2).unwrap();
    let scene = scene::load("cornell-box").unwrap();
    let film_bytes = width as u64 * height as u64 * 16;
    if !common::holds_past_one_binding(&gpu, film_bytes, "the film's vec4 buffers") {
        return;
    }
    let options = RenderOptions::resolve(
        &scene,
        Some(width),
        Some(height),
        Some(1),
        Some(1),
        Some(IntegratorKind::Primary),
        None,
    )
    .unwrap();
    let out = render(&gpu, &scene, &options, &mut |_| {}).unwrap();
    check_pixels_against_the_cpu(&scene, &out.film);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.exr");
    write_exr(&path, &out.film, &out.metadata).unwrap();
    let (back, _) = read_exr(&path).unwrap();
    assert_same_film(&back, &out.film);
    common::assert_clean(&gpu);
}

/// Every 997th pixel and the whole last row: triangle, depth and eye-light shading as
/// the CPU computes them from the same camera.
fn check_pixels_against_the_cpu(scene: &Scene, film: &Film) {
    let (w, h) = (film.width(), film.height());
    let frame = scene.camera.frame(w, h);
    let triangles = scene.gpu_triangles();
    let last_row = (h - 1) * w..h * w;
    let pixels: Vec<u32> = (0..w * h).step_by(997).chain(last_row).collect();
    let rays: Vec<Ray> = pixels
        .iter()
        .map(|&p| {
            let dir = frame.pixel_center_direction(p % w, p / w);
            Ray::new(frame.origin, dir, 0.0, f32::INFINITY)
        })
        .collect();
    let expected = cpu::closest_hits(&rays, &triangles);
    let (ids, depth) = (
        film.triangle_id.as_ref().unwrap(),
        film.depth.as_ref().unwrap(),
    );
    let mut same = 0;
    for ((&p, ray), e) in pixels.iter().zip(&rays).zip(&expected) {
        let p = p as usize;
        // The GPU makes its rays in its own kernel: a ray grazing a shared edge may
        // land on the neighbouring triangle (rendered_triangle_ids_and_depth_match_...).
        if ids[p] != e.triangle {
            continue;
        }
        same += 1;
        let want = match e.is_hit() {
            false => Vec3::ZERO,
            true => {
                let t = &scene.triangles[e.triangle as usize];
                let m = &scene.materials[t.material as usize];
                let n = triangles[e.triangle as usize].normal().normalize();
                m.emission + m.diffuse * n.dot(Vec3::from(ray.dir)).abs()
            }
        };
        let got = Vec3::from(film.mean_rgb(p));
        assert!(
            (got - want).abs().max_element() <= 1e-4,
            "pixel {p}: {got} vs {want}"
        );
        if e.is_hit() {
            assert!((depth[p] - e.t).abs() <= 1e-4 * e.t, "pixel {p}: depth");
        }
    }
    assert!(
        same * 1000 >= pixels.len() * 999,
        "{same} of {} ids match",
        pixels.len()
    );
}

/// Bit for bit, pixel by pixel (copies of films this large would cost gigabytes).
fn assert_same_film(a: &Film, b: &Film) {
    assert_eq!((a.width(), a.height()), (b.width(), b.height()));
    let bits = |c: [f32; 3]| c.map(f32::to_bits);
    let rgb = (0..a.pixel_count()).position(|i| bits(a.mean_rgb(i)) != bits(b.mean_rgb(i)));
    assert_eq!(rgb, None, "RGB differs first at this pixel");
    assert!(a.triangle_id == b.triangle_id, "triangle ids");
    let (da, db) = (a.depth.as_ref().unwrap(), b.depth.as_ref().unwrap());
    assert!(
        da.iter().zip(db).all(|(x, y)| x.to_bits() == y.to_bits()),
        "depth"
    );
    let (na, nb) = (a.normal.as_ref().unwrap(), b.normal.as_ref().unwrap());
    assert!(
        na.iter().zip(nb).all(|(x, y)| bits(*x) == bits(*y)),
        "normals"
    );
}

/// The smallest film of odd width whose vec4 buffers are past one binding, two rows
/// over (on lavapipe 3001 × 2797: 8.4M rays traced in chunks, its last row past the
/// binding). Every kernel that sees such a buffer takes all of its dispatch's buffers
/// by address, so a larger film runs the same code with larger offsets, none near 2³²
/// bytes; `docs/PERFORMANCE.md` has an 8192² render.
#[test]
fn a_film_past_one_binding_renders_and_round_trips_through_exr() {
    render_film_past_one_binding(3001);
}

/// Every GPU integrator and the AOVs in the form that takes buffers by address render
/// the very image of the default form (on lavapipe: the descriptor twins).
#[test]
fn every_gpu_integrator_renders_the_same_image_by_address() {
    let gpu = common::gpu();
    let by_address = common::gpu_with_access(BufferAccess::Addresses);
    let scene = scene::load("cornell-box").unwrap();
    for integrator in [
        IntegratorKind::Primary,
        IntegratorKind::Ao,
        IntegratorKind::Shadow,
        IntegratorKind::Reflection,
        IntegratorKind::Path,
        IntegratorKind::Pt,
        IntegratorKind::LvcBdpt,
        IntegratorKind::CisLbdpt,
    ] {
        let options = RenderOptions::resolve(
            &scene,
            Some(48),
            Some(32),
            Some(2),
            Some(1),
            Some(integrator),
            None,
        )
        .unwrap();
        let a = render(&gpu, &scene, &options, &mut |_| {}).unwrap();
        let b = render(&by_address, &scene, &options, &mut |_| {}).unwrap();
        assert!(
            a.film
                .mean_rgb_buffer()
                .iter()
                .any(|c| c.iter().any(|v| *v > 0.0)),
            "{integrator}: an image"
        );
        assert_same_film(&a.film, &b.film);
    }
    common::assert_clean(&gpu);
    common::assert_clean(&by_address);
}

/// The Cornell box with `count` more triangles after its own, hidden inside its tall
/// block: millimetre triangles on a 40 mm grid around the block's centre, so that no
/// ray reaches them, the bounds (and so the ray offset) stay the box's, and the lights
/// and materials stay the same.
fn cornell_box_with_hidden_triangles(count: usize) -> Scene {
    let mut scene = scene::load("cornell-box").unwrap();
    let white = scene.material_index("white").unwrap();
    let centre = Vec3::new(368.5, 165.0, 351.25);
    scene.triangles.extend((0..count).map(|i| {
        let cell = |k: usize| ((i / k) % 40) as f32 - 20.0;
        let p = centre + Vec3::new(cell(1), cell(40), cell(1600));
        Triangle::new(p, p + Vec3::X, p + Vec3::Y, white)
    }));
    scene
}

/// The light-vertex-cache integrators on a scene whose triangle buffer is past one
/// binding (their kernels then take it by address) render the very image they render
/// without the extra, hidden triangles (through the descriptor twins, on lavapipe).
#[test]
fn light_vertex_cache_integrators_take_a_scene_past_one_binding() {
    let gpu = common::gpu();
    let binding_triangles = gpu.info().limits.max_storage_buffer_range / 48;
    let count = binding_triangles as usize + 1000;
    let bytes = ((count + 32) * size_of::<GpuTriangle>()) as u64;
    if !common::holds_past_one_binding(&gpu, bytes, "the padded scene's triangles") {
        return;
    }
    let plain = scene::load("cornell-box").unwrap();
    let padded = cornell_box_with_hidden_triangles(count);
    assert_eq!(padded.bounds(), plain.bounds());
    for integrator in [IntegratorKind::LvcBdpt, IntegratorKind::CisLbdpt] {
        let options = RenderOptions::resolve(
            &plain,
            Some(40),
            Some(30),
            Some(2),
            Some(1),
            Some(integrator),
            // A CPU BVH traces millions of triangles in moments.
            Some(TracerKind::CpuBvh),
        )
        .unwrap();
        let a = render(&gpu, &plain, &options, &mut |_| {}).unwrap();
        let b = render(&gpu, &padded, &options, &mut |_| {}).unwrap();
        assert!(
            a.film.mean_rgb_buffer().iter().flatten().any(|v| *v > 0.0),
            "{integrator}: an image"
        );
        let bits = |f: &Film| -> Vec<u32> {
            f.mean_rgb_buffer()
                .iter()
                .flatten()
                .map(|v| v.to_bits())
                .collect()
        };
        assert!(
            bits(&a.film) == bits(&b.film),
            "{integrator}: the same image"
        );
    }
    common::assert_clean(&gpu);
}
