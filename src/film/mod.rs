//! The film: linear HDR accumulation, AOVs, and EXR/PNG output.
//!
//! - [`Film`] ([`accum`]): accumulates per-pass RGB radiance buffers from the GPU
//!   (row 0 = top, `pixel_index = y * width + x`) and holds optional AOVs
//!   (depth, triangle id, normal).
//! - [`write_exr`] / [`read_exr`] ([`exr_out`]): single-part float EXR with AOV channels
//!   and [`RenderMetadata`] as header attributes.
//! - [`write_png_preview`] ([`png_out`]): 8-bit sRGB preview.
//! - [`FilmSums`] ([`sums`]): the per-pass sums every integrator accumulates (mean and
//!   standard error), which checkpoints save and shards merge.
//! - [`write_outputs`]: both at once.
//! - [`Reference`] ([`reference`](mod@reference)): a converged image to measure a film's
//!   error against, less the reference's own noise where its standard errors are known.
//! - [`DeviceFilm`] ([`device`]): an integrator's film where it lives on the GPU, each
//!   sum in two floats ([`compensated`]).
//!
//! Every file is written atomically ([`atomic`]): to a temporary file in the target's
//! folder, renamed over the target only on success, removed on failure.
//! Errors are [`FilmError`], which names the file concerned.

pub mod accum;
pub mod atomic;
pub mod compensated;
pub mod device;
mod error;
pub mod exr_out;
mod metadata;
mod outputs;
pub mod png_out;
pub mod reference;
pub mod sums;

pub use accum::Film;
pub use atomic::{discard_all_temporaries, write_atomically, AtomicFile};
pub use device::DeviceFilm;
pub use error::FilmError;
pub use exr_out::{read_exr, write_exr};
pub use metadata::RenderMetadata;
pub use outputs::{write_outputs, ImageFiles, WrittenOutputs};
pub use png_out::{write_png_preview, write_png_preview_with, PreviewSettings, ToneMap};
pub use reference::{Reference, ReferenceError};
pub use sums::{relative_mse, FilmSums};
