//! `splitray render`: a render, a shard of one, or the continuation of a checkpoint.
//!
//! Order of work: signals are handled first, the timeline (if asked for) starts, then
//! the checkpoint to resume, the scene and the options are read, every output's
//! temporary file is created (so a path that cannot be written fails before any work),
//! and only then does the scene go to the GPU.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{anyhow, bail, Context};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use splitray::film::ImageFiles;
use splitray::integrator::bpt::technique_images;
use splitray::integrator::cbpt::CameraPaths;
use splitray::integrator::lvc::Resampling;
use splitray::integrator::IntegratorKind;
use splitray::render::{
    render_from, Checkpoint, CheckpointHook, FilmSnapshot, Progress, RenderControl, RenderError,
    RenderOptions, RenderOutput, RenderPlan, Resume, Shard,
};
use splitray::scene::Scene;
use splitray::trace::TracerKind;
use splitray::vk::{Gpu, GpuDesc, InstanceDesc};

use super::paths::{check_output, refuse_clashing_paths, same_file, Role};
use super::render_files::{write_stats, CheckpointFile, Failures, RenderFiles};
use super::signals::{self, StopSignals};
use options::{parse_shard, render_options};

mod frames;
mod options;
mod watch;

/// The scene rendered when none is named.
const DEFAULT_SCENE: &str = "cornell-box";

#[derive(Debug, Args)]
#[command(group(
    clap::ArgGroup::new("checkpoint_or_resume")
        .args(["checkpoint", "resume"])
        .multiple(true)
))]
pub struct RenderArgs {
    /// A built-in scene name (see `splitray scenes`), a scene .toml or an .obj mesh
    /// (default: cornell-box; with --resume, the checkpoint's scene). Its size is bounded
    /// by the device, not by one storage binding: 48 bytes per triangle in one buffer
    /// (2 GiB on lavapipe: 44M triangles), all buffers within the device's memory.
    scene: Option<String>,
    /// Output EXR; the PNG preview goes beside it. Default: out/<scene>.exr.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Film width in pixels (default: the scene's, else 512). Up to 16384; the device
    /// bounds the film too: one buffer of 16 bytes per pixel (2 GiB on lavapipe) and its
    /// memory (`splitray info`), checked before any work.
    #[arg(long)]
    width: Option<u32>,
    /// Film height in pixels (default: the scene's, else 512).
    #[arg(long)]
    height: Option<u32>,
    /// Samples per pixel (default: the scene's, else 1; more than 1 jitters within pixels;
    /// cbpt renders 4 a pass, so it rounds up to a multiple of 4).
    #[arg(long)]
    spp: Option<u32>,
    /// Random seed (same seed, same device → same image).
    #[arg(long)]
    seed: Option<u64>,
    /// What to compute along the rays: primary (eye-light shading), ao (ambient
    /// occlusion), shadow (one point light), reflection (one mirror bounce), path
    /// (7 diffuse bounces), pt (physically based path tracing), bpt (bidirectional path
    /// tracing on the CPU), light (light tracing on the CPU), lvc-bdpt (bidirectional
    /// path tracing with a light vertex cache on the GPU), cis-lbdpt (the same with
    /// material sorting and resampled connections) or cbpt (combinatorial BPT: CPU path
    /// populations, GPU combination).
    #[arg(long)]
    integrator: Option<IntegratorKind>,
    /// Render for this many seconds instead (stops after the pass during which the time
    /// ran out; cbpt gives that pass up between two of its steps once the film holds a
    /// pass; with --spp, at most that many passes).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    time: Option<f64>,
    /// pt, bpt, light, lvc-bdpt, cis-lbdpt, cbpt: maximum path depth as in Mitsuba (1 =
    /// emitters seen directly, 2 = direct light, -1 = unbounded; default: the scene's,
    /// else -1).
    #[arg(long, allow_hyphen_values = true, value_parser = super::max_depth_parser())]
    max_depth: Option<i32>,
    /// pt, bpt, light, lvc-bdpt, cis-lbdpt, cbpt: Russian roulette from this depth on
    /// (default: Mitsuba's 5).
    #[arg(long)]
    rr_depth: Option<u32>,
    /// pt, lvc-bdpt, cis-lbdpt: do not sort paths by material before shading (same image,
    /// other speed).
    #[arg(long, conflicts_with = "sort")]
    no_sort: bool,
    /// pt, lvc-bdpt, cis-lbdpt: sort paths by material before shading (same image). By
    /// default pt and cis-lbdpt sort where it pays, as measured: pt on GPUs but not on CPU
    /// devices such as lavapipe; cis-lbdpt on neither lavapipe nor NVIDIA's driver.
    #[arg(long)]
    sort: bool,
    /// lvc-bdpt, cis-lbdpt: connections (shadow rays) to light-vertex-cache vertices per
    /// camera vertex, N (default 5, at most 16).
    #[arg(long, value_name = "N")]
    connections: Option<u32>,
    /// cis-lbdpt: candidate cache vertices per camera vertex, M, that the N connections
    /// are resampled from (default 10, at most 16).
    #[arg(long, value_name = "M")]
    candidates: Option<u32>,
    /// cis-lbdpt: how the N connections are drawn from the M candidates: systematic
    /// (default; one random number u, draw k at (u + k) / N) or independent.
    #[arg(long)]
    resampling: Option<Resampling>,
    /// lvc-bdpt, cis-lbdpt: streams for the direct-lighting, connection and next-bounce
    /// kernels: 3 (default; concurrent where the device has several queues) or 1 (the
    /// same image).
    #[arg(long, value_name = "1|3")]
    streams: Option<u32>,
    /// pt: estimators: mis (default), nee (light sampling only) or bsdf (BSDF sampling only).
    #[arg(long)]
    strategy: Option<splitray::integrator::pt::Strategy>,
    /// How rays are cast: pdacrt (default; no acceleration structure), brute-force (the
    /// oracle), cpu-dacrt (serial CPU baseline), cpu-bvh (a BVH built and traced on every
    /// CPU core) or ray-query (driver BVH, where offered).
    #[arg(long)]
    tracer: Option<TracerKind>,
    /// Vulkan device by index or name substring (see `splitray info`); also SPLITRAY_DEVICE.
    #[arg(long, value_parser = clap::builder::NonEmptyStringValueParser::new())]
    device: Option<String>,
    /// Run with VK_LAYER_KHRONOS_validation; any validation message fails the command.
    #[arg(long)]
    validation: bool,
    /// Also enable synchronization validation (slow; implies --validation).
    #[arg(long)]
    sync_validation: bool,
    /// Write per-kernel GPU times, rays traced, rays/s and peak GPU memory as JSON.
    #[arg(long, value_name = "STATS.json")]
    stats: Option<PathBuf>,
    /// Print the GPU scopes as a tree with total and self times.
    #[arg(long)]
    profile: bool,
    /// A reference image (an EXR of this film size, e.g. a long render or a Mitsuba
    /// reference): the relative MSE against it is shown as the render goes and recorded
    /// in the stats, and without the reference's own noise where its standard errors are
    /// known (stderr.R/G/B channels, or NAME_stderr.exr beside NAME_mean.exr).
    #[arg(long, value_name = "REF.exr")]
    reference: Option<PathBuf>,
    /// Write a timeline of the render (GPU streams, host threads, counters) as
    /// trace-event JSON for ui.perfetto.dev or chrome://tracing.
    #[arg(long, value_name = "FILE.json")]
    timeline: Option<PathBuf>,
    /// Save the film (its sums, the samples done, seed, settings and a fingerprint of the
    /// scene) to FILE every --checkpoint-every seconds, and when the render ends or is
    /// stopped; `splitray render --resume FILE` continues it.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// Seconds of rendering between two checkpoints (saved at a pass boundary), of
    /// --checkpoint or of the one --resume continues.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 300.0,
        requires = "checkpoint_or_resume",
        allow_negative_numbers = true
    )]
    checkpoint_every: f64,
    /// Continue the render saved in this checkpoint: to --spp N samples per pixel in all,
    /// for --time S more seconds, or else to the target it was started with. Scene, size
    /// and settings come from the checkpoint; options given that change the image must
    /// match it, and a scene file that changed since is refused. The render goes on saving
    /// to this checkpoint, unless --checkpoint names another.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Render the I-th of N statistically independent parts of the image (numbered from
    /// 0: 0/4 … 3/4), each a disjoint block of the passes; `splitray merge` combines
    /// them. `auto` takes I and N from a Slurm job array (SLURM_ARRAY_TASK_ID,
    /// SLURM_ARRAY_TASK_COUNT) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX, with
    /// SPLITRAY_SHARD_COUNT set to its completions).
    #[arg(long, value_name = "I/N|auto")]
    shard: Option<String>,
    /// bpt, light, lvc-bdpt, cis-lbdpt: also write one MIS-weighted EXR per technique (s, t) into this
    /// (existing) folder, `s{S}_t{T}.exr` (`longer.exr`: paths of more than 8
    /// segments); they sum to the image.
    #[arg(long, value_name = "DIR")]
    bdpt_techniques: Option<PathBuf>,
    /// Render frames A to B-1 (A..B) or A to B (A..=B) of an animated scene, frame k at
    /// time k / fps: a numbered sequence beside the output (`-o shot.exr` writes
    /// shot_0000.exr, shot_0001.exr … and their PNGs). Not with --checkpoint, --resume,
    /// --shard, --reference, --bdpt-techniques, --preview or --display-server; --time
    /// limits each frame.
    #[arg(long, value_name = "A..B")]
    frames: Option<String>,
    /// Frames per second of --frames (default 24).
    #[arg(long, requires = "frames", allow_negative_numbers = true)]
    fps: Option<f64>,
    /// Show the film converging in a window (needs an X11 display); closing it stops the
    /// render and writes what it has. Keys: Up/Down exposure, A next view (colour, depth,
    /// normal, triangle id), S snapshot beside the output, Escape close.
    #[arg(long)]
    preview: bool,
    /// Stream the render as it converges to the tev image viewer listening at HOST:PORT
    /// (`tev --hostname HOST:PORT`); a listener that is away or goes away does not stop
    /// the render.
    #[arg(long, value_name = "HOST:PORT")]
    display_server: Option<String>,
    /// cbpt: N_C, the most camera paths per step, or `auto` to choose it (and N_L) by
    /// Equation 4 of the CBPT paper from measured BPT and CBPT times (default 2000; at
    /// most 1048576, as N_L and N_T).
    #[arg(long, value_name = "N|auto")]
    cbpt_nc: Option<splitray::integrator::cbpt::CameraPaths>,
    /// cbpt: N_L, light paths per step, each linked to every camera path (default 15).
    #[arg(long, value_name = "N")]
    cbpt_nl: Option<u32>,
    /// cbpt: N_T, light paths light-traced per step (default 1500; 0: no light tracing,
    /// and no paths that only light tracing samples, such as point-light caustics).
    #[arg(long, value_name = "N")]
    cbpt_nt: Option<u32>,
    /// cbpt: linking segments per GPU batch, a multiple of 32 (default 131072).
    #[arg(long, value_name = "SEGMENTS")]
    cbpt_batch: Option<u32>,
    /// cbpt: where the linking segments are evaluated: gpu (default; visibility through
    /// --tracer) or cpu (every core, the CPU BVH).
    #[arg(long, value_name = "gpu|cpu")]
    cbpt_combine: Option<splitray::integrator::cbpt::Combination>,
}

/// The output path (default `out/<scene>.exr`, `out/<scene>.shard-I-of-N.exr` for a
/// shard), checked before any work so a bad path fails fast.
fn output_path(args: &RenderArgs, scene_name: &str, shard: Shard) -> anyhow::Result<PathBuf> {
    let path = match &args.output {
        Some(p) => p.clone(),
        None => {
            let stem: String = scene_name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            std::fs::create_dir_all("out").context("cannot create the folder out/")?;
            let suffix = if shard.is_whole() {
                String::new()
            } else {
                format!(".shard-{}-of-{}", shard.index, shard.count)
            };
            PathBuf::from("out").join(format!("{stem}{suffix}.exr"))
        }
    };
    check_output(&path, &["exr"], "an .exr file")?;
    Ok(path)
}

/// Refuses outputs that would overwrite one another or an input ([`refuse_clashing_paths`]):
/// `exr` (a frame's, for a sequence), its PNG, the stats, checkpoint and timeline; the
/// reference, the checkpoint resumed and every file the scene was read from (called once
/// the scene is loaded).
fn refuse_clashes<'a>(args: &'a RenderArgs, exr: &'a Path) -> anyhow::Result<()> {
    let png = exr.with_extension("png");
    let file = |what, path: &'a Option<PathBuf>| path.as_deref().map(|p| Role::file(what, p));
    let checkpoint =
        |what, path: &'a Option<PathBuf>| path.as_deref().map(|p| Role::checkpoint(what, p));
    let outputs: Vec<Role> = [
        Some(Role::file("the image", exr)),
        Some(Role::file("its PNG preview", &png)),
        file("--stats", &args.stats),
        checkpoint("--checkpoint", &args.checkpoint),
        file("--timeline", &args.timeline),
    ]
    .into_iter()
    .flatten()
    .collect();
    let mut inputs: Vec<Role> = [
        file("--reference", &args.reference),
        checkpoint("--resume", &args.resume),
    ]
    .into_iter()
    .flatten()
    .collect();
    // The scene file, its meshes and material libraries: every other file read so far.
    let read = splitray::input::files_read();
    let named = |path: &Path| inputs.iter().any(|i| same_file(i.path, path));
    let scene_files: Vec<Role> = read
        .iter()
        .filter(|path| !named(path))
        .map(|path| Role::file("a file of the scene", path))
        .collect();
    inputs.extend(scene_files);
    refuse_clashing_paths(&outputs, &inputs)?;
    match &args.bdpt_techniques {
        Some(dir) => refuse_technique_clashes(outputs.iter().chain(&inputs), dir),
        None => Ok(()),
    }
}

/// Refuses a file of the render that a technique image of `--bdpt-techniques DIR` would
/// replace: `DIR/s{S}_t{T}.exr` or `DIR/longer.exr`, written after the render.
fn refuse_technique_clashes<'a>(
    files: impl Iterator<Item = &'a Role<'a>>,
    dir: &Path,
) -> anyhow::Result<()> {
    for file in files {
        let Some(name) = file.path.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        let technique = name
            .strip_suffix(".exr")
            .is_some_and(technique_images::is_image_name);
        if technique && same_file(file.path, &dir.join(name)) {
            bail!(
                "{}: {} and a technique image of --bdpt-techniques {} name the same file: \
                 it would be written over",
                file.path.display(),
                file.what,
                dir.display()
            );
        }
    }
    Ok(())
}

pub fn run(args: &RenderArgs) -> anyhow::Result<ExitCode> {
    if let Some(spec) = &args.frames {
        return frames::run(args, spec);
    }
    let signals = StopSignals::install("the image is written with the samples reached")?;
    let mut timeline = super::timeline::TimelineOutput::start(args.timeline.as_deref())?;
    let job = read_job(args)?;
    let output = output_path(args, &job.scene.name, job.shard)?;
    refuse_clashes(args, &output)?;
    let mut files =
        RenderFiles::create(&output, args.stats.as_deref(), args.checkpoint.as_deref())?;
    if let (None, Some(resumed)) = (&args.checkpoint, &args.resume) {
        files.checkpoint = keep_saving(resumed);
    }
    let mut watching = watch::Watching::open(
        args,
        &job.scene.name,
        &output,
        [job.options.width, job.options.height],
    )?;
    let gpu = watching.open_gpu(&gpu_desc(args))?;
    if let Some(t) = timeline.as_mut() {
        t.attach(&gpu)?;
    }
    watching.attach(&gpu)?;

    let result = render_watched(args, &gpu, &job, &watching, &signals, &mut files.checkpoint);
    let window_closed = watching.window_closed();
    watching.finish();
    let result = result?;

    let messages = gpu.validation_messages();
    if !messages.is_empty() {
        bail!(
            "{} validation message(s) (see the log above); nothing was written",
            messages.len()
        );
    }
    let stopped_by = signals.received();
    if result.sums.passes == 0 {
        return nothing_rendered(window_closed, stopped_by);
    }
    print_summary(&result, args.profile);
    let exr = write_outputs(args, &job, &result, files, timeline)?;
    report_early_stop(stopped_by, window_closed, &result, &exr);
    Ok(exit_code(stopped_by))
}

/// What one render makes, read before any output is created.
struct RenderJob<'a> {
    /// The scene: a built-in name or a file's absolute path, recorded in checkpoints.
    scene_spec: String,
    scene: Scene,
    shard: Shard,
    options: RenderOptions,
    /// The checkpoint continued, and its path.
    resume: Option<(Checkpoint, &'a Path)>,
}

/// The checkpoint to resume, the scene, the shard and the options: the command line's,
/// else the checkpoint's, else the defaults.
fn read_job(args: &RenderArgs) -> anyhow::Result<RenderJob<'_>> {
    let resume = match &args.resume {
        Some(path) => Some((Checkpoint::read(path)?, path.as_path())),
        None => None,
    };
    let checkpoint = resume.as_ref().map(|(c, _)| c);
    let scene_spec = match (&args.scene, checkpoint) {
        (Some(spec), _) => spec.clone(),
        (None, Some(c)) => c.header.scene.clone(),
        (None, None) => DEFAULT_SCENE.to_string(),
    };
    let scene = splitray::scene::load(&scene_spec).map_err(|e| match (&args.scene, &resume) {
        (None, Some((_, path))) => anyhow!(
            "{e} (the scene {} was saved from: give its path as SCENE if it moved)",
            path.display()
        ),
        _ => e.into(),
    })?;
    let scene_spec = absolute_scene_path(scene_spec);
    let shard = match (&args.shard, checkpoint) {
        (Some(spec), _) => parse_shard(spec)?,
        (None, Some(c)) => c.header.shard,
        (None, None) => Shard::WHOLE,
    };
    let options = render_options(args, &scene, resume.as_ref())?;
    let measured_here = options.integrator == IntegratorKind::Cbpt
        && options.cbpt.camera_paths == CameraPaths::Equation4;
    if measured_here && !shard.is_whole() {
        bail!(
            "--cbpt-nc auto measures the machine it runs on, so shards would render with \
             populations of their own and not merge: give --cbpt-nc N --cbpt-nl N (the EXR \
             of a render with auto names what it measured: cbpt_camera_paths, \
             cbpt_light_paths)"
        );
    }
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every >= 0.0) {
        bail!("--checkpoint-every must be a number of seconds, 0 or more");
    }
    Ok(RenderJob {
        scene_spec,
        scene,
        shard,
        options,
        resume,
    })
}

/// A scene file's absolute path (a built-in's name stays): the checkpoint names its scene
/// so, and `--resume` finds it from any folder.
fn absolute_scene_path(spec: String) -> String {
    let builtin = splitray::scene::builtin_names()
        .iter()
        .any(|(name, _)| *name == spec);
    match builtin {
        true => spec,
        false => std::fs::canonicalize(&spec)
            .map(|p| p.display().to_string())
            .unwrap_or(spec),
    }
}

/// The checkpoint a render resumed without `--checkpoint` goes on saving to, so that its
/// new samples are kept; where it cannot (a read-only folder) the render goes on without
/// saving, and says so.
fn keep_saving(resumed: &Path) -> Option<CheckpointFile> {
    CheckpointFile::create(resumed)
        .map_err(|e| {
            splitray::errln!(
                "note: {e}: the checkpoint resumed is not saved over, so the samples this \
                 render adds are kept only in its image (--checkpoint FILE saves them)"
            )
        })
        .ok()
}

/// Renders `job` behind a progress bar, saving `checkpoint_file` as it goes and showing
/// the film to whoever watches; a signal or a closed preview window stops it.
fn render_watched(
    args: &RenderArgs,
    gpu: &Gpu,
    job: &RenderJob<'_>,
    watching: &watch::Watching,
    signals: &StopSignals,
    checkpoint_file: &mut Option<CheckpointFile>,
) -> Result<RenderOutput, RenderError> {
    let RenderJob {
        scene_spec,
        scene,
        shard,
        options,
        resume,
    } = job;
    let mut publisher = watching.publisher();
    let label = match shard.is_whole() {
        true => format!("{} {}x{}", scene.name, options.width, options.height),
        false => format!(
            "{} {}x{} shard {shard}",
            scene.name, options.width, options.height
        ),
    };
    let bar = progress_bar(options, &label);
    let pixels = options.width as f64 * options.height as f64;
    let saving = checkpoint_file.is_some();
    let mut save = |snapshot: &FilmSnapshot<'_>| -> Result<(), RenderError> {
        if let Some(file) = checkpoint_file.as_mut() {
            file.save(&Checkpoint::new(scene_spec, options, snapshot))?;
        }
        Ok(())
    };
    let plan = RenderPlan {
        shard: *shard,
        resume: resume
            .as_ref()
            .map(|(checkpoint, path)| Resume { checkpoint, path }),
        checkpoint: saving.then_some(CheckpointHook {
            every_s: args.checkpoint_every,
            save: &mut save,
        }),
        watch: publisher.as_mut().map(|p| p as _),
    };
    let stop_asked = || signals.received().is_some() || watching.window_closed();
    let result = render_from(
        gpu,
        scene,
        options,
        plan,
        RenderControl {
            progress: &mut |p| show_progress(&bar, &label, p, pixels, options.time_limit),
            stop: &stop_asked,
            // Neither a signal nor a closed window waits for a long pass: Slurm's
            // KillWait, for one, is 30 s.
            abandon: &stop_asked,
        },
    );
    bar.finish_and_clear();
    result
}

/// A render that holds no passes writes nothing: fine when the window was closed or a
/// signal came first, an error otherwise.
fn nothing_rendered(window_closed: bool, stopped_by: Option<i32>) -> anyhow::Result<ExitCode> {
    if window_closed && stopped_by.is_none() {
        splitray::errln!("preview window closed before the first pass; nothing written");
        return Ok(ExitCode::SUCCESS);
    }
    let Some(signal) = stopped_by else {
        bail!("the render holds no passes; nothing was written");
    };
    splitray::errln!(
        "{}: stopped before the first pass; nothing written",
        signals::name(signal)
    );
    Ok(exit_code(stopped_by))
}

/// Writes every output of the render: the last checkpoint, the stats, the technique
/// images, the image and the timeline, each tried whatever became of the others (a disk
/// that filled up under one output need not cost the rest), and tells the user. Returns
/// the EXR's path, or an error listing every output that failed.
fn write_outputs(
    args: &RenderArgs,
    job: &RenderJob<'_>,
    result: &RenderOutput,
    files: RenderFiles,
    timeline: Option<super::timeline::TimelineOutput>,
) -> anyhow::Result<PathBuf> {
    let RenderFiles {
        image,
        stats,
        checkpoint,
    } = files;
    let mut failures = Failures::default();
    // The checkpoint first: should the image fail, the render is kept in it.
    let saved = checkpoint.and_then(|file| failures.keep(save_last_checkpoint(file, job, result)));
    if let Some(file) = stats {
        failures.keep(write_stats(file, &result.stats));
    }
    if let Some(dir) = &args.bdpt_techniques {
        let _span = tracing::info_span!("write technique images").entered();
        failures.keep(write_technique_images(
            dir,
            &result.extra_images,
            &result.metadata,
        ));
    }
    let exr = failures.keep(write_image(image, result));
    // Last, so that it shows the other outputs being written.
    if let Some(t) = timeline {
        failures.keep(t.finish(&super::timeline::command_line()));
    }
    let hint = saved.map(|checkpoint| how_to_write_the_image(&checkpoint, &job.options, result));
    failures.outcome(exr, hint)
}

/// How to write the image again from the checkpoint just saved: resuming it writes the
/// image once the render reaches its target; a timed render that spent its time needs a
/// new target (resuming refuses one that adds nothing).
fn how_to_write_the_image(
    checkpoint: &Path,
    options: &RenderOptions,
    result: &RenderOutput,
) -> String {
    let c = checkpoint.display();
    let resume = if result.stats.stopped_early {
        format!("`splitray render --resume {c} -o OUT.exr` continues it to its target and writes the image")
    } else if options.time_limit.is_some() {
        format!(
            "`splitray render --resume {c} --spp N -o OUT.exr`, N more than its {} spp, \
             continues it and writes the image",
            result.sums.spp()
        )
    } else {
        format!("`splitray render --resume {c} -o OUT.exr` writes the image again")
    };
    format!("the render is kept in the checkpoint {c}: {resume}")
}

/// Saves the finished film to the checkpoint file and says how to continue it.
fn save_last_checkpoint(
    mut file: CheckpointFile,
    job: &RenderJob<'_>,
    result: &RenderOutput,
) -> anyhow::Result<PathBuf> {
    let path = file.save(&Checkpoint::new(
        &job.scene_spec,
        &job.options,
        &result.snapshot(),
    ))?;
    splitray::outln!(
        "checkpoint {} holds {} spp: `splitray render --resume {} --spp N` continues it",
        path.display(),
        result.sums.spp(),
        path.display()
    );
    Ok(path)
}

/// Writes the EXR and its PNG preview; returns the EXR's path.
fn write_image(image: ImageFiles, result: &RenderOutput) -> anyhow::Result<PathBuf> {
    let _span = tracing::info_span!("write outputs").entered();
    let written = image.write(&result.film, &result.metadata)?;
    splitray::outln!(
        "wrote {} and {}",
        written.exr.display(),
        written.png.display()
    );
    Ok(written.exr)
}

/// Tells the user when a signal or the closed window stopped the render short of its
/// target.
fn report_early_stop(
    stopped_by: Option<i32>,
    window_closed: bool,
    result: &RenderOutput,
    exr: &Path,
) {
    if let Some(signal) = stopped_by {
        splitray::errln!(
            "{}: the render stopped at {} spp; {} records the samples reached",
            signals::name(signal),
            result.sums.spp(),
            exr.display()
        );
    } else if window_closed && result.stats.stopped_early {
        splitray::errln!(
            "preview window closed: the render stopped at {} spp; {} records the samples \
             reached",
            result.sums.spp(),
            exr.display()
        );
    }
}

/// The device `--device` names, with validation where asked for.
fn gpu_desc(args: &RenderArgs) -> GpuDesc {
    GpuDesc {
        instance: InstanceDesc {
            validation: args.validation,
            sync_validation: args.sync_validation,
        },
        device: args.device.clone(),
        ..Default::default()
    }
}

fn exit_code(stopped_by: Option<i32>) -> ExitCode {
    match stopped_by {
        Some(signal) => ExitCode::from(signals::exit_status(signal)),
        None => ExitCode::SUCCESS,
    }
}

fn progress_bar(options: &RenderOptions, label: &str) -> ProgressBar {
    let bar = match options.time_limit {
        // Timed: the bar runs over seconds; the message carries passes and samples/s.
        Some(t) => {
            let bar = ProgressBar::new((t * 10.0).ceil() as u64);
            bar.set_style(
                ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {elapsed} eta {eta}")
                    .expect("valid progress template")
                    .progress_chars("=> "),
            );
            bar
        }
        None => {
            let bar = ProgressBar::new(options.spp as u64);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} {msg} [{bar:30}] {pos}/{len} spp  {per_sec}  eta {eta}",
                )
                .expect("valid progress template")
                .progress_chars("=> "),
            );
            bar
        }
    };
    bar.set_message(label.to_string());
    bar
}

fn show_progress(
    bar: &ProgressBar,
    label: &str,
    p: &Progress,
    pixels: f64,
    time_limit: Option<f64>,
) {
    let rate = p.spp as f64 * pixels / p.elapsed_s.max(1e-9);
    let mse = p
        .relative_mse
        .map(|m| format!(", relMSE {m:.4e}"))
        .unwrap_or_default();
    bar.set_message(format!(
        "{label} {} spp, {:.3} Msamples/s{mse}",
        p.spp,
        rate * 1e-6
    ));
    if time_limit.is_some() {
        bar.set_position((p.elapsed_s * 10.0) as u64);
    } else {
        bar.set_length(p.target_spp);
        bar.set_position(p.spp);
    }
}

fn print_summary(result: &RenderOutput, profile: bool) {
    let s = &result.stats;
    splitray::outln!(
        "{}: {}x{} {} spp, {} + {} on {} in {:.3} s: {} rays, {:.2} Mrays/s, peak GPU memory {:.1} MiB",
        s.scene,
        s.width,
        s.height,
        s.spp,
        s.integrator,
        s.tracer,
        s.device,
        s.render_time_s,
        s.rays_traced,
        s.rays_per_second * 1e-6,
        s.peak_gpu_bytes as f64 / (1 << 20) as f64
    );
    if let Some(mse) = s.relative_mse {
        match s.relative_mse_excess {
            Some(excess) => splitray::outln!(
                "relative MSE against the reference: {mse:.6e} ({excess:.6e} without the \
                 reference's own noise)"
            ),
            None => splitray::outln!("relative MSE against the reference: {mse:.6e}"),
        }
    }
    if profile {
        splitray::out!("{}", s.profile.table());
    }
}

/// Refuses `--bdpt-techniques` for other integrators and a folder that is missing or not
/// writable, before anything is rendered.
pub(super) fn check_technique_dir(dir: &Path, integrator: IntegratorKind) -> anyhow::Result<()> {
    if !matches!(
        integrator,
        IntegratorKind::Bpt
            | IntegratorKind::Light
            | IntegratorKind::LvcBdpt
            | IntegratorKind::CisLbdpt
    ) {
        bail!(
            "--bdpt-techniques needs --integrator bpt, light, lvc-bdpt or cis-lbdpt, not {integrator}"
        );
    }
    if !dir.is_dir() {
        bail!(
            "{}: --bdpt-techniques needs an existing folder",
            dir.display()
        );
    }
    let probe = dir.join(format!(".splitray-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .with_context(|| format!("{}: the folder is not writable", dir.display()))?;
    std::fs::remove_file(&probe).ok();
    Ok(())
}

/// Writes each technique image as `DIR/NAME.exr` (atomically, like every output).
fn write_technique_images(
    dir: &Path,
    images: &[splitray::integrator::NamedImage],
    metadata: &splitray::film::RenderMetadata,
) -> anyhow::Result<()> {
    for image in images {
        let film = splitray::film::Film::from_mean_rgb(image.width, image.height, &image.rgb)?;
        let mut meta = metadata.clone();
        meta.extra.push(("technique".into(), image.name.clone()));
        let path = dir.join(format!("{}.exr", image.name));
        splitray::film::write_exr(&path, &film, &meta)?;
    }
    splitray::outln!(
        "wrote {} technique images to {}",
        images.len(),
        dir.display()
    );
    Ok(())
}
