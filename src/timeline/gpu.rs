//! GPU scopes on the host clock: one track per stream.
//!
//! GPU timestamps count on the device's own clock. With calibrated timestamps, a sample
//! at the start and one at the end of the capture give the offset and the rate between
//! the clocks (the rate only over captures long enough for the samples' deviation not
//! to matter). Without them, each stream's command buffers can only be placed relative
//! to their submissions: the offset is the smallest that starts no command buffer
//! before the host submitted it, which puts the least-delayed one exactly at its
//! submission.

use serde_json::{json, Map, Value};

use super::capture::{since, ClockAlignment, GpuRecording, Recording};
use super::model::{tracks_of, Slice, Track, GPU_PID};
use crate::vk::{GpuBatch, ProfileRecord};

/// Captures shorter than this (in GPU ns) keep a rate of 1 between the clocks: two
/// samples microseconds apart in deviation say nothing about drift over milliseconds.
const MIN_RATE_SPAN_NS: f64 = 1e8;

/// host ns = `host0` + (gpu ns − `gpu0`) × `rate`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ClockMap {
    pub(crate) gpu0: f64,
    pub(crate) host0: f64,
    pub(crate) rate: f64,
}

impl ClockMap {
    pub(crate) fn host_ns(&self, gpu_ns: f64) -> i64 {
        (self.host0 + (gpu_ns - self.gpu0) * self.rate).round() as i64
    }

    /// From calibration samples given as (host ns, gpu ns): the first and the last.
    pub(crate) fn calibrated(samples: &[(f64, f64)]) -> Option<Self> {
        let &(host0, gpu0) = samples.first()?;
        let &(host1, gpu1) = samples.last()?;
        let rate = if gpu1 - gpu0 >= MIN_RATE_SPAN_NS {
            (host1 - host0) / (gpu1 - gpu0)
        } else {
            1.0
        };
        Some(Self { gpu0, host0, rate })
    }

    /// Aligned at submission: from (host submission ns, earliest GPU start ns) per
    /// command buffer.
    pub(crate) fn at_submission(batches: impl Iterator<Item = (f64, f64)>) -> Self {
        let offset = batches
            .map(|(submitted, first_start)| submitted - first_start)
            .fold(f64::NEG_INFINITY, f64::max);
        Self {
            gpu0: 0.0,
            host0: if offset.is_finite() { offset } else { 0.0 },
            rate: 1.0,
        }
    }
}

/// The timeline arguments of one GPU scope.
fn record_args(r: &ProfileRecord) -> Map<String, Value> {
    let mut args = Map::new();
    args.insert("stream".into(), json!(r.stream.name()));
    args.insert("submission".into(), json!(r.submission));
    if let Some(w) = r.info.workgroups {
        args.insert("workgroups".into(), json!(w));
    }
    if let Some(n) = r.info.items {
        args.insert("items".into(), json!(n));
    }
    if let Some(b) = r.info.bytes_bound {
        args.insert("bytes_bound".into(), json!(b));
    }
    if r.info.first_use {
        args.insert("first_use".into(), json!(true));
    }
    args
}

fn first_start(batch: &GpuBatch) -> Option<f64> {
    batch
        .records
        .iter()
        .map(|r| r.start_ns)
        .min_by(|a, b| a.total_cmp(b))
}

/// The clock map a capture supports under `alignment`, and the metadata that says so.
fn clock_map(rec: &Recording, gpu: &GpuRecording, alignment: ClockAlignment) -> (ClockMap, Value) {
    let samples: Vec<(f64, f64)> = gpu
        .calibrations
        .iter()
        .map(|c| (since(rec.origin, c.host) as f64, c.gpu_ns))
        .collect();
    if alignment == ClockAlignment::Best {
        if let Some(map) = ClockMap::calibrated(&samples) {
            let c = &gpu.calibrations[0];
            let deviation = gpu
                .calibrations
                .iter()
                .map(|c| c.max_deviation_ns)
                .fold(0.0, f64::max);
            return (
                map,
                json!({
                    "alignment": "calibrated",
                    "extension": c.extension,
                    "host_domain": c.host_domain,
                    "max_deviation_ns": deviation,
                    "samples": samples.len(),
                    "rate": map.rate,
                }),
            );
        }
    }
    let map = ClockMap::at_submission(
        gpu.batches
            .iter()
            .filter_map(|b| Some((since(rec.origin, b.submitted) as f64, first_start(b)?))),
    );
    let reason = if samples.is_empty() {
        "the device offers no calibrated timestamps"
    } else {
        "asked for"
    };
    (
        map,
        json!({
            "alignment": "submission",
            "reason": reason,
            "note": "each command buffer starts no earlier than its submission; the least delayed starts exactly then",
        }),
    )
}

/// One track per stream (named with its queue), in stream order, plus lanes for any
/// partial overlaps; and the clock metadata.
pub(crate) fn stream_tracks(
    rec: &Recording,
    gpu: &GpuRecording,
    alignment: ClockAlignment,
    spare_tid: &mut u32,
) -> (Vec<Track>, Value) {
    let (map, clock) = clock_map(rec, gpu, alignment);
    let mut tracks = Vec::new();
    for (i, (kind, slot)) in gpu.streams.iter().enumerate() {
        let slices: Vec<Slice> = gpu
            .batches
            .iter()
            .filter(|b| b.stream == *kind)
            .flat_map(|b| &b.records)
            .map(|r| {
                let start_ns = map.host_ns(r.start_ns);
                Slice {
                    name: r.name.clone(),
                    category: "gpu".into(),
                    start_ns,
                    dur_ns: (map.host_ns(r.end_ns) - start_ns).max(0),
                    args: record_args(r),
                }
            })
            .collect();
        let name = format!(
            "{} (queue family {}, index {})",
            kind.name(),
            slot.family,
            slot.index
        );
        tracks.extend(tracks_of(GPU_PID, i as u32 + 1, &name, slices, spare_tid));
    }
    (tracks, clock)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibration_maps_both_samples_exactly() {
        // The GPU clock runs 1e-4 fast against the host over 1 s.
        let map = ClockMap::calibrated(&[(1_000.0, 5e9), (1_000.0 + 1e9, 5e9 + 1.0001e9)]).unwrap();
        assert_eq!(map.host_ns(5e9), 1_000);
        assert_eq!(map.host_ns(5e9 + 1.0001e9), 1_000 + 1_000_000_000);
        // A short capture keeps rate 1.
        let short = ClockMap::calibrated(&[(0.0, 10.0), (1e6, 10.0 + 1e6 + 50.0)]).unwrap();
        assert_eq!(short.rate, 1.0);
        assert_eq!(short.host_ns(110.0), 100);
        assert!(ClockMap::calibrated(&[]).is_none());
    }

    #[test]
    fn submission_alignment_starts_no_batch_before_its_submission() {
        // (host submission, gpu first start): the second batch waited least.
        let batches = [(100.0, 1_000.0), (300.0, 1_150.0), (500.0, 1_500.0)];
        let map = ClockMap::at_submission(batches.iter().copied());
        for (submitted, start) in batches {
            assert!(map.host_ns(start) as f64 >= submitted);
        }
        assert_eq!(map.host_ns(1_150.0), 300);
        assert_eq!(ClockMap::at_submission(std::iter::empty()).host_ns(7.0), 7);
    }
}
