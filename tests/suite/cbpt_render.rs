//! `cbpt` through the `Integrator` interface: the same seed gives the same image bit for
//! bit, however passes are grouped into calls, pipelined or not, with any tracer, on any
//! number of threads; the GPU and CPU combinations give the same image to float
//! rounding; N_C from Equation 4; `render --integrator cbpt` end to end with the
//! validation layer.
use crate::common;

use splitray::bidir::Counters;
use splitray::film::FilmSums;
use splitray::integrator::cbpt::combine::{combine, StepData};
use splitray::integrator::cbpt::cpu_kernels::evaluate;
use splitray::integrator::cbpt::layout::{Kinds, Tables};
use splitray::integrator::cbpt::light_tracing::light_trace;
use splitray::integrator::cbpt::population::Population;
use splitray::integrator::cbpt::steps::ImagePositions;
use splitray::integrator::cbpt::{
    CameraPaths, CbptIntegrator, CbptOptions, CbptSettings, Combination, Setup,
};
use splitray::integrator::{Integrator, IntegratorKind};
use splitray::render::RenderControl;
use splitray::scene::Scene;
use splitray::trace::TracerKind;
use splitray::vk::Gpu;

const W: u32 = 24;
const H: u32 = 16;

fn options(seed: u64, combination: Combination) -> CbptOptions {
    CbptOptions {
        seed,
        settings: CbptSettings {
            camera_paths: CameraPaths::Fixed(300),
            light_paths: 6,
            light_traced: 200,
            batch: 4096,
            combination,
        },
        ..Default::default()
    }
}

fn integrator(
    gpu: &Gpu,
    scene: &Scene,
    options: &CbptOptions,
    tracer: TracerKind,
) -> CbptIntegrator {
    let frame = scene.camera.frame(W, H);
    let pt = splitray::integrator::pt::PtScene::new(scene);
    let tracer = tracer.create(gpu, &pt.triangles).unwrap();
    CbptIntegrator::new(scene, &frame, options, Some((gpu, tracer))).unwrap()
}

fn render(gpu: &Gpu, scene: &Scene, options: &CbptOptions, tracer: TracerKind) -> FilmSums {
    let mut c = integrator(gpu, scene, options, tracer);
    c.render_passes(0, 3).unwrap();
    assert_eq!(c.counters().non_finite, 0);
    c.sums().unwrap()
}

#[test]
fn the_same_seed_gives_the_same_image() {
    let gpu = common::gpu();
    let scene = common::scenes::tricky_cornell_box();
    let o = options(3, Combination::Gpu);
    let a = render(&gpu, &scene, &o, TracerKind::BruteForce);
    assert_eq!(a.passes, 3);
    assert_eq!(a, render(&gpu, &scene, &o, TracerKind::BruteForce));
    // Visibility is the same bits through every tracer (tests/suite/cbpt_gpu.rs).
    assert_eq!(a, render(&gpu, &scene, &o, TracerKind::Pdacrt), "pdacrt");
    let sync = CbptOptions {
        pipelined: false,
        ..o
    };
    assert_eq!(
        a,
        render(&gpu, &scene, &sync, TracerKind::BruteForce),
        "sync"
    );
    // Passes in other calls: pass k is pass k.
    let mut c = integrator(&gpu, &scene, &o, TracerKind::BruteForce);
    c.render_passes(0, 1).unwrap();
    c.render_passes(1, 2).unwrap();
    assert_eq!(a, c.sums().unwrap(), "passes in two calls");
    assert_ne!(
        a,
        render(
            &gpu,
            &scene,
            &options(4, Combination::Gpu),
            TracerKind::BruteForce
        )
    );
    common::assert_clean(&gpu);
}

/// The GPU's shading tuples equal the CPU's to float rounding, its visibility bits
/// exactly: so do the images.
#[test]
fn gpu_and_cpu_combinations_give_the_same_image() {
    let gpu = common::gpu();
    let scene = common::scenes::tricky_cornell_box();
    let g = render(
        &gpu,
        &scene,
        &options(5, Combination::Gpu),
        TracerKind::BruteForce,
    );
    let c = render(
        &gpu,
        &scene,
        &options(5, Combination::Cpu),
        TracerKind::BruteForce,
    );
    let (gm, cm) = (g.mean(), c.mean());
    let mut worst = 0.0f32;
    for (a, b) in gm.iter().flatten().zip(cm.iter().flatten()) {
        worst = worst.max((a - b).abs() / a.abs().max(b.abs()).max(1e-3));
    }
    eprintln!("largest relative difference {worst:e}");
    assert!(worst < 1e-3, "{worst}");
    common::assert_clean(&gpu);
}

/// Sampling, combining and light tracing give the same results on 1 and 3 threads
/// (fixed chunks, gathered in order).
#[test]
fn the_cpu_parts_do_not_depend_on_the_thread_count() {
    let scene = common::scenes::tricky_cornell_box();
    let frame = scene.camera.frame(W, H);
    let o = options(6, Combination::Cpu);
    let setup = Setup::new(splitray::bidir::CpuScene::new(&scene), &frame, &o, 300, 6).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let cpu = setup.cpu_side();
            let mut counters = Counters::default();
            let positions = ImagePositions::new(W * H, 0, setup.streams.shuffle);
            let id = setup.steps(0..1)[1].clone();
            let population = Population::sample(&cpu.sampling, id, &positions, &mut counters);
            let tables = Tables::new(&population);
            let data = evaluate(&setup.scene, &tables, Kinds::ALL);
            let step = StepData {
                population: &population,
                tables: &tables,
                data: &data,
            };
            let values = combine(&cpu.linking, step, &mut counters);
            let splats = light_trace(&cpu.sampling, &cpu.linking, 0, 1, 200, &mut counters);
            (tables, data, values, splats, counters)
        })
    };
    let one = run(1);
    let three = run(3);
    assert!(
        one.0 == three.0 && one.1 == three.1,
        "populations or data differ"
    );
    assert_eq!(one.2, three.2, "camera-path values differ");
    assert_eq!(one.3, three.3, "splats differ");
    assert_eq!(one.4, three.4, "counters differ");
    assert!(!one.3.is_empty() && one.2.iter().any(|v| v.max_element() > 0.0));
}

#[test]
fn equation_4_chooses_the_camera_paths() {
    let gpu = common::gpu();
    let scene = splitray::scene::builtin("cornell-box").unwrap();
    let mut o = options(7, Combination::Gpu);
    o.settings.camera_paths = CameraPaths::Equation4;
    o.settings.light_paths = 15;
    let c = integrator(&gpu, &scene, &o, TracerKind::BruteForce);
    let e = c.equation4().expect("measured");
    eprintln!("{e}");
    // Steps of the default N_C = 2000, or of a whole pass where a pass holds fewer.
    assert_eq!(e.pairs, u64::from((W * H * 4).min(2000)) * 15);
    assert!(e.camera_paths as f64 > e.step_seconds / e.pair_seconds);
    assert_eq!(c.setup().camera_paths, e.camera_paths);
    assert_eq!(c.setup().light_paths, e.light_paths);
    let settings = c.settings();
    assert!(settings.contains(&("cbpt_camera_paths".into(), e.camera_paths.to_string())));

    // An 8 × 8 film's pass is one step of 256 camera paths: Equation 4 times the steps
    // of later passes (not none) and counts the pairs those steps hold.
    let frame = scene.camera.frame(8, 8);
    let pt = splitray::integrator::pt::PtScene::new(&scene);
    let tracer = TracerKind::BruteForce.create(&gpu, &pt.triangles).unwrap();
    let c = CbptIntegrator::new(&scene, &frame, &o, Some((&gpu, tracer))).unwrap();
    let e = c.equation4().expect("measured");
    eprintln!("{e}");
    assert_eq!(e.pairs, 8 * 8 * 4 * 15);
    // A step is several dispatches and a readback: far more than 10 µs on any device.
    assert!(e.step_seconds > 1e-5, "{e}");
    common::assert_clean(&gpu);
}

#[test]
fn render_command_writes_a_cbpt_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cbpt.exr");
    let stats = dir.path().join("stats.json");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_splitray"))
        .args([
            "render",
            "cornell-box",
            "--integrator",
            "cbpt",
            "--width",
            "16",
        ])
        .args(["--height", "12", "--spp", "8", "--tracer", "brute-force"])
        .args(["--cbpt-nc", "100", "--cbpt-nl", "3", "--cbpt-nt", "50"])
        .args(["--cbpt-batch", "1024", "--validation", "-o"])
        .arg(&out)
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(s["integrator"], "cbpt");
    assert_eq!(s["spp"], 8);
    assert!(s["counters"]["basic_contributions"].as_u64().unwrap() > 1000);
    assert_eq!(s["counters"]["non_finite_dropped"], 0);
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_splitray"))
        .args([
            "render",
            "cornell-box",
            "--integrator",
            "cbpt",
            "--cbpt-batch",
            "100",
        ])
        .arg("-o")
        .arg(dir.path().join("bad.exr"))
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("--cbpt-batch 100"), "{err}");
    assert!(!dir.path().join("bad.exr").exists());
}

/// `bench cbpt` checks the GPU's combination data against the CPU's before timing and
/// reports every table.
#[test]
fn bench_cbpt_checks_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_splitray"))
        .args([
            "bench",
            "cbpt",
            "cornell-box",
            "--width",
            "24",
            "--height",
            "16",
        ])
        .args(["--tracers", "brute-force", "--steps", "1", "--rounds", "1"])
        .args(["--batches", "4096", "--validation", "--json"])
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(r["visibility_mismatches"], 0, "{stdout}");
    assert_eq!(r["shading_mismatches"], 0, "{stdout}");
    assert_eq!(r["throughput"].as_array().unwrap().len(), 3);
    assert_eq!(r["contributions"].as_array().unwrap().len(), 4);
    assert_eq!(r["steps"].as_array().unwrap().len(), 2);
    for row in r["contributions"].as_array().unwrap() {
        assert!(row["per_second"].as_f64().unwrap() > 0.0, "{row}");
    }
    assert!(stdout.contains("pipelining:"), "{stdout}");
}

/// A stop within a pass gives the pass up between two steps: the film holds the passes
/// before it, bit for bit those of a render of that many passes, and the render reports
/// that it stopped early.
#[test]
fn a_pass_is_given_up_between_its_steps() {
    let gpu = common::gpu();
    let scene = splitray::scene::builtin("cornell-box").unwrap();
    let o = options(7, Combination::Gpu);
    let mut one = integrator(&gpu, &scene, &o, TracerKind::BruteForce);
    one.render_passes(0, 1).unwrap();
    // 24 × 16 × 4 camera paths a pass, 300 a step: six steps a pass.
    assert_eq!(one.setup().plan.steps, 6);

    let mut c = integrator(&gpu, &scene, &o, TracerKind::BruteForce);
    let asked = std::cell::Cell::new(0);
    // Asked after each step is launched: true after the second step of pass 1.
    let abandon = || {
        asked.set(asked.get() + 1);
        asked.get() == 8
    };
    let done = c.render_passes_or_abandon(0, 3, &abandon).unwrap();
    assert_eq!((done, asked.get()), (1, 8));
    assert!(c.sums().unwrap() == one.sums().unwrap(), "not pass 0 alone");

    // Through the render loop: stopped early, with the passes before the one given up.
    let mut render_options = common::small_render_options(&scene, IntegratorKind::Cbpt, 12);
    render_options.cbpt = o.settings;
    render_options.tracer = TracerKind::BruteForce;
    let asked = std::cell::Cell::new(0);
    let out = splitray::render::render_with(
        &gpu,
        &scene,
        &render_options,
        RenderControl {
            progress: &mut |_| {},
            stop: &|| false,
            abandon: &|| {
                asked.set(asked.get() + 1);
                asked.get() == 8
            },
        },
    )
    .unwrap();
    assert!(out.stats.stopped_early);
    assert_eq!(out.sums.passes, 1);
    assert!(
        out.sums == one.sums().unwrap(),
        "the render's film is not pass 0 alone"
    );
    common::assert_clean(&gpu);
}
