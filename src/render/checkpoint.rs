//! Checkpoints: a render's film sums and everything needed to continue it.
//!
//! # File format (version 1)
//!
//! | bytes          | content                                                        |
//! |----------------|----------------------------------------------------------------|
//! | 16             | signature `\x89splitray-ckpt\r\n`                              |
//! | 4              | format version, u32 little-endian (1)                          |
//! | 4              | header length `h`, u32 little-endian                           |
//! | h              | header: UTF-8 JSON ([`CheckpointHeader`])                      |
//! | 24·w·h         | Σ estimate per pixel, RGB f64 little-endian, row 0 at the top |
//! | 24·w·h or 0    | Σ estimate², likewise, when `second_moments`                   |
//! | 32             | SHA-256 of every byte before it                                |
//!
//! Why this and not an EXR: sums must come back bit for bit, and they are `f64` (CPU
//! integrators accumulate in `f64`; EXR has no 64-bit float channel); a checkpoint is
//! state, not an image for viewers. The JSON header keeps the file self-describing and
//! readable with `head -c`, and lets later versions add fields with defaults. The
//! signature starts with a non-ASCII byte and holds `\r\n` (as PNG's does), so a file
//! mangled by a text-mode transfer is refused at once. The checksum catches a copy cut
//! short or a disk error; splitray itself writes checkpoints atomically (a temporary
//! file renamed over the target), so a render killed while saving leaves the previous
//! checkpoint whole.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::fingerprint::Fingerprint;
use super::shard::Shard;
use super::{FilmSnapshot, RenderError, RenderOptions};
use crate::film::{AtomicFile, FilmError, FilmSums};
use crate::integrator::cbpt::options::{CameraPaths, CbptSettings};

/// The first 16 bytes of every checkpoint.
pub const SIGNATURE: &[u8; 16] = b"\x89splitray-ckpt\r\n";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
const CHECKSUM_BYTES: usize = 32;
/// The first bytes of an OpenEXR file, to name the mistake of passing an image.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// The render options a checkpoint continues with (all of [`RenderOptions`] but the
/// reference image, which only measures).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SavedOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    pub integrator: String,
    pub tracer: String,
    pub ao_rays: u32,
    pub max_depth: i32,
    pub rr_depth: u32,
    /// `None`: the device's default (checkpoints that predate it hold a bool).
    #[serde(default)]
    pub sort_materials: Option<bool>,
    pub strategy: String,
    pub time_limit: Option<f64>,
    #[serde(default)]
    pub cbpt: crate::integrator::cbpt::CbptSettings,
    /// Absent in checkpoints of integrators that have none.
    #[serde(default)]
    pub lvc: crate::integrator::lvc::options::LvcSettings,
}

impl SavedOptions {
    pub fn new(options: &RenderOptions) -> Self {
        Self {
            width: options.width,
            height: options.height,
            spp: options.spp,
            seed: options.seed,
            integrator: options.integrator.name().into(),
            tracer: options.tracer.name().into(),
            ao_rays: options.ao_rays,
            max_depth: options.max_depth,
            rr_depth: options.rr_depth,
            sort_materials: options.sort_materials,
            strategy: format!("{:?}", options.strategy).to_lowercase(),
            time_limit: options.time_limit,
            cbpt: options.cbpt,
            lvc: match options.integrator.lvc_variant() {
                Some(_) => options.lvc.with_estimator_pinned(),
                None => options.lvc,
            },
        }
    }

    /// The options again; the error names what this build does not know.
    pub fn to_options(&self) -> Result<RenderOptions, String> {
        Ok(RenderOptions {
            width: self.width,
            height: self.height,
            spp: self.spp,
            seed: self.seed,
            integrator: self.integrator.parse()?,
            tracer: self.tracer.parse()?,
            ao_rays: self.ao_rays,
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            sort_materials: self.sort_materials,
            strategy: self.strategy.parse()?,
            time_limit: self.time_limit,
            reference: None,
            // Technique images are not saved in a checkpoint: a resumed render cannot
            // write them (the command line refuses the combination).
            bdpt_techniques: false,
            cbpt: self.cbpt,
            lvc: self.lvc,
        })
    }
}

/// `cbpt`'s settings with the populations `--cbpt-nc auto` measured (the render's
/// `fingerprint` holds them) in place of `auto`: measured again on resuming, they would
/// differ, and the checkpoint would not match its own render.
fn measured_populations(cbpt: CbptSettings, fingerprint: &Fingerprint) -> CbptSettings {
    let measured = |key| fingerprint.setting(key).and_then(|v| v.parse::<u32>().ok());
    match (
        cbpt.camera_paths,
        measured("cbpt_camera_paths"),
        measured("cbpt_light_paths"),
    ) {
        (CameraPaths::Equation4, Some(camera_paths), Some(light_paths)) => CbptSettings {
            camera_paths: CameraPaths::Fixed(camera_paths),
            light_paths,
            ..cbpt
        },
        _ => cbpt,
    }
}

/// Everything in a checkpoint besides the sums.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckpointHeader {
    /// `splitray <version>` that wrote it.
    pub software: String,
    /// How to load the scene again: a built-in name or a path (`render` saves absolute ones).
    pub scene: String,
    pub fingerprint: Fingerprint,
    pub options: SavedOptions,
    pub shard: Shard,
    /// Global index of the film's first pass; its passes are `first_pass..first_pass +
    /// passes`.
    pub first_pass: u32,
    pub passes: u32,
    pub samples_per_pass: u32,
    pub width: u32,
    pub height: u32,
    pub second_moments: bool,
    /// Seconds spent rendering so far, over every run that added to the film.
    pub render_time_s: f64,
}

/// A saved film and how to continue it.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    pub header: CheckpointHeader,
    pub sums: FilmSums,
}

impl Checkpoint {
    /// The checkpoint of `snapshot`, a film of `scene` (a built-in name or a path, as
    /// loading it again takes) rendered with `options`.
    pub fn new(scene: &str, options: &RenderOptions, snapshot: &FilmSnapshot<'_>) -> Self {
        let sums = snapshot.sums.clone();
        Self {
            header: CheckpointHeader {
                software: format!("splitray {}", env!("CARGO_PKG_VERSION")),
                scene: scene.to_string(),
                fingerprint: snapshot.fingerprint.clone(),
                options: SavedOptions {
                    cbpt: measured_populations(options.cbpt, snapshot.fingerprint),
                    ..SavedOptions::new(options)
                },
                shard: snapshot.shard,
                first_pass: snapshot.first_pass,
                passes: sums.passes,
                samples_per_pass: sums.samples_per_pass,
                width: sums.width,
                height: sums.height,
                second_moments: sums.sum_sq.is_some(),
                render_time_s: snapshot.render_time_s,
            },
            sums,
        }
    }

    /// Encodes the checkpoint into `file` and renames it over its target.
    pub fn write(&self, mut file: AtomicFile) -> Result<PathBuf, RenderError> {
        let path = file.target().to_path_buf();
        let header = serde_json::to_vec(&self.header)
            .map_err(|e| bad(&path, format!("cannot encode the header: {e}")))?;
        let mut out = HashingWriter {
            inner: file.writer(),
            hash: Sha256::new(),
        };
        let io = |e| FilmError::io(&path, "write", e);
        out.write_all(SIGNATURE).map_err(io)?;
        out.write_all(&VERSION.to_le_bytes()).map_err(io)?;
        out.write_all(&(header.len() as u32).to_le_bytes())
            .map_err(io)?;
        out.write_all(&header).map_err(io)?;
        write_f64s(&mut out, &self.sums.sum).map_err(io)?;
        if let Some(sq) = &self.sums.sum_sq {
            write_f64s(&mut out, sq).map_err(io)?;
        }
        let checksum = out.hash.finalize();
        file.writer().write_all(&checksum).map_err(io)?;
        Ok(file.commit()?)
    }

    /// Reads and checks a checkpoint: errors name `path` and say what is wrong with it
    /// (not a checkpoint, another version, truncated, corrupted).
    pub fn read(path: impl AsRef<Path>) -> Result<Self, RenderError> {
        // Generic only in this shim: the parser is compiled once, here.
        Self::read_at(path.as_ref())
    }

    fn read_at(path: &Path) -> Result<Self, RenderError> {
        let bytes = crate::input::read(path).map_err(|e| FilmError::io(path, "read", e))?;
        let header_start = SIGNATURE.len() + 8;
        if !bytes.starts_with(SIGNATURE) {
            let what = if bytes.is_empty() {
                "is empty, not a splitray checkpoint"
            } else if SIGNATURE.starts_with(&bytes) {
                "is truncated: it ends inside the checkpoint signature"
            } else if bytes.starts_with(&EXR_MAGIC) {
                "is an EXR image, not a splitray checkpoint (written by render --checkpoint)"
            } else {
                "is not a splitray checkpoint (it does not start with the checkpoint signature)"
            };
            return Err(bad(path, what));
        }
        if bytes.len() < header_start {
            return Err(bad(path, "is truncated: it ends inside its header"));
        }
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let version = word(SIGNATURE.len());
        if version != VERSION {
            return Err(bad(
                path,
                format!("is a version {version} checkpoint; this splitray reads version {VERSION}"),
            ));
        }
        let header_len = word(SIGNATURE.len() + 4) as usize;
        let data_start = header_start + header_len;
        if bytes.len() < data_start {
            return Err(bad(path, "is truncated: it ends inside its header"));
        }
        let header: CheckpointHeader = serde_json::from_slice(&bytes[header_start..data_start])
            .map_err(|e| bad(path, format!("has a corrupted header: {e}")))?;
        if let Some(contradiction) = header_contradiction(&header) {
            return Err(bad(
                path,
                format!("has a corrupted header: {contradiction}"),
            ));
        }
        let pixels = header.width as usize * header.height as usize;
        let planes = 1 + header.second_moments as usize;
        let expected = (planes * 24)
            .checked_mul(pixels)
            .and_then(|b| b.checked_add(data_start + CHECKSUM_BYTES))
            .ok_or_else(|| bad(path, "has a corrupted header: its film size is impossible"))?;
        if bytes.len() != expected {
            let how = if bytes.len() < expected {
                "is truncated"
            } else {
                "has trailing bytes"
            };
            return Err(bad(
                path,
                format!(
                    "{how}: {} bytes, where its header describes {expected}",
                    bytes.len()
                ),
            ));
        }
        let (body, checksum) = bytes.split_at(expected - CHECKSUM_BYTES);
        if Sha256::digest(body).as_slice() != checksum {
            return Err(bad(
                path,
                "is corrupted: its checksum does not match its contents",
            ));
        }
        let plane = |i: usize| read_f64s(&body[data_start + i * pixels * 24..][..pixels * 24]);
        let sums = FilmSums {
            width: header.width,
            height: header.height,
            passes: header.passes,
            samples_per_pass: header.samples_per_pass,
            sum: plane(0),
            sum_sq: header.second_moments.then(|| plane(1)),
        };
        Ok(Self { header, sums })
    }
}

/// What in `header` no render could have saved, if anything: the checksum covers the
/// header, so only a writer's bug or a hand-made file gets here, and resuming from it
/// must fail at once rather than part way.
fn header_contradiction(h: &CheckpointHeader) -> Option<String> {
    use crate::scene::validate::{is_film_side, MAX_FILM_DIM};
    let film = (h.width, h.height);
    if !is_film_side(h.width) || !is_film_side(h.height) {
        return Some(format!(
            "its film is {}x{}, outside 1..={MAX_FILM_DIM}",
            film.0, film.1
        ));
    }
    if film != (h.options.width, h.options.height) {
        return Some(format!(
            "its film is {}x{} but its options ask for {}x{}",
            film.0, film.1, h.options.width, h.options.height
        ));
    }
    if h.samples_per_pass == 0 {
        return Some("its passes have no samples".into());
    }
    if h.first_pass.checked_add(h.passes).is_none() {
        return Some(format!(
            "its passes {} + {} run past the last pass number",
            h.first_pass, h.passes
        ));
    }
    if let Err(e) = Shard::new(h.shard.index, h.shard.count) {
        return Some(e);
    }
    // (JSON has no NaN or infinity: serde refuses those as null before this.)
    if !(h.render_time_s.is_finite() && h.render_time_s >= 0.0) {
        return Some(format!("its render time is {} s", h.render_time_s));
    }
    None
}

fn bad(path: &Path, message: impl Into<String>) -> RenderError {
    RenderError::BadFile {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Passes bytes through to `inner` and hashes them.
struct HashingWriter<W> {
    inner: W,
    hash: Sha256,
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

fn write_f64s(out: &mut impl Write, values: &[[f64; 3]]) -> std::io::Result<()> {
    let mut bytes = Vec::with_capacity(values.len() * 24);
    for v in values.iter().flatten() {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    out.write_all(&bytes)
}

fn read_f64s(bytes: &[u8]) -> Vec<[f64; 3]> {
    bytes
        .chunks_exact(24)
        .map(|p| {
            let c = |i: usize| f64::from_le_bytes(p[i * 8..i * 8 + 8].try_into().unwrap());
            [c(0), c(1), c(2)]
        })
        .collect()
}
