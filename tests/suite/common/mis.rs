//! The check the MIS tests make of a weight the integrators computed: the brute-force
//! oracle's balance heuristic n_s p_s / Σ_j n_j p_j (src/bidir/oracle.rs) on the
//! densities of the path it weighs.

use splitray::bidir::connect::Sample;
use splitray::bidir::mis::TechniqueCounts;
use splitray::bidir::oracle::PathDensities;

/// A recursive weight (f32, accumulated vertex by vertex) against the oracle's (f64
/// products over the whole path): the recursion's rounding on paths of up to 8 segments.
pub fn close(recursive: f64, oracle: f64) -> bool {
    (recursive - oracle).abs() <= 2e-4 + 2e-4 * oracle.abs()
}

/// Asserts that technique (s, t) of `sample` can make the path whose densities are `d`
/// with the technique counts `counts`, and that its weight is the oracle's.
pub fn assert_weight_is_the_oracles(d: &PathDensities, counts: &TechniqueCounts, sample: &Sample) {
    let (s, t, k) = (sample.s as usize, sample.t, d.segments());
    assert!(
        d.can_sample(counts, s),
        "({s}, {t}) cannot make its path of {k} segments"
    );
    let oracle = d.balance_weights(counts)[s];
    assert!(
        close(sample.weight as f64, oracle),
        "({s}, {t}), {k} segments: recursive {} vs oracle {oracle}; {d:?}",
        sample.weight
    );
}
