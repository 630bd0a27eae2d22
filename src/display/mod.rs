//! Watching a render converge: [`FilmFeed`] carries the film from the render loop to
//! watchers on other threads; [`tonemap`] turns it (or an AOV) into 8-bit pixels on the
//! GPU, with a CPU twin, for the preview window; [`tev`] streams it to the tev image
//! viewer; [`readback`] reads a film on the GPU to the host without stopping the render;
//! [`view`] is what the preview window shows and says.

pub mod feed;
pub mod readback;
pub mod tev;
pub mod tonemap;
pub mod view;

pub use feed::{FeedInfo, FeedPublisher, FeedSnapshot, FilmFeed, HostFilm};
