//! What must not change the image of `lvc-bdpt` and `cis-lbdpt`, bit for bit: one stream
//! or three, material sorting on or off, a cache that starts too small and grows (the
//! light pass runs again), camera passes cut into pixel ranges. For CIS-LBDPT,
//! resampling one connection from one candidate is LVC-BDPT's uniform connection, up to
//! the rounding of two different shaders. Lights a power of two brighter scale the image
//! and its second moments exactly, even where the estimates' squares leave f32's range.
//! Then: the technique images sum to the image,
//! and a render is free of hazards under synchronization validation with the three
//! streams on distinct queues where the device has them.
use crate::common;

use glam::Vec3;
use splitray::film::FilmSums;
use splitray::integrator::lvc::{LvcIntegrator, LvcOptions, Variant};
use splitray::integrator::pt::PtScene;
use splitray::integrator::Integrator;
use splitray::scene::{builtin, PointLight, Scene};
use splitray::trace::TracerKind;
use splitray::vk::{Gpu, StreamPlacement};

const WIDTH: u32 = 16;
const HEIGHT: u32 = 12;
const PASSES: u32 = 3;

fn scene() -> Scene {
    let mut s = builtin("cornell-box").unwrap();
    s.point_lights.push(PointLight {
        position: Vec3::new(150.0, 450.0, 200.0),
        intensity: Vec3::splat(2e4),
    });
    s
}

fn integrator<'a>(gpu: &Gpu, scene: &Scene, options: &LvcOptions) -> LvcIntegrator<'a> {
    let pt = PtScene::new(scene);
    let tracer = TracerKind::default().create(gpu, &pt.triangles).unwrap();
    let frame = scene.camera.frame(WIDTH, HEIGHT);
    LvcIntegrator::new(gpu, tracer, &pt, &frame, options).unwrap()
}

fn render(gpu: &Gpu, scene: &Scene, options: &LvcOptions) -> FilmSums {
    let mut lvc = integrator(gpu, scene, options);
    lvc.render_passes(0, PASSES).unwrap();
    lvc.sums().unwrap()
}

fn options(variant: Variant) -> LvcOptions {
    let mut o = LvcOptions::new(variant, false);
    o.seed = 9;
    o.spp = PASSES;
    o.connections = 3;
    o.candidates = 5;
    o
}

#[test]
fn streams_sorting_and_cache_growth_leave_the_image_bit_identical() {
    let gpu = common::gpu();
    let scene = scene();
    for variant in [Variant::LvcBdpt, Variant::CisLbdpt] {
        let base = options(variant);
        let expected = render(&gpu, &scene, &base);
        assert!(expected.sum.iter().flatten().any(|&v| v > 0.0));
        let one_stream = LvcOptions { streams: 1, ..base };
        assert_eq!(
            render(&gpu, &scene, &one_stream),
            expected,
            "{variant:?}: 1 stream"
        );
        let sorted = LvcOptions { sort: true, ..base };
        assert_eq!(
            render(&gpu, &scene, &sorted),
            expected,
            "{variant:?}: sorted"
        );
        let small = LvcOptions {
            initial_cache: Some(1),
            ..base
        };
        let mut lvc = integrator(&gpu, &scene, &small);
        lvc.render_passes(0, PASSES).unwrap();
        assert!(lvc.lvc_counters().cache_regrowths >= 1);
        assert_eq!(lvc.sums().unwrap(), expected, "{variant:?}: grown cache");
    }
    common::assert_clean(&gpu);
}

#[test]
fn emitters_a_power_of_two_brighter_scale_the_image_exactly() {
    // Scaling the lights by 2^k scales every estimate by 2^k exactly (light subpaths'
    // roulette ignores their emitted flux), light tracing's fixed-point splats included:
    // they are scaled to the scene's brightest emitter, so that splats of lights in any
    // units keep all their bits (lights of 1e-8 lost 9 % of their light-traced image).
    // So are the second moments, which square estimates at that scale: squared as they
    // are, estimates of lights × 2^70 overflow f32 and those of lights × 2^-80 vanish,
    // and the standard error was infinite or zero.
    let gpu = common::gpu();
    let scene = scene();
    for variant in [Variant::LvcBdpt, Variant::CisLbdpt] {
        let expected = render(&gpu, &scene, &options(variant));
        let expected_se = expected.stderr().unwrap();
        assert!(
            expected_se.iter().flatten().any(|&v| v > 0.0),
            "{variant:?}"
        );
        for exponent in [-80, -40, 40, 70] {
            let factor = 2f32.powi(exponent);
            let got = render(
                &gpu,
                &common::scenes::brighter(&scene, factor),
                &options(variant),
            );
            let what = format!("{variant:?}, lights × 2^{exponent}");
            common::scenes::assert_scaled_exactly(&got, &expected, factor, &what);
            if exponent.abs() > 60 {
                assert!(
                    common::scenes::squares_leave_f32(&got.mean()),
                    "{what}: no estimate whose square leaves f32's range"
                );
            }
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn pixel_ranges_with_the_same_light_paths_leave_the_image_bit_identical() {
    let gpu = common::gpu();
    let scene = scene();
    let base = LvcOptions {
        light_paths: Some(64),
        ..options(Variant::CisLbdpt)
    };
    let expected = render(&gpu, &scene, &base);
    let ranges = LvcOptions {
        max_paths_per_chunk: 64,
        ..base
    };
    let mut lvc = integrator(&gpu, &scene, &ranges);
    assert_eq!(
        (lvc.plan().passes_per_chunk, lvc.plan().pixels_per_chunk),
        (1, 64)
    );
    lvc.render_passes(0, PASSES).unwrap();
    assert_eq!(lvc.sums().unwrap(), expected);
    common::assert_clean(&gpu);
}

#[test]
fn one_candidate_resampled_once_is_a_uniform_connection() {
    let gpu = common::gpu();
    let scene = scene();
    let uniform = LvcOptions {
        connections: 1,
        sort: true,
        ..options(Variant::LvcBdpt)
    };
    let resampled = LvcOptions {
        variant: Variant::CisLbdpt,
        candidates: 1,
        ..uniform
    };
    // The two are different pipelines (camera_connect.comp with and without
    // LVC_RESAMPLE), and Vulkan lets each one fuse a * b + c into an FMA where its
    // compiler likes (SPIR-V without NoContraction): NVIDIA's rounds a few values 1 ulp
    // apart, lavapipe's not at all. A wrong RIS weight or a different candidate would
    // change a pixel by a factor, not by 1e-5.
    let (a, b) = (
        render(&gpu, &scene, &resampled),
        render(&gpu, &scene, &uniform),
    );
    assert_eq!((a.width, a.height, a.passes), (b.width, b.height, b.passes));
    assert!(a.sum.iter().flatten().any(|&v| v > 0.0));
    for (pixel, (x, y)) in a.sum.iter().zip(&b.sum).enumerate() {
        for c in 0..3 {
            let bound = 1e-5 * x[c].abs().max(y[c].abs());
            assert!(
                (x[c] - y[c]).abs() <= bound,
                "pixel {pixel} channel {c}: resampled {} against uniform {}",
                x[c],
                y[c]
            );
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn technique_images_sum_to_the_image() {
    let gpu = common::gpu();
    let scene = scene();
    let o = LvcOptions {
        technique_images: true,
        ..options(Variant::CisLbdpt)
    };
    let mut lvc = integrator(&gpu, &scene, &o);
    lvc.render_passes(0, PASSES).unwrap();
    let mean = lvc.sums().unwrap().mean();
    let images = lvc.extra_images().unwrap();
    assert!(images.iter().any(|i| i.name == "s0_t2"));
    assert!(images.iter().any(|i| i.name == "s1_t2"));
    assert!(images.iter().any(|i| i.name == "s2_t2"));
    assert!(images.iter().any(|i| i.name == "s3_t1"));
    for (p, m) in mean.iter().enumerate() {
        for (c, &want) in m.iter().enumerate() {
            let sum: f32 = images.iter().map(|i| i.rgb[p][c]).sum();
            assert!(
                (sum - want).abs() <= 1e-4 * want.abs().max(1e-3),
                "pixel {p}: techniques sum to {sum}, the image is {want}"
            );
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn three_streams_are_hazard_free_under_synchronization_validation() {
    let gpu = common::gpu_with(StreamPlacement::Spread, true);
    let scene = scene();
    for variant in [Variant::LvcBdpt, Variant::CisLbdpt] {
        let o = LvcOptions {
            sort: true,
            ..options(variant)
        };
        let mut lvc = integrator(&gpu, &scene, &o);
        lvc.render_passes(0, 1).unwrap();
    }
    common::assert_clean(&gpu);
}
