//! Benchmarks behind `splitray bench`: each verifies its results before timing and
//! compares against references measured in the same run.

pub mod bdpt;
pub mod cbpt;
pub mod dynamic;
pub mod host;
pub mod lvc;
pub mod primitives;
pub mod pt;
pub mod trace;
pub mod workloads;

/// Today's date (UTC) as YYYY-MM-DD, for the records in docs/PERFORMANCE.md.
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    // Civil-from-days (H. Hinnant's algorithm).
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + (month <= 2) as i64;
    format!("{year:04}-{month:02}-{day:02}")
}

/// Which value stands for the middle of an even number of samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EvenMedian {
    /// The mean of the two middle samples (the usual median).
    Mean,
    /// The upper of the two middle samples: always one of the measured samples (a
    /// frame's or a run's time), never a blend of two.
    Upper,
}

/// The median of `samples`. They are ordered by [`f64::total_cmp`], so a NaN counts as
/// a sample and sorts above every number (below, if its sign bit is set) instead of
/// being skipped. No samples give NaN: there is no figure to report, and NaN shows that
/// rather than passing for a measurement.
pub fn median(samples: impl IntoIterator<Item = f64>, even: EvenMedian) -> f64 {
    let mut v: Vec<f64> = samples.into_iter().collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match (n, even) {
        (0, _) => f64::NAN,
        (n, EvenMedian::Mean) if n % 2 == 0 => 0.5 * (v[n / 2 - 1] + v[n / 2]),
        _ => v[n / 2],
    }
}

#[cfg(test)]
mod tests {
    use super::{median, EvenMedian};

    #[test]
    fn median_of_odd_and_even_counts() {
        for even in [EvenMedian::Mean, EvenMedian::Upper] {
            assert_eq!(median([3.0, 1.0, 2.0], even), 2.0);
            assert_eq!(median([5.0], even), 5.0);
            assert!(median([], even).is_nan());
        }
        assert_eq!(median([4.0, 1.0, 3.0, 2.0], EvenMedian::Mean), 2.5);
        assert_eq!(median([4.0, 1.0, 3.0, 2.0], EvenMedian::Upper), 3.0);
    }

    #[test]
    fn median_counts_nan_as_a_sample() {
        let (nan, negative_nan) = (f64::NAN.copysign(1.0), f64::NAN.copysign(-1.0));
        assert_eq!(median([nan, 1.0, 2.0], EvenMedian::Mean), 2.0);
        assert_eq!(median([2.0, nan, 1.0, 3.0], EvenMedian::Upper), 3.0);
        assert!(median([nan, 1.0], EvenMedian::Mean).is_nan());
        assert_eq!(median([negative_nan, 1.0, 2.0], EvenMedian::Mean), 1.0);
    }
}
