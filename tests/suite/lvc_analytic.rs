//! `lvc-bdpt` and `cis-lbdpt` against analytic answers: a closed sphere of flat facets
//! whose walls all emit Le and reflect diffusely with albedo ρ, seen from inside. Radiance is uniform in
//! such an enclosure, whatever its shape: a path of k segments carries Le ρ^(k−1) to
//! every pixel, so the image mean is Le Σ_k ρ^(k−1) over the lengths sampled — Le / (1 − ρ)
//! unbounded. Each technique family alone (the others turned off, which removes them
//! from the weights) must converge to the lengths it can sample:
//!
//! | family                         | lengths k      |
//! |--------------------------------|----------------|
//! | s = 0 (emitter hits)           | 1 ..= max_depth |
//! | s = 1 (direct lighting)        | 2 ..= max_depth |
//! | t = 1 (light tracing)          | 2 ..= max_depth |
//! | s, t ≥ 2 (cache connections)   | 3 ..= max_depth |
//!
//! — the connections uniform and resampled, by independent and by systematic draws (an
//! unbiased resampling must leave the answer alone) — and all of them together,
//! weighted, to the whole sum. A wall of mixed diffuse and mirror layers (total albedo
//! Σ wᵢ ρᵢ) keeps the answer and puts delta vertices inside the paths. The image mean's
//! standard error comes from the spread of independent groups of passes (the pixels of a
//! pass are correlated through the cache and the splats).
use crate::common;

use common::analytic::{assert_agrees, lambert, mixed};

use glam::Vec3;
use splitray::integrator::lvc::{Families, LvcIntegrator, LvcOptions, Resampling, Variant};
use splitray::integrator::pt::PtScene;
use splitray::integrator::Integrator;
use splitray::scene::{Camera, FilmSize, Material, RenderSettings, Scene, Triangle};
use splitray::trace::TracerKind;
use splitray::vk::Gpu;

const SIZE: u32 = 12;
/// Groups of passes (the samples of the image mean) and passes per group: all techniques
/// weighted have little variance, single families more.
const WEIGHTED: Groups = Groups {
    groups: 6,
    passes: 3,
};
const ALONE: Groups = Groups {
    groups: 8,
    passes: 6,
};

#[derive(Clone, Copy)]
struct Groups {
    groups: u32,
    passes: u32,
}

/// A unit sphere of latitude-longitude facets (24 × 12), facing in: the angles between
/// neighbouring facets are shallow, so connections across an edge stay bounded (a box's
/// right-angled corners give single techniques tails too heavy to converge in a test).
fn enclosure(material: Material) -> Scene {
    let (slices, stacks) = (24usize, 12usize);
    let at = |i: usize, j: usize| {
        let (phi, theta) = (
            std::f32::consts::TAU * i as f32 / slices as f32,
            std::f32::consts::PI * j as f32 / stacks as f32,
        );
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        )
    };
    let mut triangles = Vec::new();
    for i in 0..slices {
        for j in 0..stacks {
            let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            for [a, b, c] in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let mut t = Triangle::new(a, b, c, 0);
                if t.is_degenerate() {
                    continue;
                }
                if t.geometric_normal().dot(-t.centroid()) < 0.0 {
                    t = Triangle::new(a, c, b, 0);
                }
                triangles.push(t);
            }
        }
    }
    Scene {
        name: "sphere-enclosure".into(),
        camera: Camera {
            position: Vec3::new(0.1, -0.2, 0.05),
            look_at: Vec3::new(0.4, 0.1, 1.0),
            up: Vec3::Y,
            fov_y: 80.0,
        },
        film: FilmSize {
            width: SIZE,
            height: SIZE,
        },
        triangles,
        materials: vec![material],
        point_lights: vec![],
        settings: RenderSettings::default(),
    }
}

/// The image mean and its standard error over groups of passes.
fn image_mean(gpu: &Gpu, scene: &Scene, options: &LvcOptions, g: Groups) -> (f64, f64) {
    let options = &LvcOptions {
        spp: g.passes,
        ..*options
    };
    let pt = PtScene::new(scene);
    let tracer = TracerKind::default().create(gpu, &pt.triangles).unwrap();
    let frame = scene.camera.frame(SIZE, SIZE);
    let mut lvc = LvcIntegrator::new(gpu, tracer, &pt, &frame, options).unwrap();
    let pixels = (SIZE * SIZE) as f64;
    let total = |l: &mut LvcIntegrator| -> f64 {
        l.sums().unwrap().sum.iter().flatten().sum::<f64>() / (3.0 * pixels * g.passes as f64)
    };
    let (mut prev, mut means) = (0.0, Vec::new());
    for k in 0..g.groups {
        lvc.render_passes(k * g.passes, g.passes).unwrap();
        let now = total(&mut lvc);
        means.push(now - prev);
        prev = now;
    }
    assert_eq!(lvc.kernel_counters().unwrap(), [0, 0]);
    common::analytic::mean_and_standard_error(&means)
}

/// Le Σ_{k=lo}^{hi} ρ^(k−1).
fn lengths(rho: f64, lo: u32, hi: u32) -> f64 {
    (lo..=hi).map(|k| rho.powi(k as i32 - 1)).sum()
}

fn options(variant: Variant, max_depth: i32, families: Families) -> LvcOptions {
    let mut o = LvcOptions::new(variant, false);
    o.seed = 5;
    o.max_depth = max_depth;
    o.families = families;
    o.connections = 2;
    o.candidates = 4;
    // Many more light paths than pixels: light tracing alone needs them to reach every
    // pixel a few times per pass.
    o.light_paths = Some(1024);
    o
}

#[test]
fn furnace_converges_to_le_over_one_minus_albedo() {
    let gpu = common::gpu();
    let all = Families::default();
    let scene = enclosure(lambert(0.5, 1.0));
    for variant in [Variant::LvcBdpt, Variant::CisLbdpt] {
        let got = image_mean(&gpu, &scene, &options(variant, -1, all), WEIGHTED);
        assert_agrees(&format!("{variant:?} lambert, unbounded"), got, 2.0);
    }
    // Delta vertices inside the paths, at a depth that keeps the test short.
    let scene = enclosure(mixed(1.0));
    for variant in [Variant::LvcBdpt, Variant::CisLbdpt] {
        let got = image_mean(&gpu, &scene, &options(variant, 6, all), WEIGHTED);
        let what = format!("{variant:?} lambert + mirror, max_depth 6");
        assert_agrees(&what, got, lengths(0.65, 1, 6));
    }
    common::assert_clean(&gpu);
}

#[test]
fn each_technique_family_alone_sums_the_path_lengths_it_samples() {
    let gpu = common::gpu();
    let (rho, depth) = (0.5, 4);
    let scene = enclosure(lambert(rho as f32, 1.0));
    let none = Families {
        emitter_hit: false,
        light_sample: false,
        connection: false,
        light_trace: false,
    };
    let families = [
        (
            "s = 0",
            Variant::LvcBdpt,
            Families {
                emitter_hit: true,
                ..none
            },
            1,
        ),
        (
            "s = 1",
            Variant::LvcBdpt,
            Families {
                light_sample: true,
                ..none
            },
            2,
        ),
        (
            "t = 1",
            Variant::LvcBdpt,
            Families {
                light_trace: true,
                ..none
            },
            2,
        ),
        (
            "s, t >= 2 uniform",
            Variant::LvcBdpt,
            Families {
                connection: true,
                ..none
            },
            3,
        ),
        (
            "s, t >= 2 resampled (systematic draws)",
            Variant::CisLbdpt,
            Families {
                connection: true,
                ..none
            },
            3,
        ),
    ];
    for (what, variant, f, shortest) in families {
        let got = image_mean(&gpu, &scene, &options(variant, depth, f), ALONE);
        assert_agrees(what, got, lengths(rho, shortest, depth as u32));
    }
    let connections = Families {
        connection: true,
        ..none
    };
    // The resampled family above drew systematically (the default); independent draws
    // must leave the answer alone too.
    let independent = LvcOptions {
        resampling: Resampling::Independent,
        ..options(Variant::CisLbdpt, depth, connections)
    };
    let got = image_mean(&gpu, &scene, &independent, ALONE);
    let what = "s, t >= 2 resampled by independent draws";
    assert_agrees(what, got, lengths(rho, 3, depth as u32));
    common::assert_clean(&gpu);
}
