//! The film: linear HDR accumulation, AOVs, and EXR/PNG output.
//!
//! - [`Film`] ([`accum`]): accumulates per-pass RGB radiance buffers from the GPU
//!   (row 0 = top, `pixel_index = y * width + x`) and holds optional AOVs
//!   (depth, triangle id, normal).
//!
//! Every file is written atomically ([`atomic`]): to a temporary file in the target's
//! folder, renamed over the target only on success, removed on failure.
//! Errors are [`FilmError`], which names the file concerned.

pub mod accum;
pub mod atomic;
mod error;
mod metadata;

pub use accum::Film;
pub use atomic::{write_atomically, AtomicFile};
pub use error::FilmError;
pub use metadata::RenderMetadata;
