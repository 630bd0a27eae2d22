//! [`FilmFeed`]: the render's film as watchers on other threads see it.
//!
//! The render loop publishes through a [`FeedPublisher`] (a [`FilmWatch`]): the film's size
//! and AOVs, then after every batch its progress and, where the integrator keeps its film
//! on the host, the film itself; at the end, the finished film the outputs are written
//! from. Watchers take [`FeedSnapshot`]s whenever they like and may wait for the next
//! change. Where the integrator keeps its film on the GPU, the snapshot carries that
//! [`DeviceFilm`] instead, and watchers read it there, as often as they like, without the
//! render loop doing anything for them.

use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use crate::film::{DeviceFilm, FilmSums};
use crate::integrator::aov::Aovs;
use crate::integrator::IntegratorError;
use crate::render::{FilmWatch, Progress, RenderError, WatchStart};

/// What stays fixed for a whole render.
#[derive(Debug)]
pub struct FeedInfo {
    pub width: u32,
    pub height: u32,
    pub aovs: Aovs,
    /// The integrator's film on the GPU, where it keeps one.
    pub device_film: Option<DeviceFilm>,
    /// Samples per pixel the film held when the render started (a resumed render's).
    pub start_spp: u64,
}

/// A film on the host: each pixel's estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct HostFilm {
    pub width: u32,
    pub height: u32,
    pub spp: u64,
    /// Row 0 at the top; exactly [`FilmSums::mean`], the values the EXR holds.
    pub mean: Vec<[f32; 3]>,
}

impl HostFilm {
    pub fn from_sums(sums: &FilmSums) -> Self {
        Self {
            width: sums.width,
            height: sums.height,
            spp: sums.spp(),
            mean: sums.mean(),
        }
    }
}

/// The feed at one moment.
#[derive(Clone, Debug, Default)]
pub struct FeedSnapshot {
    /// `None` until the render starts its first pass.
    pub info: Option<Arc<FeedInfo>>,
    /// The latest film on the host: after every batch where the integrator keeps its film
    /// there, and the finished film once [`FeedSnapshot::finished`].
    pub host: Option<Arc<HostFilm>>,
    /// The latest batch's progress.
    pub progress: Option<Progress>,
    /// The render ended; `host` is the film its outputs are written from.
    pub finished: bool,
    /// Grows with every change, so a watcher can tell whether anything happened.
    pub version: u64,
}

impl FeedSnapshot {
    /// Samples per pixel of the newest film: the progress's, the finished film's, or the
    /// start's.
    pub fn spp(&self) -> u64 {
        match (&self.host, self.finished, &self.progress, &self.info) {
            (Some(host), true, _, _) => host.spp,
            (_, _, Some(p), _) => p.spp,
            (_, _, None, Some(info)) => info.start_spp,
            _ => 0,
        }
    }
}

/// The film of one render, shared between the render loop and its watchers.
#[derive(Debug, Default)]
pub struct FilmFeed {
    state: Mutex<FeedSnapshot>,
    changed: Condvar,
    /// The longest batch the watchers want (see [`FilmWatch::batch_target_s`]).
    batch_target_s: Option<f64>,
}

impl FilmFeed {
    /// A feed whose watchers want the render loop back at least every `batch_target_s`
    /// seconds (`None`: whenever it comes): for the progress they show, for a film on the
    /// host, and for integrators whose film on the GPU changes once per call.
    pub fn new(batch_target_s: Option<f64>) -> Arc<Self> {
        Arc::new(Self {
            batch_target_s,
            ..Default::default()
        })
    }

    /// What the render loop publishes through.
    pub fn publisher(self: &Arc<Self>) -> FeedPublisher {
        FeedPublisher { feed: self.clone() }
    }

    pub fn snapshot(&self) -> FeedSnapshot {
        self.lock().clone()
    }

    /// Waits until the feed's version exceeds `seen` or `timeout` passed, then returns
    /// the feed as it is.
    pub fn wait_newer(&self, seen: u64, timeout: Duration) -> FeedSnapshot {
        let state = self.lock();
        let (state, _) = self
            .changed
            .wait_timeout_while(state, timeout, |s| s.version <= seen)
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        state.clone()
    }

    fn lock(&self) -> MutexGuard<'_, FeedSnapshot> {
        // Every change is a few field assignments: a writer that panicked left it whole.
        self.state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn update(&self, change: impl FnOnce(&mut FeedSnapshot)) {
        let mut state = self.lock();
        change(&mut state);
        state.version += 1;
        drop(state);
        self.changed.notify_all();
    }
}

/// The render loop's side of a [`FilmFeed`].
pub struct FeedPublisher {
    feed: Arc<FilmFeed>,
}

impl FilmWatch for FeedPublisher {
    fn batch_target_s(&self) -> Option<f64> {
        self.feed.batch_target_s
    }

    fn start(&mut self, start: &WatchStart<'_>) -> Result<(), RenderError> {
        let info = Arc::new(FeedInfo {
            width: start.width,
            height: start.height,
            aovs: start.aovs.clone(),
            device_film: start.device_film.clone(),
            start_spp: start.spp,
        });
        self.feed.update(|s| s.info = Some(info));
        Ok(())
    }

    fn batch(
        &mut self,
        progress: &Progress,
        sums: &mut dyn FnMut() -> Result<FilmSums, IntegratorError>,
    ) -> Result<(), RenderError> {
        let on_host = self
            .feed
            .lock()
            .info
            .as_ref()
            .is_some_and(|i| i.device_film.is_none());
        let host = match on_host {
            true => Some(Arc::new(HostFilm::from_sums(&sums()?))),
            false => None,
        };
        self.feed.update(|s| {
            s.progress = Some(*progress);
            if host.is_some() {
                s.host = host;
            }
        });
        Ok(())
    }

    fn finish(&mut self, sums: &FilmSums) -> Result<(), RenderError> {
        let host = Arc::new(HostFilm::from_sums(sums));
        self.feed.update(|s| {
            s.host = Some(host);
            s.finished = true;
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn aovs(n: usize) -> Aovs {
        Aovs {
            depth: vec![1.0; n],
            triangle_id: vec![0; n],
            normal: vec![[0.0, 0.0, 1.0]; n],
        }
    }

    fn progress(spp: u64) -> Progress {
        Progress {
            passes: spp as u32,
            spp,
            target_spp: 8,
            elapsed_s: 1.0,
            time_limit: None,
            relative_mse: None,
        }
    }

    #[test]
    fn host_films_are_published_each_batch_and_the_finished_one_last() {
        let feed = FilmFeed::new(Some(0.25));
        let mut publisher = feed.publisher();
        assert_eq!(feed.snapshot().spp(), 0);
        let start_aovs = aovs(2);
        publisher
            .start(&WatchStart {
                width: 2,
                height: 1,
                aovs: &start_aovs,
                device_film: None,
                spp: 3,
            })
            .unwrap();
        assert_eq!(publisher.batch_target_s(), Some(0.25));
        assert_eq!(feed.snapshot().spp(), 3);
        let mut sums = FilmSums::new(2, 1, 1, false);
        sums.add_pass(&[[1.0, 2.0, 3.0], [0.5, 0.0, 0.0]]);
        sums.add_pass(&[[3.0, 2.0, 1.0], [0.5, 0.0, 0.0]]);
        let seen = feed.snapshot().version;
        publisher
            .batch(&progress(2), &mut || Ok(sums.clone()))
            .unwrap();
        let snap = feed.wait_newer(seen, Duration::from_secs(5));
        assert!(snap.version > seen && !snap.finished);
        assert_eq!(snap.spp(), 2);
        let host = snap.host.unwrap();
        assert_eq!(host.mean, vec![[2.0, 2.0, 2.0], [0.5, 0.0, 0.0]]);

        sums.add_pass(&[[2.0, 2.0, 2.0], [0.5, 0.0, 0.0]]);
        publisher.finish(&sums).unwrap();
        let snap = feed.snapshot();
        assert!(snap.finished);
        assert_eq!(snap.spp(), 3);
        assert_eq!(snap.host.unwrap().mean, sums.mean());
    }

    #[test]
    fn waiting_without_a_change_times_out_with_the_same_version() {
        let feed = FilmFeed::new(None);
        let seen = feed.snapshot().version;
        let snap = feed.wait_newer(seen, Duration::from_millis(10));
        assert_eq!(snap.version, seen);
    }
}
