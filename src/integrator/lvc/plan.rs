//! How a render is cut into chunks, and the prepass that sizes the light vertex cache
//! (thesis §4.3: "a coarse light prepass … using a fraction of the intended light
//! paths … the average path length was then computed from the prepass and was used to
//! allocate enough memory").
//!
//! A chunk holds P whole passes: P N_L light paths (one light pass, one cache, whose
//! index keeps the passes apart) and P × the pixels of the camera pass (in pixel ranges
//! when one pass alone exceeds the wavefront). N_L, the light paths of a pass, is one per
//! pixel by default, bounded by the wavefront and by the largest cache one storage-buffer
//! binding can hold.

use super::cache::capacity_for;
use super::gpu::{Contribution, LvcVertex};
use super::options::LvcOptions;
use crate::vk::Gpu;

/// Light paths of the prepass: an eighth of a pass, at least 4096 (all of a small pass).
pub fn prepass_paths(light_paths: u32) -> u32 {
    light_paths.min((light_paths / 8).max(4096))
}

/// The prepass's sample index: its light paths are independent of every pass's (passes
/// are numbered below u32::MAX), so the count factor it yields is a fixed function of the
/// scene and seed, and the MIS weights a function of the path alone.
pub const PREPASS_SAMPLE: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan {
    pub pixels: u32,
    /// N_L.
    pub light_paths: u32,
    /// P: passes per chunk.
    pub passes_per_chunk: u32,
    /// Pixels of one camera wavefront (all of them unless a pass exceeds it).
    pub pixels_per_chunk: u32,
    /// Paths the wavefront holds.
    pub wave_capacity: u32,
}

impl Plan {
    /// The plan before the prepass (the wavefront it needs).
    pub fn new(gpu: &Gpu, width: u32, height: u32, options: &LvcOptions) -> Self {
        let pixels = width * height;
        let max_paths = max_wavefront(gpu, options);
        let light_paths = options.light_paths.unwrap_or(pixels).clamp(1, max_paths);
        let pixels_per_chunk = pixels.min(max_paths);
        let passes_per_chunk =
            (max_paths / light_paths.max(pixels_per_chunk)).clamp(1, options.spp.max(1));
        Self {
            pixels,
            light_paths,
            passes_per_chunk,
            pixels_per_chunk,
            wave_capacity: passes_per_chunk * light_paths.max(pixels_per_chunk),
        }
    }

    /// Bounds N_L and P so that a chunk's cache, at `per_path` vertices per light path,
    /// fits one storage-buffer binding.
    pub fn fit_cache(&mut self, gpu: &Gpu, per_path: f64) {
        let most = (cache_limit(gpu) as f64 / 1.25).max(1.0);
        let paths = (most / per_path.max(1e-9)).floor().max(1.0) as u64;
        self.light_paths = self.light_paths.min(paths.min(u32::MAX as u64) as u32);
        let passes = (paths / self.light_paths as u64).max(1);
        self.passes_per_chunk = self
            .passes_per_chunk
            .min(passes.min(u32::MAX as u64) as u32);
    }

    /// Light paths of a chunk of `passes` passes.
    pub fn chunk_light_paths(&self, passes: u32) -> u32 {
        passes * self.light_paths
    }

    /// Slots for a chunk of the most passes.
    pub fn cache_capacity(&self, per_path: f64) -> u64 {
        capacity_for(self.chunk_light_paths(self.passes_per_chunk), per_path)
    }
}

/// The most paths a wavefront may hold: the option, and what keeps the shadow-ray and
/// contribution buffers ((1 + N) per path) within one binding.
fn max_wavefront(gpu: &Gpu, options: &LvcOptions) -> u32 {
    let limit = gpu.info().limits.max_storage_buffer_range;
    let per_path = (1 + options.connections as u64) * size_of::<Contribution>() as u64;
    let shadow = (limit / per_path).saturating_sub(64).max(1);
    (options.max_paths_per_chunk as u64).min(shadow).max(1) as u32
}

/// The most vertices one binding holds.
pub fn cache_limit(gpu: &Gpu) -> u64 {
    gpu.info().limits.max_storage_buffer_range / size_of::<LvcVertex>() as u64
}
