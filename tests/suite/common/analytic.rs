//! Checking a Monte Carlo estimate against a closed-form value.

/// The mean of independent estimates (passes of a render) and its standard error.
pub fn mean_and_standard_error(estimates: &[f64]) -> (f64, f64) {
    let n = estimates.len() as f64;
    let mean = estimates.iter().sum::<f64>() / n;
    let variance = estimates.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

/// Asserts an estimate `(mean, standard error)` agrees with `expected` within four of its
/// standard errors (and a 1e-4 relative allowance for float summation), and that it is
/// precise enough for the comparison to mean something (standard error under 2 %).
pub fn assert_agrees(what: &str, (mean, se): (f64, f64), expected: f64) {
    eprintln!("{what}: {mean:.5} ± {se:.5}, expected {expected:.5}");
    assert!(
        (mean - expected).abs() < 4.0 * se + 1e-4 * expected,
        "{what}: {mean} vs {expected} (se {se})"
    );
    assert!(se < 0.02 * expected, "{what}: too noisy to say ({se})");
}
