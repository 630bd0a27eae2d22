//! `splitray bench`: measurements, never timed tests. Each verifies its results first.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Context;
use clap::{Args, Subcommand};
use splitray::bench::bdpt::{self as bdpt_bench, BdptBenchOptions};
use splitray::bench::cbpt::{self as cbpt_bench, CbptBenchOptions};
use splitray::bench::dynamic::{self, Contender, DynamicBenchOptions};
use splitray::bench::lvc::{SortSetting, SppPlan};
use splitray::bench::primitives::{self, PrimitivesBenchOptions};
use splitray::bench::pt::{self as pt_bench, PtBenchOptions};
use splitray::bench::trace::{self, TraceBenchOptions};
use splitray::bench::workloads::Workload;
use splitray::film::Reference;
use splitray::integrator::lvc::Resampling;
use splitray::integrator::IntegratorKind;
use splitray::scene::{AnimatedScene, Scene};
use splitray::trace::pdacrt::LevelStats;
use splitray::trace::{FlushReduce, LevelSplit, PdacrtParams, TracerKind};
use splitray::vk::{Gpu, GpuDesc, InstanceDesc};

use super::paths::{refuse_clashing_paths, Role};

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: BenchCommand,
    /// Vulkan device by index or name substring (see `splitray info`).
    #[arg(long, value_parser = clap::builder::NonEmptyStringValueParser::new(), global = true)]
    device: Option<String>,
    /// Run with the validation layer (slower; for checking, not for figures).
    #[arg(long, global = true)]
    validation: bool,
    /// Write a timeline of the benchmark (GPU streams, host threads, counters) as
    /// trace-event JSON for ui.perfetto.dev or chrome://tracing.
    #[arg(long, global = true, value_name = "FILE.json")]
    timeline: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
enum BenchCommand {
    /// Scan, radix sort, reduce-by-key, compaction and gather against CPU references.
    Primitives {
        /// Items for sort, reduce-by-key, compaction and gather.
        #[arg(long, default_value_t = 1 << 22)]
        n: usize,
        /// Items for the scan and the copy it is compared with.
        #[arg(long, default_value_t = 1 << 24)]
        scan_n: usize,
        /// Timed runs per primitive (at least 5).
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Also write the report as JSON.
        #[arg(long, value_name = "OUT.json")]
        json: Option<PathBuf>,
    },
    /// The path tracer's samples/s and Mrays/s with and without material sorting.
    Pt {
        /// A built-in scene, a scene .toml or an .obj.
        scene: String,
        #[arg(long, default_value_t = 256, value_parser = super::film_side_parser())]
        width: u32,
        #[arg(long, default_value_t = 256, value_parser = super::film_side_parser())]
        height: u32,
        #[arg(long, default_value_t = 16, value_parser = super::at_least_one())]
        spp: u32,
        /// Mitsuba's max_depth (-1 = unbounded, Russian roulette from depth 5).
        #[arg(long, default_value_t = -1, allow_hyphen_values = true, value_parser = super::max_depth_parser())]
        max_depth: i32,
        #[arg(long, default_value = "pdacrt")]
        tracer: TracerKind,
        /// Also write the report as JSON.
        #[arg(long, value_name = "OUT.json")]
        json: Option<PathBuf>,
    },
    /// Integrators at equal wall time, taken in turns: samples/s, Mrays/s, basic
    /// contributions/s (bpt, light) and, with --reference, relative MSE; then lvc-bdpt
    /// and cis-lbdpt at equal spp with 1 and 3 streams: time, per-stream busy time and
    /// overlap, per-kernel GPU time.
    Bdpt {
        /// Built-in scenes, scene .toml or .obj files, each benchmarked in turn.
        #[arg(required = true, num_args = 1..)]
        scenes: Vec<String>,
        #[arg(long, default_value_t = 160, value_parser = super::film_side_parser())]
        width: u32,
        #[arg(long, default_value_t = 120, value_parser = super::film_side_parser())]
        height: u32,
        /// Comma-separated integrators to compare.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "pt,bpt,light,lvc-bdpt,cis-lbdpt"
        )]
        integrators: Vec<IntegratorKind>,
        /// Seconds each integrator renders.
        #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
        time: f64,
        /// Slices each integrator's time is cut into (taken in turns).
        #[arg(long, default_value_t = 10, value_parser = super::at_least_one())]
        rounds: u32,
        /// Mitsuba's max_depth (-1 = unbounded, Russian roulette from depth 5).
        #[arg(long, default_value_t = -1, allow_hyphen_values = true, value_parser = super::max_depth_parser())]
        max_depth: i32,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// A converged image of this film size (EXR): relative MSE of each film, and
        /// without the reference's own noise where its standard errors are known
        /// (stderr.R/G/B channels, or NAME_stderr.exr beside NAME_mean.exr). Once per
        /// scene, in the scenes' order (all or none).
        #[arg(long, value_name = "REF.exr")]
        reference: Vec<PathBuf>,
        /// cis-lbdpt's draws of its connections from the candidates: systematic (the
        /// default) or independent; both (systematic,independent) make two contestants,
        /// `cis-lbdpt` and `cis-lbdpt independent`.
        #[arg(long, value_delimiter = ',', default_value = "systematic")]
        resampling: Vec<Resampling>,
        /// Passes of the equal-spp comparison of lvc-bdpt and cis-lbdpt (0: none).
        #[arg(long, default_value_t = 4)]
        spp: u32,
        /// Rounds of the equal-spp comparison (the median is reported).
        #[arg(long, default_value_t = 3, value_parser = super::at_least_one())]
        spp_rounds: u32,
        /// Stream counts of the equal-spp comparison (each 1 or 3).
        #[arg(long, value_delimiter = ',', default_value = "1,3")]
        streams: Vec<u32>,
        /// Material sorting in the equal-spp comparison: default (each integrator's
        /// choice on the device), on, off; several compare them (e.g. on,off).
        #[arg(long, value_delimiter = ',', default_value = "default")]
        sort: Vec<SortSetting>,
        /// Also write the reports as JSON (a list, one per scene).
        #[arg(long, value_name = "OUT.json")]
        json: Option<PathBuf>,
    },
    /// CBPT's measurements (§6 of the paper): combination throughput of the GPU and of
    /// every CPU core (Table 1), batch sizes (Fig. 6), basic contributions/s of cbpt
    /// and bpt (Table 3), a step's parts pipelined and synchronous (Algorithm 2) and,
    /// with --reference, relative MSE at equal time against bpt and pt.
    Cbpt {
        /// A built-in scene, a scene .toml or an .obj.
        scene: String,
        #[arg(long, default_value_t = 160, value_parser = super::film_side_parser())]
        width: u32,
        #[arg(long, default_value_t = 120, value_parser = super::film_side_parser())]
        height: u32,
        /// Comma-separated tracers whose visibility throughput is measured; the first
        /// serves every other measurement.
        #[arg(long, value_delimiter = ',', default_value = "pdacrt,cpu-bvh")]
        tracers: Vec<TracerKind>,
        /// Steps per measured block.
        #[arg(long, default_value_t = 6, value_parser = super::at_least_one())]
        steps: u32,
        /// Alternating blocks (runs) per comparison.
        #[arg(long, default_value_t = 3, value_parser = super::at_least_one())]
        rounds: u32,
        /// Comma-separated batch sizes (segments, multiples of 32) of the sweep.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "1024,4096,16384,65536,262144,1048576"
        )]
        batches: Vec<u32>,
        /// Seconds each integrator renders for the equal-time comparison.
        #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
        time: f64,
        /// Mitsuba's max_depth (-1 = unbounded, Russian roulette from depth 5).
        #[arg(long, default_value_t = -1, allow_hyphen_values = true, value_parser = super::max_depth_parser())]
        max_depth: i32,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// A converged image of this film size (EXR): relative MSE at equal time.
        #[arg(long, value_name = "REF.exr")]
        reference: Option<PathBuf>,
        /// Also write the report as JSON.
        #[arg(long, value_name = "OUT.json")]
        json: Option<PathBuf>,
    },
    /// Build + trace time per frame of each tracer on a scene and ray workload.
    Trace {
        /// A built-in scene, a scene .toml or an .obj.
        scene: String,
        #[arg(long, default_value_t = 1024, value_parser = super::film_side_parser())]
        width: u32,
        #[arg(long, default_value_t = 1024, value_parser = super::film_side_parser())]
        height: u32,
        /// primary, shadow (one point light), reflection (one mirror bounce), ao (8 rays
        /// per hit) or path (7 diffuse bounces).
        #[arg(long, default_value = "primary")]
        workload: Workload,
        /// Comma-separated tracers to compare: pdacrt, brute-force, cpu-dacrt, cpu-bvh
        /// (also prints its BVH build time and trace rate without GPU transfers),
        /// ray-query.
        #[arg(long, value_delimiter = ',', default_value = "pdacrt,brute-force")]
        tracers: Vec<TracerKind>,
        /// Timed frames per tracer (at least 5, after a warm-up frame).
        #[arg(long, default_value_t = 5)]
        frames: usize,
        /// Write the primary-ray hits in pixel order as little-endian (u32 triangle, f32 t),
        /// once every tracer agreed with brute force (the hits of PDACRT with its default
        /// parameters, from which the workload's rays start).
        #[arg(long, value_name = "FILE")]
        dump_hits: Option<PathBuf>,
        /// Print PDACRT's per-level statistics.
        #[arg(long)]
        levels: bool,
        /// Print each tracer's GPU scopes of its last frame as a tree (total and self times).
        #[arg(long)]
        profile: bool,
        /// PDACRT α: nodes with fewer triangles are terminal (default 256).
        #[arg(long)]
        alpha: Option<u32>,
        /// PDACRT β: nodes with fewer rays are terminal (default 256).
        #[arg(long)]
        beta: Option<u32>,
        /// PDACRT η: terminal-node buffer capacity in ids.
        #[arg(long)]
        eta: Option<u32>,
        /// PDACRT λ: flush threshold in ids (≤ η).
        #[arg(long)]
        lambda: Option<u32>,
        /// PDACRT T: triangles per shared-memory batch in the segmented intersection.
        #[arg(long)]
        batch: Option<u32>,
        /// PDACRT N: workgroup size of the segmented intersection.
        #[arg(long)]
        intersect_workgroup: Option<u32>,
        /// PDACRT: invocations per workgroup (one tile each) of the prefix-sum split's
        /// filters and scatter.
        #[arg(long)]
        tile_workgroup: Option<u32>,
        /// PDACRT: rays per chunk of the level loop.
        #[arg(long)]
        chunk: Option<u32>,
        /// PDACRT: stage triangles through shared memory in the segmented intersection
        /// (true) or read them directly (false); the default depends on the device.
        #[arg(long)]
        stage_triangles: Option<bool>,
        /// PDACRT: give each child the bounds of its triangles as its box (true) or the
        /// half of its parent's box, as the paper does (false); the default depends on
        /// the device.
        #[arg(long)]
        tight_boxes: Option<bool>,
        /// PDACRT: a node with fewer than β rays is terminal only while rays × triangles
        /// is below this many tests (0: always, the paper's rule).
        #[arg(long)]
        terminal_cost: Option<u32>,
        /// PDACRT: the fewest ray ids a level must hold for --terminal-cost to apply.
        #[arg(long)]
        terminal_cost_min_rays: Option<u32>,
        /// PDACRT: scan, make the children and total a level in one dispatch where its
        /// scans fit one workgroup (true), or in four (false); the default is true.
        #[arg(long)]
        one_dispatch_plan: Option<bool>,
        /// PDACRT: split levels by `sort` (the paper's sort by status key) or `scan`
        /// (one prefix scan of side flags); the default is `scan`.
        #[arg(long)]
        split: Option<SplitArg>,
        /// PDACRT: reduce flushes by `sort` (the paper's sort by ray id and segmented
        /// arg-min) or `atomic` (64-bit atomicMin; the default where the device has it).
        #[arg(long)]
        flush: Option<FlushArg>,
        /// Also write the report as JSON.
        #[arg(long, value_name = "OUT.json")]
        json: Option<PathBuf>,
    },
    /// Per-frame time on an animated scene (waves, swarm, or a scene file with keys): the
    /// geometry update (nothing for PDACRT, a BVH build for the others) plus the
    /// frame's primary and shadow rays, tracers taking turns frame by frame.
    Dynamic {
        /// An animated built-in scene (waves, swarm) or scene .toml.
        scene: String,
        /// Timed frames, after one warm-up frame.
        #[arg(long, default_value_t = 8)]
        frames: u32,
        /// Frames per second: frame k shows time k / fps.
        #[arg(long, default_value_t = 24.0, allow_negative_numbers = true)]
        fps: f64,
        /// The warm-up frame; frames first+1 ..= first+frames are timed.
        #[arg(long, default_value_t = 0)]
        first: u32,
        #[arg(long, default_value_t = 512, value_parser = super::film_side_parser())]
        width: u32,
        #[arg(long, default_value_t = 512, value_parser = super::film_side_parser())]
        height: u32,
        /// Comma-separated workloads: primary, shadow (also reflection, ao).
        #[arg(long, value_delimiter = ',', default_value = "primary,shadow")]
        workloads: Vec<Workload>,
        /// Comma-separated tracers: pdacrt, ray-query (BLAS + TLAS built every frame),
        /// ray-query-refit (BLAS refitted), cpu-dacrt, cpu-bvh (rebuilt every frame).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "pdacrt,ray-query,ray-query-refit,cpu-dacrt,cpu-bvh"
        )]
        tracers: Vec<Contender>,
        /// Also write the report as JSON.
        #[arg(long, value_name = "OUT.json")]
        json: Option<PathBuf>,
    },
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum SplitArg {
    Sort,
    Scan,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum FlushArg {
    Sort,
    Atomic,
}

fn write_json<T: serde::Serialize>(path: &Option<PathBuf>, value: &T) -> anyhow::Result<()> {
    if let Some(path) = path {
        let bytes = serde_json::to_vec_pretty(value)?;
        splitray::film::atomic::write_bytes_atomically(path, &bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

/// What a bench reads before the device opens.
enum Inputs {
    /// Nothing (primitives).
    None,
    /// The scene of pt and trace.
    Scene(Scene),
    /// The animated scene of dynamic.
    Animated(AnimatedScene),
    /// Each scene of bdpt with its reference, if any.
    Bdpt(Vec<(Scene, Option<Arc<Reference>>)>),
    /// The scene of cbpt and its reference, if any.
    Cbpt {
        scene: Scene,
        reference: Option<Arc<Reference>>,
    },
}

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    check_outputs(args)?;
    let mut timeline = super::timeline::TimelineOutput::start(args.timeline.as_deref())?;
    check_lists(&args.what)?;
    // Load inputs before opening the device, so bad input fails fast.
    let inputs = load_inputs(&args.what)?;
    let gpu = Gpu::new(&GpuDesc {
        instance: InstanceDesc {
            validation: args.validation,
            sync_validation: false,
        },
        device: args.device.clone(),
        ..Default::default()
    })?;
    if let Some(t) = timeline.as_mut() {
        t.attach(&gpu)?;
    }
    dispatch(&gpu, &args.what, inputs)?;
    let messages = gpu.validation_messages();
    if !messages.is_empty() {
        anyhow::bail!(
            "{} validation message(s) (see the log above)",
            messages.len()
        );
    }
    if let Some(t) = timeline {
        t.finish(&super::timeline::command_line())?;
    }
    Ok(())
}

/// Fails at once, naming the path, where the outputs would overwrite one another or a
/// reference read, or where one could not be written at the end (a missing folder, a
/// folder in its place, no permission): a temporary file is created there and removed
/// again.
fn check_outputs(args: &BenchArgs) -> anyhow::Result<()> {
    let (json, dump_hits, references) = match &args.what {
        BenchCommand::Primitives { json, .. }
        | BenchCommand::Pt { json, .. }
        | BenchCommand::Dynamic { json, .. } => (json, &None, &[][..]),
        BenchCommand::Bdpt {
            json, reference, ..
        } => (json, &None, reference.as_slice()),
        BenchCommand::Cbpt {
            json, reference, ..
        } => (json, &None, reference.as_slice()),
        BenchCommand::Trace {
            json, dump_hits, ..
        } => (json, dump_hits, &[][..]),
    };
    let outputs: Vec<Role> = [
        ("--json", json),
        ("--dump-hits", dump_hits),
        ("--timeline", &args.timeline),
    ]
    .into_iter()
    .filter_map(|(what, path)| path.as_deref().map(|p| Role::file(what, p)))
    .collect();
    let inputs: Vec<Role> = references
        .iter()
        .map(|r| Role::file("--reference", r))
        .collect();
    refuse_clashing_paths(&outputs, &inputs)?;
    for path in [json, dump_hits].into_iter().flatten() {
        drop(splitray::film::AtomicFile::create(path)?);
    }
    Ok(())
}

/// Refuses a comma list that names an entry twice: it would be measured twice, beside
/// itself, for nothing.
fn check_lists(what: &BenchCommand) -> anyhow::Result<()> {
    fn shown<T: std::fmt::Display>(list: &[T]) -> Vec<String> {
        list.iter().map(T::to_string).collect()
    }
    let lists: Vec<(&str, Vec<String>)> = match what {
        BenchCommand::Bdpt { integrators, .. } => vec![("--integrators", shown(integrators))],
        BenchCommand::Cbpt {
            tracers, batches, ..
        } => vec![("--tracers", shown(tracers)), ("--batches", shown(batches))],
        BenchCommand::Trace { tracers, .. } => vec![("--tracers", shown(tracers))],
        BenchCommand::Dynamic {
            workloads, tracers, ..
        } => {
            let tracers = tracers.iter().map(|t| t.name().to_string()).collect();
            vec![("--workloads", shown(workloads)), ("--tracers", tracers)]
        }
        BenchCommand::Primitives { .. } | BenchCommand::Pt { .. } => Vec::new(),
    };
    for (option, list) in lists {
        let repeated = list
            .iter()
            .enumerate()
            .find(|(k, x)| list[..*k].contains(x));
        if let Some((_, twice)) = repeated {
            anyhow::bail!("{option} names {twice} twice");
        }
    }
    Ok(())
}

/// Loads and checks the scenes and references the bench `what` needs.
fn load_inputs(what: &BenchCommand) -> anyhow::Result<Inputs> {
    Ok(match what {
        BenchCommand::Trace { scene, .. } | BenchCommand::Pt { scene, .. } => {
            Inputs::Scene(splitray::scene::load(scene)?)
        }
        BenchCommand::Cbpt {
            scene,
            reference,
            width,
            height,
            time,
            ..
        } => {
            let scene = splitray::scene::load(scene)?;
            let reference = match reference {
                Some(path) => {
                    check_time(*time)?;
                    Some(Arc::new(Reference::read(path, *width, *height)?))
                }
                None => None,
            };
            Inputs::Cbpt { scene, reference }
        }
        BenchCommand::Bdpt {
            scenes,
            reference,
            width,
            height,
            time,
            streams,
            ..
        } => Inputs::Bdpt(load_bdpt_inputs(
            scenes, reference, *width, *height, *time, streams,
        )?),
        BenchCommand::Dynamic { scene, .. } => {
            Inputs::Animated(splitray::scene::load_animated(scene)?)
        }
        BenchCommand::Primitives { .. } => Inputs::None,
    })
}

/// Checks `bench bdpt`'s options, then loads each scene with its reference.
fn load_bdpt_inputs(
    scenes: &[String],
    reference: &[PathBuf],
    width: u32,
    height: u32,
    time: f64,
    streams: &[u32],
) -> anyhow::Result<Vec<(Scene, Option<Arc<Reference>>)>> {
    check_time(time)?;
    if let Some(s) = streams.iter().find(|s| !matches!(s, 1 | 3)) {
        anyhow::bail!("--streams: {s} streams; the kernels run on 1 or 3");
    }
    if !reference.is_empty() && reference.len() != scenes.len() {
        anyhow::bail!(
            "--reference: {} given for {} scenes (one per scene, in order, or none)",
            reference.len(),
            scenes.len()
        );
    }
    let mut inputs = Vec::new();
    for (k, name) in scenes.iter().enumerate() {
        let r = reference
            .get(k)
            .map(|p| Reference::read(p, width, height).map(Arc::new))
            .transpose()?;
        inputs.push((splitray::scene::load(name)?, r));
    }
    Ok(inputs)
}

/// Fails unless `--time` is a positive number of seconds.
fn check_time(time: f64) -> anyhow::Result<()> {
    if !time.is_finite() || time <= 0.0 {
        anyhow::bail!("--time must be a positive, finite number of seconds");
    }
    Ok(())
}

/// Runs the bench `what` names on the inputs [`load_inputs`] loaded for it.
fn dispatch(gpu: &Gpu, what: &BenchCommand, inputs: Inputs) -> anyhow::Result<()> {
    match (what, inputs) {
        (
            BenchCommand::Primitives {
                n,
                scan_n,
                runs,
                json,
            },
            Inputs::None,
        ) => run_primitives(gpu, *n, *scan_n, *runs, json),
        (BenchCommand::Pt { .. }, Inputs::Scene(scene)) => run_pt(gpu, what, &scene),
        (BenchCommand::Bdpt { .. }, Inputs::Bdpt(inputs)) => run_bdpt(gpu, what, inputs),
        (BenchCommand::Cbpt { .. }, Inputs::Cbpt { scene, reference }) => {
            run_cbpt(gpu, what, &scene, reference)
        }
        (BenchCommand::Dynamic { .. }, Inputs::Animated(animated)) => {
            run_dynamic(gpu, what, &animated)
        }
        (BenchCommand::Trace { .. }, Inputs::Scene(scene)) => run_trace(gpu, what, &scene),
        _ => unreachable!("load_inputs loads each bench's own inputs"),
    }
}

/// `bench primitives`: runs, prints and writes the primitives' report.
fn run_primitives(
    gpu: &Gpu,
    n: usize,
    scan_n: usize,
    runs: usize,
    json: &Option<PathBuf>,
) -> anyhow::Result<()> {
    let report = primitives::run(
        gpu,
        &PrimitivesBenchOptions {
            n,
            scan_n,
            runs,
            tuning: None,
        },
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    splitray::out!("{report}");
    write_json(json, &report)
}

/// `bench pt`: runs, prints and writes the path tracer's report on `scene`.
fn run_pt(gpu: &Gpu, what: &BenchCommand, scene: &Scene) -> anyhow::Result<()> {
    let BenchCommand::Pt {
        width,
        height,
        spp,
        max_depth,
        tracer,
        json,
        ..
    } = what
    else {
        unreachable!("run_pt runs bench pt")
    };
    let report = pt_bench::run(
        gpu,
        scene,
        &PtBenchOptions {
            width: *width,
            height: *height,
            spp: *spp,
            max_depth: *max_depth,
            tracer: *tracer,
            ..Default::default()
        },
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    splitray::out!("{report}");
    write_json(json, &report)
}

/// `bench bdpt`: runs and prints a report per scene, then writes them all.
fn run_bdpt(
    gpu: &Gpu,
    what: &BenchCommand,
    inputs: Vec<(Scene, Option<Arc<Reference>>)>,
) -> anyhow::Result<()> {
    let BenchCommand::Bdpt {
        width,
        height,
        integrators,
        time,
        rounds,
        max_depth,
        seed,
        spp,
        spp_rounds,
        streams,
        sort,
        resampling,
        json,
        ..
    } = what
    else {
        unreachable!("run_bdpt runs bench bdpt")
    };
    let mut reports = Vec::new();
    for (scene, reference) in inputs {
        let report = bdpt_bench::run(
            gpu,
            &scene,
            &BdptBenchOptions {
                width: *width,
                height: *height,
                integrators: integrators.clone(),
                seconds: *time,
                rounds: *rounds,
                max_depth: *max_depth,
                seed: *seed,
                reference,
                tracer: None,
                resampling: resampling.clone(),
                equal_spp: SppPlan {
                    passes: *spp,
                    rounds: *spp_rounds,
                    streams: streams.clone(),
                    sort: sort.clone(),
                },
            },
        )?;
        splitray::out!("{report}");
        reports.push(report);
    }
    write_json(json, &reports)
}

/// `bench cbpt`: checks the batch sizes, then runs, prints and writes CBPT's report.
fn run_cbpt(
    gpu: &Gpu,
    what: &BenchCommand,
    scene: &Scene,
    reference: Option<Arc<Reference>>,
) -> anyhow::Result<()> {
    let BenchCommand::Cbpt {
        width,
        height,
        tracers,
        steps,
        rounds,
        batches,
        time,
        max_depth,
        seed,
        json,
        ..
    } = what
    else {
        unreachable!("run_cbpt runs bench cbpt")
    };
    if let Some(b) = batches.iter().find(|b| **b == 0 || **b % 32 != 0) {
        anyhow::bail!("--batches: {b} is not a positive multiple of 32");
    }
    let report = cbpt_bench::run(
        gpu,
        scene,
        &CbptBenchOptions {
            width: *width,
            height: *height,
            tracers: tracers.clone(),
            steps: *steps,
            rounds: *rounds,
            batches: batches.clone(),
            seconds: *time,
            max_depth: *max_depth,
            seed: *seed,
            reference,
        },
    )?;
    splitray::out!("{report}");
    write_json(json, &report)
}

/// `bench dynamic`: runs, prints and writes the per-frame report on `animated`.
fn run_dynamic(gpu: &Gpu, what: &BenchCommand, animated: &AnimatedScene) -> anyhow::Result<()> {
    let BenchCommand::Dynamic {
        frames,
        fps,
        first,
        width,
        height,
        workloads,
        tracers,
        json,
        ..
    } = what
    else {
        unreachable!("run_dynamic runs bench dynamic")
    };
    let report = dynamic::run(
        gpu,
        animated,
        &DynamicBenchOptions {
            width: *width,
            height: *height,
            first: *first,
            frames: *frames,
            fps: *fps,
            workloads: workloads.clone(),
            contenders: tracers.clone(),
            ..Default::default()
        },
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    splitray::out!("{report}");
    write_json(json, &report)
}

/// `bench trace`: runs and prints the tracers' report (with --profile and --levels
/// tables), then writes it.
fn run_trace(gpu: &Gpu, what: &BenchCommand, scene: &Scene) -> anyhow::Result<()> {
    let BenchCommand::Trace {
        width,
        height,
        workload,
        tracers,
        frames,
        dump_hits,
        levels,
        profile,
        json,
        ..
    } = what
    else {
        unreachable!("run_trace runs bench trace")
    };
    let report = trace::run(
        gpu,
        scene,
        &TraceBenchOptions {
            width: *width,
            height: *height,
            workload: *workload,
            tracers: tracers.clone(),
            frames: *frames,
            pdacrt: Some(pdacrt_params(gpu, what)),
            ..Default::default()
        },
        dump_hits.as_deref(),
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    splitray::out!("{report}");
    if *profile {
        for row in &report.rows {
            splitray::outln!("\n{} GPU scopes (last frame):", row.tracer);
            splitray::out!("{}", row.profile.table());
        }
    }
    let pdacrt_ran = report
        .rows
        .iter()
        .any(|r| r.tracer == TracerKind::Pdacrt.name());
    match (*levels, pdacrt_ran) {
        (true, true) => print_levels(&report.pdacrt_levels),
        (true, false) => {
            splitray::outln!("--levels: PDACRT's levels, but pdacrt was not among --tracers")
        }
        (false, _) => {}
    }
    write_json(json, &report)
}

/// PDACRT's parameters for the device, with `bench trace`'s overrides applied.
fn pdacrt_params(gpu: &Gpu, what: &BenchCommand) -> PdacrtParams {
    let BenchCommand::Trace {
        alpha,
        beta,
        eta,
        lambda,
        batch,
        intersect_workgroup,
        tile_workgroup,
        chunk,
        stage_triangles,
        tight_boxes,
        terminal_cost,
        terminal_cost_min_rays,
        one_dispatch_plan,
        split,
        flush,
        ..
    } = what
    else {
        unreachable!("pdacrt_params reads bench trace's options")
    };
    let mut params = PdacrtParams::for_device(gpu);
    params.alpha = alpha.unwrap_or(params.alpha);
    params.beta = beta.unwrap_or(params.beta);
    params.eta = eta.unwrap_or(params.eta);
    params.lambda = lambda.unwrap_or(params.lambda.min(params.eta));
    params.batch = batch.unwrap_or(params.batch);
    params.intersect_workgroup = intersect_workgroup.unwrap_or(params.intersect_workgroup);
    params.tile_workgroup = tile_workgroup.unwrap_or(params.tile_workgroup);
    params.max_rays_per_chunk = chunk.unwrap_or(params.max_rays_per_chunk);
    params.stage_triangles = stage_triangles.unwrap_or(params.stage_triangles);
    params.tight_boxes = tight_boxes.unwrap_or(params.tight_boxes);
    params.terminal_cost = terminal_cost.unwrap_or(params.terminal_cost);
    params.terminal_cost_min_rays = terminal_cost_min_rays.unwrap_or(params.terminal_cost_min_rays);
    params.one_dispatch_plan = one_dispatch_plan.unwrap_or(params.one_dispatch_plan);
    if let Some(split) = split {
        params.split = match split {
            SplitArg::Sort => LevelSplit::SortByKey,
            SplitArg::Scan => LevelSplit::PrefixSums,
        };
    }
    if let Some(flush) = flush {
        params.flush_reduce = match flush {
            FlushArg::Sort => FlushReduce::SortByRay,
            FlushArg::Atomic => FlushReduce::AtomicMin,
        };
    }
    params
}

/// Prints `--levels`' table of PDACRT's per-level statistics.
fn print_levels(levels: &[LevelStats]) {
    splitray::outln!("PDACRT levels (last frame):");
    splitray::outln!(
        "{:>5} {:>6} {:>8} {:>10} {:>10} {:>6} {:>9} {:>8}",
        "chunk",
        "level",
        "nodes",
        "triangles",
        "rays",
        "dup",
        "terminal",
        "ms"
    );
    for l in levels {
        splitray::outln!(
            "{:>5} {:>6} {:>8} {:>10} {:>10} {:>6.2} {:>9} {:>8.2}{}",
            l.chunk,
            l.level,
            l.nodes,
            l.triangles,
            l.rays,
            l.ray_duplication,
            l.terminal_nodes,
            l.ms,
            if l.flushed { "  flush" } else { "" }
        );
    }
}
