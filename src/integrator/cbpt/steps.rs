//! How passes split into steps, where each step's camera paths start on the film, and
//! which random numbers each population draws.
//!
//! **Passes and steps.** A pass of `cbpt` is one use of the array of image positions of
//! §3.2 ("Correlated sampling"): every pixel's four strata (2 × 2, one jittered position
//! in each), shuffled, so [`SAMPLES_PER_PIXEL`] samples per pixel. Its 4·pixels camera
//! paths are cut into S = ⌈4·pixels / N_C⌉ steps of near-equal size (at most N_C each),
//! consumed in order; the array is made afresh for the next pass. So a pass holds whole
//! steps: its random numbers are a function of (seed, pass) only, as the `Integrator`
//! interface asks, and passes are independent, which keeps per-pass standard errors
//! honest although the camera paths of a step share their light paths.
//!
//! **Random numbers.** Counter-based ([`crate::bidir::random`]): camera path k of a pass
//! is (index k, sample pass); light path l of step s is (s·N_L + l, pass) and light-traced
//! path m is (s·N_T + m, pass), each family under a seed of its own derived from the
//! user's, and the shuffle under a fourth.

use std::ops::Range;

use crate::bidir::random::{fold_seed, pcg_hash};
use crate::bidir::walk::FilmPoint;

/// Camera samples per pixel and pass: the strata of a pixel (2 × 2).
pub const SAMPLES_PER_PIXEL: u32 = 4;

/// The steps of every pass of one film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PassPlan {
    /// Camera paths per pass: [`SAMPLES_PER_PIXEL`] × pixels.
    pub camera_paths: u32,
    /// Steps per pass.
    pub steps: u32,
}

impl PassPlan {
    /// The plan for `pixels` pixels and at most `max_camera_paths` (N_C) per step.
    pub fn new(pixels: u32, max_camera_paths: u32) -> Self {
        let camera_paths = pixels * SAMPLES_PER_PIXEL;
        Self {
            camera_paths,
            steps: camera_paths.div_ceil(max_camera_paths.max(1)),
        }
    }

    /// The positions (indices into the pass's shuffled array) of step `step`'s camera
    /// paths: the first `camera_paths % steps` steps take one more.
    pub fn step_cameras(&self, step: u32) -> Range<u32> {
        let base = self.camera_paths / self.steps;
        let extra = self.camera_paths % self.steps;
        let start = step * base + step.min(extra);
        start..start + base + (step < extra) as u32
    }
}

/// One step: a population couple.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StepId {
    pub pass: u32,
    /// Step within the pass.
    pub step: u32,
    pub cameras: Range<u32>,
}

/// The seeds of the four random-number families of a render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Streams {
    pub camera: u32,
    pub light: u32,
    pub traced: u32,
    pub shuffle: u32,
}

impl Streams {
    pub fn new(seed: u64) -> Self {
        let base = fold_seed(seed);
        // Distinct odd constants per family ("ligh", "trac", "shuf").
        Self {
            camera: base,
            light: pcg_hash(base ^ 0x6c69_6768),
            traced: pcg_hash(base ^ 0x7472_6163),
            shuffle: pcg_hash(base ^ 0x7368_7566),
        }
    }
}

/// The image positions of one pass: entry = pixel · 4 + stratum, in shuffled order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImagePositions {
    entries: Vec<u32>,
}

impl ImagePositions {
    /// Every stratum of `pixels` pixels, shuffled (Fisher–Yates) by `(pass, seed)`.
    pub fn new(pixels: u32, pass: u32, seed: u32) -> Self {
        let _span = tracing::info_span!("cbpt image positions", pixels).entered();
        let mut entries: Vec<u32> = (0..pixels * SAMPLES_PER_PIXEL).collect();
        let key = pcg_hash(pass ^ pcg_hash(seed));
        for i in (1..entries.len()).rev() {
            let hi = pcg_hash(i as u32 ^ key) as u64;
            let lo = pcg_hash(hi as u32 ^ key.rotate_left(16)) as u64;
            let j = ((hi << 32 | lo) % (i as u64 + 1)) as usize;
            entries.swap(i, j);
        }
        Self { entries }
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Film point of position `k`, jittered in its stratum by `u` ∈ [0, 1)².
    pub fn film_point(&self, k: u32, u: [f32; 2]) -> FilmPoint {
        let e = self.entries[k as usize];
        let stratum = e % SAMPLES_PER_PIXEL;
        let half = |cell: u32, u: f32| (cell as f32 + u) * 0.5;
        FilmPoint {
            pixel: e / SAMPLES_PER_PIXEL,
            jitter: [half(stratum & 1, u[0]), half(stratum >> 1, u[1])],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_cover_a_pass_once_in_near_equal_parts() {
        for (pixels, nc) in [(1u32, 2000u32), (4096, 2000), (4096, 1), (100, 7), (6, 24)] {
            let plan = PassPlan::new(pixels, nc);
            assert_eq!(plan.steps, (4 * pixels).div_ceil(nc));
            let mut next = 0;
            for s in 0..plan.steps {
                let r = plan.step_cameras(s);
                assert_eq!(r.start, next);
                assert!(r.len() as u32 <= nc && !r.is_empty());
                assert!(r.len() as u32 >= plan.camera_paths / plan.steps);
                next = r.end;
            }
            assert_eq!(next, plan.camera_paths);
        }
    }

    #[test]
    fn positions_hold_every_stratum_once_shuffled_by_pass() {
        let a = ImagePositions::new(50, 3, 7);
        let mut sorted = a.entries.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..200).collect::<Vec<_>>());
        assert_ne!(a.entries, (0..200).collect::<Vec<_>>(), "not shuffled");
        assert_ne!(a, ImagePositions::new(50, 4, 7));
        assert_eq!(a, ImagePositions::new(50, 3, 7));
        // The four positions of a pixel fall in its four quarters.
        let mut quarters = [[false; 4]; 50];
        for k in 0..200 {
            let p = a.film_point(k, [0.999, 0.001]);
            let q = (p.jitter[0] >= 0.5) as usize + 2 * (p.jitter[1] >= 0.5) as usize;
            assert!(p.jitter.iter().all(|j| (0.0..1.0).contains(j)));
            quarters[p.pixel as usize][q] = true;
        }
        assert!(quarters.iter().all(|q| q.iter().all(|&b| b)));
    }
}
