//! CBPT's weights against the brute-force oracle (src/bidir/oracle.rs): on population
//! couples the walks really trace through a scene with mirrors, a mixed delta/diffuse
//! material, shading normals and a point light, every technique `combine()` and the
//! light tracer evaluate has the balance-heuristic weight n_s p_s / Σ n_j p_j of the
//! counts of `bidir::combinatorial` (N_L light paths per camera path, no light-traced
//! direct lighting) — with N_C = N_L = 1 (the estimator is then BPT's, less the
//! light-traced direct lighting) and with the paper's N_L = 15. And with N_C = N_L = 1
//! the image agrees with `bpt`'s (the per-pixel and block z-tests of
//! tests/suite/common/reference.rs). The CPU combination (the kernels' CPU twins) supplies the
//! combination data; tests/suite/cbpt_gpu.rs holds the GPU's equal to it.
use crate::common;

use splitray::bidir::combinatorial::CombinatorialCounts;
use splitray::bidir::connect::Sample;
use splitray::bidir::densities::path_densities;
use splitray::bidir::random::PathSampler;
use splitray::bidir::walk::light_subpath;
use splitray::bidir::{Counters, CpuScene, Vertex};
use splitray::integrator::bpt::{BidirMode, BptIntegrator, BptOptions};
use splitray::integrator::cbpt::combine::{for_each_technique, StepData};
use splitray::integrator::cbpt::cpu_kernels::evaluate;
use splitray::integrator::cbpt::layout::{Kinds, Tables};
use splitray::integrator::cbpt::population::Population;
use splitray::integrator::cbpt::steps::ImagePositions;
use splitray::integrator::cbpt::{
    CameraPaths, CbptIntegrator, CbptOptions, CbptSettings, Combination, Setup,
};
use splitray::integrator::Integrator;
use splitray::scene::Scene;

fn options(camera_paths: u32, light_paths: u32, light_traced: u32, seed: u64) -> CbptOptions {
    CbptOptions {
        seed,
        max_depth: 8,
        rr_depth: 3,
        settings: CbptSettings {
            camera_paths: CameraPaths::Fixed(camera_paths),
            light_paths,
            light_traced,
            combination: Combination::Cpu,
            ..Default::default()
        },
        pipelined: true,
    }
}

/// Techniques checked: emitter hits, links to y₀, connections, light tracing; paths of
/// two segments, through a delta vertex and from the point light among them.
#[derive(Debug, Default)]
struct Checked {
    families: [usize; 4],
    two_segments: usize,
    through_delta: usize,
    from_point_light: usize,
}

/// Checks `sample`, made from `light` (the light vertices up to its linking vertex) and
/// `camera` (likewise), against the oracle and counts it in `checked`.
fn check(
    setup: &Setup,
    counts: &CombinatorialCounts,
    sample: &Sample,
    light: &[Vertex],
    camera: &[Vertex],
    checked: &mut Checked,
) {
    let d = path_densities(&setup.scene, &setup.camera, light, camera);
    let k = d.segments();
    common::mis::assert_weight_is_the_oracles(&d, &counts.of_path(k), sample);
    checked.families[match sample.s {
        0 => 0,
        1 if sample.t > 1 => 1,
        _ if sample.t == 1 => 3,
        _ => 2,
    }] += 1;
    checked.two_segments += (k == 2) as usize;
    checked.through_delta += d.delta[1..k].contains(&true) as usize;
    checked.from_point_light += d.delta[0] as usize;
}

fn check_passes(scene: &Scene, options: &CbptOptions, passes: u32) -> Checked {
    let frame = scene.camera.frame(12, 12);
    let CameraPaths::Fixed(nc) = options.settings.camera_paths else {
        unreachable!()
    };
    let setup = Setup::new(
        CpuScene::new(scene),
        &frame,
        options,
        nc,
        options.settings.light_paths,
    )
    .unwrap();
    let cpu = setup.cpu_side();
    let counts = setup.counts;
    let mut counters = Counters::default();
    let mut checked = Checked::default();
    for id in setup.steps(0..passes) {
        let (pass, step_index) = (id.pass, id.step);
        let positions = ImagePositions::new(144, pass, setup.streams.shuffle);
        let population = Population::sample(&cpu.sampling, id, &positions, &mut counters);
        let tables = Tables::new(&population);
        let data = evaluate(&setup.scene, &tables, Kinds::ALL);
        let step = StepData {
            population: &population,
            tables: &tables,
            data: &data,
        };
        for k in 0..population.camera.len() {
            let camera = population.camera.path(k);
            for_each_technique(&cpu.linking, step, k, &mut counters, &mut |c| {
                let j = c.sample.t as usize - 1;
                let light: &[Vertex] = match c.light_path {
                    None => &[],
                    Some(l) => &population.light.path(l)[..c.sample.s as usize],
                };
                check(
                    &setup,
                    &counts,
                    &c.sample,
                    light,
                    &camera[..=j],
                    &mut checked,
                );
            });
        }
        // The light tracer's techniques, on light paths of the step's streams.
        for m in 0..8 {
            let sampler = PathSampler::new(step_index * 8 + m, pass, setup.streams.traced);
            let mut path = Vec::new();
            light_subpath(
                &setup.scene,
                &setup.walk,
                &sampler,
                &mut path,
                &mut counters,
            );
            let pinhole = Vertex::camera(setup.camera.position(), Default::default());
            for i in 0..path.len() {
                let sample = cpu.linking.connector.light_trace(&path, i, &mut counters);
                match sample {
                    Some(s) if counts.traces_light_vertex(i) => {
                        check(&setup, &counts, &s, &path[..=i], &[pinhole], &mut checked);
                    }
                    // Direct lighting and emitters are not light-traced: their count is 0
                    // (or, for i = 1, the light tracer skips them).
                    Some(_) => assert_eq!(i, 1, "light vertex {i} traced"),
                    None => {}
                }
            }
        }
    }
    assert_eq!(counters.non_finite, 0);
    checked
}

#[test]
fn weights_with_one_camera_and_one_light_path_equal_the_oracle() {
    let scene = common::scenes::tricky_cornell_box();
    let c = check_passes(&scene, &options(1, 1, 1, 3), 4);
    eprintln!("N_C = N_L = 1: {c:?}");
    assert!(
        c.families[0] > 20 && c.families[1..].iter().all(|&n| n > 400),
        "{c:?}"
    );
    assert!(
        c.two_segments > 20 && c.through_delta > 100 && c.from_point_light > 100,
        "{c:?}"
    );
}

#[test]
fn weights_of_populations_equal_the_oracle() {
    let scene = common::scenes::tricky_cornell_box();
    let c = check_passes(&scene, &options(40, 15, 30, 5), 4);
    eprintln!("N_C = 40, N_L = 15: {c:?}");
    // Emitter hits are the rarest (~40): the light is small and they need no light path.
    assert!(
        c.families[0] > 20 && c.families[1..].iter().all(|&n| n > 400),
        "{c:?}"
    );
    assert!(
        c.two_segments > 100 && c.through_delta > 100 && c.from_point_light > 100,
        "{c:?}"
    );
}

/// With N_C = N_L = N_T = 1 a step is a BPT sample of one pixel (the estimator is BPT's
/// but for light-traced direct lighting): the images agree.
#[test]
fn one_camera_and_one_light_path_agree_with_bpt() {
    const SIZE: u32 = 16;
    let scene = common::scenes::tricky_cornell_box();
    let frame = scene.camera.frame(SIZE, SIZE);
    let mut o = options(1, 1, 1, 7);
    o.max_depth = -1;
    o.rr_depth = 5;
    let mut cbpt = CbptIntegrator::new(&scene, &frame, &o, None).unwrap();
    cbpt.render_passes(0, 64).unwrap();
    assert_eq!(cbpt.counters().non_finite, 0);
    let bpt_options = BptOptions {
        seed: 8,
        ..Default::default()
    };
    let mut bpt = BptIntegrator::new(BidirMode::Bpt, &scene, &frame, &bpt_options);
    bpt.render_passes(0, 256).unwrap();
    let (a, b) = (cbpt.sums().unwrap(), bpt.sums().unwrap());
    common::reference::compare_images(
        "bpt 256 passes",
        SIZE as usize,
        (&a.mean(), &a.stderr().unwrap()),
        (&b.mean(), &b.stderr().unwrap()),
    )
    .assert_agrees("cbpt N_C = N_L = N_T = 1, 64 passes");
}
