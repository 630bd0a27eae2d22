//! `pt`'s kernels against their CPU twins (`integrator::pt::twin`):
//! - `finish` and `nee_accumulate` alone, on synthetic records: no path, one, sizes
//!   around the workgroup's and a large one; several samples per pixel; live ids in any
//!   order; contributions absent, occluded, and NaN or infinite radiance; `finish` on
//!   radiance near 1, 2^70 and 2^-80 with the brightness scale that brings it back
//!   near 1. Their sums and the count of dropped samples must be the twin's bit for bit
//!   (the kernels only add, in the twin's order).
//! - whole samples: every pixel of a film rendered by `generate`, `shade`,
//!   `nee_accumulate` and `finish` on the GPU against `PathTwin`, which walks the same
//!   paths with the same random numbers on the CPU, for each strategy and several
//!   depths, on scenes with mirrors, layered BSDFs, glass, shading normals and a point
//!   light.

use crate::common;

use bytemuck::Zeroable;
use glam::Vec3;
use splitray::bidir::CpuScene;
use splitray::film::compensated;
use splitray::integrator::pt::gpu::{PathState, PtParams};
use splitray::integrator::pt::twin::{finish, nee_accumulate, PathTwin};
use splitray::integrator::pt::{render_pt, PtOptions, PtScene, Strategy};
use splitray::scene::{BsdfKind, MaterialBsdf, MaterialLayer, MicrofacetModel, Scene};
use splitray::shaders;
use splitray::trace::{Hit, TracerKind, MISS};
use splitray::vk::{self, Buffer, Gpu, StreamKind};

const WORKGROUP: u32 = 64;

/// A buffer of at least one element (an empty list still needs a binding).
fn upload<T: bytemuck::Pod>(gpu: &Gpu, name: &str, data: &[T]) -> Buffer {
    if data.is_empty() {
        gpu.upload(name, &[T::zeroed()]).unwrap()
    } else {
        gpu.upload(name, data).unwrap()
    }
}

fn run(gpu: &Gpu, kernel: shaders::Kernel, bindings: &[&Buffer], params: &PtParams, items: u32) {
    let pipeline = vk::compute_pipeline(
        gpu,
        kernel,
        bindings.len() as u32,
        size_of::<PtParams>() as u32,
        &[WORKGROUP],
    )
    .unwrap();
    let bindings: Vec<_> = bindings.iter().map(|&b| b.into()).collect();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch_items(&pipeline, &bindings, params, items as u64)
        .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
}

/// Path states with radiance drawn from `seed`: a few NaN or infinite.
fn path_states(n: usize, seed: u64) -> Vec<PathState> {
    let words = common::random_u32s(n, seed);
    let values = common::uniforms(n, seed + 1);
    words
        .iter()
        .zip(values)
        .map(|(w, v)| {
            let mut radiance = [v, 0.5 * v, 3.0 * v, 0.25];
            match w % 32 {
                0 => radiance[0] = f32::NAN,
                1 => radiance[1] = f32::INFINITY,
                2 => radiance[2] = f32::NEG_INFINITY,
                3 => radiance = [0.0; 4],
                _ => {}
            }
            PathState {
                radiance,
                ..Zeroable::zeroed()
            }
        })
        .collect()
}

fn bits_equal(a: &[[f32; 4]], b: &[[f32; 4]]) -> bool {
    a.len() == b.len()
        && a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// `finish` over `pixels` pixels and `samples` samples of each, of radiance about
/// 2^`exponent` squared at the brightness scale 2^-`exponent`, added to sums (and
/// remainders) that already hold a pass.
fn check_finish(gpu: &Gpu, pixels: usize, samples: usize, exponent: i32) {
    let unit = 2f32.powi(exponent);
    let mut paths = path_states(pixels * samples, 7 + pixels as u64);
    for p in &mut paths {
        for c in &mut p.radiance[..3] {
            *c *= unit;
        }
    }
    let start = common::uniforms(pixels, 3);
    // Remainders well inside their sums' last bit (film::compensated).
    let rest = |v: f32, k: i32| v * 2f32.powi(k);
    let mut want: Vec<[f32; 4]> = start
        .iter()
        .map(|&v| [v * unit, v, 0.0, 1.0])
        .chain(
            start
                .iter()
                .map(|&v| [rest(v * unit, -28), -rest(v, -33), 0.0, 0.0]),
        )
        .collect();
    let mut want2: Vec<[f32; 4]> = start
        .iter()
        .map(|&v| [v, v, v, 0.0])
        .chain(
            start
                .iter()
                .map(|&v| [0.0, rest(v, -26), -rest(v, -45), 0.0]),
        )
        .collect();
    let (sums, sums2) = (
        compensated::film_rgb(&want, 1.0),
        compensated::film_rgb(&want2, 1.0),
    );
    let buffers = [
        upload(gpu, "paths", &paths),
        upload(gpu, "accum", &want),
        upload(gpu, "accum2", &want2),
        gpu.zeroed::<u32>("counters", 1).unwrap(),
    ];
    let dropped = if pixels == 0 {
        0
    } else {
        finish(&paths, &mut want, &mut want2, 1.0 / unit)
    };
    let params = PtParams {
        width: pixels as u32,
        height: 1,
        pixel_count: pixels as u32,
        path_count: paths.len() as u32,
        brightness_scale: 1.0 / unit,
        ..Zeroable::zeroed()
    };
    run(
        gpu,
        shaders::INTEGRATOR_PT_FINISH,
        &buffers.iter().collect::<Vec<_>>(),
        &params,
        pixels as u32,
    );
    let what = format!("finish: {pixels} pixels × {samples} samples of about 2^{exponent}");
    let got: Vec<[f32; 4]> = buffers[1].read().unwrap();
    let got2: Vec<[f32; 4]> = buffers[2].read().unwrap();
    assert!(bits_equal(&got[..2 * pixels], &want), "{what}: Σ L");
    assert!(bits_equal(&got2[..2 * pixels], &want2), "{what}: Σ L²");
    assert_eq!(buffers[3].read::<u32>().unwrap()[0], dropped, "{what}");
    if pixels * samples >= 1000 {
        assert!(dropped > 0, "{what}: the case holds non-finite samples");
    }
    // Σ L keeps every sample's bits: each addition rounds by half the pair's quantum
    // (2^-48 of the sum at most, 2^-127 below 2^-79) and its remainder's sum by about
    // 2^-47 of the sum. Squared unscaled, radiance of 2^70 overflows f32 and radiance of
    // 2^-80 vanishes; scaled, the second moments are the f64 sums' to f32 rounding of
    // each square.
    let (mut exact, mut exact2) = (sums, sums2);
    for (p, path) in paths.iter().enumerate() {
        let l = &path.radiance[..3];
        if l.iter().all(|v| v.is_finite()) {
            for k in 0..3 {
                exact[p % pixels.max(1)][k] += l[k] as f64;
                exact2[p % pixels.max(1)][k] += (l[k] as f64 / unit as f64).powi(2);
            }
        }
    }
    let (got, got2) = (
        compensated::film_rgb(&want, 1.0),
        compensated::film_rgb(&want2, 1.0),
    );
    let bound = |e: f64| (samples as f64) * (e.abs() * 2f64.powi(-46) + 2f64.powi(-126));
    for p in 0..pixels {
        for k in 0..3 {
            let (s, e) = (got[p][k], exact[p][k]);
            assert!(
                (s - e).abs() <= bound(e),
                "{what}: pixel {p}: Σ L {s} vs {e}"
            );
            let (q, e) = (got2[p][k], exact2[p][k]);
            assert!(
                (q - e).abs() <= 1e-6 * e,
                "{what}: pixel {p}: Σ (s L)² {q} vs {e}"
            );
        }
    }
}

/// `nee_accumulate` for `live` paths scattered among twice as many.
fn check_nee_accumulate(gpu: &Gpu, live: usize) {
    let total = 2 * live + 3;
    let mut ids: Vec<u32> = (0..total as u32).collect();
    let shuffle = common::random_u32s(total, live as u64);
    for i in (1..total).rev() {
        ids.swap(i, shuffle[i] as usize % (i + 1));
    }
    ids.truncate(live);
    let words = common::random_u32s(live, 11);
    let values = common::uniforms(live, 12);
    // A third occluded; a quarter without a contribution (w = 0).
    let shadow_hits: Vec<Hit> = words
        .iter()
        .map(|w| Hit {
            t: 1.0,
            triangle: if w % 3 == 0 { 5 } else { MISS },
            u: 0.0,
            v: 0.0,
        })
        .collect();
    let nee: Vec<[f32; 4]> = words
        .iter()
        .zip(&values)
        .map(|(w, &v)| [v, 2.0 * v, 0.125, if w % 4 == 1 { 0.0 } else { 1.0 }])
        .collect();
    let mut want = path_states(total, 13);
    let buffers = [
        upload(gpu, "live-ids", &ids),
        upload(gpu, "shadow-hits", &shadow_hits),
        upload(gpu, "nee", &nee),
        upload(gpu, "paths", &want),
    ];
    nee_accumulate(&ids, &shadow_hits, &nee, &mut want);
    let params = PtParams {
        active_count: live as u32,
        ..Zeroable::zeroed()
    };
    run(
        gpu,
        shaders::INTEGRATOR_PT_NEE_ACCUMULATE,
        &buffers.iter().collect::<Vec<_>>(),
        &params,
        live as u32,
    );
    let got: Vec<PathState> = buffers[3].read().unwrap();
    let radiance = |p: &[PathState]| p.iter().map(|s| s.radiance).collect::<Vec<_>>();
    assert!(
        bits_equal(&radiance(&got), &radiance(&want)),
        "nee_accumulate: {live} live paths"
    );
}

#[test]
fn finish_and_nee_accumulate_match_their_twins_bit_for_bit() {
    let gpu = common::gpu();
    for pixels in [0, 1, 63, 64, 65, 1000, 100_003] {
        for samples in [1, 3] {
            for exponent in [0, 70, -80] {
                check_finish(&gpu, pixels, samples, exponent);
            }
        }
    }
    for live in [0, 1, 63, 64, 65, 1000, 100_003] {
        check_nee_accumulate(&gpu, live);
    }
    common::assert_clean(&gpu);
}

/// The tricky Cornell box with its tall block made of smooth glass.
fn glass_cornell_box() -> Scene {
    let mut scene = common::scenes::tricky_cornell_box();
    let mut glass = scene.materials[0].clone();
    glass.name = "glass".into();
    glass.bsdf = Some(MaterialBsdf {
        layers: vec![MaterialLayer {
            kind: BsdfKind::from_name("glass").unwrap(),
            reflectance: Vec3::ONE,
            roughness: 0.0,
            distribution: MicrofacetModel::Ggx,
            ior: 1.5,
            weight: 1.0,
        }],
    });
    scene.materials.push(glass);
    let glass = scene.materials.len() as u32 - 1;
    // Triangles 20..30 are the tall block (scene::builtin).
    for t in &mut scene.triangles[20..30] {
        t.material = glass;
    }
    scene
}

/// Whether two sums of radiance agree up to float rounding.
fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().cmple(1e-3 * (a.abs() + b.abs()) + 1e-6).all()
}

/// Renders `scene` at 32×24 with `samples` samples per pixel in one chunk and checks
/// every pixel's sums against the twin's samples.
fn check_samples(gpu: &Gpu, scene: &Scene, options: PtOptions, what: &str) {
    let (width, height) = (32, 24);
    let tables = PtScene::new(scene);
    let mut tracer = TracerKind::Pdacrt.create(gpu, &tables.triangles).unwrap();
    let camera = scene.camera.frame(width, height);
    let out = render_pt(
        gpu,
        tracer.as_mut(),
        &tables,
        &camera,
        &options,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(out.non_finite_dropped, 0, "{what}");
    let cpu = CpuScene::new(scene);
    let twin = PathTwin::new(&cpu, &camera, &options);
    let mut parted = Vec::new();
    let mut deepest = 0;
    let mut lit = 0;
    for pixel in 0..width * height {
        let (mut sum, mut sum2) = (Vec3::ZERO, Vec3::ZERO);
        for sample in 0..options.spp {
            let (l, depth) = twin.radiance(pixel, sample);
            deepest = deepest.max(depth);
            sum += l;
            let scaled = l * out.brightness_scale;
            sum2 += scaled * scaled;
        }
        lit += usize::from(sum.max_element() > 0.0);
        let got = &out.sum_rgb[pixel as usize];
        assert_eq!(
            got[3], options.spp as f32,
            "{what}: pixel {pixel}'s samples"
        );
        let got2 = Vec3::from_slice(&out.sum_sq[pixel as usize][..3]);
        if !close(Vec3::from_slice(&got[..3]), sum) || !close(got2, sum2) {
            parted.push(pixel);
        }
    }
    let pixels = (width * height) as usize;
    eprintln!(
        "{what}: {} of {} pixels parted from the twin {parted:?}; deepest path {deepest}, \
         {lit} lit",
        parted.len(),
        pixels
    );
    assert!(
        parted.len() * 100 <= pixels,
        "{what}: {} pixels parted from the twin: {parted:?}",
        parted.len()
    );
    // Not a comparison of black films: BSDF sampling alone finds the small light
    // rarely, light sampling nearly everywhere.
    let needed = match options.strategy {
        Strategy::Bsdf => pixels / 100,
        _ => pixels / 2,
    };
    assert!(lit > needed, "{what}: {lit} pixels lit");
    if options.max_depth < 0 {
        assert!(deepest > options.rr_depth, "{what}: Russian roulette ran");
    }
}

#[test]
fn every_sample_is_its_cpu_twins() {
    let gpu = common::gpu();
    let scenes = [
        ("tricky Cornell box", common::scenes::tricky_cornell_box()),
        ("glass Cornell box", glass_cornell_box()),
    ];
    for (name, scene) in &scenes {
        for strategy in [Strategy::Mis, Strategy::Nee, Strategy::Bsdf] {
            for max_depth in [2, -1] {
                let options = PtOptions {
                    spp: 2,
                    seed: 0x5eed_0000_0000_0007,
                    max_depth,
                    rr_depth: 3,
                    strategy,
                    ..Default::default()
                };
                let what = format!("{name}, {strategy:?}, max depth {max_depth}");
                check_samples(&gpu, scene, options, &what);
            }
        }
    }
    common::assert_clean(&gpu);
}
