//! Recording a timeline: host spans and counters from `tracing`, GPU scopes from the
//! device.
//!
//! The first capture installs a global `tracing` subscriber with one layer that keeps a
//! span's lifetime (creation to close) as a slice on the track of the thread that
//! created it. Between captures the layer declines every span after one relaxed atomic
//! load, and before the first capture no subscriber exists at all, so instrumented code
//! costs what `tracing` costs with nothing listening.

use std::cell::Cell;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

use serde_json::{json, Map, Value};
use tracing::field::{Field, Visit};
use tracing::span::{Attributes, Id, Record};
use tracing::{Event, Metadata, Subscriber};
use tracing_subscriber::layer::{Context, Layer, SubscriberExt};
use tracing_subscriber::registry::LookupSpan;

use super::model::{tracks_of, Counter, Process, Slice, Trace, GPU_PID, HOST_PID};
use super::TimelineError;
use crate::vk::{ClockCalibration, Gpu, GpuBatch, QueueSlot, StreamKind};

/// The `tracing` target of counter events ([`timeline_counter!`](crate::timeline_counter)).
const COUNTER_TARGET: &str = "splitray::counter";

static CAPTURING: AtomicBool = AtomicBool::new(false);
static HOST_LOG: Mutex<Option<HostLog>> = Mutex::new(None);
static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();
static NEXT_THREAD: AtomicU32 = AtomicU32::new(1);

thread_local! {
    /// This thread's track number (0 until its first span during a capture).
    static THREAD_TRACK: Cell<u32> = const { Cell::new(0) };
}

/// A finished host span.
#[derive(Clone, Debug)]
pub(crate) struct HostSpan {
    pub(crate) thread: u32,
    pub(crate) name: String,
    pub(crate) start: Instant,
    pub(crate) end: Instant,
    pub(crate) args: Map<String, Value>,
}

/// One counter sample.
#[derive(Clone, Debug)]
pub(crate) struct HostCounter {
    pub(crate) name: String,
    pub(crate) series: String,
    pub(crate) at: Instant,
    pub(crate) value: f64,
}

#[derive(Default)]
struct HostLog {
    spans: Vec<HostSpan>,
    counters: Vec<HostCounter>,
    /// Track number → thread name.
    threads: BTreeMap<u32, String>,
}

/// A span that is still open: kept in the span's registry extensions.
struct OpenSpan {
    thread: u32,
    name: String,
    start: Instant,
    args: Map<String, Value>,
}

/// The calling thread's track number, registering its name on first use.
fn thread_track(log: &mut HostLog) -> u32 {
    let mut id = THREAD_TRACK.with(Cell::get);
    if id == 0 {
        id = NEXT_THREAD.fetch_add(1, Ordering::Relaxed);
        THREAD_TRACK.with(|t| t.set(id));
    }
    log.threads.entry(id).or_insert_with(|| {
        let current = std::thread::current();
        match (current.name(), rayon::current_thread_index()) {
            (Some(name), _) => name.to_string(),
            (None, Some(i)) => format!("rayon worker {i}"),
            (None, None) => format!("thread {id}"),
        }
    });
    id
}

/// Collects a span's or event's fields: `what` joins the name, the rest become args.
#[derive(Default)]
struct Fields {
    what: Option<String>,
    args: Map<String, Value>,
}

impl Visit for Fields {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        self.record_value(field, Value::String(format!("{value:?}")));
    }
    fn record_str(&mut self, field: &Field, value: &str) {
        self.record_value(field, Value::String(value.to_string()));
    }
    fn record_u64(&mut self, field: &Field, value: u64) {
        self.record_value(field, json!(value));
    }
    fn record_i64(&mut self, field: &Field, value: i64) {
        self.record_value(field, json!(value));
    }
    fn record_f64(&mut self, field: &Field, value: f64) {
        self.record_value(field, json!(value));
    }
    fn record_bool(&mut self, field: &Field, value: bool) {
        self.record_value(field, json!(value));
    }
}

impl Fields {
    fn record_value(&mut self, field: &Field, value: Value) {
        if field.name() == "what" {
            self.what = Some(match value {
                Value::String(s) => s,
                other => other.to_string(),
            });
        } else {
            self.args.insert(field.name().to_string(), value);
        }
    }
}

struct CaptureLayer;

impl<S> Layer<S> for CaptureLayer
where
    S: Subscriber + for<'a> LookupSpan<'a>,
{
    fn register_callsite(&self, _: &'static Metadata<'static>) -> tracing::subscriber::Interest {
        // Asked again at every span, so that captures can start and stop.
        tracing::subscriber::Interest::sometimes()
    }

    fn enabled(&self, _: &Metadata<'_>, _: Context<'_, S>) -> bool {
        CAPTURING.load(Ordering::Relaxed)
    }

    fn on_new_span(&self, attrs: &Attributes<'_>, id: &Id, ctx: Context<'_, S>) {
        let mut fields = Fields::default();
        attrs.record(&mut fields);
        let name = match fields.what {
            Some(what) => format!("{} {what}", attrs.metadata().name()),
            None => attrs.metadata().name().to_string(),
        };
        let thread = match HOST_LOG.lock().unwrap().as_mut() {
            Some(log) => thread_track(log),
            None => return,
        };
        if let Some(span) = ctx.span(id) {
            span.extensions_mut().insert(OpenSpan {
                thread,
                name,
                start: Instant::now(),
                args: fields.args,
            });
        }
    }

    fn on_record(&self, id: &Id, values: &Record<'_>, ctx: Context<'_, S>) {
        if let Some(span) = ctx.span(id) {
            if let Some(open) = span.extensions_mut().get_mut::<OpenSpan>() {
                let mut fields = Fields::default();
                values.record(&mut fields);
                open.args.extend(fields.args);
            }
        }
    }

    fn on_event(&self, event: &Event<'_>, _: Context<'_, S>) {
        if event.metadata().target() != COUNTER_TARGET {
            return;
        }
        let at = Instant::now();
        let mut fields = Fields::default();
        event.record(&mut fields);
        let text = |key: &str| match fields.args.get(key) {
            Some(Value::String(s)) => s.clone(),
            _ => key.to_string(),
        };
        let Some(value) = fields.args.get("value").and_then(Value::as_f64) else {
            return;
        };
        if let Some(log) = HOST_LOG.lock().unwrap().as_mut() {
            log.counters.push(HostCounter {
                name: text("counter"),
                series: text("series"),
                at,
                value,
            });
        }
    }

    fn on_close(&self, id: Id, ctx: Context<'_, S>) {
        let end = Instant::now();
        let Some(open) = ctx
            .span(&id)
            .and_then(|span| span.extensions_mut().remove::<OpenSpan>())
        else {
            return;
        };
        if let Some(log) = HOST_LOG.lock().unwrap().as_mut() {
            log.spans.push(HostSpan {
                thread: open.thread,
                name: open.name,
                start: open.start,
                end,
                args: open.args,
            });
        }
    }
}

/// Installs the capture layer as the process's `tracing` subscriber, once.
fn install() -> Result<(), TimelineError> {
    INSTALLED
        .get_or_init(|| {
            let subscriber = tracing_subscriber::registry().with(CaptureLayer);
            tracing::subscriber::set_global_default(subscriber).map_err(|e| {
                format!("another tracing subscriber is installed in this process ({e})")
            })
        })
        .clone()
        .map_err(TimelineError::Subscriber)
}

/// How GPU times are placed on the host clock.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ClockAlignment {
    /// By calibrated timestamps where the device offers them, else at submission.
    #[default]
    Best,
    /// At submission even where calibration is possible (each command buffer starts no
    /// earlier than the host submitted it, and the earliest-starting one exactly then).
    Submission,
}

/// A running timeline capture. One at a time per process; dropping it unfinished
/// discards what it recorded.
pub struct Capture {
    origin: Instant,
    gpu: Option<(Gpu, Option<ClockCalibration>)>,
    finished: bool,
}

/// What a capture recorded, before GPU times are placed on the host clock.
#[derive(Clone, Debug)]
pub struct Recording {
    pub(crate) origin: Instant,
    pub(crate) spans: Vec<HostSpan>,
    pub(crate) counters: Vec<HostCounter>,
    pub(crate) threads: BTreeMap<u32, String>,
    pub(crate) gpu: Option<GpuRecording>,
}

/// The GPU's part of a [`Recording`].
#[derive(Clone, Debug)]
pub(crate) struct GpuRecording {
    pub(crate) device: String,
    pub(crate) driver: String,
    pub(crate) timestamp_period_ns: f32,
    pub(crate) streams: Vec<(StreamKind, QueueSlot)>,
    pub(crate) single_queue: bool,
    pub(crate) batches: Vec<GpuBatch>,
    /// At the start and at the end of the capture, where the device can calibrate.
    pub(crate) calibrations: Vec<ClockCalibration>,
}

impl Capture {
    /// Starts recording host spans and counters (from now on, on every thread).
    pub fn start() -> Result<Self, TimelineError> {
        install()?;
        let mut log = HOST_LOG.lock().unwrap();
        if log.is_some() {
            return Err(TimelineError::AlreadyCapturing);
        }
        *log = Some(HostLog::default());
        CAPTURING.store(true, Ordering::Relaxed);
        Ok(Self {
            origin: Instant::now(),
            gpu: None,
            finished: false,
        })
    }

    /// Records `gpu`'s command buffers from now on, and samples its clock against the
    /// host's where it can.
    pub fn attach(&mut self, gpu: &Gpu) -> Result<(), TimelineError> {
        gpu.start_timeline();
        crate::timeline_counter!("GPU memory", "bytes", gpu.memory_bytes().0);
        let calibration = gpu.calibrate_clocks()?;
        self.gpu = Some((gpu.clone(), calibration));
        Ok(())
    }

    /// Waits for the attached GPU's streams, stops recording and returns everything.
    pub fn finish(mut self) -> Result<Recording, TimelineError> {
        let gpu = match self.gpu.take() {
            Some((gpu, first)) => {
                gpu.wait_idle()?;
                let last = gpu.calibrate_clocks()?;
                Some(GpuRecording {
                    device: gpu.info().name.clone(),
                    driver: format!("{} {}", gpu.info().driver_name, gpu.info().driver_info),
                    timestamp_period_ns: gpu.info().limits.timestamp_period_ns,
                    streams: StreamKind::ALL
                        .iter()
                        .map(|&k| (k, gpu.stream_mapping().slot(k)))
                        .collect(),
                    single_queue: gpu.stream_mapping().is_single_queue(),
                    batches: gpu.take_timeline(),
                    calibrations: first.into_iter().chain(last).collect(),
                })
            }
            None => None,
        };
        let log = stop().unwrap_or_default();
        self.finished = true;
        Ok(Recording {
            origin: self.origin,
            spans: log.spans,
            counters: log.counters,
            threads: log.threads,
            gpu,
        })
    }
}

fn stop() -> Option<HostLog> {
    CAPTURING.store(false, Ordering::Relaxed);
    HOST_LOG.lock().unwrap().take()
}

impl Drop for Capture {
    fn drop(&mut self) {
        if !self.finished {
            stop();
            if let Some((gpu, _)) = self.gpu.take() {
                gpu.take_timeline();
            }
        }
    }
}

/// Nanoseconds from `origin` to `t` (negative before it).
pub(crate) fn since(origin: Instant, t: Instant) -> i64 {
    match t.checked_duration_since(origin) {
        Some(d) => d.as_nanos() as i64,
        None => -(origin.duration_since(t).as_nanos() as i64),
    }
}

impl Recording {
    /// The trace: host threads' tracks, GPU streams' tracks with GPU times placed on the
    /// host clock, counters, and metadata saying how the clocks were aligned.
    pub fn trace(&self, alignment: ClockAlignment) -> Trace {
        let mut metadata = Map::new();
        metadata.insert(
            "generator".into(),
            json!(format!("splitray {}", env!("CARGO_PKG_VERSION"))),
        );
        metadata.insert(
            "time_origin".into(),
            json!("ts 0 is the start of the capture (host monotonic clock)"),
        );
        // GPU streams first: what ran on the device, then what the host did meanwhile.
        let mut processes = Vec::new();
        let mut tracks = Vec::new();
        let mut spare_tid = 1000;
        if let Some(gpu) = &self.gpu {
            processes.push(Process {
                pid: GPU_PID,
                name: format!("GPU: {}", gpu.device),
            });
            let (gpu_tracks, clock) =
                super::gpu::stream_tracks(self, gpu, alignment, &mut spare_tid);
            tracks.extend(gpu_tracks);
            metadata.insert("device".into(), json!(gpu.device));
            metadata.insert("driver".into(), json!(gpu.driver));
            metadata.insert("timestamp_period_ns".into(), json!(gpu.timestamp_period_ns));
            metadata.insert("clock".into(), clock);
            let streams: Map<String, Value> = gpu
                .streams
                .iter()
                .map(|(k, s)| {
                    (
                        k.name().to_string(),
                        json!({"queue_family": s.family, "queue_index": s.index}),
                    )
                })
                .collect();
            metadata.insert("streams".into(), Value::Object(streams));
            metadata.insert("single_queue".into(), json!(gpu.single_queue));
        }
        processes.push(Process {
            pid: HOST_PID,
            name: "host".into(),
        });
        tracks.extend(self.host_tracks(&mut spare_tid));
        Trace {
            metadata,
            processes,
            tracks,
            counters: self.counter_series(),
        }
    }

    fn host_tracks(&self, spare_tid: &mut u32) -> Vec<super::Track> {
        let mut by_thread: BTreeMap<u32, Vec<Slice>> = BTreeMap::new();
        for s in &self.spans {
            let start_ns = since(self.origin, s.start);
            by_thread.entry(s.thread).or_default().push(Slice {
                name: s.name.clone(),
                category: "host".into(),
                start_ns,
                dur_ns: since(self.origin, s.end) - start_ns,
                args: s.args.clone(),
            });
        }
        by_thread
            .into_iter()
            .flat_map(|(thread, slices)| {
                let name = self
                    .threads
                    .get(&thread)
                    .cloned()
                    .unwrap_or_else(|| format!("thread {thread}"));
                tracks_of(HOST_PID, thread, &name, slices, spare_tid)
            })
            .collect()
    }

    fn counter_series(&self) -> Vec<Counter> {
        let pid = if self.gpu.is_some() {
            GPU_PID
        } else {
            HOST_PID
        };
        let mut out: Vec<Counter> = Vec::new();
        for c in &self.counters {
            let sample = (since(self.origin, c.at), c.value);
            match out
                .iter_mut()
                .find(|k| k.name == c.name && k.series == c.series)
            {
                Some(k) => k.samples.push(sample),
                None => out.push(Counter {
                    pid,
                    name: c.name.clone(),
                    series: c.series.clone(),
                    samples: vec![sample],
                }),
            }
        }
        for k in &mut out {
            k.samples.sort_by_key(|&(t, _)| t);
        }
        out
    }
}
