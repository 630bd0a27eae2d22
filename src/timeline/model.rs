//! The trace model: processes, tracks of slices, counters. Times are integer
//! nanoseconds from the start of the capture, so nesting survives every conversion.

use std::fmt::Write as _;

use serde_json::{Map, Value};

/// The process that holds the host threads' tracks.
pub const HOST_PID: u32 = 1;
/// The process that holds the GPU streams' tracks and the counters.
pub const GPU_PID: u32 = 2;

/// One span of work on a track.
#[derive(Clone, Debug, PartialEq)]
pub struct Slice {
    pub name: String,
    /// "host" or "gpu".
    pub category: String,
    pub start_ns: i64,
    pub dur_ns: i64,
    pub args: Map<String, Value>,
}

impl Slice {
    pub fn end_ns(&self) -> i64 {
        self.start_ns + self.dur_ns
    }
}

/// A track (a thread in the trace-event format): slices that never partly overlap.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub pid: u32,
    pub tid: u32,
    pub name: String,
    /// Sorted by start, enclosing slices before the slices they enclose.
    pub slices: Vec<Slice>,
}

/// One series of a counter: (time, value) samples, each holding until the next.
#[derive(Clone, Debug, PartialEq)]
pub struct Counter {
    pub pid: u32,
    /// The counter's name ("pt"); Perfetto names the track "name series".
    pub name: String,
    pub series: String,
    pub samples: Vec<(i64, f64)>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Process {
    pub pid: u32,
    pub name: String,
}

/// A whole timeline.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    /// Written as the file's `otherData`: device, clock alignment, stream mapping, ...
    pub metadata: Map<String, Value>,
    pub processes: Vec<Process>,
    /// In display order.
    pub tracks: Vec<Track>,
    pub counters: Vec<Counter>,
}

/// Orders slices by start, longer (enclosing) first among equal starts.
pub(crate) fn sort_slices(slices: &mut [Slice]) {
    slices.sort_by(|a, b| {
        a.start_ns
            .cmp(&b.start_ns)
            .then(b.dur_ns.cmp(&a.dur_ns))
            .then_with(|| a.name.cmp(&b.name))
    });
}

/// Splits slices into lanes in each of which slices either nest or are disjoint: the
/// trace-event format (and Perfetto's importer) cannot show partly overlapping slices
/// on one track. The first lane keeps every slice that fits; the rest go to further
/// lanes, in order.
pub(crate) fn nest_into_lanes(mut slices: Vec<Slice>) -> Vec<Vec<Slice>> {
    sort_slices(&mut slices);
    // Per lane: its slices and the ends of the slices still open at the sweep.
    let mut lanes: Vec<(Vec<Slice>, Vec<i64>)> = Vec::new();
    for slice in slices {
        let fits = |open: &mut Vec<i64>| {
            while open.last().is_some_and(|&end| end <= slice.start_ns) {
                open.pop();
            }
            open.last().is_none_or(|&end| end >= slice.end_ns())
        };
        let lane = match lanes.iter_mut().position(|(_, open)| fits(open)) {
            Some(i) => i,
            None => {
                lanes.push((Vec::new(), Vec::new()));
                lanes.len() - 1
            }
        };
        lanes[lane].1.push(slice.end_ns());
        lanes[lane].0.push(slice);
    }
    lanes.into_iter().map(|(s, _)| s).collect()
}

/// `slices` as one track, plus one more per lane that partial overlaps needed (tids
/// from `spare_tid` on, names marked as overlapping).
pub(crate) fn tracks_of(
    pid: u32,
    tid: u32,
    name: &str,
    slices: Vec<Slice>,
    spare_tid: &mut u32,
) -> Vec<Track> {
    let mut lanes = nest_into_lanes(slices).into_iter();
    let mut tracks = vec![Track {
        pid,
        tid,
        name: name.to_string(),
        slices: lanes.next().unwrap_or_default(),
    }];
    for (i, slices) in lanes.enumerate() {
        tracks.push(Track {
            pid,
            tid: *spare_tid,
            name: format!("{name} (overlapping {})", i + 1),
            slices,
        });
        *spare_tid += 1;
    }
    tracks
}

/// Nanoseconds covered by at least one of the slices.
pub(crate) fn busy_ns(slices: &[Slice]) -> i64 {
    let mut spans: Vec<(i64, i64)> = slices.iter().map(|s| (s.start_ns, s.end_ns())).collect();
    spans.sort_unstable();
    let (mut busy, mut reach) = (0i64, i64::MIN);
    for (start, end) in spans {
        let from = start.max(reach);
        if end > from {
            busy += end - from;
        }
        reach = reach.max(end);
    }
    busy
}

impl Trace {
    /// The first start and last end of any slice or counter sample.
    pub fn extent_ns(&self) -> Option<(i64, i64)> {
        let slices = self
            .tracks
            .iter()
            .flat_map(|t| &t.slices)
            .map(|s| (s.start_ns, s.end_ns()));
        let samples = self
            .counters
            .iter()
            .flat_map(|c| &c.samples)
            .map(|&(t, _)| (t, t));
        slices
            .chain(samples)
            .reduce(|(a0, a1), (b0, b1)| (a0.min(b0), a1.max(b1)))
    }

    pub fn process_name(&self, pid: u32) -> &str {
        self.processes
            .iter()
            .find(|p| p.pid == pid)
            .map_or("", |p| p.name.as_str())
    }

    /// A few lines per track: slices, busy time (time inside at least one slice) and,
    /// for host tracks, the time spent in host waits; then the counters' ranges.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        if let Some((t0, t1)) = self.extent_ns() {
            let _ = writeln!(s, "timeline: {:.3} ms", (t1 - t0) as f64 * 1e-6);
        }
        if let Some(Value::String(clock)) =
            self.metadata.get("clock").and_then(|c| c.get("alignment"))
        {
            let _ = writeln!(s, "clock alignment: {clock}");
        }
        let extent = self.extent_ns().map_or(1, |(a, b)| (b - a).max(1));
        for t in &self.tracks {
            let busy = busy_ns(&t.slices);
            let _ = write!(
                s,
                "{:<6} {:<44} {:>7} slices, busy {:>10.3} ms ({:>5.1}%)",
                if t.pid == GPU_PID { "gpu" } else { "host" },
                t.name,
                t.slices.len(),
                busy as f64 * 1e-6,
                100.0 * busy as f64 / extent as f64
            );
            let waits: Vec<Slice> = t
                .slices
                .iter()
                .filter(|x| x.name.starts_with("wait "))
                .cloned()
                .collect();
            if !waits.is_empty() {
                let _ = write!(
                    s,
                    ", {} waits {:.3} ms",
                    waits.len(),
                    busy_ns(&waits) as f64 * 1e-6
                );
            }
            s.push('\n');
        }
        for c in &self.counters {
            let max = c.samples.iter().map(|&(_, v)| v).fold(0.0, f64::max);
            let _ = writeln!(
                s,
                "counter {} {}: {} samples, max {max}",
                c.name,
                c.series,
                c.samples.len()
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slice(name: &str, start: i64, end: i64) -> Slice {
        Slice {
            name: name.into(),
            category: "host".into(),
            start_ns: start,
            dur_ns: end - start,
            args: Map::new(),
        }
    }

    fn names(lane: &[Slice]) -> Vec<&str> {
        lane.iter().map(|s| s.name.as_str()).collect()
    }

    #[test]
    fn nested_and_disjoint_slices_share_a_lane() {
        let lanes = nest_into_lanes(vec![
            slice("inner", 3, 5),
            slice("outer", 0, 10),
            slice("same-start", 0, 3),
            slice("after", 10, 12),
        ]);
        assert_eq!(lanes.len(), 1);
        assert_eq!(names(&lanes[0]), ["outer", "same-start", "inner", "after"]);
    }

    #[test]
    fn partly_overlapping_slices_move_to_further_lanes() {
        // b starts inside a and ends after it; c partly overlaps both a and b.
        let lanes = nest_into_lanes(vec![
            slice("a", 0, 10),
            slice("b", 5, 15),
            slice("c", 8, 20),
        ]);
        assert_eq!(lanes.len(), 3);
        assert_eq!(names(&lanes[1]), ["b"]);
        let mut spare = 100;
        let tracks = tracks_of(
            HOST_PID,
            1,
            "main",
            vec![slice("a", 0, 10), slice("b", 5, 15)],
            &mut spare,
        );
        assert_eq!(tracks.len(), 2);
        assert_eq!(
            (tracks[1].tid, tracks[1].name.as_str()),
            (100, "main (overlapping 1)")
        );
        assert_eq!(spare, 101);
    }

    #[test]
    fn busy_time_counts_overlaps_once() {
        let s = [
            slice("a", 0, 10),
            slice("b", 5, 15),
            slice("c", 20, 25),
            slice("d", 21, 22),
        ];
        assert_eq!(busy_ns(&s), 20);
        assert_eq!(busy_ns(&[]), 0);
    }
}
