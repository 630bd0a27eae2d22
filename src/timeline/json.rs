//! The Chrome trace-event JSON format (the "JSON Object Format" of the Trace Event
//! Format document), as ui.perfetto.dev and chrome://tracing read it:
//!
//! - `M` metadata events name processes and threads (a thread is a track) and order them;
//! - `X` complete events are slices: `ts` and `dur` in microseconds, written here with
//!   three decimals so that integer nanoseconds round-trip exactly and nesting survives;
//! - `C` counter events carry one numeric arg per series;
//! - `otherData` holds the metadata (device, clock alignment, streams).
//!
//! One event per line, slices in time order (enclosing ones first).

use std::fmt::Write as _;

use serde_json::{json, Map, Value};

use super::model::{sort_slices, Counter, Process, Slice, Trace, Track};
use super::TimelineError;

/// `ns` as microseconds with exactly three decimals.
fn micros(ns: i64) -> String {
    let sign = if ns < 0 { "-" } else { "" };
    let abs = ns.unsigned_abs();
    format!("{sign}{}.{:03}", abs / 1000, abs % 1000)
}

fn json_string(s: &str) -> String {
    Value::String(s.to_string()).to_string()
}

fn metadata_event(out: &mut String, pid: u32, tid: Option<u32>, name: &str, args: Value) {
    let tid = tid.map_or(String::new(), |t| format!(",\"tid\":{t}"));
    let _ = writeln!(
        out,
        "{{\"ph\":\"M\",\"pid\":{pid}{tid},\"name\":\"{name}\",\"args\":{args}}},"
    );
}

/// The trace as a trace-event JSON document.
pub fn to_json(trace: &Trace) -> String {
    let mut out = String::from("{\"displayTimeUnit\":\"ns\",\n\"otherData\":");
    out.push_str(&Value::Object(trace.metadata.clone()).to_string());
    out.push_str(",\n\"traceEvents\":[\n");
    for (i, p) in trace.processes.iter().enumerate() {
        metadata_event(
            &mut out,
            p.pid,
            None,
            "process_name",
            json!({"name": p.name}),
        );
        metadata_event(
            &mut out,
            p.pid,
            None,
            "process_sort_index",
            json!({"sort_index": i}),
        );
    }
    let mut slices: Vec<(&Track, &Slice)> = Vec::new();
    for (i, t) in trace.tracks.iter().enumerate() {
        metadata_event(
            &mut out,
            t.pid,
            Some(t.tid),
            "thread_name",
            json!({"name": t.name}),
        );
        metadata_event(
            &mut out,
            t.pid,
            Some(t.tid),
            "thread_sort_index",
            json!({"sort_index": i}),
        );
        slices.extend(t.slices.iter().map(|s| (t, s)));
    }
    slices.sort_by(|(_, a), (_, b)| a.start_ns.cmp(&b.start_ns).then(b.dur_ns.cmp(&a.dur_ns)));
    for (t, s) in slices {
        let _ = writeln!(
            out,
            "{{\"ph\":\"X\",\"pid\":{},\"tid\":{},\"ts\":{},\"dur\":{},\"name\":{},\"cat\":{},\"args\":{}}},",
            t.pid,
            t.tid,
            micros(s.start_ns),
            micros(s.dur_ns),
            json_string(&s.name),
            json_string(&s.category),
            Value::Object(s.args.clone())
        );
    }
    for c in &trace.counters {
        for &(ts, value) in &c.samples {
            let _ = writeln!(
                out,
                "{{\"ph\":\"C\",\"pid\":{},\"ts\":{},\"name\":{},\"args\":{{{}:{}}}}},",
                c.pid,
                micros(ts),
                json_string(&c.name),
                json_string(&c.series),
                json!(value)
            );
        }
    }
    // Every event line ends in a comma; the last one must not.
    if out.ends_with(",\n") {
        out.truncate(out.len() - 2);
        out.push('\n');
    }
    out.push_str("]}\n");
    out
}

fn field<'a>(event: &'a Value, key: &str, index: usize) -> Result<&'a Value, TimelineError> {
    event
        .get(key)
        .ok_or_else(|| TimelineError::Format(format!("event {index} has no \"{key}\"")))
}

fn number(event: &Value, key: &str, index: usize) -> Result<f64, TimelineError> {
    field(event, key, index)?
        .as_f64()
        .ok_or_else(|| TimelineError::Format(format!("event {index}: \"{key}\" is not a number")))
}

fn id(event: &Value, key: &str, index: usize) -> Result<u32, TimelineError> {
    let n = number(event, key, index)?;
    if n < 0.0 || n > u32::MAX as f64 || n.fract() != 0.0 {
        return Err(TimelineError::Format(format!(
            "event {index}: \"{key}\" {n} is not a process or thread id"
        )));
    }
    Ok(n as u32)
}

/// `key` of event `index`, microseconds, as nanoseconds: refused where it is not finite
/// or beyond the ±106 days that i64 nanoseconds hold (a cast would clamp it silently,
/// and a clamped slice would stretch the chart over nothing).
fn time_ns(event: &Value, key: &str, index: usize) -> Result<i64, TimelineError> {
    let micros = number(event, key, index)?;
    let ns = (micros * 1000.0).round();
    if !ns.is_finite() || ns.abs() >= i64::MAX as f64 {
        return Err(TimelineError::Format(format!(
            "event {index}: \"{key}\" {micros:e} µs is not a time a trace can hold"
        )));
    }
    Ok(ns as i64)
}

fn track(tracks: &mut Vec<Track>, pid: u32, tid: u32) -> &mut Track {
    match tracks.iter().position(|t| t.pid == pid && t.tid == tid) {
        Some(i) => &mut tracks[i],
        None => {
            tracks.push(Track {
                pid,
                tid,
                name: format!("thread {tid}"),
                slices: Vec::new(),
            });
            tracks.last_mut().unwrap()
        }
    }
}

/// The events of a document and its metadata (`otherData`; none in the bare-array form).
fn events_and_metadata(doc: &Value) -> Result<(&Vec<Value>, Map<String, Value>), TimelineError> {
    match doc {
        Value::Array(events) => Ok((events, Map::new())),
        Value::Object(o) => Ok((
            o.get("traceEvents")
                .and_then(Value::as_array)
                .ok_or_else(|| TimelineError::Format("no \"traceEvents\" array".into()))?,
            o.get("otherData")
                .and_then(Value::as_object)
                .cloned()
                .unwrap_or_default(),
        )),
        _ => Err(TimelineError::Format(
            "neither an object nor an array".into(),
        )),
    }
}

/// The sort indices that `M` events give processes and tracks.
#[derive(Default)]
struct SortIndices {
    processes: Vec<(u32, f64)>,
    tracks: Vec<((u32, u32), f64)>,
}

impl SortIndices {
    /// Orders `tracks` by their process's sort index, then their own, then by id; a
    /// process or track without an index comes after those with one.
    fn sort(&self, tracks: &mut [Track]) {
        let process_rank = |pid: u32| {
            self.processes
                .iter()
                .find(|(p, _)| *p == pid)
                .map_or(f64::MAX, |(_, r)| *r)
        };
        let track_rank = |t: &Track| {
            self.tracks
                .iter()
                .find(|(k, _)| *k == (t.pid, t.tid))
                .map_or(f64::MAX, |(_, r)| *r)
        };
        tracks.sort_by(|a, b| {
            process_rank(a.pid)
                .total_cmp(&process_rank(b.pid))
                .then(track_rank(a).total_cmp(&track_rank(b)))
                .then((a.pid, a.tid).cmp(&(b.pid, b.tid)))
        });
    }
}

/// An `X` event, `index` in the document: a slice on its track.
fn read_slice(
    trace: &mut Trace,
    e: &Value,
    index: usize,
    name: &str,
    args: Map<String, Value>,
) -> Result<(), TimelineError> {
    let slice = Slice {
        name: name.to_string(),
        category: e
            .get("cat")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string(),
        start_ns: time_ns(e, "ts", index)?,
        dur_ns: time_ns(e, "dur", index)?,
        args,
    };
    if slice.dur_ns < 0 || slice.start_ns.checked_add(slice.dur_ns).is_none() {
        return Err(TimelineError::Format(format!(
            "event {index}: a slice of negative duration or ending past the time a trace can hold"
        )));
    }
    track(
        &mut trace.tracks,
        id(e, "pid", index)?,
        id(e, "tid", index)?,
    )
    .slices
    .push(slice);
    Ok(())
}

/// A `C` event, `index` in the document: a sample of each of its numeric series.
fn read_counter_samples(
    counters: &mut Vec<Counter>,
    e: &Value,
    index: usize,
    name: &str,
    args: Map<String, Value>,
) -> Result<(), TimelineError> {
    let (pid, ts) = (id(e, "pid", index)?, time_ns(e, "ts", index)?);
    for (series, value) in args {
        let Some(value) = value.as_f64() else {
            continue;
        };
        match counters
            .iter_mut()
            .find(|c| c.pid == pid && c.name == name && c.series == series)
        {
            Some(c) => c.samples.push((ts, value)),
            None => counters.push(Counter {
                pid,
                name: name.to_string(),
                series,
                samples: vec![(ts, value)],
            }),
        }
    }
    Ok(())
}

/// An `M` event, `index` in the document: a process's or track's name or sort index.
fn read_metadata_event(
    trace: &mut Trace,
    order: &mut SortIndices,
    e: &Value,
    index: usize,
    name: &str,
    args: &Map<String, Value>,
) -> Result<(), TimelineError> {
    let pid = id(e, "pid", index)?;
    let arg = |k: &str| args.get(k).cloned().unwrap_or(Value::Null);
    match name {
        "process_name" => trace.processes.push(Process {
            pid,
            name: arg("name").as_str().unwrap_or("").to_string(),
        }),
        "process_sort_index" => order
            .processes
            .push((pid, arg("sort_index").as_f64().unwrap_or(0.0))),
        "thread_name" => {
            let tid = id(e, "tid", index)?;
            track(&mut trace.tracks, pid, tid).name =
                arg("name").as_str().unwrap_or("").to_string();
        }
        "thread_sort_index" => order.tracks.push((
            (pid, id(e, "tid", index)?),
            arg("sort_index").as_f64().unwrap_or(0.0),
        )),
        _ => {}
    }
    Ok(())
}

/// Reads a trace-event JSON document (object form with `traceEvents`, or a bare array)
/// back into a [`Trace`]: `X` slices, `C` counters, names and sort orders from `M`
/// events; other phases are skipped.
pub fn from_json(text: &str) -> Result<Trace, TimelineError> {
    let doc: Value = serde_json::from_str(text)?;
    let (events, metadata) = events_and_metadata(&doc)?;
    let mut trace = Trace {
        metadata,
        ..Default::default()
    };
    let mut order = SortIndices::default();
    for (i, e) in events.iter().enumerate() {
        let phase = field(e, "ph", i)?.as_str().unwrap_or("");
        let name = e.get("name").and_then(Value::as_str).unwrap_or("");
        let args = e
            .get("args")
            .and_then(Value::as_object)
            .cloned()
            .unwrap_or_default();
        match phase {
            "X" => read_slice(&mut trace, e, i, name, args)?,
            "C" => read_counter_samples(&mut trace.counters, e, i, name, args)?,
            "M" => read_metadata_event(&mut trace, &mut order, e, i, name, &args)?,
            _ => {}
        }
    }
    order.sort(&mut trace.tracks);
    for t in &mut trace.tracks {
        sort_slices(&mut t.slices);
    }
    for c in &mut trace.counters {
        c.samples.sort_by_key(|&(t, _)| t);
    }
    Ok(trace)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timeline::{GPU_PID, HOST_PID};

    fn sample_trace() -> Trace {
        let slice = |name: &str, start: i64, dur: i64| Slice {
            name: name.into(),
            category: "gpu".into(),
            start_ns: start,
            dur_ns: dur,
            args: json!({"items": 7, "stream": "main"})
                .as_object()
                .unwrap()
                .clone(),
        };
        Trace {
            metadata: json!({"clock": {"alignment": "calibrated"}})
                .as_object()
                .unwrap()
                .clone(),
            processes: vec![
                Process {
                    pid: GPU_PID,
                    name: "GPU: \"x\"".into(),
                },
                Process {
                    pid: HOST_PID,
                    name: "host".into(),
                },
            ],
            tracks: vec![
                Track {
                    pid: GPU_PID,
                    tid: 1,
                    name: "main (queue family 0, index 0)".into(),
                    slices: vec![slice("level", 1_001, 5_000), slice("split\n", 1_001, 999)],
                },
                Track {
                    pid: HOST_PID,
                    tid: 3,
                    name: "main".into(),
                    slices: vec![slice("wait", -7, 12_345_678)],
                },
            ],
            counters: vec![Counter {
                pid: GPU_PID,
                name: "pt".into(),
                series: "live paths".into(),
                samples: vec![(0, 4096.0), (2_500, 12.0)],
            }],
        }
    }

    #[test]
    fn microseconds_keep_every_nanosecond() {
        assert_eq!(micros(0), "0.000");
        assert_eq!(micros(1), "0.001");
        assert_eq!(micros(12_345_678), "12345.678");
        assert_eq!(micros(-7), "-0.007");
    }

    #[test]
    fn a_trace_round_trips_through_its_json() {
        let trace = sample_trace();
        let text = to_json(&trace);
        let doc: Value = serde_json::from_str(&text).expect("valid JSON");
        assert!(doc["traceEvents"]
            .as_array()
            .unwrap()
            .iter()
            .all(|e| e["ph"].is_string()));
        assert_eq!(from_json(&text).unwrap(), trace);
    }

    #[test]
    fn bad_documents_are_refused_with_the_reason() {
        let err = |t: &str| from_json(t).unwrap_err().to_string();
        assert!(err("{").contains("JSON"));
        assert!(err("{\"x\": 1}").contains("traceEvents"));
        assert!(
            err("[{\"ph\":\"X\",\"pid\":1,\"tid\":1,\"ts\":0}]").contains("event 0 has no \"dur\"")
        );
        assert!(err("[{\"ph\":\"X\",\"pid\":-1,\"tid\":1,\"ts\":0,\"dur\":1}]").contains("pid"));
        assert_eq!(from_json("[]").unwrap(), Trace::default());
    }

    #[test]
    fn times_a_trace_cannot_hold_are_refused() {
        let slice = |ts: &str, dur: &str| {
            from_json(&format!(
                "[{{\"ph\":\"X\",\"pid\":1,\"tid\":1,\"ts\":{ts},\"dur\":{dur}}}]"
            ))
            .map_err(|e| e.to_string())
        };
        assert!(slice("0", "-5").unwrap_err().contains("negative duration"));
        assert!(slice("1e308", "1").unwrap_err().contains("\"ts\" 1e308"));
        assert!(slice("0", "1e20").unwrap_err().contains("\"dur\""));
        assert!(slice("5e15", "5e15").unwrap_err().contains("event 0"));
        let counter = "[{\"ph\":\"C\",\"pid\":1,\"ts\":-1e300,\"name\":\"c\",\"args\":{\"v\":1}}]";
        assert!(from_json(counter)
            .unwrap_err()
            .to_string()
            .contains("\"ts\""));
        // Times before the capture began are times too.
        let end = slice("-1", "1").unwrap().tracks[0].slices[0].clone();
        assert_eq!((end.start_ns, end.dur_ns), (-1000, 1000));
    }
}
