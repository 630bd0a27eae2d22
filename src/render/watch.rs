//! [`FilmWatch`]: what a render tells someone watching it converge (a preview window, a
//! display server): the film's size and AOVs before the first pass, its progress after
//! every batch of passes, and the finished film.

use super::{Progress, RenderError};
use crate::film::{DeviceFilm, FilmSums};
use crate::integrator::aov::Aovs;
use crate::integrator::IntegratorError;

/// The film a watcher is about to see.
pub struct WatchStart<'a> {
    pub width: u32,
    pub height: u32,
    /// First-hit AOVs (depth, normal, triangle id): fixed for the whole render.
    pub aovs: &'a Aovs,
    /// The integrator's film on the GPU, where it keeps one: a watcher may read it at any
    /// time from work on the main stream. `None`: the film reaches watchers only as the
    /// host sums [`FilmWatch::batch`] offers.
    pub device_film: Option<DeviceFilm>,
    /// Samples per pixel the film holds already (a resumed render's).
    pub spp: u64,
}

/// Told how a render goes. Every call comes from the rendering thread, at a pass boundary.
pub trait FilmWatch {
    /// Seconds a batch of passes should last at most while watched (`None`: as long as
    /// the render loop likes). Shorter batches update a watcher sooner and cost some
    /// throughput (each batch pays the integrator's per-call overhead).
    fn batch_target_s(&self) -> Option<f64> {
        None
    }

    /// Before the first pass.
    fn start(&mut self, start: &WatchStart<'_>) -> Result<(), RenderError>;

    /// After every batch of passes. `sums` reads the film to the host (a copy of the whole
    /// film: call it only where the film is not on the GPU).
    fn batch(
        &mut self,
        progress: &Progress,
        sums: &mut dyn FnMut() -> Result<FilmSums, IntegratorError>,
    ) -> Result<(), RenderError>;

    /// Once, with the film the render's outputs are written from (after the last pass or
    /// a stop).
    fn finish(&mut self, sums: &FilmSums) -> Result<(), RenderError>;
}
