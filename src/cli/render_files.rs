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

/// One file a render reads or writes, named as the command line names it.
pub struct Role<'a> {
    pub what: &'a str,
    pub path: &'a Path,
    /// The render's checkpoint: the one it saves, or the one it resumes. The two may be
    /// one file (that is how a resumed render keeps going); no other pair may.
    pub checkpoint: bool,
}

impl<'a> Role<'a> {
    pub fn file(what: &'a str, path: &'a Path) -> Self {
        Self {
            what,
            path,
            checkpoint: false,
        }
    }

    pub fn checkpoint(what: &'a str, path: &'a Path) -> Self {
        Self {
            what,
            path,
            checkpoint: true,
        }
    }
}

/// Refuses a render whose outputs would overwrite one another, or overwrite one of its
/// inputs (a reference image, the checkpoint it resumes): the later write would replace
/// the earlier one after the render, losing it. Saving the checkpoint over the one the
/// render resumes is allowed.
pub fn refuse_clashing_paths(outputs: &[Role], inputs: &[Role]) -> anyhow::Result<()> {
    for (i, a) in outputs.iter().enumerate() {
        let later_outputs = outputs[i + 1..].iter().map(|b| (b, false));
        for (b, input) in later_outputs.chain(inputs.iter().map(|b| (b, true))) {
            let saves_over_its_resumed_checkpoint = input && a.checkpoint && b.checkpoint;
            if !saves_over_its_resumed_checkpoint && same_file(a.path, b.path) {
                anyhow::bail!(
                    "{}: {} and {} name the same file: the render would be lost",
                    a.path.display(),
                    a.what,
                    b.what
                );
            }
        }
    }
    Ok(())
}

/// Whether two paths name one file: their folders resolved (where they exist), then
/// their file names compared.
fn same_file(a: &Path, b: &Path) -> bool {
    fn resolved(path: &Path) -> PathBuf {
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        match (folder.canonicalize(), path.file_name()) {
            (Ok(folder), Some(name)) => folder.join(name),
            _ => path.to_path_buf(),
        }
    }
    resolved(a) == resolved(b)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn clash(outputs: &[Role], inputs: &[Role]) -> Option<String> {
        refuse_clashing_paths(outputs, inputs)
            .err()
            .map(|e| e.to_string())
    }

    #[test]
    fn only_a_checkpoint_saved_over_the_one_resumed_may_share_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let same = dir.path().join("run.ckpt");
        let other = dir.path().join("other.ckpt");
        let saved = Role::checkpoint("--checkpoint", &same);
        let resumed = Role::checkpoint("--resume", &same);
        assert_eq!(clash(&[saved], &[resumed]), None);
        let saved = Role::checkpoint("--checkpoint", &same);
        let resumed_elsewhere = Role::checkpoint("--resume", &other);
        assert_eq!(clash(&[saved], &[resumed_elsewhere]), None);

        // Any other pair on one path is refused, naming both roles.
        let pairs = [
            (
                Role::file("the image", &same),
                Role::checkpoint("--resume", &same),
            ),
            (
                Role::checkpoint("--checkpoint", &same),
                Role::file("--reference", &same),
            ),
            (
                Role::file("--stats", &same),
                Role::file("--reference", &same),
            ),
        ];
        for (output, input) in pairs {
            let (a, b) = (output.what, input.what);
            let message = clash(&[output], &[input]).expect("refused");
            assert!(
                message.contains(&format!("{a} and {b} name the same file")),
                "{message}"
            );
        }
        let outputs = [
            Role::checkpoint("--checkpoint", &same),
            Role::file("--timeline", &same),
        ];
        let message = clash(&outputs, &[]).expect("two outputs on one path");
        assert!(message.contains("--checkpoint and --timeline"), "{message}");
    }
}
