//! Timelines: when work ran on which GPU stream and host thread, in the Chrome
//! trace-event JSON format that ui.perfetto.dev and chrome://tracing open.
//!
//! - [`Capture`] records a timeline: host spans from `tracing` (any thread, rayon
//!   workers included, each on its own track), counters, and the GPU's timestamp scopes
//!   per stream ([`Gpu::start_timeline`](crate::vk::Gpu::start_timeline)).
//! - [`Recording::trace`] places GPU times on the host clock — by calibrated timestamps
//!   where the device offers them, else at submission — into a [`Trace`]: tracks of
//!   properly nested slices, and counters.
//! - [`json`] writes and reads the file; [`draw`] draws a trace as a Gantt chart (SVG
//!   or PNG).
//!
//! Instrumenting code: a host span is any `tracing` span (`tracing::info_span!(name,
//! what = ..., fields...).entered()`): its lifetime becomes a slice named `name what` on
//! the track of the thread that created it, its other fields the slice's arguments. A
//! counter is [`timeline_counter!`](crate::timeline_counter). Without a capture running
//! both cost a relaxed atomic load (and nothing at all before the first capture).

mod capture;
pub mod draw;
mod gpu;
pub mod json;
mod model;

pub use capture::{Capture, ClockAlignment, Recording};
pub use model::{Counter, Process, Slice, Trace, Track, GPU_PID, HOST_PID};

/// Why a timeline could not be recorded, read or drawn.
#[derive(Debug, thiserror::Error)]
pub enum TimelineError {
    #[error("a timeline capture is already running in this process")]
    AlreadyCapturing,
    #[error("cannot record host spans: {0}")]
    Subscriber(String),
    #[error(transparent)]
    Gpu(#[from] crate::vk::VkError),
    /// The message carries the cause, not also a `source` (a chain would repeat it).
    #[error("not a trace-event JSON file: {0}")]
    Json(serde_json::Error),
    #[error("not a trace-event file: {0}")]
    Format(String),
    #[error("cannot draw the timeline: {0}")]
    Draw(String),
}

impl From<serde_json::Error> for TimelineError {
    fn from(error: serde_json::Error) -> Self {
        Self::Json(error)
    }
}

/// Sets a timeline counter: `timeline_counter!("pt", "live paths", n)` makes a sample
/// of series "live paths" on counter "pt" (Perfetto shows the track as "pt live
/// paths"). Costs nothing measurable without a capture running.
#[macro_export]
macro_rules! timeline_counter {
    ($counter:expr, $series:expr, $value:expr) => {
        ::tracing::trace!(
            target: "splitray::counter",
            counter = $counter,
            series = $series,
            value = ($value) as f64
        )
    };
}
