//! CBPT's combination kernels (glsl/integrator/cbpt/) against their CPU twins
//! (src/integrator/cbpt/cpu_kernels.rs): the shadow rays and the packing of visibility
//! kernel by kernel, then the whole GPU combination — batches, double-buffered results,
//! downloads on the transfer stream, two population couples in flight — on real
//! populations and on adversarial ones (coincident ends, point lights, no linking
//! vertex at all), at 0, 1, non-power-of-two and large segment counts, through several
//! tracers: visibility bit for bit, shading within float tolerance.
use crate::common;

use std::sync::Arc;

use glam::Vec3;
use splitray::bidir::{Counters, CpuScene};
use splitray::integrator::cbpt::compare::{compare_shading, visibility_differences, End};
use splitray::integrator::cbpt::cpu_kernels::{self, evaluate};
use splitray::integrator::cbpt::gpu::CbptPush;
use splitray::integrator::cbpt::layout::{CombinationData, GpuVertex, Kinds, Shading, Tables};
use splitray::integrator::cbpt::pipeline::Evaluator;
use splitray::integrator::cbpt::population::Population;
use splitray::integrator::cbpt::steps::ImagePositions;
use splitray::integrator::cbpt::{CameraPaths, CbptOptions, CbptSettings, GpuCombiner, Setup};
use splitray::scene::Scene;
use splitray::shaders;
use splitray::trace::{Hit, Ray, TracerKind, MISS};
use splitray::vk::{compute_pipeline, Gpu, StreamKind};

/// The tables of step `step` of pass 0 of a 24 × 16 film of `scene`.
fn population_tables(scene: &Scene, nc: u32, nl: u32, step: u32) -> (CpuScene, Tables) {
    let options = CbptOptions {
        seed: 11,
        settings: CbptSettings {
            camera_paths: CameraPaths::Fixed(nc),
            light_paths: nl,
            ..Default::default()
        },
        ..Default::default()
    };
    let frame = scene.camera.frame(24, 16);
    let setup = Setup::new(CpuScene::new(scene), &frame, &options, nc, nl).unwrap();
    let cpu = setup.cpu_side();
    let positions = ImagePositions::new(24 * 16, 0, setup.streams.shuffle);
    let id = setup.steps(0..1)[step as usize].clone();
    let population = Population::sample(&cpu.sampling, id, &positions, &mut Counters::default());
    let tables = Tables::new(&population);
    (CpuScene::new(scene), tables)
}

/// Tables of vertices at random points of the Cornell box, some on its walls' planes,
/// a few at the same place in both tables (coincident ends), point-light vertices (zero
/// normal) and every material.
fn adversarial_tables(scene: &CpuScene, cameras: usize, lights: usize, surface: usize) -> Tables {
    let u = common::uniforms((cameras + lights) * 16, 5);
    let materials = scene.tables.bsdfs.len() as u32;
    let vertex = |k: usize| {
        let r = &u[k * 16..];
        let p = Vec3::new(r[0], r[1], r[2]) * 550.0;
        let unit = |a: f32, b: f32, c: f32| (Vec3::new(a, b, c) - 0.5).normalize_or(Vec3::Y);
        let ng = unit(r[3], r[4], r[5]);
        let ns = (ng + 0.3 * unit(r[6], r[7], r[8])).normalize();
        let wo = unit(r[9], r[10], r[11]);
        let wo = if wo.dot(ng) < 0.0 && r[12] < 0.7 {
            -wo
        } else {
            wo
        };
        GpuVertex {
            p: p.into(),
            material: (r[13] * materials as f32) as u32 % materials,
            ng: ng.into(),
            ns: ns.into(),
            wo: wo.into(),
            ..Default::default()
        }
    };
    let camera: Vec<GpuVertex> = (0..cameras).map(vertex).collect();
    let mut light: Vec<GpuVertex> = (0..lights).map(|k| vertex(cameras + k)).collect();
    for (k, l) in light.iter_mut().enumerate() {
        if k % 7 == 3 && !camera.is_empty() {
            l.p = camera[k % camera.len()].p; // coincident with a camera vertex
        }
        if k >= surface && k % 2 == 0 {
            l.ng = [0.0; 3]; // a point light
            l.ns = [0.0; 3];
            l.wo = [0.0; 3];
        }
    }
    Tables {
        camera,
        light,
        light_surface: surface as u32,
        ..Default::default()
    }
}

/// `end`'s shading agrees with the twin's by the rules `bench cbpt` checks too
/// (`splitray::integrator::cbpt::compare`): each value within 1e-4, a segment along its
/// endpoint's tangent plane on f alone, at most 1 in 10 000 only within 1e-2.
fn assert_shading_close(gpu: &Shading, cpu: &Shading, tables: &Tables, end: End, what: &str) {
    assert_eq!(gpu.segments, cpu.segments, "{what}");
    let n = gpu.segments;
    let c = compare_shading(gpu, cpu, tables, end);
    if let Some(s) = c.first_beyond {
        panic!(
            "{what}: segment {s} of {n}: GPU {:?} vs CPU {:?}",
            gpu.get(s),
            cpu.get(s)
        );
    }
    if c.tangent > 0 {
        eprintln!(
            "{what}: {} of {n} segments along a tangent plane agree on f alone",
            c.tangent
        );
    }
    assert!(
        !c.too_many_loose(),
        "{what}: {} of {n} segments only within 1e-2",
        c.loose
    );
}

fn assert_data_equal(gpu: &CombinationData, cpu: &CombinationData, tables: &Tables, what: &str) {
    let differ = visibility_differences(gpu, cpu);
    assert_eq!(gpu.visibility.len(), cpu.visibility.len(), "{what}");
    assert_eq!(differ, 0, "{what}: {differ} visibility bits differ");
    let camera = format!("{what}, camera shading");
    assert_shading_close(&gpu.camera, &cpu.camera, tables, End::Camera, &camera);
    let light = format!("{what}, light shading");
    assert_shading_close(&gpu.light, &cpu.light, tables, End::Light, &light);
}

fn combiner(gpu: &Gpu, scene: &CpuScene, tracer: TracerKind, batch: u32) -> GpuCombiner {
    let tracer = tracer.create(gpu, &scene.tables.triangles).unwrap();
    GpuCombiner::new(gpu, tracer, scene, batch).unwrap()
}

fn gpu_data(c: &mut GpuCombiner, tables: &Tables) -> CombinationData {
    let pending = c.start(Arc::new(tables.clone())).unwrap();
    c.finish(pending).unwrap()
}

#[test]
fn shadow_rays_and_packing_equal_their_twins() {
    let gpu = common::gpu();
    let scene = CpuScene::new(&splitray::scene::builtin("cornell-box").unwrap());
    let mut tables = adversarial_tables(&scene, 37, 29, 20);
    // A camera end in space at a point light: the two ends coincide.
    tables.camera[0].ng = [0.0; 3];
    tables.light[28].p = tables.camera[0].p;
    let n = tables.segments() as usize;
    let camera = gpu.upload("camera", &tables.camera).unwrap();
    let light = gpu.upload("light", &tables.light).unwrap();
    let rays = gpu.zeroed::<Ray>("rays", n).unwrap();
    let rays_kernel = compute_pipeline(
        &gpu,
        shaders::INTEGRATOR_CBPT_VISIBILITY_RAYS,
        3,
        size_of::<CbptPush>() as u32,
        &[64],
    )
    .unwrap();
    // Two launches (an offset second half) to exercise `first`.
    let half = n as u32 / 2 + 5;
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    for (first, count) in [(0, half), (half, n as u32 - half)] {
        let push = CbptPush {
            first,
            count,
            inner: tables.light.len() as u32,
            plane: 0,
            ray_epsilon: scene.ray_epsilon,
            shadow_reach: splitray::bidir::scene::SHADOW_RAY_REACH,
            ..Default::default()
        };
        let out = rays.slice(first as u64 * 32, count as u64 * 32);
        rec.dispatch_items(
            &rays_kernel,
            &[(&camera).into(), (&light).into(), out],
            &push,
            count as u64,
        )
        .unwrap();
    }
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let got = rays.read::<Ray>().unwrap();
    let mut exact = 0;
    for (s, g) in got.iter().enumerate() {
        let want = cpu_kernels::visibility_ray(&scene, &tables, s);
        let (o, d) = (Vec3::from(g.origin), Vec3::from(g.dir));
        let (wo, wd) = (Vec3::from(want.origin), Vec3::from(want.dir));
        assert!(
            (o - wo).abs().max_element() <= 1e-6 * wo.abs().max_element().max(1.0)
                && (d - wd).abs().max_element() <= 1e-6
                && (g.tmax - want.tmax).abs() <= 1e-6 * want.tmax.max(1.0)
                && (g.tmax > 0.0) == (want.tmax > 0.0),
            "segment {s}: GPU {g:?} vs CPU {want:?}"
        );
        exact += (*g == want) as usize;
    }
    eprintln!("{exact} of {n} rays bit for bit");
    assert!(got.iter().any(|r| r.tmax == 0.0), "no coincident ends");

    // Packing: adversarial hits at 0, 1, 31, 32, 33 and 100 segments.
    let pack = compute_pipeline(
        &gpu,
        shaders::INTEGRATOR_CBPT_VISIBILITY_PACK,
        3,
        size_of::<CbptPush>() as u32,
        &[64],
    )
    .unwrap();
    let bits = common::random_u32s(2 * n, 9);
    let hits: Vec<Hit> = (0..n)
        .map(|s| match bits[s] % 3 {
            0 => Hit::NONE,
            _ => Hit {
                t: 1.0,
                triangle: bits[n + s] % 40,
                u: 0.0,
                v: 0.0,
            },
        })
        .collect();
    let hit_buf = gpu.upload("hits", &hits).unwrap();
    for count in [0u32, 1, 31, 32, 33, 100, n as u32] {
        let words = gpu
            .zeroed::<u32>("words", (count as usize).div_ceil(32) + 1)
            .unwrap();
        let push = CbptPush {
            count,
            ..Default::default()
        };
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.dispatch_items(
            &pack,
            &[(&rays).into(), (&hit_buf).into(), (&words).into()],
            &push,
            count.div_ceil(32) as u64,
        )
        .unwrap();
        gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
        let mut want =
            cpu_kernels::pack_visibility(&got[..count as usize], &hits[..count as usize]);
        want.push(0);
        assert_eq!(words.read::<u32>().unwrap(), want, "{count} segments");
    }
    assert!(hits.iter().any(|h| h.triangle == MISS));
    common::assert_clean(&gpu);
}

#[test]
fn the_gpu_combination_equals_the_cpu_on_populations() {
    let gpu = common::gpu();
    let scene = common::scenes::tricky_cornell_box();
    let (cpu_scene, tables) = population_tables(&scene, 300, 15, 0);
    let want = evaluate(&cpu_scene, &tables, Kinds::ALL);
    eprintln!(
        "{} camera and {} light vertices ({} on surfaces): {} segments",
        tables.camera.len(),
        tables.light.len(),
        tables.light_surface,
        tables.segments()
    );
    assert!(tables.segments() > 10_000 && tables.light_surface > 0);
    for (tracer, batch) in [
        (TracerKind::BruteForce, 8192),
        (TracerKind::CpuBvh, 4000),
        (TracerKind::Pdacrt, 1 << 17),
    ] {
        let mut c = combiner(&gpu, &cpu_scene, tracer, batch);
        let got = gpu_data(&mut c, &tables);
        assert_data_equal(
            &got,
            &want,
            &tables,
            &format!("{tracer} batches of {batch}"),
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn edge_sizes_and_adversarial_vertices_equal_the_cpu() {
    let gpu = common::gpu();
    let scene = CpuScene::new(&splitray::scene::builtin("cornell-box").unwrap());
    let mut small = combiner(&gpu, &scene, TracerKind::BruteForce, 96);
    let mut large = combiner(&gpu, &scene, TracerKind::BruteForce, 1 << 18);
    // (camera vertices, light vertices, of which on surfaces); batches of 96 segments
    // up to 97 × 61 (62 batches of each kind, the last ones partial), of 2^18 beyond.
    let sizes = [
        (0, 0, 0),
        (0, 5, 3),
        (4, 0, 0),
        (1, 1, 1),
        (1, 1, 0),
        (3, 31, 17),
        (7, 13, 13),
        (97, 61, 40),
        (1100, 1000, 700),
    ];
    for (cameras, lights, surface) in sizes {
        let c = if cameras * lights > 10_000 {
            &mut large
        } else {
            &mut small
        };
        let tables = adversarial_tables(&scene, cameras, lights, surface);
        let want = evaluate(&scene, &tables, Kinds::ALL);
        let got = gpu_data(c, &tables);
        let what = format!("{cameras} x {lights} ({surface} on surfaces)");
        assert_data_equal(&got, &want, &tables, &what);
        if tables.segments() > 1000 {
            let visible = want.visibility.iter().map(|w| w.count_ones()).sum::<u32>();
            assert!(
                visible > 0 && (visible as u64) < tables.segments(),
                "{what}"
            );
        }
    }
    common::assert_clean(&gpu);
}

/// Two population couples in flight (start, start, finish, finish), as the pipeline
/// runs them, give each its own data: the slots and the alternating result buffers
/// keep them apart.
#[test]
fn two_steps_in_flight_keep_their_own_data() {
    let gpu = common::gpu_with(splitray::vk::StreamPlacement::Spread, true);
    let scene = common::scenes::tricky_cornell_box();
    let (cpu_scene, a) = population_tables(&scene, 150, 7, 0);
    let (_, b) = population_tables(&scene, 150, 7, 1);
    let mut c = combiner(&gpu, &cpu_scene, TracerKind::BruteForce, 4096);
    for round in 0..2 {
        let pa = c.start(Arc::new(a.clone())).unwrap();
        let pb = c.start(Arc::new(b.clone())).unwrap();
        let da = c.finish(pa).unwrap();
        let pc = c.start(Arc::new(a.clone())).unwrap();
        let db = c.finish(pb).unwrap();
        let dc = c.finish(pc).unwrap();
        let (wa, wb) = (
            evaluate(&cpu_scene, &a, Kinds::ALL),
            evaluate(&cpu_scene, &b, Kinds::ALL),
        );
        assert_data_equal(&da, &wa, &a, &format!("round {round}, first"));
        assert_data_equal(&db, &wb, &b, &format!("round {round}, second"));
        assert_eq!(dc, da, "round {round}: the same step twice");
    }
    common::assert_clean(&gpu);
}
