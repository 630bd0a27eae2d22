//! The balance heuristic by brute force: every technique's density as an explicit
//! product of per-vertex area densities, every weight as n_s p_s / Σ_j n_j p_j (Veach
//! 1997, §10.2). This is the oracle the recursive weights of [`crate::bidir::mis`] are
//! tested against, here and in the GPU methods: dump a path's densities into a
//! [`PathDensities`] and compare.
//!
//! Which techniques can produce a path: s = 0 unless x₀ is a point light; a connection
//! between x_{s−1} and x_s unless either endpoint scattered through a delta lobe (x₀ and
//! the pinhole x_k may end a connection; technique (1, 1) needs an area light); t = 0
//! never (a pinhole cannot be hit); and only techniques of non-zero count.

use super::mis::TechniqueCounts;

/// A complete path x₀ (on a light) … x_k (the pinhole) as the densities with which each
/// technique samples its vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct PathDensities {
    /// p→ᵢ: area density of xᵢ under light-subpath sampling (x₀: the emission sample's
    /// position density; a point light's is its discrete pmf). `fwd[k]` is unused.
    pub fwd: Vec<f64>,
    /// p←ᵢ: area density of xᵢ under camera-subpath sampling (`rev[k]` = 1: the pinhole).
    pub rev: Vec<f64>,
    /// Density with which next-event estimation chooses x₀ (technique s = 1, t ≥ 2).
    pub direct: f64,
    /// `delta[i]`: xᵢ scattered through a delta lobe (1 ≤ i < k); `delta[0]`: x₀ is a
    /// point light. `delta[k]` is unused.
    pub delta: Vec<bool>,
}

impl PathDensities {
    /// k: the path's segments.
    pub fn segments(&self) -> usize {
        self.fwd.len() - 1
    }

    /// Whether technique s (t = k + 1 − s) can sample this path.
    pub fn can_sample(&self, counts: &TechniqueCounts, s: usize) -> bool {
        let k = self.segments();
        if s > k || counts.of(s, k + 1 - s) <= 0.0 {
            return false;
        }
        if s == 0 {
            return !self.delta[0];
        }
        if s == 1 && k == 1 && self.delta[0] {
            return false;
        }
        let light_end_ok = s == 1 || !self.delta[s - 1];
        let camera_end_ok = s == k || !self.delta[s];
        light_end_ok && camera_end_ok
    }

    /// n_s p_s of technique s (0 where it cannot sample the path).
    pub fn weighted_density(&self, counts: &TechniqueCounts, s: usize) -> f64 {
        if !self.can_sample(counts, s) {
            return 0.0;
        }
        let k = self.segments();
        let t = k + 1 - s;
        let mut p = counts.of(s, t) as f64;
        for i in 0..s {
            p *= if i == 0 && s == 1 && t >= 2 {
                self.direct
            } else {
                self.fwd[i]
            };
        }
        for i in s..=k {
            p *= self.rev[i];
        }
        p
    }

    /// The balance-heuristic weight of every technique s = 0..=k (0 for those that
    /// cannot sample the path).
    pub fn balance_weights(&self, counts: &TechniqueCounts) -> Vec<f64> {
        let k = self.segments();
        let p: Vec<f64> = (0..=k).map(|s| self.weighted_density(counts, s)).collect();
        let total: f64 = p.iter().sum();
        p.iter()
            .map(|&v| if total > 0.0 { v / total } else { 0.0 })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_segment_path_weights_by_hand() {
        // x0 (area light), x1, x2 (camera): techniques s = 0 (hit), 1 (NEE), 2 (trace).
        let d = PathDensities {
            fwd: vec![0.5, 2.0, 0.0],
            rev: vec![3.0, 4.0, 1.0],
            direct: 0.25,
            delta: vec![false; 3],
        };
        let counts = TechniqueCounts::bpt(10.0);
        let p = [3.0 * 4.0, 0.25 * 4.0, 10.0 * 0.5 * 2.0];
        let total: f64 = p.iter().sum();
        let w = d.balance_weights(&counts);
        for s in 0..3 {
            assert!((w[s] - p[s] / total).abs() < 1e-12);
        }
        // A mirror at x1 leaves only the hit; a point light leaves NEE and tracing.
        let mirror = PathDensities {
            delta: vec![false, true, false],
            ..d.clone()
        };
        assert_eq!(mirror.balance_weights(&counts), vec![1.0, 0.0, 0.0]);
        let point = PathDensities {
            delta: vec![true, false, false],
            ..d
        };
        let w = point.balance_weights(&counts);
        assert_eq!(w[0], 0.0);
        assert!((w[1] + w[2] - 1.0).abs() < 1e-12);
    }
}
