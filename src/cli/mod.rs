//! Subcommands of the `splitray` binary. Errors surface as `anyhow` only here, at the
//! edge; the library speaks in typed errors.

mod bench;
mod export;
mod info;
mod merge;
mod paths;
mod render;
mod render_files;
mod signals;
mod timeline;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// splitray renders scenes headlessly on any Vulkan 1.3 device (a GPU, or the lavapipe
/// CPU driver) with GLSL compute kernels.
///
/// Start with `splitray info` to see the devices, `splitray scenes` for the built-in
/// scenes, and `splitray render` to render the Cornell box to out/cornell-box.exr (+ .png).
#[derive(Debug, Parser)]
#[command(name = "splitray", version, about, long_about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

impl Cli {
    /// The command line, parsed; exits with clap's message on a usage error. A negative
    /// number is read as the value of the option before it (`--width -3` is refused as a
    /// width, not taken for an unknown option `-3`).
    pub fn from_command_line() -> Self {
        let matches = negative_numbers_are_values(Self::command()).get_matches();
        Self::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
    }
}

/// `cmd` with every option that takes a value, in every subcommand, accepting a negative
/// number as that value.
fn negative_numbers_are_values(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|arg| {
        if arg.get_action().takes_values() {
            arg.allow_negative_numbers(true)
        } else {
            arg
        }
    })
    .mut_subcommands(negative_numbers_are_values)
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// List Vulkan devices, their queue families, the stream-to-queue mapping, the limits
    /// that matter and whether the validation layer is installed.
    Info(info::InfoArgs),
    /// Render a scene to an EXR (linear HDR, with AOVs) and a PNG preview beside it; or
    /// one shard of it (--shard), or continue a checkpoint (--resume).
    Render(Box<render::RenderArgs>),
    /// Merge the shards of one image (`render --shard I/N`) into one EXR, weighted by
    /// their samples, with the merged standard error.
    Merge(merge::MergeArgs),
    /// List the built-in scenes (usable as `splitray render NAME`).
    Scenes,
    /// Measure, after checking the results: `bench primitives` (GPU sort/scan/... vs
    /// CPU), `bench trace SCENE` (tracers compared on a ray workload), `bench dynamic
    /// SCENE` (tracers on an animated scene, per frame), `bench pt SCENE` (material
    /// sorting on and off), `bench bdpt SCENE…` (integrators at equal time and at equal
    /// spp) or `bench cbpt SCENE` (CBPT's combination throughput, batches and steps).
    Bench(bench::BenchArgs),
    /// Draw a timeline (`--timeline FILE.json` of `render` or `bench`) as a Gantt chart:
    /// `splitray timeline FILE.json -o timeline.svg` (or .png).
    Timeline(timeline::TimelineArgs),
    /// Write the scene as splitray resolves it — triangles in order with their winding,
    /// per-triangle materials, emission and BSDF layers as `pt` evaluates them, point
    /// lights, camera and film — as JSON: the input of reference renderers
    /// (tools/mitsuba_reference.py builds its Mitsuba 3 scene from it).
    ExportScene(export::ExportArgs),
}

/// Runs a command; the exit code is not 0 only for a render a signal stopped (errors
/// come back as `Err`; a signal ends the other commands that write files at once, with
/// 128 + its number, leaving no temporary file).
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Info(args) => info::run(&args),
        Command::Render(args) => return render::run(&args),
        Command::Merge(args) => exiting_at_a_signal(|| merge::run(&args)),
        Command::Bench(args) => exiting_at_a_signal(|| bench::run(&args)),
        Command::Timeline(args) => exiting_at_a_signal(|| timeline::run(&args)),
        Command::ExportScene(args) => exiting_at_a_signal(|| export::run(&args)),
        Command::Scenes => {
            for (name, description) in splitray::scene::builtin_names() {
                splitray::outln!("{name:<14} {description}");
            }
            Ok(())
        }
    }
    .map(|()| ExitCode::SUCCESS)
}

/// Runs `command`, which writes its outputs atomically but has nothing worth finishing
/// once stopped: a signal exits at once, removing its temporary files
/// ([`signals::exit_at_first_signal`]).
fn exiting_at_a_signal(command: impl FnOnce() -> anyhow::Result<()>) -> anyhow::Result<()> {
    signals::exit_at_first_signal()?;
    command()
}

/// `--max-depth` as Mitsuba takes it: -1 (unbounded) or a depth of 0 or more. Anything
/// below -1 is refused rather than read as "unbounded".
fn max_depth_parser() -> clap::builder::RangedI64ValueParser<i32> {
    clap::value_parser!(i32).range(-1..)
}

/// A film's width or height in pixels: 1 to 16384, as `render` takes it.
fn film_side_parser() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=16384)
}

/// A count of rounds, steps or samples that means nothing at 0.
fn at_least_one() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// clap's own checks of the command line as `from_command_line` builds it (names,
    /// conflicts, value parsers), which it otherwise makes only when an option is used.
    #[test]
    fn the_command_line_is_well_formed() {
        negative_numbers_are_values(Cli::command()).debug_assert();
    }
}
