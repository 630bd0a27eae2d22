//! The output files of `splitray render`, created before any work: every output's
//! temporary file exists before the scene goes to the GPU, so a path that cannot be
//! written fails at once instead of after the render. Until they are written, the
//! temporary files stay open; a render that fails or is stopped removes them (they are
//! [`AtomicFile`]s), so no partial output is ever left behind.

use std::path::{Path, PathBuf};

use anyhow::Context;
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
    fn create(path: &Path) -> Result<Self, FilmError> {
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
