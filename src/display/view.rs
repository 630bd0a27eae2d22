//! What the preview window shows and says: the view and exposure the keys choose
//! ([`ViewState`]) and the title line ([`title`]: samples per pixel, samples per second,
//! time left).

use super::feed::FeedSnapshot;
use super::tonemap::View;

/// Exposure steps the keys take, in stops.
pub const EXPOSURE_STEP_STOPS: f32 = 0.5;
/// The exposure keys stay within ± this many stops.
pub const EXPOSURE_LIMIT_STOPS: f32 = 20.0;

/// What a key asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewAction {
    Brighter,
    Darker,
    ResetExposure,
    NextView,
    Snapshot,
    Close,
}

/// The view and exposure the window shows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewState {
    pub view: View,
    /// Exposure in stops (the film is multiplied by 2^stops); 0 shows what the PNG shows.
    pub exposure_stops: f32,
}

impl ViewState {
    /// Applies an action that changes the view; returns whether it did.
    pub fn apply(&mut self, action: ViewAction) -> bool {
        let before = *self;
        let limit = EXPOSURE_LIMIT_STOPS;
        match action {
            ViewAction::Brighter => {
                self.exposure_stops = (self.exposure_stops + EXPOSURE_STEP_STOPS).min(limit)
            }
            ViewAction::Darker => {
                self.exposure_stops = (self.exposure_stops - EXPOSURE_STEP_STOPS).max(-limit)
            }
            ViewAction::ResetExposure => self.exposure_stops = 0.0,
            ViewAction::NextView => self.view = self.view.next(),
            ViewAction::Snapshot | ViewAction::Close => {}
        }
        *self != before
    }

    /// The linear factor the film is multiplied by.
    pub fn exposure(&self) -> f32 {
        self.exposure_stops.exp2()
    }

    /// A file-name-safe name of the view: `colour`, `depth`, `normal`, `triangle-id`.
    pub fn file_tag(&self) -> String {
        self.view.name().replace(' ', "-")
    }
}

/// `m:ss` (or `h:mm:ss`) of a number of seconds, rounded up.
fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).ceil() as u64;
    match s / 3600 {
        0 => format!("{}:{:02}", s / 60, s % 60),
        h => format!("{h}:{:02}:{:02}", (s / 60) % 60, s % 60),
    }
}

/// The window's title: `splitray: NAME — SPP spp, RATE samples/s, TIME left — VIEW`,
/// `done` in place of the time once the render finished.
pub fn title(name: &str, feed: &FeedSnapshot, state: &ViewState, closing: bool) -> String {
    let mut parts = vec![format!("splitray: {name}")];
    if let (Some(info), Some(p)) = (&feed.info, &feed.progress) {
        let pixels = info.width as f64 * info.height as f64;
        let done_here = p.spp.saturating_sub(info.start_spp) as f64;
        let rate = done_here * pixels / p.elapsed_s.max(1e-9);
        let spp = match p.target_spp {
            t if t < u32::MAX as u64 => format!("{}/{t} spp", feed.spp()),
            _ => format!("{} spp", feed.spp()),
        };
        let mut left = f64::INFINITY;
        if let Some(limit) = p.time_limit {
            left = limit - p.elapsed_s;
        }
        if rate > 0.0 && p.target_spp < u32::MAX as u64 {
            left = left.min(p.target_spp.saturating_sub(p.spp) as f64 * pixels / rate);
        }
        let status = if feed.finished {
            "done".to_string()
        } else if closing {
            "stopping".to_string()
        } else if left.is_finite() {
            format!("{} left", clock(left))
        } else {
            "time left unknown".to_string()
        };
        parts.push(format!("{spp}, {} samples/s, {status}", si(rate)));
    } else if feed.info.is_some() {
        parts.push("first pass".into());
    } else {
        parts.push("preparing".into());
    }
    let mut view = state.view.name().to_string();
    if state.view == View::Colour && state.exposure_stops != 0.0 {
        view.push_str(&format!(" {:+.1} EV", state.exposure_stops));
    }
    parts.push(view);
    parts.join(" — ")
}

/// A rate with an SI prefix: `950`, `1.23 k`, `4.56 M`, `7.89 G`.
fn si(value: f64) -> String {
    match value {
        v if v >= 1e9 => format!("{:.2} G", v * 1e-9),
        v if v >= 1e6 => format!("{:.2} M", v * 1e-6),
        v if v >= 1e3 => format!("{:.2} k", v * 1e-3),
        v => format!("{v:.0}"),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::display::feed::{FeedInfo, HostFilm};
    use crate::integrator::aov::Aovs;
    use crate::render::Progress;

    fn feed(progress: Option<Progress>, finished: bool) -> FeedSnapshot {
        FeedSnapshot {
            info: Some(Arc::new(FeedInfo {
                width: 100,
                height: 10,
                aovs: Aovs {
                    depth: vec![],
                    triangle_id: vec![],
                    normal: vec![],
                },
                device_film: None,
                start_spp: 0,
            })),
            host: finished.then(|| {
                Arc::new(HostFilm {
                    width: 100,
                    height: 10,
                    spp: 40,
                    mean: vec![],
                })
            }),
            progress,
            finished,
            version: 1,
        }
    }

    #[test]
    fn title_shows_samples_rate_and_time_left() {
        let state = ViewState::default();
        let p = Progress {
            passes: 10,
            spp: 10,
            target_spp: 40,
            elapsed_s: 2.0,
            time_limit: None,
            relative_mse: None,
        };
        // 10 spp × 1000 pixels in 2 s: 5000 samples/s; 30 spp to go: 6 s.
        assert_eq!(
            title("box", &feed(Some(p), false), &state, false),
            "splitray: box — 10/40 spp, 5.00 k samples/s, 0:06 left — colour"
        );
        let timed = Progress {
            target_spp: u32::MAX as u64,
            time_limit: Some(3725.0),
            ..p
        };
        let bright = ViewState {
            exposure_stops: 1.5,
            ..state
        };
        assert_eq!(
            title("box", &feed(Some(timed), false), &bright, false),
            "splitray: box — 10 spp, 5.00 k samples/s, 1:02:03 left — colour +1.5 EV"
        );
        assert!(title("box", &feed(Some(p), true), &state, false).contains("40/40 spp"));
        assert!(title("box", &feed(Some(p), true), &state, false).contains("done"));
        assert!(title("box", &feed(Some(p), false), &state, true).contains("stopping"));
        assert!(title("box", &feed(None, false), &state, false).contains("first pass"));
        assert!(title("box", &FeedSnapshot::default(), &state, false).contains("preparing"));
    }

    #[test]
    fn keys_step_exposure_within_limits_and_cycle_views() {
        let mut s = ViewState::default();
        assert!(s.apply(ViewAction::Brighter));
        assert_eq!(s.exposure(), 2f32.sqrt());
        assert!(s.apply(ViewAction::ResetExposure));
        for _ in 0..100 {
            s.apply(ViewAction::Darker);
        }
        assert_eq!(s.exposure_stops, -EXPOSURE_LIMIT_STOPS);
        assert!(!s.apply(ViewAction::Darker));
        assert!(!s.apply(ViewAction::Snapshot));
        assert!(s.apply(ViewAction::NextView));
        assert_eq!(s.view, View::Depth);
        s.apply(ViewAction::NextView);
        s.apply(ViewAction::NextView);
        assert_eq!(s.file_tag(), "triangle-id");
        s.apply(ViewAction::NextView);
        assert_eq!(s.view, View::Colour);
    }
}
