//! The path tracer against analytic answers, its estimators against each other, and
//! its determinism (sorting on or off gives the same film bit for bit; scenes a power of
//! two larger, or with lights a power of two brighter, give the same film, scaled).
use crate::common;

use glam::Vec3;
use splitray::film::FilmSums;
use splitray::integrator::pt::{render_pt, PtOptions, PtOutput, PtScene, Strategy};
use splitray::integrator::IntegratorKind;
use splitray::render::{create_integrator, RenderOptions};
use splitray::scene::{builtin, Camera, FilmSize, Material, RenderSettings, Scene, Triangle};
use splitray::trace::TracerKind;
use splitray::vk::Gpu;

fn render(gpu: &Gpu, scene: &Scene, size: u32, tracer: TracerKind, opts: PtOptions) -> PtOutput {
    let pt = PtScene::new(scene);
    let mut tracer = tracer.create(gpu, &pt.triangles).unwrap();
    let camera = scene.camera.frame(size, size);
    render_pt(gpu, tracer.as_mut(), &pt, &camera, &opts, &mut |_| {}).unwrap()
}

/// Image mean (average of the channel means) and its standard error, from the
/// per-pixel sample variances.
fn image_mean(out: &PtOutput) -> (f64, f64) {
    let (mean, se) = out.mean_and_stderr();
    let p = mean.len() as f64;
    let m: f64 = mean.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3.0 * p);
    let var: f64 = se
        .iter()
        .flatten()
        .map(|&s| (s as f64).powi(2))
        .sum::<f64>()
        / (9.0 * p * p);
    (m, var.sqrt())
}

/// A closed cube [-1, 1]^3, every wall facing inwards, Lambert albedo `a`, emission
/// `le` on every triangle; the camera sits at the centre.
fn furnace(a: f32, le: f32) -> Scene {
    let mut tris = Vec::new();
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    for axis in 0..3 {
        for s in [-1.0f32, 1.0] {
            let corner = |u: f32, v: f32| {
                let mut p = [0.0; 3];
                p[axis] = s;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                c(p[0], p[1], p[2])
            };
            let (p0, p1, p2, p3) = (
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            );
            let mut t0 = Triangle::new(p0, p1, p2, 0);
            let mut t1 = Triangle::new(p0, p2, p3, 0);
            // Normals point at the centre.
            if t0.geometric_normal().dot(-t0.centroid()) < 0.0 {
                t0 = Triangle::new(p0, p2, p1, 0);
                t1 = Triangle::new(p0, p3, p2, 0);
            }
            tris.push(t0);
            tris.push(t1);
        }
    }
    Scene {
        name: "furnace".into(),
        camera: Camera {
            position: Vec3::ZERO,
            look_at: Vec3::new(0.3, 0.2, 1.0),
            up: Vec3::Y,
            fov_y: 100.0,
        },
        film: FilmSize {
            width: 16,
            height: 16,
        },
        triangles: tris,
        materials: vec![Material {
            diffuse: Vec3::splat(a),
            emission: Vec3::splat(le),
            ..Material::named("furnace")
        }],
        point_lights: vec![],
        settings: RenderSettings::default(),
    }
}

fn opts(spp: u32, max_depth: i32, strategy: Strategy) -> PtOptions {
    PtOptions {
        spp,
        seed: 7,
        max_depth,
        strategy,
        ..Default::default()
    }
}

#[test]
fn furnace_converges_to_le_over_one_minus_albedo() {
    let gpu = common::gpu();
    for (a, spp) in [(0.5f32, 64), (0.8, 32)] {
        let scene = furnace(a, 1.0);
        let out = render(
            &gpu,
            &scene,
            16,
            TracerKind::BruteForce,
            opts(spp, -1, Strategy::Mis),
        );
        let expected = 1.0 / (1.0 - a as f64);
        let (m, se) = image_mean(&out);
        eprintln!("furnace a={a}: mean {m:.5} ± {se:.5}, expected {expected:.5}");
        assert!(
            (m - expected).abs() < 4.0 * se + 1e-4,
            "a={a}: {m} vs {expected} (se {se})"
        );
        // Every pixel sees the same radiance: a per-pixel z-test (grey, so one channel).
        // All pixels share one distribution, so the standard error is pooled over the
        // image: a single pixel's own sample variance at 32 samples underestimates the
        // heavy tail that Russian roulette gives.
        let (mean, stderr) = out.mean_and_stderr();
        let pooled = (stderr.iter().map(|s| (s[0] as f64).powi(2)).sum::<f64>()
            / stderr.len() as f64)
            .sqrt();
        let z: Vec<f64> = mean
            .iter()
            .map(|m| (m[0] as f64 - expected).abs() / pooled)
            .collect();
        let beyond = z.iter().filter(|&&z| z > 4.0).count();
        let zmax = z.iter().cloned().fold(0.0, f64::max);
        eprintln!(
            "furnace a={a}: {beyond} of {} pixels beyond 4 sigma (max |z| {zmax:.2})",
            z.len()
        );
        assert!(
            beyond * 100 <= z.len(),
            "a={a}: {beyond} pixels beyond 4 sigma"
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn furnace_depth_limits_give_partial_sums_for_every_strategy() {
    let gpu = common::gpu();
    let a = 0.5f32;
    let scene = furnace(a, 1.0);
    // max_depth 0: nothing, not even the emitters around the camera.
    let out = render(
        &gpu,
        &scene,
        8,
        TracerKind::BruteForce,
        opts(2, 0, Strategy::Mis),
    );
    assert!(out
        .pixel_sums()
        .iter()
        .all(|s| s[..3] == [0.0; 3] && s[3] == 2.0));
    // max_depth 1: only emission seen directly, with no noise at all.
    let out = render(
        &gpu,
        &scene,
        8,
        TracerKind::BruteForce,
        opts(2, 1, Strategy::Mis),
    );
    let (mean, _) = out.mean_and_stderr();
    assert!(mean.iter().flatten().all(|&v| v == 1.0), "{:?}", &mean[..4]);
    // max_depth 3: Le (1 + a + a^2), by light sampling, BSDF sampling and MIS alike.
    let expected = 1.0 + 0.5 + 0.25;
    for strategy in [Strategy::Mis, Strategy::Nee, Strategy::Bsdf] {
        let out = render(
            &gpu,
            &scene,
            16,
            TracerKind::BruteForce,
            opts(32, 3, strategy),
        );
        let (m, se) = image_mean(&out);
        eprintln!("furnace depth 3 {strategy:?}: {m:.5} ± {se:.5}, expected {expected}");
        assert!(
            (m - expected).abs() < 4.0 * se + 1e-4,
            "{strategy:?}: {m} vs {expected} (se {se})"
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn cornell_strategies_agree() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let mut results = Vec::new();
    for strategy in [Strategy::Mis, Strategy::Nee, Strategy::Bsdf] {
        let spp = if strategy == Strategy::Bsdf { 128 } else { 32 };
        let out = render(
            &gpu,
            &scene,
            24,
            TracerKind::BruteForce,
            opts(spp, 4, strategy),
        );
        let (m, se) = image_mean(&out);
        eprintln!("cornell {strategy:?}: {m:.5} ± {se:.5}");
        results.push((strategy, m, se));
    }
    let (_, m0, s0) = results[0];
    for &(strategy, m, s) in &results[1..] {
        let sigma = (s0 * s0 + s * s).sqrt();
        assert!(
            (m - m0).abs() < 4.0 * sigma,
            "{strategy:?}: {m} vs MIS {m0} (sigma {sigma})"
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn sorting_never_changes_the_image_and_seeds_decide_it() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let run = |sort: bool, seed: u64| {
        let o = PtOptions {
            spp: 4,
            seed,
            sort,
            ..Default::default()
        };
        render(&gpu, &scene, 24, TracerKind::Pdacrt, o)
    };
    let sorted = run(true, 3);
    let unsorted = run(false, 3);
    let bits =
        |o: &PtOutput| -> Vec<u32> { o.sum_rgb.iter().flatten().map(|v| v.to_bits()).collect() };
    assert_eq!(sorted.rays_traced, unsorted.rays_traced);
    assert!(bits(&sorted) == bits(&unsorted), "sorting changed the film");
    assert!(
        bits(&run(true, 3)) == bits(&sorted),
        "same seed, different film"
    );
    assert!(
        bits(&run(true, 4)) != bits(&sorted),
        "the seed changed nothing"
    );
    common::assert_clean(&gpu);
}

#[test]
fn a_film_of_a_million_samples_keeps_every_bit_of_the_next_ones() {
    // Seen at depth 1 the furnace's every sample is its emission, 0.1 (as an f32). A
    // film resumed at 2^20 samples sums near 104857.6, where an f32 sum steps by 2^-7:
    // each new 0.1 would be rounded to 13 steps, 1.6 % too much, and the mean would move
    // 3 ulps off 0.1 after 16 of them. The film's sums in two floats keep every bit.
    let gpu = common::gpu();
    let le = 0.1f32;
    let scene = furnace(0.5, le);
    let (size, start, more) = (8u32, 1u32 << 20, 16u32);
    let mut options = RenderOptions::resolve(
        &scene,
        Some(size),
        Some(size),
        Some(start + more),
        Some(7),
        Some(IntegratorKind::Pt),
        Some(TracerKind::BruteForce),
    )
    .unwrap();
    options.max_depth = 1;
    let mut pt = create_integrator(&gpu, &scene, &options).unwrap();
    let pixels = (size * size) as usize;
    let le = le as f64;
    let mut film = FilmSums::new(size, size, 1, true);
    film.passes = start;
    film.sum = vec![[le * start as f64; 3]; pixels];
    film.sum_sq = Some(vec![[le * le * start as f64; 3]; pixels]);
    pt.restore(&film).unwrap();
    pt.render_passes(start, more).unwrap();
    let sums = pt.sums().unwrap();
    assert_eq!(sums.passes, start + more);
    // The kernel squares each sample in f32.
    let (n, square) = ((start + more) as f64, (0.1f32 * 0.1f32) as f64);
    let (sum, sum_sq) = (le * n, le * le * start as f64 + square * more as f64);
    let sums_sq = sums.sum_sq.as_ref().unwrap();
    for (s, q) in sums.sum.iter().flatten().zip(sums_sq.iter().flatten()) {
        assert!(
            (s - sum).abs() <= sum * 2f64.powi(-46),
            "Σ L = {s}, not {sum}"
        );
        assert!(
            (q - sum_sq).abs() <= sum_sq * 2f64.powi(-46),
            "Σ L² = {q}, not {sum_sq}"
        );
    }
    assert!(sums.mean().iter().flatten().all(|&m| m == le as f32));
    // Every sample alike: the standard error is nothing but the sums' rounding.
    let se = sums.stderr().unwrap();
    assert!(se.iter().flatten().all(|&e| e < 1e-9), "{:?}", se[0]);
    drop(pt);
    common::assert_clean(&gpu);
}

#[test]
fn time_limit_stops_after_the_pass_it_ran_out_in() {
    let gpu = common::gpu();
    let scene = furnace(0.5, 1.0);
    let o = PtOptions {
        spp: u32::MAX,
        time_limit: Some(0.2),
        max_paths_per_chunk: 64,
        max_depth: 2,
        ..Default::default()
    };
    let start = std::time::Instant::now();
    let out = render(&gpu, &scene, 8, TracerKind::BruteForce, o);
    assert!(out.passes >= 1 && out.passes < 100_000);
    assert!(out.pixel_sums().iter().all(|s| s[3] == out.passes as f32));
    assert!(start.elapsed().as_secs_f64() < 30.0);
    common::assert_clean(&gpu);
}

#[test]
fn a_scene_a_power_of_two_larger_or_smaller_renders_the_same_image() {
    // Every length scales exactly, so must every ray and its offset off surfaces (a
    // fixed floor on that offset once made scenes of about 1e-6 lose 10 % of their
    // indirect light).
    let gpu = common::gpu();
    let scene = common::scenes::tricky_cornell_box();
    let opts = opts(2, 5, Strategy::Mis);
    let expected = render(&gpu, &scene, 16, TracerKind::Pdacrt, opts);
    for exponent in [-30, 20] {
        let smaller = common::scenes::scaled(&scene, 2f32.powi(exponent));
        let out = render(&gpu, &smaller, 16, TracerKind::Pdacrt, opts);
        assert!(
            out.sum_rgb == expected.sum_rgb,
            "scene × 2^{exponent}: the image changed"
        );
    }
    common::assert_clean(&gpu);
}

/// The film of `out` (`size × size`), second moments unscaled.
fn film_sums(out: &PtOutput, size: u32) -> FilmSums {
    FilmSums::from_gpu(
        size,
        size,
        out.passes,
        1,
        &out.sum_rgb,
        Some(&out.sum_sq),
        out.brightness_scale,
    )
}

#[test]
fn emitters_a_power_of_two_brighter_scale_the_image_and_its_standard_error_exactly() {
    // Roulette and MIS look at throughputs and densities, never at emission, so lights
    // 2^k as bright scale every sample by 2^k exactly. The second moments square samples
    // multiplied by a power of two that puts the brightest emitter near 1: squared as
    // they are, samples of lights × 2^70 overflow f32 and those of lights × 2^-80
    // vanish, and the standard error was infinite or zero.
    let gpu = common::gpu();
    let scene = common::scenes::tricky_cornell_box();
    let size = 16;
    let opts = opts(3, 5, Strategy::Mis);
    let expected = film_sums(&render(&gpu, &scene, size, TracerKind::Pdacrt, opts), size);
    let expected_se = expected.stderr().unwrap();
    assert!(expected_se.iter().flatten().any(|&v| v > 0.0));
    for exponent in [-80, 70] {
        let factor = 2f32.powi(exponent);
        let brighter = common::scenes::brighter(&scene, factor);
        let out = render(&gpu, &brighter, size, TracerKind::Pdacrt, opts);
        assert_eq!(out.non_finite_dropped, 0);
        let got = film_sums(&out, size);
        let what = format!("lights × 2^{exponent}");
        common::scenes::assert_scaled_exactly(&got, &expected, factor, &what);
        let se = got.stderr().unwrap();
        // The test means something: some samples' squares leave f32's range.
        assert!(
            common::scenes::squares_leave_f32(&got.mean()),
            "{what}: no mean whose square leaves f32's range"
        );
        // What the benchmarks and reference comparisons read agrees.
        let (_, se_out) = out.mean_and_stderr();
        assert_eq!(se_out, se, "{what}: PtOutput's standard error");
    }
    common::assert_clean(&gpu);
}
