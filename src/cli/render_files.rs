//! The output files of `splitray render`, created before any work: every output's
//! temporary file exists before the scene goes to the GPU, so a path that cannot be
//! written fails at once instead of after the render. Until they are written, the
//! temporary files stay open; a render that fails or is stopped removes them (they are
//! [`AtomicFile`]s), so no partial output is ever left behind. [`Failures`] collects
//! the outputs that could not be written at the end, a still's or a sequence's.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context};
use splitray::film::{AtomicFile, FilmError, ImageFiles};
use splitray::render::{Checkpoint, RenderError};

/// Every output of one render.
pub struct RenderFiles {
    /// The EXR and its PNG preview.
    pub image: ImageFiles,
    /// `--stats`.
    pub stats: Option<AtomicFile>,
    /// `--checkpoint`.
    pub checkpoint: Option<CheckpointFile>,
}

impl RenderFiles {
    /// Creates the temporary file of every output; the error names the path that cannot
    /// be written (once: the error carries the reason).
    pub fn create(
        exr: &Path,
        stats: Option<&Path>,
        checkpoint: Option<&Path>,
    ) -> Result<Self, FilmError> {
        Ok(Self {
            image: ImageFiles::create(exr)?,
            stats: stats.map(AtomicFile::create).transpose()?,
            checkpoint: checkpoint.map(CheckpointFile::create).transpose()?,
        })
    }
}

/// Writes `stats` as JSON into `file`, then renames it into place.
pub fn write_stats(mut file: AtomicFile, stats: &impl serde::Serialize) -> anyhow::Result<()> {
    let json = serde_json::to_vec_pretty(stats).context("cannot encode the stats")?;
    let path = file.target().to_path_buf();
    std::io::Write::write_all(file.writer(), &json)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    file.commit()?;
    Ok(())
}

/// The checkpoint file: written every so often, each time atomically.
pub struct CheckpointFile {
    path: PathBuf,
    /// The next write's temporary file (the first one is created up front).
    next: Option<AtomicFile>,
}

impl CheckpointFile {
    /// The checkpoint file at `path`, its first temporary file created.
    pub fn create(path: &Path) -> Result<Self, FilmError> {
        Ok(Self {
            path: path.to_path_buf(),
            next: Some(AtomicFile::create(path)?),
        })
    }

    /// Writes `checkpoint` over the file (atomically).
    pub fn save(&mut self, checkpoint: &Checkpoint) -> Result<PathBuf, RenderError> {
        let file = match self.next.take() {
            Some(file) => file,
            None => AtomicFile::create(&self.path)?,
        };
        checkpoint.write(file)
    }
}

/// The outputs of a render that could not be written: each output is tried whatever
/// became of the others (a disk that filled up under one need not cost the rest), and
/// the error lists them all.
#[derive(Default)]
pub struct Failures(Vec<anyhow::Error>);

impl Failures {
    /// The value written, or `None` with the error kept.
    pub fn keep<T>(&mut self, written: anyhow::Result<T>) -> Option<T> {
        written.map_err(|e| self.0.push(e)).ok()
    }

    /// `Ok` where every output was written; otherwise an error naming each failure,
    /// then `hint` (what the user can do about them), if any.
    pub fn check(self, hint: Option<String>) -> anyhow::Result<()> {
        let mut message = match self.0.as_slice() {
            [] => return Ok(()),
            [one] => format!("{one:#}"),
            all => {
                let lines: Vec<String> = all.iter().map(|e| format!("\n  {e:#}")).collect();
                format!("{} outputs were not written:{}", all.len(), lines.concat())
            }
        };
        if let Some(hint) = hint {
            message.push('\n');
            message.push_str(&hint);
        }
        Err(anyhow!(message))
    }

    /// `Ok(exr)` where every output was written; otherwise [`Failures::check`]'s error,
    /// with `hint` (how to write the image from the checkpoint saved, if one was) where
    /// the image is among the failures.
    pub fn outcome(self, exr: Option<PathBuf>, hint: Option<String>) -> anyhow::Result<PathBuf> {
        let image_lost = exr.is_none();
        self.check(hint.filter(|_| image_lost))?;
        exr.ok_or_else(|| anyhow!("the image was not written"))
    }
}
