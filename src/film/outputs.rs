//! [`write_outputs`] and [`ImageFiles`]: the EXR and its PNG preview, together.

use std::path::{Path, PathBuf};

use super::atomic::AtomicFile;
use super::exr_out::{encode_exr, warn_non_finite};
use super::png_out::{encode_png, PreviewSettings};
use super::{Film, FilmError, RenderMetadata};

/// What [`write_outputs`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WrittenOutputs {
    /// The EXR file.
    pub exr: PathBuf,
    /// The PNG preview beside it (same stem, `.png`).
    pub png: PathBuf,
    /// Pixels whose estimate was NaN or infinite (written as-is to the EXR, magenta in
    /// the PNG; a warning was logged when non-zero).
    pub non_finite_pixels: usize,
}

/// Writes `exr_path` and a PNG preview beside it (same stem, extension `.png`, default
/// [`PreviewSettings`]: exposure 1, clamp).
///
/// Both files are first written completely to temporary files; only when both encodings
/// succeeded are they renamed over their targets (EXR first). On any error no new or
/// partial output is left behind and pre-existing files are untouched (except in the
/// unlikely case that the second rename fails after the first succeeded).
pub fn write_outputs(
    exr_path: impl AsRef<Path>,
    film: &Film,
    meta: &RenderMetadata,
) -> Result<WrittenOutputs, FilmError> {
    ImageFiles::create(exr_path)?.write(film, meta)
}

/// The EXR and PNG outputs of one image, their temporary files created ahead of the work
/// that fills them: a render checks that it can write its outputs before it starts, and
/// a render that fails or is dropped leaves nothing behind.
#[derive(Debug)]
pub struct ImageFiles {
    exr: AtomicFile,
    png: AtomicFile,
}

impl ImageFiles {
    /// Creates the temporary files of `exr_path` and of its PNG preview.
    pub fn create(exr_path: impl AsRef<Path>) -> Result<Self, FilmError> {
        let exr_path = exr_path.as_ref();
        let png_path = exr_path.with_extension("png");
        if png_path == exr_path {
            return Err(FilmError::invalid(
                exr_path,
                "EXR output path must not end in .png",
            ));
        }
        Ok(Self {
            exr: AtomicFile::create(exr_path)?,
            png: AtomicFile::create(&png_path)?,
        })
    }

    /// The EXR's final path.
    pub fn exr_path(&self) -> &Path {
        self.exr.target()
    }

    /// Encodes both files, then renames them over their targets (see [`write_outputs`]).
    pub fn write(self, film: &Film, meta: &RenderMetadata) -> Result<WrittenOutputs, FilmError> {
        let Self {
            exr: mut exr_file,
            png: mut png_file,
        } = self;
        let exr_path = exr_file.target().to_path_buf();
        let png_path = png_file.target().to_path_buf();
        encode_exr(film, meta, exr_file.writer(), &exr_path)?;
        encode_png(
            film,
            &PreviewSettings::default(),
            png_file.writer(),
            &png_path,
        )?;
        let non_finite_pixels = warn_non_finite(film, &exr_path);
        let exr = exr_file.commit()?;
        let png = png_file.commit()?;
        Ok(WrittenOutputs {
            exr,
            png,
            non_finite_pixels,
        })
    }
}
