//! [`RenderMetadata`]: how an image was made, stored in the EXR header.

use serde::{Deserialize, Serialize};

/// Provenance of a rendered image. Written into the EXR header as custom attributes
/// (see [`crate::film::write_exr`] for the exact names and types).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RenderMetadata {
    /// Samples per pixel of the final image.
    pub spp: u32,
    /// Random seed of the render.
    pub seed: u64,
    /// Integrator name (e.g. "pdacrt", "cis-lbdpt", "cbpt").
    pub integrator: String,
    /// Tracer implementation name.
    pub tracer: String,
    /// Device description (GPU name, driver).
    pub device: String,
    /// Wall-clock render time in seconds.
    pub render_time_s: f64,
    /// Free-form key/value pairs. Keys must be unique and non-empty. After an EXR round
    /// trip they come back sorted by key.
    pub extra: Vec<(String, String)>,
}
