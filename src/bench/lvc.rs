//! The light-vertex-cache integrators at equal samples per pixel (thesis Table 4.1):
//! LVC-BDPT and CIS-LBDPT with one stream and with three, each rendering the same passes
//! in turns (the order rotates every round), with the GPU time of every kernel and the
//! busy time of every stream, and how long two or more streams were busy at once (their
//! overlap: zero where the streams share one queue, as on lavapipe).

use serde::Serialize;

use crate::film::FilmSums;
use crate::integrator::{Integrator, IntegratorKind};
use crate::render::{create_integrator, RenderError, RenderOptions};
use crate::scene::Scene;
use crate::vk::{Gpu, KernelTime, ProfileLog, StreamKind};

/// One configuration's figures.
#[derive(Clone, Debug, Serialize)]
pub struct SppRow {
    pub integrator: String,
    pub streams: u32,
    pub sorted: bool,
    /// Median over the rounds of the wall time of `passes` passes.
    pub seconds: f64,
    pub passes: u32,
    /// GPU busy time per stream (ms, all rounds), main first.
    pub stream_busy_ms: Vec<(String, f64)>,
    /// Time during which two or more streams were busy at once (ms, all rounds).
    pub overlap_ms: f64,
    /// GPU time per kernel (all rounds), longest first.
    pub kernels: Vec<KernelTime>,
}

/// The configurations measured for `integrators` (those of them that use a cache).
pub fn configurations(integrators: &[IntegratorKind]) -> Vec<(IntegratorKind, u32)> {
    let mut out = Vec::new();
    for &kind in integrators {
        if matches!(kind, IntegratorKind::LvcBdpt | IntegratorKind::CisLbdpt) {
            out.extend([(kind, 1), (kind, 3)]);
        }
    }
    out
}

/// Busy time per stream and the time two or more were busy at once, from the outermost
/// scopes of a profile (intervals in GPU clock nanoseconds).
pub fn stream_use(log: &ProfileLog) -> (Vec<(String, f64)>, f64) {
    let mut events: Vec<(f64, i32, usize)> = Vec::new();
    let mut busy = Vec::new();
    for (k, stream) in StreamKind::ALL.iter().enumerate() {
        let mut spans: Vec<(f64, f64)> = log
            .records
            .iter()
            .filter(|r| r.stream == *stream && r.depth == 0 && r.end_ns > r.start_ns)
            .map(|r| (r.start_ns, r.end_ns))
            .collect();
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        // The union of the stream's intervals.
        let mut merged: Vec<(f64, f64)> = Vec::new();
        for (s, e) in spans {
            match merged.last_mut() {
                Some(last) if s <= last.1 => last.1 = last.1.max(e),
                _ => merged.push((s, e)),
            }
        }
        let total: f64 = merged.iter().map(|(s, e)| e - s).sum();
        if total > 0.0 {
            busy.push((stream.name().to_string(), total * 1e-6));
        }
        for (s, e) in merged {
            events.push((s, 1, k));
            events.push((e, -1, k));
        }
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let (mut depth, mut overlap, mut last) = (0, 0.0, 0.0);
    for (t, step, _) in events {
        if depth >= 2 {
            overlap += t - last;
        }
        depth += step;
        last = t;
    }
    (busy, overlap * 1e-6)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

struct Config {
    kind: IntegratorKind,
    streams: u32,
    integrator: Box<dyn Integrator>,
    seconds: Vec<f64>,
    log: ProfileLog,
}

/// Renders `passes` passes with every configuration, `rounds` times in turns.
#[allow(clippy::too_many_arguments)]
pub fn equal_spp(
    gpu: &Gpu,
    scene: &Scene,
    base: &RenderOptions,
    integrators: &[IntegratorKind],
    passes: u32,
    rounds: u32,
) -> Result<Vec<SppRow>, RenderError> {
    let mut configs = Vec::new();
    for (kind, streams) in configurations(integrators) {
        let mut o = base.clone();
        o.integrator = kind;
        o.spp = passes.max(1);
        o.lvc.streams = Some(streams);
        let mut integrator = create_integrator(gpu, scene, &o)?;
        // Warm-up: the first dispatch of each kernel compiles it on some drivers.
        integrator.render_passes(0, 1)?;
        configs.push(Config {
            kind,
            streams,
            integrator,
            seconds: Vec::new(),
            log: ProfileLog::default(),
        });
    }
    gpu.wait_idle()?;
    let _ = gpu.take_profile();
    let empty = FilmSums::new(base.width, base.height, 1, true);
    let n = configs.len();
    for round in 0..rounds.max(1) as usize {
        for k in 0..n {
            let c = &mut configs[(round + k) % n];
            c.integrator.restore(&empty)?;
            gpu.wait_idle()?;
            let _ = gpu.take_profile();
            let start = std::time::Instant::now();
            c.integrator.render_passes(1, passes.max(1))?;
            gpu.wait_idle()?;
            c.seconds.push(start.elapsed().as_secs_f64());
            c.log.extend(gpu.take_profile());
        }
    }
    Ok(configs
        .into_iter()
        .map(|c| {
            let (stream_busy_ms, overlap_ms) = stream_use(&c.log);
            let sorted = c
                .integrator
                .settings()
                .iter()
                .any(|(k, v)| k == "sort_materials" && v == "true");
            SppRow {
                integrator: c.kind.name().to_string(),
                streams: c.streams,
                sorted,
                seconds: median(c.seconds),
                passes: passes.max(1),
                stream_busy_ms,
                overlap_ms,
                kernels: c.log.summary(),
            }
        })
        .collect())
}

/// The equal-spp section of `bench bdpt`'s report.
pub fn write_equal_spp(f: &mut std::fmt::Formatter<'_>, rows: &[SppRow]) -> std::fmt::Result {
    let Some(first) = rows.first() else {
        return Ok(());
    };
    writeln!(
        f,
        "equal spp: {} passes, median of the rounds; GPU busy per stream and the time two \
         or more were busy at once (all rounds)",
        first.passes
    )?;
    writeln!(
        f,
        "{:<10} {:>7} {:>6} {:>9} {:>28} {:>11}",
        "", "streams", "sorted", "seconds", "busy ms (main/aux0/aux1)", "overlap ms"
    )?;
    let busy = |r: &SppRow, s: &str| {
        r.stream_busy_ms
            .iter()
            .find(|(n, _)| n == s)
            .map_or(0.0, |(_, ms)| *ms)
    };
    for r in rows {
        writeln!(
            f,
            "{:<10} {:>7} {:>6} {:>9.3} {:>28} {:>11.1}",
            r.integrator,
            r.streams,
            r.sorted,
            r.seconds,
            format!(
                "{:.0}/{:.0}/{:.0}",
                busy(r, "main"),
                busy(r, "aux0"),
                busy(r, "aux1")
            ),
            r.overlap_ms
        )?;
    }
    let time = |k: &str, s: u32| {
        rows.iter()
            .find(|r| r.integrator == k && r.streams == s)
            .map(|r| r.seconds)
    };
    for s in [1, 3] {
        if let (Some(lvc), Some(cis)) = (time("lvc-bdpt", s), time("cis-lbdpt", s)) {
            writeln!(
                f,
                "lvc-bdpt / cis-lbdpt time at equal spp, {s} stream(s): {:.3}",
                lvc / cis
            )?;
        }
    }
    for k in ["lvc-bdpt", "cis-lbdpt"] {
        if let (Some(one), Some(three)) = (time(k, 1), time(k, 3)) {
            writeln!(f, "{k}: 1 stream / 3 streams time: {:.3}", one / three)?;
        }
    }
    for r in rows.iter().filter(|r| r.streams == 3) {
        let mut kernels = r.kernels.clone();
        kernels.sort_by(|a, b| b.self_ms.total_cmp(&a.self_ms));
        let top: Vec<String> = kernels
            .iter()
            .take(8)
            .map(|k| {
                format!(
                    "{} {:.0}",
                    k.name.trim_start_matches("integrator_lvc_"),
                    k.self_ms
                )
            })
            .collect();
        writeln!(f, "{} kernels (self ms): {}", r.integrator, top.join(", "))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::{ProfileRecord, ScopeInfo};

    fn record(stream: StreamKind, start: f64, end: f64) -> ProfileRecord {
        ProfileRecord {
            stream,
            name: "k".into(),
            start_ns: start,
            end_ns: end,
            depth: 0,
            submission: 1,
            info: ScopeInfo::default(),
        }
    }

    #[test]
    fn stream_use_unions_each_stream_and_measures_the_overlap() {
        let log = ProfileLog {
            records: vec![
                record(StreamKind::Main, 0.0, 4e6),
                record(StreamKind::Main, 3e6, 6e6),
                record(StreamKind::Aux0, 5e6, 7e6),
                record(StreamKind::Aux1, 5.5e6, 6.5e6),
            ],
        };
        let (busy, overlap) = stream_use(&log);
        assert_eq!(
            busy,
            vec![
                ("main".to_string(), 6.0),
                ("aux0".to_string(), 2.0),
                ("aux1".to_string(), 1.0)
            ]
        );
        // Two or more busy from 5 to 6.5 ms.
        assert!((overlap - 1.5).abs() < 1e-9, "{overlap}");
    }
}
