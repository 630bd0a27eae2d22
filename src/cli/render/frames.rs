//! `splitray render --frames A..B [--fps F]`: a numbered image sequence of an animated
//! scene. Frame k shows the scene at time k / F and is written, as soon as it is done, to
//! the output path with `_` and the frame number before the extension (`-o shot.exr`
//! gives `shot_0000.exr`, `shot_0001.exr`, … and a PNG preview beside each), the number
//! zero-padded to 4 digits or to as many as the last frame needs.
//!
//! Options that belong to one image are refused with the sequence: checkpoints and
//! resuming (a stopped sequence continues with the frames left: `--frames K..B`),
//! shards (a render farm splits a sequence by giving each job its own frame range),
//! `--reference`, `--bdpt-techniques`, `--preview` and `--display-server`. `--time` limits each frame; `--stats` writes
//! one JSON file with every frame's statistics.
//!
//! A frame whose image or PNG cannot be written ends the sequence there (a full disk
//! would fail every later frame: rendering them would waste the work). The frames before
//! it keep their files; the stats file, which lists the frames written (not the one that
//! failed: its image is not on disk), and the timeline are still written. The error
//! lists every output that failed, the frames written and the `--frames` range that
//! renders the rest. Any other error that ends a sequence (a device lost) is reported
//! the same way.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{anyhow, bail};
use splitray::film::{AtomicFile, ImageFiles};
use splitray::render::frames::{
    check_frames, frame_named, frame_path, render_frames, Frame, FrameRange, FramesControl,
    FramesRun, DEFAULT_FPS,
};
use splitray::render::{RenderError, RenderOptions, RenderStats, Shard};
use splitray::scene::AnimatedScene;
use splitray::vk::Gpu;

use super::super::render_files::{write_stats, Failures, RenderFiles};
use super::super::signals::{self, StopSignals};
use super::super::timeline::{command_line, TimelineOutput};
use super::options::render_options;
use super::{
    gpu_desc, output_path, print_summary, progress_bar, show_progress, RenderArgs, DEFAULT_SCENE,
};

/// One frame's line of the `--stats` file.
#[derive(serde::Serialize)]
struct FrameStats {
    frame: u32,
    /// Scene time in seconds.
    time: f32,
    /// Triangles uploaded again for the frame.
    changed_triangles: usize,
    #[serde(flatten)]
    stats: RenderStats,
}

/// Options that make no sense for a sequence, and why.
fn refuse_single_image_options(args: &RenderArgs) -> anyhow::Result<()> {
    if args.checkpoint.is_some() || args.resume.is_some() {
        bail!(
            "--checkpoint and --resume work on one image, not with --frames: a stopped \
             sequence continues with the frames it has left (--frames K..B)"
        );
    }
    if args.shard.is_some() {
        bail!(
            "--shard splits one image, not with --frames: give each job of a render farm \
             its own frame range instead"
        );
    }
    if args.reference.is_some() {
        bail!("--reference compares one image: it cannot be used with --frames");
    }
    if args.preview || args.display_server.is_some() {
        bail!(
            "--preview and --display-server watch one image converge: they cannot be used \
             with --frames"
        );
    }
    if args.bdpt_techniques.is_some() {
        bail!("--bdpt-techniques writes the technique images of one image: it cannot be used with --frames");
    }
    Ok(())
}

pub(super) fn run(args: &RenderArgs, spec: &str) -> anyhow::Result<ExitCode> {
    refuse_single_image_options(args)?;
    let signals =
        StopSignals::install("the frame in progress is dropped; the frames written are kept")?;
    let mut timeline = TimelineOutput::start(args.timeline.as_deref())?;
    let job = read_sequence(args, spec)?;
    let range = job.range;
    let base = output_path(args, &job.animated.scene.name, Shard::WHOLE)?;
    refuse_clashes(args, &base, &range)?;
    // The first frame's files (and the stats file) before the GPU: a path that cannot be
    // written fails at once. Each later frame's files are created before its render.
    let files = RenderFiles::create(
        &frame_path(&base, range.first, &range),
        args.stats.as_deref(),
        None,
    )?;
    let gpu = Gpu::new(&gpu_desc(args))?;
    if let Some(t) = timeline.as_mut() {
        t.attach(&gpu)?;
    }

    let RenderFiles { image, stats, .. } = files;
    let (ended, frame_stats) = render_sequence(args, &gpu, &job, &base, image, &signals);
    let written = frame_stats.len() as u32;
    write_sequence_outputs(ended, frame_stats, stats, timeline, &range)?;
    Ok(report_sequence_end(
        signals.received(),
        written,
        &range,
        &base,
    ))
}

/// Writes the stats of the frames written and the timeline, each tried whatever ended
/// the sequence (a frame that could not be written, say) and whatever became of the
/// other. Returns an error listing every failure, `ended`'s first, and, where frames
/// are left, which were written and the range that renders the rest.
fn write_sequence_outputs(
    ended: Result<FramesRun, RenderError>,
    frame_stats: Vec<FrameStats>,
    stats: Option<AtomicFile>,
    timeline: Option<TimelineOutput>,
    range: &FrameRange,
) -> anyhow::Result<()> {
    let written = frame_stats.len() as u32;
    let mut failures = Failures::default();
    failures.keep(ended.map_err(anyhow::Error::from));
    if let Some(file) = stats {
        failures.keep(write_stats(
            file,
            &serde_json::json!({ "frames": frame_stats }),
        ));
    }
    if let Some(t) = timeline {
        failures.keep(t.finish(&command_line()));
    }
    let left = written < range.len();
    failures.check(left.then(|| rest_of_sequence(written, range)))
}

/// Refuses a sequence whose files would overwrite one another: the first frame's against
/// the others (stats, timeline), and the frame whose image or PNG the stats file names, if
/// any. (Frames cannot clash with one another, their numbers differ, and the timeline is
/// a .json file.)
fn refuse_clashes(args: &RenderArgs, base: &Path, range: &FrameRange) -> anyhow::Result<()> {
    let named = args
        .stats
        .as_deref()
        .and_then(|stats| frame_named(base, range, stats));
    for frame in std::iter::once(range.first).chain(named) {
        super::refuse_clashes(args, &frame_path(base, frame, range))?;
    }
    Ok(())
}

/// What one sequence makes, read before any output is created.
struct SequenceJob {
    animated: AnimatedScene,
    range: FrameRange,
    options: RenderOptions,
}

/// The animated scene, the frames and the options, checked for every frame.
fn read_sequence(args: &RenderArgs, spec: &str) -> anyhow::Result<SequenceJob> {
    let scene_spec = args.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    let animated = splitray::scene::load_animated(scene_spec)?;
    let range = FrameRange::parse(spec, args.fps.unwrap_or(DEFAULT_FPS))
        .map_err(|e| anyhow!("--frames: {e}"))?;
    let options = render_options(args, &animated.scene, None)?;
    check_frames(&animated, &options, &range)?;
    if !animated.is_animated() {
        splitray::errln!(
            "note: nothing moves in scene '{}': every frame is the same image",
            animated.scene.name
        );
    }
    Ok(SequenceJob {
        animated,
        range,
        options,
    })
}

/// Renders `job`'s frames behind a progress bar, writing each as it is done (`image` is
/// the first frame's files); a signal stops it. Returns how the sequence ended and the
/// statistics of each frame written.
fn render_sequence(
    args: &RenderArgs,
    gpu: &Gpu,
    job: &SequenceJob,
    base: &Path,
    image: ImageFiles,
    signals: &StopSignals,
) -> (Result<FramesRun, RenderError>, Vec<FrameStats>) {
    let SequenceJob {
        animated,
        range,
        options,
    } = job;
    let mut files = FrameFiles {
        base,
        range,
        next: Some(image),
        written: Vec::new(),
    };
    let name = &animated.scene.name;
    let (w, h) = (options.width, options.height);
    let bar = progress_bar(options, &format!("{name} {w}x{h}"));
    let pixels = w as f64 * h as f64;
    let result = render_frames(
        gpu,
        animated,
        options,
        range,
        FramesControl {
            progress: &mut |k, p| {
                let label = format!("{name} {w}x{h} frame {k} ({}..{})", range.first, range.end);
                show_progress(&bar, &label, p, pixels, options.time_limit)
            },
            stop: &|| signals.received().is_some(),
            frame_done: &mut |frame| bar.suspend(|| files.write(gpu, frame, args.profile)),
        },
    );
    bar.finish_and_clear();
    // Dropping the next frame's files (a sequence that ended early) removes them.
    (result, files.written)
}

/// The files of a sequence as it renders: the next frame's, created ahead of its render,
/// and the statistics of each frame written.
struct FrameFiles<'a> {
    base: &'a Path,
    range: &'a FrameRange,
    next: Option<ImageFiles>,
    written: Vec<FrameStats>,
}

impl FrameFiles<'_> {
    /// Writes `frame` and records its statistics, then creates the next frame's files:
    /// a path that cannot be written stops the sequence before that frame's render.
    fn write(&mut self, gpu: &Gpu, frame: Frame, profile: bool) -> Result<(), RenderError> {
        let image = self.next.take().expect("created for each frame");
        write_frame(gpu, &frame, image, profile)?;
        self.written.push(FrameStats {
            frame: frame.index,
            time: frame.time,
            changed_triangles: frame.changed_triangles,
            stats: frame.output.stats,
        });
        let next = frame.index + 1;
        if next < self.range.end {
            let path = frame_path(self.base, next, self.range);
            self.next = Some(ImageFiles::create(path)?);
        }
        Ok(())
    }
}

/// Tells the user which frames were written (the first `written` of `range`), or, when
/// `stopped_by` a signal, which frames are left to render; returns the exit code.
fn report_sequence_end(
    stopped_by: Option<i32>,
    written: u32,
    range: &FrameRange,
    base: &Path,
) -> ExitCode {
    match stopped_by {
        Some(signal) => {
            splitray::errln!(
                "{}: {}",
                signals::name(signal),
                rest_of_sequence(written, range)
            );
            ExitCode::from(signals::exit_status(signal))
        }
        None => {
            splitray::outln!(
                "wrote frames {}..{} ({} at {} fps) as {}",
                range.first,
                range.end,
                written,
                range.fps,
                display_pattern(base, range)
            );
            ExitCode::SUCCESS
        }
    }
}

/// Which frames a sequence that stopped short of `range` wrote (its first `written`),
/// and the `--frames` range that renders the rest.
fn rest_of_sequence(written: u32, range: &FrameRange) -> String {
    let done = range.first..range.first + written;
    format!(
        "the sequence stopped after {written} frame(s) ({done:?}); `--frames {}..{}` renders \
         the rest",
        done.end, range.end
    )
}

/// Writes one frame's EXR and PNG, unless the device reported validation messages.
fn write_frame(
    gpu: &Gpu,
    frame: &Frame,
    image: ImageFiles,
    profile: bool,
) -> Result<(), RenderError> {
    let messages = gpu.validation_messages();
    if !messages.is_empty() {
        return Err(RenderError::Options(format!(
            "{} validation message(s) (see the log above); frame {} was not written",
            messages.len(),
            frame.index
        )));
    }
    let written = image.write(&frame.output.film, &frame.output.metadata)?;
    splitray::out!("frame {} (t = {} s): ", frame.index, frame.time);
    print_summary(&frame.output, profile);
    splitray::outln!(
        "wrote {} and {}",
        written.exr.display(),
        written.png.display()
    );
    Ok(())
}

/// `out/shot_{0000..0011}.exr` for messages.
fn display_pattern(base: &Path, range: &FrameRange) -> String {
    let first = frame_path(base, range.first, range);
    let last = frame_path(base, range.end - 1, range);
    if first == last {
        return first.display().to_string();
    }
    format!(
        "{} … {}",
        first.display(),
        PathBuf::from(last.file_name().unwrap_or_default()).display()
    )
}
