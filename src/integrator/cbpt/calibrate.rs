//! N_C from Equation 4 (§3.2, "Setting N_C and N_L"): with t_b the time standard BPT
//! takes to sample, combine and splat one pair of paths, and t_s(P) the time of a CBPT
//! step of P = N_C·N_L pairs (about constant for a given P), CBPT covers the image at
//! least as fast as BPT — with each camera path combined with N_L > 1 light paths — when
//!
//!   N_C > t_s(P) / t_b.                                                    (4)
//!
//! P is kept at the default N_C times the N_L asked for; N_L = P / N_C follows. When that
//! leaves N_L < 1, "the machine on which CBPT is running is not fast enough to bring any
//! advantage over standard BPT for the chosen P": N_L is then 1 and the choice says so.

use super::options::MAX_POPULATION;

/// The outcome of Equation 4.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equation4 {
    /// t_b in seconds.
    pub pair_seconds: f64,
    /// t_s(P) in seconds.
    pub step_seconds: f64,
    pub pairs: u64,
    /// N_C = ⌊t_s / t_b⌋ + 1.
    pub camera_paths: u32,
    /// N_L = max(1, P / N_C).
    pub light_paths: u32,
    /// P / N_C ≥ 1: CBPT can be faster than BPT here.
    pub advantage: bool,
}

impl Equation4 {
    pub fn solve(pair_seconds: f64, step_seconds: f64, pairs: u64) -> Self {
        let ratio = step_seconds / pair_seconds.max(1e-12);
        // Both stay within the populations CBPT takes (MAX_POPULATION): a slow step
        // against a fast BPT pair would otherwise ask for more camera paths than memory
        // holds.
        let needed = ratio.floor() + 1.0;
        let camera_paths = needed.clamp(1.0, f64::from(MAX_POPULATION)) as u32;
        let per_camera = pairs / camera_paths as u64;
        Self {
            pair_seconds,
            step_seconds,
            pairs,
            camera_paths,
            light_paths: per_camera.clamp(1, u64::from(MAX_POPULATION)) as u32,
            // Against the N_C Equation 4 asks for, not the one kept.
            advantage: pairs as f64 >= needed,
        }
    }
}

impl std::fmt::Display for Equation4 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Equation 4: t_b {:.3} µs per BPT pair, t_s {:.2} ms per step of {} pairs → N_C {}, N_L {}",
            self.pair_seconds * 1e6,
            self.step_seconds * 1e3,
            self.pairs,
            self.camera_paths,
            self.light_paths
        )?;
        if !self.advantage {
            write!(
                f,
                " (N_L would be below 1: this machine is not fast enough for CBPT to bring \
                 an advantage over BPT at this P)"
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equation_4_keeps_the_pairs_and_flags_a_slow_machine() {
        let e = Equation4::solve(1e-6, 30e-3, 30_000);
        assert_eq!(e.camera_paths, 30_001);
        assert_eq!(e.light_paths, 1);
        assert!(!e.advantage);
        // Powers of two: the ratio is exactly 1024.
        let e = Equation4::solve(2f64.powi(-16), 2f64.powi(-6), 30_000);
        assert_eq!((e.camera_paths, e.light_paths), (1025, 29));
        assert!(e.advantage && e.camera_paths as f64 > e.step_seconds / e.pair_seconds);
        // A step ten billion times a pair: N_C stops at the populations' bound, and the
        // machine is still reported too slow.
        let e = Equation4::solve(1e-9, 10.0, 30_000);
        assert_eq!((e.camera_paths, e.light_paths), (MAX_POPULATION, 1));
        assert!(!e.advantage);
    }
}
