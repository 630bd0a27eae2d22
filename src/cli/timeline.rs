//! `--timeline FILE.json` on `render` and `bench`, and `splitray timeline` (a trace
//! drawn as SVG or PNG).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use splitray::film::atomic::write_bytes_atomically;
use splitray::film::AtomicFile;
use splitray::timeline::{self, draw::DrawOptions, Capture, ClockAlignment};
use splitray::vk::Gpu;

use super::paths::check_output;

/// A timeline being recorded for `--timeline FILE.json`.
pub struct TimelineOutput {
    /// Created when recording starts, so a path that cannot be written fails before the
    /// work; removed if the command fails.
    file: AtomicFile,
    capture: Capture,
}

impl TimelineOutput {
    /// Checks the path and starts recording host spans, or does nothing without a path.
    pub fn start(path: Option<&Path>) -> anyhow::Result<Option<Self>> {
        let Some(path) = path else {
            return Ok(None);
        };
        check_output(path, &["json"], "a .json file")?;
        Ok(Some(Self {
            file: AtomicFile::create(path)?,
            capture: Capture::start()?,
        }))
    }

    /// Records `gpu`'s streams too.
    pub fn attach(&mut self, gpu: &Gpu) -> anyhow::Result<()> {
        Ok(self.capture.attach(gpu)?)
    }

    /// Stops recording and writes the file (atomically); `command` goes into its metadata.
    pub fn finish(self, command: &str) -> anyhow::Result<()> {
        let mut trace = self.capture.finish()?.trace(ClockAlignment::Best);
        trace
            .metadata
            .insert("command".into(), serde_json::Value::String(command.into()));
        let mut file = self.file;
        let path = file.target().to_path_buf();
        file.writer()
            .write_all(timeline::json::to_json(&trace).as_bytes())
            .with_context(|| format!("{}: cannot write", path.display()))?;
        file.commit()?;
        splitray::outln!(
            "wrote {} ({} tracks; open it in ui.perfetto.dev or chrome://tracing)",
            path.display(),
            trace.tracks.len()
        );
        Ok(())
    }
}

/// The command line as run, for a timeline's metadata.
pub fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

#[derive(Debug, Args)]
pub struct TimelineArgs {
    /// A trace-event JSON file (from `--timeline`).
    input: PathBuf,
    /// The chart: .svg or .png.
    #[arg(short, long)]
    output: PathBuf,
    /// Width in pixels (520 to 32768).
    #[arg(long, default_value_t = 1600, value_parser = width_parser())]
    width: u32,
    /// Draw from this time on (ms from the trace's start).
    #[arg(long, value_name = "MS")]
    from: Option<f64>,
    /// Draw up to this time (ms from the trace's start).
    #[arg(long, value_name = "MS")]
    to: Option<f64>,
}

pub fn run(args: &TimelineArgs) -> anyhow::Result<()> {
    let ext = check_output(&args.output, &["svg", "png"], "a .svg or .png file")?;
    let text = splitray::input::read_to_string(&args.input)
        .with_context(|| format!("cannot read {}", args.input.display()))?;
    let trace =
        timeline::json::from_json(&text).with_context(|| format!("{}", args.input.display()))?;
    let options = DrawOptions {
        width: args.width,
        from_ms: args.from,
        to_ms: args.to,
    };
    let drawn = if ext == "png" {
        timeline::draw::png(&trace, &options)
    } else {
        timeline::draw::svg(&trace, &options).map(String::into_bytes)
    };
    let bytes = drawn.with_context(|| format!("{}", args.input.display()))?;
    // The error names the file.
    write_bytes_atomically(&args.output, &bytes)?;
    splitray::out!("{}", trace.summary());
    splitray::outln!("wrote {}", args.output.display());
    Ok(())
}

/// `--width` within the widths the chart can be drawn at.
fn width_parser() -> clap::builder::RangedI64ValueParser<u32> {
    let range = timeline::draw::WIDTH_RANGE;
    clap::value_parser!(u32).range(i64::from(*range.start())..=i64::from(*range.end()))
}
