//! [`RenderPlan`]: where a render starts (a fresh film or a checkpoint's), which of the
//! image's passes it takes (a [`Shard`]'s block), when it saves its film and who watches.

use std::path::Path;

use super::{Checkpoint, FilmWatch, Fingerprint, RenderError, RenderOptions, Shard};
use crate::film::FilmSums;
use crate::integrator::Integrator;

/// Where a render starts, which of the image's passes it takes and when it saves its
/// film. The default is a whole render from pass 0 that saves nothing.
#[derive(Default)]
pub struct RenderPlan<'a> {
    /// The part of the image's passes to take ([`Shard::WHOLE`] by default).
    pub shard: Shard,
    /// A checkpoint to continue: the render restores its film and goes on after its
    /// passes, and refuses it when the scene or settings changed.
    pub resume: Option<Resume<'a>>,
    /// Saves the film every so many seconds, at a pass boundary.
    pub checkpoint: Option<CheckpointHook<'a>>,
    /// Shows the film as it converges (a preview window, a display server).
    pub watch: Option<&'a mut dyn FilmWatch>,
}

/// A checkpoint to continue, and the file it came from (errors name it).
pub struct Resume<'a> {
    pub checkpoint: &'a Checkpoint,
    pub path: &'a Path,
}

/// Called with the film every `every_s` seconds of rendering, at a pass boundary (not
/// after the last pass: the caller has the finished film then). A save that fails is
/// logged as a warning and the render goes on; the next one comes `every_s` later.
pub struct CheckpointHook<'a> {
    pub every_s: f64,
    pub save: &'a mut dyn FnMut(&FilmSnapshot<'_>) -> Result<(), RenderError>,
}

/// A render's film at a pass boundary, with what continuing it needs.
pub struct FilmSnapshot<'s> {
    pub sums: &'s FilmSums,
    pub fingerprint: &'s Fingerprint,
    pub shard: Shard,
    /// Global index of the film's first pass.
    pub first_pass: u32,
    /// Seconds spent rendering the film, resumed runs included.
    pub render_time_s: f64,
}

/// Restores the film of the checkpoint `plan` continues, after checking that it was
/// saved from this scene, these settings and this shard; returns the global index of the
/// film's first pass and the passes it holds already.
pub(super) fn start_film(
    integrator: &mut dyn Integrator,
    options: &RenderOptions,
    plan: &RenderPlan<'_>,
    fingerprint: &Fingerprint,
) -> Result<(u32, u32), RenderError> {
    let per_pass = integrator.samples_per_pass().max(1);
    let total = options.spp.div_ceil(per_pass);
    let block = plan.shard.passes(total);
    if block.is_empty() {
        return Err(RenderError::Options(format!(
            "shard {} of a render of {total} passes has none: ask for at least {} samples \
             per pixel",
            plan.shard,
            plan.shard.count as u64 * per_pass as u64
        )));
    }
    let Some(resume) = &plan.resume else {
        return Ok((block.start, 0));
    };
    let header = &resume.checkpoint.header;
    let refuse = |message: String| RenderError::BadFile {
        path: resume.path.to_path_buf(),
        message,
    };
    if header.fingerprint != *fingerprint {
        let differences =
            header
                .fingerprint
                .differences(fingerprint, "in the checkpoint", "in this render");
        return Err(refuse(format!(
            "was saved from another scene or settings: {}",
            differences.join("; ")
        )));
    }
    if header.shard != plan.shard {
        return Err(refuse(format!(
            "was saved as shard {}, not {}",
            header.shard, plan.shard
        )));
    }
    // A shard's block depends on the render's length: continued to another length, it
    // would overlap or leave a gap between its neighbours' blocks. (A whole render may
    // grow: its block always starts at 0.)
    let saved_block = plan.shard.passes(header.options.spp.div_ceil(per_pass));
    if header.first_pass != block.start || (!plan.shard.is_whole() && saved_block != block) {
        let passes = |r: &std::ops::Range<u32>| format!("passes {}..{}", r.start, r.end);
        return Err(refuse(format!(
            "was saved as shard {} of a render of {} ({}); this render's shard {} is {}: \
             continue it with the samples per pixel (or --time) it was started with",
            header.shard,
            spp_or_time(header.options.spp),
            passes(&saved_block),
            plan.shard,
            passes(&block)
        )));
    }
    integrator
        .restore(&resume.checkpoint.sums)
        .map_err(|e| refuse(e.to_string()))?;
    Ok((block.start, resume.checkpoint.sums.passes))
}

/// A render's length as asked for: samples per pixel, or `--time` (no sample target).
fn spp_or_time(spp: u32) -> String {
    match spp {
        u32::MAX => "a time budget".to_string(),
        spp => format!("{spp} spp"),
    }
}
