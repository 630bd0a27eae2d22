//! Timelines: the trace-event file of a real path-tracer render, of a PDACRT trace and
//! of streams driven directly parses, has every field the format needs, never partly
//! overlaps events on a track, puts every GPU event inside the host window of the
//! submission that ran it, and shows streams sharing one queue serialised in the order
//! their timeline semaphores demand. The profile tree of the same render adds up.
//!
//! A capture is process-wide (host spans come from every thread), so the tests here take
//! turns.

use crate::common;

use std::collections::BTreeMap;
use std::sync::Mutex;

use serde_json::Value;
use splitray::integrator::IntegratorKind;
use splitray::render::{render, RenderOptions};
use splitray::shaders;
use splitray::timeline::{json, Capture, ClockAlignment, Recording, TimelineError};
use splitray::trace::{PdacrtParams, PdacrtTracer, Query, Tracer};
use splitray::vk::{ComputePipeline, Gpu, PipelineDesc, ProfileNode, StreamKind, StreamPlacement};

static ONE_CAPTURE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn turn() -> std::sync::MutexGuard<'static, ()> {
    ONE_CAPTURE_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

/// Runs `work` inside a capture with `gpu` attached.
fn capture(gpu: &Gpu, work: impl FnOnce()) -> Recording {
    let mut capture = Capture::start().expect("capture");
    capture.attach(gpu).expect("attach");
    work();
    capture.finish().expect("finish")
}

/// One event of the file, in microseconds as written.
#[derive(Clone, Debug)]
struct Event {
    pid: u64,
    tid: u64,
    name: String,
    ts: f64,
    dur: f64,
    args: serde_json::Map<String, Value>,
}

impl Event {
    fn end(&self) -> f64 {
        self.ts + self.dur
    }
    fn arg_str(&self, key: &str) -> Option<&str> {
        self.args.get(key).and_then(Value::as_str)
    }
    fn arg_u64(&self, key: &str) -> Option<u64> {
        self.args.get(key).and_then(Value::as_u64)
    }
}

/// A written file, read back with serde_json alone (not with the library's reader).
struct File {
    doc: Value,
    slices: Vec<Event>,
    /// (pid, tid) → track name.
    tracks: BTreeMap<(u64, u64), String>,
    /// "name series" → samples.
    counters: BTreeMap<String, Vec<(f64, f64)>>,
}

fn number(e: &Value, key: &str) -> f64 {
    e[key]
        .as_f64()
        .unwrap_or_else(|| panic!("\"{key}\" missing or not a number in {e}"))
}

/// Parses the file and checks that every event has the fields its phase needs.
fn parse(text: &str) -> File {
    let doc: Value = serde_json::from_str(text).expect("the file parses as JSON");
    let events = doc["traceEvents"].as_array().expect("traceEvents array");
    assert!(doc["otherData"].is_object(), "otherData holds the metadata");
    let mut file = File {
        doc: doc.clone(),
        slices: Vec::new(),
        tracks: BTreeMap::new(),
        counters: BTreeMap::new(),
    };
    for e in events {
        let ph = e["ph"].as_str().unwrap_or_else(|| panic!("no ph: {e}"));
        let name = e["name"].as_str().unwrap_or_else(|| panic!("no name: {e}"));
        let pid = e["pid"].as_u64().unwrap_or_else(|| panic!("no pid: {e}"));
        match ph {
            "X" => {
                let tid = e["tid"].as_u64().unwrap_or_else(|| panic!("no tid: {e}"));
                let (ts, dur) = (number(e, "ts"), number(e, "dur"));
                assert!(dur >= 0.0, "negative duration: {e}");
                file.slices.push(Event {
                    pid,
                    tid,
                    name: name.into(),
                    ts,
                    dur,
                    args: e["args"].as_object().cloned().unwrap_or_default(),
                });
            }
            "C" => {
                let args = e["args"].as_object().expect("counter args");
                assert!(!args.is_empty(), "a counter event without values: {e}");
                for (series, v) in args {
                    let v = v
                        .as_f64()
                        .unwrap_or_else(|| panic!("non-numeric counter: {e}"));
                    file.counters
                        .entry(format!("{name} {series}"))
                        .or_default()
                        .push((number(e, "ts"), v));
                }
            }
            "M" => {
                assert!(e["args"].is_object(), "metadata without args: {e}");
                if name == "thread_name" {
                    let tid = e["tid"].as_u64().expect("thread_name has a tid");
                    let track = e["args"]["name"].as_str().expect("a thread name");
                    file.tracks.insert((pid, tid), track.into());
                }
            }
            other => panic!("unexpected phase {other}: {e}"),
        }
    }
    for s in &file.slices {
        assert!(
            file.tracks.contains_key(&(s.pid, s.tid)),
            "slice on an unnamed track: {s:?}"
        );
    }
    file
}

/// Events on one track either nest or are disjoint.
fn assert_no_partial_overlaps(file: &File) {
    let mut by_track: BTreeMap<(u64, u64), Vec<&Event>> = BTreeMap::new();
    for s in &file.slices {
        by_track.entry((s.pid, s.tid)).or_default().push(s);
    }
    for (track, mut slices) in by_track {
        slices.sort_by(|a, b| a.ts.total_cmp(&b.ts).then(b.dur.total_cmp(&a.dur)));
        let mut open: Vec<&Event> = Vec::new();
        for s in slices {
            while open.last().is_some_and(|o| o.end() <= s.ts) {
                open.pop();
            }
            if let Some(o) = open.last() {
                assert!(
                    s.end() <= o.end(),
                    "track {track:?}: {s:?} partly overlaps {o:?}"
                );
            }
            open.push(s);
        }
    }
}

/// Every GPU event starts no earlier than the host span that submitted its command
/// buffer and ends no later than the first host wait on that stream that covers it.
/// Returns how many GPU events were checked.
fn assert_gpu_inside_host_windows(file: &File, tolerance_us: f64) -> usize {
    let host: Vec<&Event> = file.slices.iter().filter(|s| s.pid == 1).collect();
    let gpu: Vec<&Event> = file.slices.iter().filter(|s| s.pid == 2).collect();
    for g in &gpu {
        let stream = g.arg_str("stream").expect("GPU events name their stream");
        let value = g
            .arg_u64("submission")
            .expect("GPU events name their submission");
        let submit = host
            .iter()
            .find(|h| {
                h.name.starts_with("submit ")
                    && h.arg_str("stream") == Some(stream)
                    && h.arg_u64("value") == Some(value)
            })
            .unwrap_or_else(|| panic!("no submit span for {stream}@{value}"));
        assert!(
            g.ts >= submit.ts - tolerance_us,
            "{} on {stream}@{value} starts at {} µs, before its submission at {} µs",
            g.name,
            g.ts,
            submit.ts
        );
        let wait = host
            .iter()
            .filter(|h| {
                h.name.starts_with("wait ")
                    && h.arg_str("stream") == Some(stream)
                    && h.arg_u64("value").is_some_and(|v| v >= value)
                    && h.end() >= submit.ts
            })
            .min_by(|a, b| a.end().total_cmp(&b.end()))
            .unwrap_or_else(|| panic!("no host wait covers {stream}@{value}"));
        assert!(
            g.end() <= wait.end() + tolerance_us,
            "{} on {stream}@{value} ends at {} µs, after the wait for it returned at {} µs",
            g.name,
            g.end(),
            wait.end()
        );
    }
    gpu.len()
}

/// The deviation the file's clock metadata allows, in µs (plus 1 ns of rounding).
fn clock_tolerance_us(file: &File) -> f64 {
    let clock = &file.doc["otherData"]["clock"];
    clock["max_deviation_ns"].as_f64().unwrap_or(0.0) * 1e-3 + 1e-3
}

fn assert_adds_up(node: &ProfileNode) {
    let children: f64 = node.children.iter().map(|c| c.total_ms).sum();
    assert!(
        (node.self_ms + children - node.total_ms).abs() <= 1e-9 * node.total_ms.max(1.0),
        "{}: self {} + children {} != total {}",
        node.name,
        node.self_ms,
        children,
        node.total_ms
    );
    node.children.iter().for_each(assert_adds_up);
}

#[test]
fn a_path_tracer_render_makes_a_well_formed_timeline_and_a_profile_tree_that_adds_up() {
    let _turn = turn();
    let gpu = common::gpu();
    let scene = splitray::scene::load("cornell-box").unwrap();
    let options = RenderOptions::resolve(
        &scene,
        Some(16),
        Some(16),
        Some(2),
        Some(3),
        Some(IntegratorKind::Pt),
        None,
    )
    .unwrap();
    let mut output = None;
    let recording = capture(&gpu, || {
        output = Some(render(&gpu, &scene, &options, &mut |_| {}).unwrap());
    });
    let stats = output.unwrap().stats;
    let calibrated = !gpu.info().calibrated_time_domains.is_empty();

    for alignment in [ClockAlignment::Best, ClockAlignment::Submission] {
        let file = parse(&json::to_json(&recording.trace(alignment)));
        let clock = file.doc["otherData"]["clock"]["alignment"]
            .as_str()
            .unwrap();
        let expected = if calibrated && alignment == ClockAlignment::Best {
            "calibrated"
        } else {
            "submission"
        };
        assert_eq!(clock, expected);
        assert_no_partial_overlaps(&file);
        let checked = assert_gpu_inside_host_windows(&file, clock_tolerance_us(&file));
        assert!(checked > 20, "only {checked} GPU events");

        // One track per stream, named with its queue; host work on the test's thread.
        for stream in ["main", "aux0", "aux1", "transfer"] {
            assert!(
                file.tracks.iter().any(|((pid, _), n)| *pid == 2
                    && n.starts_with(stream)
                    && n.contains("queue family")),
                "no track for stream {stream}: {:?}",
                file.tracks
            );
        }
        let host_names: Vec<&str> = file
            .slices
            .iter()
            .filter(|s| s.pid == 1)
            .map(|s| s.name.as_str())
            .collect();
        for prefix in [
            "create pipeline ",
            "record main",
            "submit main@",
            "wait main@",
            "readback ",
            "pt bounce",
            "pdacrt trace",
        ] {
            assert!(
                host_names.iter().any(|n| n.starts_with(prefix)),
                "no host span {prefix:?}"
            );
        }
        // Dispatches carry their work.
        let shade = file
            .slices
            .iter()
            .find(|s| s.name == "integrator_pt_shade")
            .expect("a shading dispatch");
        assert!(shade.arg_u64("items").is_some_and(|n| n > 0));
        assert!(shade.args["workgroups"].is_array());
        assert!(shade.arg_u64("bytes_bound").is_some_and(|b| b > 0));
        let live = &file.counters["pt live paths"];
        // The render loop's first batch is one pass (it times a pass before it sizes
        // the batches after it): its bounce 0 starts every path of that pass.
        assert_eq!(live[0].1, 16.0 * 16.0, "bounce 0 starts every path");
        assert!(file.counters["GPU memory bytes"]
            .iter()
            .any(|&(_, v)| v > 0.0));

        // The profile tree adds up, and its total is the time of the outermost GPU
        // events of the same render.
        stats.profile.roots.iter().for_each(assert_adds_up);
        let outermost: f64 = {
            let mut gpu_slices: Vec<&Event> = file.slices.iter().filter(|s| s.pid == 2).collect();
            gpu_slices.sort_by(|a, b| a.ts.total_cmp(&b.ts).then(b.dur.total_cmp(&a.dur)));
            let mut reach = f64::MIN;
            let mut total = 0.0;
            for s in gpu_slices {
                if s.ts >= reach {
                    total += s.dur;
                    reach = s.end();
                }
            }
            total * 1e-3
        };
        assert!(
            (stats.profile.total_ms - outermost).abs() <= 1e-3 * stats.profile.total_ms + 1e-2,
            "tree {} ms, timeline {} ms",
            stats.profile.total_ms,
            outermost
        );
    }
    assert!(stats.samples_per_second > 0.0);
    common::assert_clean(&gpu);
}

#[test]
fn a_pdacrt_trace_counts_rays_per_level_with_its_scopes_nested() {
    let _turn = turn();
    let gpu = common::gpu();
    let triangles = common::triangle_soup(3000, 11);
    let rays = common::random_rays(20_000, 12);
    let params = PdacrtParams::for_device(&gpu);
    let mut tracer = PdacrtTracer::with_params(&gpu, &triangles, params).unwrap();
    let ray_buf = gpu.upload("rays", &rays).unwrap();
    let hit_buf = gpu
        .zeroed::<splitray::trace::Hit>("hits", rays.len())
        .unwrap();
    let recording = capture(&gpu, || {
        let done = tracer
            .trace(
                &ray_buf,
                &hit_buf,
                rays.len() as u32,
                Query::ClosestHit,
                &[],
            )
            .unwrap();
        gpu.wait(&done).unwrap();
    });
    let levels = tracer.stats().levels.clone();
    assert!(levels.len() >= 2, "the soup splits into levels");
    let file = parse(&json::to_json(&recording.trace(ClockAlignment::Best)));
    assert_no_partial_overlaps(&file);
    assert_gpu_inside_host_windows(&file, clock_tolerance_us(&file));

    // The counter follows the level loop: the root level holds every ray, then one
    // sample per level, and zero once the trace is done.
    let samples: Vec<f64> = file.counters["pdacrt rays per level"]
        .iter()
        .map(|&(_, v)| v)
        .collect();
    let expected: Vec<f64> = levels.iter().map(|l| l.rays as f64).chain([0.0]).collect();
    assert_eq!(samples, expected);
    assert_eq!(samples[0], rays.len() as f64);

    // Kernels of a level sit inside its scope on the main stream's track.
    let level = file
        .slices
        .iter()
        .find(|s| s.name == "pdacrt-level")
        .expect("a level scope");
    let inside = file
        .slices
        .iter()
        .filter(|s| (s.pid, s.tid) == (level.pid, level.tid) && s.name != "pdacrt-level")
        .filter(|s| s.ts >= level.ts && s.end() <= level.end())
        .count();
    assert!(inside >= 2, "{inside} kernels inside the level scope");
    common::assert_clean(&gpu);
}

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct CopyPush {
    n: u32,
    add: u32,
}

#[test]
fn streams_forced_onto_one_queue_appear_serialised_in_timeline_semaphore_order() {
    let _turn = turn();
    let gpu = common::gpu_with(StreamPlacement::SingleQueue, false);
    assert!(gpu.stream_mapping().is_single_queue());
    let pipeline = ComputePipeline::new(
        &gpu,
        &PipelineDesc {
            kernel: shaders::TEST_COPY_WORDS,
            bindings: 2,
            push_constant_bytes: 8,
            spec: &[64],
        },
    )
    .unwrap();
    let n = 200_000usize;
    let a = gpu.upload("a", &common::random_u32s(n, 5)).unwrap();
    let b = gpu.zeroed::<u32>("b", n).unwrap();
    let push = CopyPush {
        n: n as u32,
        add: 1,
    };
    // aux1 → aux0 → aux1 → aux0, each step waiting on the one before: the submission
    // order of the streams alternates, and only the semaphores order the steps.
    let chain = [
        StreamKind::Aux1,
        StreamKind::Aux0,
        StreamKind::Aux1,
        StreamKind::Aux0,
    ];
    let mut steps = Vec::new();
    let recording = capture(&gpu, || {
        let mut last = None;
        for (i, &stream) in chain.iter().enumerate() {
            let mut rec = gpu.recorder(stream).unwrap();
            let (src, dst) = if i % 2 == 0 { (&a, &b) } else { (&b, &a) };
            for _ in 0..3 {
                rec.dispatch_items(&pipeline, &[src.into(), dst.into()], &push, n as u64)
                    .unwrap();
                rec.barrier();
            }
            let waits: Vec<_> = last.iter().collect();
            let point = rec.submit(&waits).unwrap();
            steps.push((stream, point.value));
            last = Some(point);
        }
        gpu.wait(last.as_ref().unwrap()).unwrap();
    });
    let file = parse(&json::to_json(&recording.trace(ClockAlignment::Best)));
    assert_no_partial_overlaps(&file);
    assert_gpu_inside_host_windows(&file, clock_tolerance_us(&file));
    let span_of = |(stream, value): (StreamKind, u64)| {
        let events: Vec<&Event> = file
            .slices
            .iter()
            .filter(|s| {
                s.pid == 2
                    && s.arg_str("stream") == Some(stream.name())
                    && s.arg_u64("submission") == Some(value)
            })
            .collect();
        assert_eq!(events.len(), 3, "{stream:?}@{value}");
        (
            events.iter().map(|e| e.ts).fold(f64::MAX, f64::min),
            events.iter().map(|e| e.end()).fold(f64::MIN, f64::max),
        )
    };
    let spans: Vec<(f64, f64)> = steps.iter().map(|&s| span_of(s)).collect();
    for (i, w) in spans.windows(2).enumerate() {
        assert!(
            w[0].1 <= w[1].0,
            "step {i} ({:?}) ends at {} µs after step {} starts at {} µs",
            steps[i],
            w[0].1,
            i + 1,
            w[1].0
        );
    }
    // Both streams' tracks name the one queue they share.
    let names: Vec<&String> = file
        .tracks
        .iter()
        .filter(|((pid, _), _)| *pid == 2)
        .map(|(_, n)| n)
        .collect();
    assert!(
        names.iter().all(|n| n.contains("queue family 0, index 0")),
        "{names:?}"
    );
    common::assert_clean(&gpu);
}

#[test]
fn spans_of_rayon_workers_land_on_their_own_tracks() {
    let _turn = turn();
    let triangles = common::triangle_soup(64, 3);
    let rays = common::random_rays(50_000, 4);
    let capture = Capture::start().unwrap();
    assert!(
        matches!(Capture::start(), Err(TimelineError::AlreadyCapturing)),
        "one capture at a time"
    );
    let hits = splitray::trace::cpu::closest_hits(&rays, &triangles);
    assert_eq!(hits.len(), rays.len());
    let file = parse(&json::to_json(
        &capture.finish().unwrap().trace(ClockAlignment::Best),
    ));
    assert_no_partial_overlaps(&file);
    let chunks: Vec<&Event> = file
        .slices
        .iter()
        .filter(|s| s.name == "cpu closest hits")
        .collect();
    assert_eq!(chunks.len(), rays.len().div_ceil(4096));
    let covered: u64 = chunks.iter().map(|c| c.arg_u64("rays").unwrap()).sum();
    assert_eq!(covered, rays.len() as u64);
    for c in &chunks {
        let track = &file.tracks[&(c.pid, c.tid)];
        assert!(
            track.starts_with("rayon worker"),
            "a chunk on track {track:?}"
        );
    }
}

fn splitray(args: &[&str], cwd: &std::path::Path) -> (bool, String) {
    let out = common::cli::splitray(args, cwd);
    let text = common::cli::printed(&out);
    assert!(!text.contains("panicked"), "{text}");
    (out.status.success(), text)
}

#[test]
fn render_writes_a_timeline_that_timeline_draws_and_bad_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ok, text) = splitray(
        &[
            "render",
            "cornell-box",
            "-o",
            "img.exr",
            "--width",
            "8",
            "--height",
            "8",
            "--validation",
            "--profile",
            "--timeline",
            "t.json",
        ],
        d,
    );
    assert!(ok, "{text}");
    assert!(
        text.contains("all scopes"),
        "the profile tree is printed:\n{text}"
    );
    let file = parse(&std::fs::read_to_string(d.join("t.json")).unwrap());
    assert_no_partial_overlaps(&file);
    assert_gpu_inside_host_windows(&file, clock_tolerance_us(&file));
    assert!(file.doc["otherData"]["command"]
        .as_str()
        .unwrap()
        .contains("--timeline"));
    for out in ["t.svg", "t.png"] {
        let (ok, text) = splitray(&["timeline", "t.json", "-o", out], d);
        assert!(ok, "{text}");
        assert!(text.contains("clock alignment"), "{text}");
    }
    let svg = std::fs::read_to_string(d.join("t.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("main (queue family"));
    let png = std::fs::read(d.join("t.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");

    // Bad input: a clear error naming the file, a non-zero exit, nothing written.
    std::fs::write(d.join("bad.json"), "{\"traceEvents\": [{\"ph\": \"X\"}]}").unwrap();
    for (args, expect) in [
        (&["timeline", "bad.json", "-o", "bad.svg"][..], "bad.json"),
        (
            &["timeline", "missing.json", "-o", "bad.svg"][..],
            "missing.json",
        ),
        (&["timeline", "t.json", "-o", "bad.pdf"][..], ".svg or .png"),
        (
            &["timeline", "t.json", "-o", "bad.svg", "--width", "0"][..],
            "520..=32768",
        ),
        (
            &["timeline", "t.json", "-o", "nowhere/bad.svg"][..],
            "nowhere",
        ),
        // An endless window drew forever.
        (
            &["timeline", "t.json", "-o", "bad.svg", "--to", "inf"][..],
            "--to inf: a time window needs finite bounds",
        ),
        (
            &["render", "-o", "bad.exr", "--timeline", "bad.txt"][..],
            ".json",
        ),
        (
            &["render", "-o", "bad.exr", "--timeline", "nowhere/t.json"][..],
            "nowhere",
        ),
    ] {
        let (ok, text) = splitray(args, d);
        assert!(!ok, "{args:?} succeeded");
        assert!(
            text.contains(expect),
            "{args:?}: expected {expect:?} in:\n{text}"
        );
    }
    let mut left: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("bad.") && n != "bad.json" || n.contains(".tmp"))
        .collect();
    left.sort();
    assert!(left.is_empty(), "left behind: {left:?}");
}
