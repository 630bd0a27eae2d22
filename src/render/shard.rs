//! [`Shard`]: one of N statistically independent parts of one image, by pass index.
//!
//! Pass `k`'s random numbers depend only on (seed, k), so parts that take disjoint sets of
//! pass indices are independent, and parts that together take passes `0..P` hold exactly
//! the samples of one render of `P` passes. Shard `I` of `N` takes the contiguous block
//! `⌊I·P/N⌋ .. ⌊(I+1)·P/N⌋` of the `P` passes the render asks for, rather than every
//! N-th pass: contiguous blocks keep an integrator's batching of several passes into one
//! GPU submission (`passes_per_call`), and shard 0's film is bit-identical to the first
//! block of an unsharded render. A render bounded by time only asks for `u32::MAX`
//! samples, so its shards start at indices `⌊I·2³²/N⌋` and stay disjoint unless one of
//! them renders more than 2³²/N passes.
//!
//! Merged shards equal one render of the same passes up to the rounding of the films'
//! sums (GPU films add their passes in `f32`; a merged film adds the shards' sums in
//! another order), not bit for bit: see tests/suite/shards.rs for the bound.
//!
//! Shard numbers are 0-based: `0/4` … `3/4`, as Slurm array task ids and Kubernetes
//! completion indices usually are.

use std::fmt;
use std::ops::Range;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// Part `index` of `count` (0-based); `0/1` is the whole image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Default for Shard {
    fn default() -> Self {
        Self::WHOLE
    }
}

impl Shard {
    /// The whole image.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    pub fn new(index: u32, count: u32) -> Result<Self, String> {
        if count == 0 {
            return Err("a shard count must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "shard {index}/{count}: the index must be below the count (shards are numbered from 0)"
            ));
        }
        Ok(Self { index, count })
    }

    pub fn is_whole(&self) -> bool {
        self.count == 1
    }

    /// The global pass indices this shard takes of a render of `total_passes` passes.
    pub fn passes(&self, total_passes: u32) -> Range<u32> {
        let at = |i: u32| (i as u64 * total_passes as u64 / self.count as u64) as u32;
        at(self.index)..at(self.index + 1)
    }

    /// The shard an array job's task runs as, from its scheduler's environment:
    /// - Slurm job arrays: `SLURM_ARRAY_TASK_ID` counted from `SLURM_ARRAY_TASK_MIN` in
    ///   steps of `SLURM_ARRAY_TASK_STEP`, of `SLURM_ARRAY_TASK_COUNT` tasks;
    /// - Kubernetes Indexed Jobs: `JOB_COMPLETION_INDEX`, of `SPLITRAY_SHARD_COUNT`
    ///   shards (Kubernetes does not pass the Job's completions to its pods; the Job
    ///   sets the variable, see tools/k8s/render-indexed-job.yaml).
    ///
    /// `SPLITRAY_SHARD_COUNT`, where set, also overrides Slurm's count.
    pub fn from_environment(var: impl Fn(&str) -> Option<String>) -> Result<Self, String> {
        let number = |name: &str| -> Result<Option<u32>, String> {
            match var(name) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse()
                    .map(Some)
                    .map_err(|_| format!("{name}={v:?} is not a whole number")),
            }
        };
        let count_override = number("SPLITRAY_SHARD_COUNT")?;
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let count = count_override
                .or(number("SLURM_ARRAY_TASK_COUNT")?)
                .ok_or("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?;
            if id < min || (id - min) % step != 0 {
                return Err(format!(
                    "SLURM_ARRAY_TASK_ID={id} is not in the array {min}, {}, … (step {step})",
                    min + step
                ));
            }
            return Self::new((id - min) / step, count).map_err(|e| format!("Slurm array: {e}"));
        }
        if let Some(index) = number("JOB_COMPLETION_INDEX")? {
            let count = count_override.ok_or(
                "JOB_COMPLETION_INDEX is set but SPLITRAY_SHARD_COUNT is not: \
                 set it to the Indexed Job's completions",
            )?;
            return Self::new(index, count).map_err(|e| format!("Indexed Job: {e}"));
        }
        Err(
            "--shard auto: neither SLURM_ARRAY_TASK_ID (a Slurm job array) nor \
             JOB_COMPLETION_INDEX (a Kubernetes Indexed Job) is set"
                .into(),
        )
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let parse = |v: &str| v.trim().parse::<u32>().ok();
        match s.split_once('/').map(|(i, n)| (parse(i), parse(n))) {
            Some((Some(i), Some(n))) => Self::new(i, n),
            _ => Err(format!(
                "shard '{s}' is not I/N (e.g. 0/4 for the first of four) or auto"
            )),
        }
    }
}

/// Passes by global index, as disjoint sorted ranges: `0..4,8..12`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PassRanges(Vec<Range<u32>>);

impl PassRanges {
    /// One range (none when empty).
    pub fn single(range: Range<u32>) -> Self {
        let mut r = Self::default();
        r.add(range);
        r
    }

    pub fn ranges(&self) -> &[Range<u32>] {
        &self.0
    }

    /// Passes in all.
    pub fn count(&self) -> u64 {
        self.0.iter().map(|r| (r.end - r.start) as u64).sum()
    }

    /// The first range of `self` that shares a pass with `other`.
    pub fn overlap(&self, other: &PassRanges) -> Option<Range<u32>> {
        self.0.iter().find_map(|a| {
            other.0.iter().find_map(|b| {
                let (start, end) = (a.start.max(b.start), a.end.min(b.end));
                (start < end).then_some(start..end)
            })
        })
    }

    /// The passes before the last one held that these ranges do not hold.
    pub fn gaps(&self) -> Vec<Range<u32>> {
        let mut gaps = Vec::new();
        let mut next = 0;
        for r in &self.0 {
            if r.start > next {
                gaps.push(next..r.start);
            }
            next = r.end;
        }
        gaps
    }

    /// Adds `range` (which must not overlap these), joining ranges that touch.
    pub fn add(&mut self, range: Range<u32>) {
        if range.is_empty() {
            return;
        }
        self.0.push(range);
        self.0.sort_by_key(|r| r.start);
        let mut joined: Vec<Range<u32>> = Vec::with_capacity(self.0.len());
        for r in self.0.drain(..) {
            match joined.last_mut() {
                Some(last) if last.end >= r.start => last.end = last.end.max(r.end),
                _ => joined.push(r),
            }
        }
        self.0 = joined;
    }
}

impl fmt::Display for PassRanges {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self
            .0
            .iter()
            .map(|r| format!("{}..{}", r.start, r.end))
            .collect();
        f.write_str(&parts.join(","))
    }
}

impl FromStr for PassRanges {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let mut out = PassRanges::default();
        if s.is_empty() {
            return Ok(out);
        }
        for part in s.split(',') {
            let range = part
                .split_once("..")
                .and_then(|(a, b)| Some(a.parse::<u32>().ok()?..b.parse::<u32>().ok()?))
                .filter(|r| r.start < r.end)
                .ok_or_else(|| format!("'{part}' is not a range of passes like 0..8"))?;
            if out.overlap(&PassRanges(vec![range.clone()])).is_some() {
                return Err(format!("pass ranges '{s}' overlap"));
            }
            out.add(range);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn shards_split_the_passes_into_disjoint_covering_blocks() {
        for total in [0u32, 1, 3, 8, 17, 1000, u32::MAX] {
            for count in [1u32, 2, 3, 4, 7] {
                let mut next = 0u32;
                for index in 0..count {
                    let r = Shard::new(index, count).unwrap().passes(total);
                    assert_eq!(r.start, next, "{index}/{count} of {total}");
                    next = r.end;
                }
                assert_eq!(next, total);
            }
        }
        assert_eq!(Shard::new(1, 4).unwrap().passes(8), 2..4);
    }

    #[test]
    fn parsing_and_bad_shards() {
        assert_eq!("2/4".parse::<Shard>().unwrap(), Shard::new(2, 4).unwrap());
        assert_eq!(Shard::new(2, 4).unwrap().to_string(), "2/4");
        for bad in ["4/4", "1/0", "x/2", "1", "-1/2", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let map: HashMap<String, String> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k| map.get(k).cloned()
    }

    #[test]
    fn schedulers_environments_map_onto_shards() {
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(Shard::from_environment(slurm).unwrap().to_string(), "3/4");
        // --array=1-8:2 → tasks 1, 3, 5, 7.
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(Shard::from_environment(stepped).unwrap().to_string(), "2/4");
        let k8s = env(&[("JOB_COMPLETION_INDEX", "1"), ("SPLITRAY_SHARD_COUNT", "3")]);
        assert_eq!(Shard::from_environment(k8s).unwrap().to_string(), "1/3");
        let no_count = Shard::from_environment(env(&[("JOB_COMPLETION_INDEX", "1")]));
        assert!(no_count.unwrap_err().contains("SPLITRAY_SHARD_COUNT"));
        let nothing = Shard::from_environment(env(&[]));
        assert!(nothing.unwrap_err().contains("SLURM_ARRAY_TASK_ID"));
        let bad = env(&[
            ("SLURM_ARRAY_TASK_ID", "x"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert!(Shard::from_environment(bad).unwrap_err().contains("\"x\""));
        let outside = env(&[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert!(Shard::from_environment(outside).is_err());
    }

    #[test]
    fn pass_ranges_join_parse_and_detect_overlaps() {
        let mut r = PassRanges::single(4..8);
        r.add(0..4);
        r.add(10..12);
        assert_eq!(r.to_string(), "0..8,10..12");
        assert_eq!(r.count(), 10);
        assert_eq!("0..8,10..12".parse::<PassRanges>().unwrap(), r);
        assert_eq!(r.overlap(&PassRanges::single(11..20)), Some(11..12));
        assert_eq!(r.overlap(&PassRanges::single(8..10)), None);
        let gap = |r: &PassRanges| {
            r.gaps()
                .iter()
                .map(|g| (g.start, g.end))
                .collect::<Vec<_>>()
        };
        assert_eq!(gap(&r), [(8, 10)]);
        assert_eq!(gap(&PassRanges::single(3..5)), [(0, 3)]);
        assert!(PassRanges::single(0..5).gaps().is_empty());
        for bad in ["0..", "3..3", "a..b", "0..4,2..6"] {
            assert!(bad.parse::<PassRanges>().is_err(), "{bad}");
        }
    }
}
