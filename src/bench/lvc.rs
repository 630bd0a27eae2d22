//! The light-vertex-cache integrators at equal samples per pixel (thesis Table 4.1):
//! LVC-BDPT and CIS-LBDPT with one stream and with three (`--streams`), with material
//! sorting as the device's default, on or off (`--sort`), each configuration rendering
//! the same passes in turns (the order rotates every round), with the GPU time of every
//! kernel and the busy time of every stream, and how long two or more streams were busy
//! at once (their overlap: zero where the streams share one queue, as on lavapipe).

use serde::Serialize;

use super::{median, EvenMedian};
use crate::film::FilmSums;
use crate::integrator::lvc::sort_pays;
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
    /// Connection shadow rays per camera path and the share of them unoccluded (the
    /// integrator's counters over all its passes): what resampling does to visibility
    /// tests.
    pub connection_rays_per_path: f64,
    pub connections_unoccluded: f64,
}

/// Material sorting in a configuration: the integrator's default on the device, or
/// forced on or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SortSetting {
    Default,
    On,
    Off,
}

impl std::str::FromStr for SortSetting {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "default" => Ok(Self::Default),
            "on" => Ok(Self::On),
            "off" => Ok(Self::Off),
            _ => Err(format!("'{s}': the sort setting is default, on or off")),
        }
    }
}

impl SortSetting {
    /// Whether `kind` sorts with this setting on a device where sorting does or does not
    /// pay (`sort_pays`).
    fn resolve(self, kind: IntegratorKind, sort_pays: bool) -> bool {
        match self {
            Self::On => true,
            Self::Off => false,
            Self::Default => kind == IntegratorKind::CisLbdpt && sort_pays,
        }
    }
}

/// What the equal-spp comparison measures.
#[derive(Clone, Debug, PartialEq)]
pub struct SppPlan {
    /// Passes per round (0: no comparison).
    pub passes: u32,
    pub rounds: u32,
    /// Stream counts, each 1 or 3.
    pub streams: Vec<u32>,
    pub sort: Vec<SortSetting>,
}

impl Default for SppPlan {
    fn default() -> Self {
        Self {
            passes: 4,
            rounds: 3,
            streams: vec![1, 3],
            sort: vec![SortSetting::Default],
        }
    }
}

/// The configurations measured for `integrators` (those of them that use a cache): every
/// stream count and sort setting of `plan` (on a device where sorting does or does not
/// pay), a setting that resolves to one already listed measured once.
pub fn configurations(
    integrators: &[IntegratorKind],
    plan: &SppPlan,
    sort_pays: bool,
) -> Vec<(IntegratorKind, u32, bool)> {
    let mut out = Vec::new();
    for &kind in integrators {
        if kind.lvc_variant().is_none() {
            continue;
        }
        for &sort in &plan.sort {
            for &streams in &plan.streams {
                let c = (kind, streams, sort.resolve(kind, sort_pays));
                if !out.contains(&c) {
                    out.push(c);
                }
            }
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

struct Config {
    kind: IntegratorKind,
    streams: u32,
    sorted: bool,
    integrator: Box<dyn Integrator>,
    seconds: Vec<f64>,
    log: ProfileLog,
}

/// Renders `plan.passes` passes with every configuration, `plan.rounds` times in turns.
/// Refuses to time configurations whose warm-up passes differ: the stream count and
/// material sorting never change an integrator's image, bit for bit.
fn check_configurations_agree(configs: &mut [Config]) -> Result<(), RenderError> {
    let mut firsts: Vec<(IntegratorKind, String, FilmSums)> = Vec::new();
    for c in configs.iter_mut() {
        let sums = c.integrator.sums()?;
        let name = format!(
            "{} stream(s), {}",
            c.streams,
            if c.sorted { "sorted" } else { "unsorted" }
        );
        match firsts.iter().find(|(kind, _, _)| *kind == c.kind) {
            None => firsts.push((c.kind, name, sums)),
            Some((_, first, want)) if *want != sums => {
                return Err(crate::vk::VkError::Usage(format!(
                    "bench bdpt: {}'s first pass with {name} differs from the one with {first} \
                     (a bug); not timing it",
                    c.kind.name()
                ))
                .into())
            }
            Some(_) => {}
        }
    }
    Ok(())
}

pub fn equal_spp(
    gpu: &Gpu,
    scene: &Scene,
    base: &RenderOptions,
    integrators: &[IntegratorKind],
    plan: &SppPlan,
) -> Result<Vec<SppRow>, RenderError> {
    let passes = plan.passes.max(1);
    let mut configs = Vec::new();
    for (kind, streams, sorted) in configurations(integrators, plan, sort_pays(gpu)) {
        let mut o = base.clone();
        o.integrator = kind;
        o.spp = passes;
        o.lvc.streams = Some(streams);
        o.lvc.sort = Some(sorted);
        let mut integrator = create_integrator(gpu, scene, &o)?;
        // Warm-up: the first dispatch of each kernel compiles it on some drivers.
        integrator.render_passes(0, 1)?;
        configs.push(Config {
            kind,
            streams,
            sorted,
            integrator,
            seconds: Vec::new(),
            log: ProfileLog::default(),
        });
    }
    check_configurations_agree(&mut configs)?;
    gpu.wait_idle()?;
    let _ = gpu.take_profile();
    let empty = FilmSums::new(base.width, base.height, 1, true);
    let n = configs.len();
    for round in 0..plan.rounds.max(1) as usize {
        for k in 0..n {
            let c = &mut configs[(round + k) % n];
            c.integrator.restore(&empty)?;
            gpu.wait_idle()?;
            let _ = gpu.take_profile();
            let start = std::time::Instant::now();
            c.integrator.render_passes(1, passes)?;
            gpu.wait_idle()?;
            let seconds = start.elapsed().as_secs_f64();
            c.seconds.push(seconds);
            let log = gpu.take_profile();
            let (busy, _) = stream_use(&log);
            let busy_ms: f64 = busy.iter().map(|(_, ms)| ms).sum();
            c.log.extend(log);
            // Each timing as it comes, on stderr: a run cut short by a job's time limit
            // keeps what it measured. The GPU's busy time beside it tells host time
            // (waits, recording) from GPU time.
            crate::errln!(
                "equal spp, round {}/{}: {} {} stream(s) {}: {seconds:.3} s, GPU busy {busy_ms:.0} ms \
                 (streams summed)",
                round + 1,
                plan.rounds.max(1),
                c.kind.name(),
                c.streams,
                if c.sorted { "sorted" } else { "unsorted" }
            );
        }
    }
    Ok(configs
        .into_iter()
        .map(|c| {
            let (stream_busy_ms, overlap_ms) = stream_use(&c.log);
            let counters = c.integrator.stats().counters;
            let count = |name: &str| counters.get(name).copied().unwrap_or(0) as f64;
            let rays = count("connection_shadow_rays");
            SppRow {
                integrator: c.kind.name().to_string(),
                streams: c.streams,
                sorted: c.sorted,
                seconds: median(c.seconds, EvenMedian::Mean),
                passes,
                stream_busy_ms,
                overlap_ms,
                kernels: c.log.summary(),
                connection_rays_per_path: rays / count("camera_paths").max(1.0),
                connections_unoccluded: count("connections_unoccluded") / rays.max(1.0),
            }
        })
        .collect())
}

/// The median time of `integrator` with `streams` streams, sorted or not, where measured.
fn seconds_of(rows: &[SppRow], integrator: &str, streams: u32, sorted: bool) -> Option<f64> {
    rows.iter()
        .find(|r| r.integrator == integrator && r.streams == streams && r.sorted == sorted)
        .map(|r| r.seconds)
}

/// The first configuration of `integrator`: the one with its own default sorting.
fn first_of<'a>(rows: &'a [SppRow], integrator: &str) -> Option<&'a SppRow> {
    rows.iter().find(|r| r.integrator == integrator)
}

fn on_off(sorted: bool) -> &'static str {
    if sorted {
        "sorted"
    } else {
        "unsorted"
    }
}

/// The heading and one line per configuration: time, busy time per stream, overlap.
fn write_spp_table(f: &mut std::fmt::Formatter<'_>, rows: &[SppRow]) -> std::fmt::Result {
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
    Ok(())
}

/// lvc-bdpt's time over cis-lbdpt's: at the same settings, and each with its own
/// default sorting where those differ.
fn write_method_ratios(f: &mut std::fmt::Formatter<'_>, rows: &[SppRow]) -> std::fmt::Result {
    let time = |k: &str, streams: u32, sorted: bool| seconds_of(rows, k, streams, sorted);
    for (streams, sorted) in [(1, false), (3, false), (1, true), (3, true)] {
        if let (Some(lvc), Some(cis)) = (
            time("lvc-bdpt", streams, sorted),
            time("cis-lbdpt", streams, sorted),
        ) {
            writeln!(
                f,
                "lvc-bdpt / cis-lbdpt time at equal spp, {streams} stream(s), both {}: {:.3}",
                on_off(sorted),
                lvc / cis
            )?;
        }
    }
    // Each method with its own default sorting (the first configuration of each).
    if let (Some(lvc), Some(cis)) = (first_of(rows, "lvc-bdpt"), first_of(rows, "cis-lbdpt")) {
        if lvc.sorted != cis.sorted {
            for streams in [1, 3] {
                if let (Some(l), Some(c)) = (
                    time("lvc-bdpt", streams, lvc.sorted),
                    time("cis-lbdpt", streams, cis.sorted),
                ) {
                    writeln!(
                        f,
                        "lvc-bdpt ({}) / cis-lbdpt ({}) time at equal spp, {streams} stream(s): {:.3}",
                        on_off(lvc.sorted),
                        on_off(cis.sorted),
                        l / c
                    )?;
                }
            }
        }
    }
    Ok(())
}

/// Within each method: one stream's time over three's, and unsorted over sorted.
fn write_setting_ratios(f: &mut std::fmt::Formatter<'_>, rows: &[SppRow]) -> std::fmt::Result {
    let time = |k: &str, streams: u32, sorted: bool| seconds_of(rows, k, streams, sorted);
    for k in ["lvc-bdpt", "cis-lbdpt"] {
        for sorted in [false, true] {
            if let (Some(one), Some(three)) = (time(k, 1, sorted), time(k, 3, sorted)) {
                writeln!(
                    f,
                    "{k} ({}): 1 stream / 3 streams time: {:.3}",
                    on_off(sorted),
                    one / three
                )?;
            }
        }
        for streams in [1, 3] {
            if let (Some(off), Some(on)) = (time(k, streams, false), time(k, streams, true)) {
                writeln!(
                    f,
                    "{k}, {streams} stream(s): unsorted / sorted time: {:.3}",
                    off / on
                )?;
            }
        }
    }
    Ok(())
}

/// Each method's connection shadow rays per camera path and the share unoccluded.
fn write_connection_counts(f: &mut std::fmt::Formatter<'_>, rows: &[SppRow]) -> std::fmt::Result {
    // The images, and so these counts, are the same in every configuration of a method.
    for k in ["lvc-bdpt", "cis-lbdpt"] {
        if let Some(r) = first_of(rows, k) {
            writeln!(
                f,
                "{k}: {:.2} connection shadow rays per camera path, {:.1} % unoccluded",
                r.connection_rays_per_path,
                100.0 * r.connections_unoccluded
            )?;
        }
    }
    Ok(())
}

/// The eight kernels with the longest self time of each three-stream configuration.
fn write_top_kernels(f: &mut std::fmt::Formatter<'_>, rows: &[SppRow]) -> std::fmt::Result {
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
        writeln!(
            f,
            "{} ({}) kernels (self ms): {}",
            r.integrator,
            on_off(r.sorted),
            top.join(", ")
        )?;
    }
    Ok(())
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
    write_spp_table(f, rows)?;
    write_method_ratios(f, rows)?;
    write_setting_ratios(f, rows)?;
    write_connection_counts(f, rows)?;
    write_top_kernels(f, rows)
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
    fn configurations_cover_streams_and_sorting_once_each() {
        use IntegratorKind::{CisLbdpt, LvcBdpt, Pt};
        let plan = SppPlan {
            sort: vec![SortSetting::Default, SortSetting::On, SortSetting::Off],
            ..Default::default()
        };
        // Where sorting does not pay, each default is "off" and measured once.
        assert_eq!(
            configurations(&[Pt, LvcBdpt, CisLbdpt], &plan, false),
            vec![
                (LvcBdpt, 1, false),
                (LvcBdpt, 3, false),
                (LvcBdpt, 1, true),
                (LvcBdpt, 3, true),
                (CisLbdpt, 1, false),
                (CisLbdpt, 3, false),
                (CisLbdpt, 1, true),
                (CisLbdpt, 3, true),
            ]
        );
        let plan = SppPlan {
            streams: vec![3],
            ..Default::default()
        };
        assert_eq!(
            configurations(&[LvcBdpt, CisLbdpt], &plan, true),
            vec![(LvcBdpt, 3, false), (CisLbdpt, 3, true)]
        );
        assert_eq!("on".parse(), Ok(SortSetting::On));
        assert!("yes"
            .parse::<SortSetting>()
            .unwrap_err()
            .contains("default, on or off"));
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
