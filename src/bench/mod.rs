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
