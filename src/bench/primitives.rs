//! `splitray bench primitives`: every primitive verified against its CPU twin, then
//! timed (median of `runs` after a warm-up) with GPU timestamps and wall clock, next to
//! CPU references measured in the same run.

use std::fmt;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use rayon::slice::ParallelSliceMut;
use serde::Serialize;

use super::host;
use super::{median, EvenMedian};
use crate::primitives::compact::Kept;
use crate::primitives::gather::Direction;
use crate::primitives::reduce_by_key::{Reduction, RunOutputs};
use crate::primitives::{cpu, Compact, Gather, RadixSort, ReduceByKey, Scan, ScanKind, Tuning};
use crate::vk::{Buffer, Gpu, MemoryKind, Recorder, StreamKind};

/// What to measure.
#[derive(Clone, Debug)]
pub struct PrimitivesBenchOptions {
    /// Items for the sort, reduce-by-key, compaction and gather (default 4M).
    pub n: usize,
    /// Items for the scan and the copy it is compared with (default 16M).
    pub scan_n: usize,
    /// Timed runs per primitive (at least 5 are made).
    pub runs: usize,
    /// Tuning to use instead of [`Tuning::for_device`].
    pub tuning: Option<Tuning>,
}

impl Default for PrimitivesBenchOptions {
    fn default() -> Self {
        Self {
            n: 1 << 22,
            scan_n: 1 << 24,
            runs: 5,
            tuning: None,
        }
    }
}

/// One timed primitive.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    pub primitive: String,
    pub n: usize,
    /// Median GPU time (timestamps around the whole recording).
    pub gpu_ms: f64,
    /// Median wall-clock time of submit + wait (on a GPU, where the timed runs share
    /// one submission: that submission's wall time per run).
    pub wall_ms: f64,
    /// Items per second from `gpu_ms`, in millions.
    pub mkeys_per_s: f64,
    /// Reference timings in the same run (name, median ms, reference ms / gpu ms).
    pub references: Vec<Reference>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Reference {
    pub name: String,
    pub ms: f64,
    /// `ms / gpu_ms`: above 1 the GPU primitive is faster.
    pub speedup: f64,
}

/// A target of issue 3 and whether this run met it.
#[derive(Clone, Debug, Serialize)]
pub struct TargetCheck {
    pub target: String,
    pub measured: f64,
    pub required: f64,
    pub met: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct PrimitivesReport {
    pub device: String,
    pub driver: String,
    pub subgroup_size: u32,
    pub variant: String,
    pub tuning: Tuning,
    pub runs: usize,
    /// The host's processor ([`host::cpu_model`]): on a CPU device it runs the kernels.
    pub host_cpu: String,
    /// Threads the host lends (rayon's count) and the effective parallel cores measured
    /// just before the two target comparisons and just after them ([`host`]): on a
    /// CPU device the kernels share those cores, the single-thread references do not.
    pub host_threads: usize,
    pub host_cores_before: f64,
    pub host_cores_after: f64,
    pub rows: Vec<BenchRow>,
    pub targets: Vec<TargetCheck>,
}

impl PrimitivesReport {
    pub fn print(&self) {
        crate::out!("{self}");
    }
}

impl fmt::Display for PrimitivesReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "device : {} ({})", self.device, self.driver)?;
        writeln!(f, "variant: {}", self.variant)?;
        writeln!(f, "runs   : median of {}", self.runs)?;
        writeln!(
            f,
            "host   : {}, {} threads, effective parallel cores {:.2} before the targets, {:.2} after",
            self.host_cpu, self.host_threads, self.host_cores_before, self.host_cores_after
        )?;
        writeln!(
            f,
            "{:<28} {:>10} {:>10} {:>10} {:>10}  references (ms, speedup)",
            "primitive", "n", "gpu ms", "wall ms", "Mkeys/s"
        )?;
        for r in &self.rows {
            let refs: Vec<String> = r
                .references
                .iter()
                .map(|x| format!("{} {:.2} ms ({:.2}x)", x.name, x.ms, x.speedup))
                .collect();
            writeln!(
                f,
                "{:<28} {:>10} {:>10.2} {:>10.2} {:>10.1}  {}",
                r.primitive,
                r.n,
                r.gpu_ms,
                r.wall_ms,
                r.mkeys_per_s,
                refs.join("; ")
            )?;
        }
        for t in &self.targets {
            writeln!(
                f,
                "target {:<52} measured {:.2}, required {:.2}: {}",
                t.target,
                t.measured,
                t.required,
                if t.met { "MET" } else { "MISSED" }
            )?;
        }
        Ok(())
    }
}

pub type BenchResult<T> = std::result::Result<T, Box<dyn std::error::Error + Send + Sync>>;

fn time_cpu(runs: usize, mut f: impl FnMut() -> f64) -> f64 {
    median((0..runs).map(|_| f()), EvenMedian::Upper)
}

/// One submission: `prepare` (e.g. restoring an input from a pristine copy on the
/// device), then `record` inside a timestamp scope: (GPU ms of the scope, or the wall
/// time where there are no timestamps; wall ms of submit + wait).
fn gpu_once(
    gpu: &Gpu,
    prepare: &impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    record: &impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    print_profile: bool,
) -> BenchResult<(f64, f64)> {
    let (times, wall) = gpu_batch(gpu, prepare, record, 1, print_profile)?;
    Ok((times.first().copied().unwrap_or(wall), wall))
}

/// Nothing to prepare.
fn no_prepare(_: &mut Recorder) -> crate::vk::Result<()> {
    Ok(())
}

/// Runs `record` once as a warm-up, then `runs` times; returns median (gpu ms, wall ms).
fn time_gpu(
    gpu: &Gpu,
    runs: usize,
    prepare: impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    record: impl Fn(&mut Recorder) -> crate::vk::Result<()>,
) -> BenchResult<(f64, f64)> {
    let (g, w, _) = time_against(gpu, runs, prepare, record, || Ok(0.0))?;
    Ok((g, w))
}

/// Least GPU-busy time before the timed runs on a GPU: a discrete GPU idles at low
/// clocks (an H100 at 345 MHz) and raises them only under sustained load. Single
/// submissions of a 1 ms primitive keep it busy too little of the time (the host waits,
/// reads timestamps and records between them), and the figures then moved 2-3x from run
/// to run (H100, 2026-11-23: the same 16M sort at 1.67 and 2.70 ms per pass count).
const GPU_WARM_UP_MS: f64 = 300.0;

/// GPU time of one warm-up submission: long enough that host gaps between submissions
/// are a small part of the time.
const GPU_WARM_UP_BATCH_MS: f64 = 50.0;

/// `count` runs of `prepare` then `record` back to back in one submission, each run's
/// `record` in its own timestamp scope: the GPU ms of every run, in order, and the wall
/// ms of the whole submission divided by `count`.
fn gpu_batch(
    gpu: &Gpu,
    prepare: &impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    record: &impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    count: usize,
    print_profile: bool,
) -> BenchResult<(Vec<f64>, f64)> {
    let scope = "bench-primitive";
    gpu.wait_idle()?;
    let _ = gpu.take_profile();
    let mut rec = gpu.recorder(StreamKind::Main)?;
    for _ in 0..count {
        prepare(&mut rec)?;
        rec.begin_scope(scope)?;
        record(&mut rec)?;
        rec.end_scope()?;
    }
    let t0 = Instant::now();
    let point = rec.submit(&[])?;
    gpu.wait(&point)?;
    let wall = t0.elapsed().as_secs_f64() * 1e3 / count.max(1) as f64;
    gpu.wait_idle()?;
    let profile = gpu.take_profile();
    if print_profile && std::env::var_os("SPLITRAY_BENCH_PROFILE").is_some() {
        crate::err!("{}", profile.table());
    }
    let runs: Vec<f64> = profile
        .records
        .iter()
        .filter(|r| r.name == scope)
        .map(|r| r.duration_ms())
        .collect();
    Ok((runs, wall))
}

/// As [`time_gpu`], with a reference measurement (`reference`, returning its ms).
///
/// On a CPU device the reference runs after every GPU run, so that both sides see the
/// same machine: on a shared or throttled machine, timing one block of runs after the
/// other lets a change of load decide the ratio. On a GPU the reference shares nothing
/// with the kernels, while the idle time it would put between GPU runs lets the clocks
/// fall: there [`GPU_WARM_UP_MS`] of back-to-back runs come first, then the timed runs
/// back to back in one submission (each in its own timestamp scope, as a CUDA benchmark
/// times kernels with events), then the references. Returns the medians (gpu ms, wall
/// ms, reference ms).
fn time_against(
    gpu: &Gpu,
    runs: usize,
    prepare: impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    record: impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    mut reference: impl FnMut() -> BenchResult<f64>,
) -> BenchResult<(f64, f64, f64)> {
    let (mut gpu_ms, mut wall_ms, mut ref_ms) = (Vec::new(), Vec::new(), Vec::new());
    if gpu.info().is_cpu() {
        gpu_once(gpu, &prepare, &record, false)?; // warm-up: LLVM compiles on first use
        for run in 0..runs {
            let (g, w) = gpu_once(gpu, &prepare, &record, run + 1 == runs)?;
            gpu_ms.push(g);
            wall_ms.push(w);
            ref_ms.push(reference()?);
        }
    } else {
        let (first, _) = gpu_once(gpu, &prepare, &record, false)?;
        let batch = (GPU_WARM_UP_BATCH_MS / first.max(1e-3)).clamp(1.0, 1000.0) as usize;
        let start = Instant::now();
        while start.elapsed().as_secs_f64() * 1e3 < GPU_WARM_UP_MS {
            gpu_batch(gpu, &prepare, &record, batch, false)?;
        }
        let (times, wall) = gpu_batch(gpu, &prepare, &record, runs, true)?;
        if times.len() != runs {
            // No timestamps on this queue: the batch's wall time per run stands in.
            gpu_ms = vec![wall; runs];
        } else {
            gpu_ms = times;
        }
        wall_ms.push(wall);
        for _ in 0..runs {
            ref_ms.push(reference()?);
        }
    }
    Ok((
        median(gpu_ms, EvenMedian::Upper),
        median(wall_ms, EvenMedian::Upper),
        median(ref_ms, EvenMedian::Upper),
    ))
}

/// As [`time_gpu`], the minimum GPU time instead of the median.
fn time_gpu_min(
    gpu: &Gpu,
    runs: usize,
    prepare: impl Fn(&mut Recorder) -> crate::vk::Result<()>,
    record: impl Fn(&mut Recorder) -> crate::vk::Result<()>,
) -> BenchResult<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..runs {
        best = best.min(time_gpu(gpu, 1, &prepare, &record)?.0);
    }
    Ok(best)
}

fn check<T: PartialEq + fmt::Debug>(what: &str, gpu: &[T], cpu: &[T]) -> BenchResult<()> {
    if gpu.len() != cpu.len() {
        return Err(format!("{what}: GPU gave {} items, CPU {}", gpu.len(), cpu.len()).into());
    }
    if let Some(i) = (0..gpu.len()).find(|&i| gpu[i] != cpu[i]) {
        return Err(format!(
            "{what}: mismatch at {i}: GPU {:?}, CPU {:?}",
            gpu[i], cpu[i]
        )
        .into());
    }
    Ok(())
}

fn random_u32s(n: usize, seed: u64) -> Vec<u32> {
    let mut state = seed;
    (0..n)
        .map(|_| {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as u32
        })
        .collect()
}

fn row(primitive: &str, n: usize, (gpu_ms, wall_ms): (f64, f64), refs: &[(&str, f64)]) -> BenchRow {
    BenchRow {
        primitive: primitive.to_string(),
        n,
        gpu_ms,
        wall_ms,
        mkeys_per_s: n as f64 / gpu_ms / 1e3,
        references: refs
            .iter()
            .map(|&(name, ms)| Reference {
                name: name.to_string(),
                ms,
                speedup: ms / gpu_ms,
            })
            .collect(),
    }
}

fn device_buffer(gpu: &Gpu, name: &str, bytes: u64) -> crate::vk::Result<Buffer> {
    gpu.create_buffer(name, bytes, MemoryKind::Device)
}

/// Verifies and times every primitive.
pub fn run(gpu: &Gpu, opts: &PrimitivesBenchOptions) -> BenchResult<PrimitivesReport> {
    let runs = opts.runs.max(5);
    let tuning = opts
        .tuning
        .unwrap_or_else(|| Tuning::for_device(gpu.info()));
    let mut rows = Vec::new();
    let mut targets = Vec::new();

    // The largest inputs, checked before their host data is made: a count the device
    // cannot hold fails at once, not after filling the host's memory.
    gpu.check_buffer_size("bench-keys", opts.n as u64 * 4)?;
    gpu.check_buffer_size("bench-scan", opts.scan_n as u64 * 4)?;
    let host_cores_before = host::effective_cores();
    let (sorted, sort_target) = bench_sort(gpu, &tuning, opts.n, runs)?;
    rows.extend(sorted);
    targets.push(sort_target);
    let (scanned, scan_target) = bench_scan(gpu, &tuning, opts.scan_n, runs)?;
    rows.extend(scanned);
    targets.extend(scan_target);
    let host_cores_after = host::effective_cores();

    let values = Values::new(gpu, opts.n)?;
    rows.extend(bench_reduce_by_key(gpu, &tuning, &values, runs)?);
    rows.push(bench_compact(gpu, &tuning, &values, runs)?);
    rows.extend(bench_gather(gpu, &tuning, &values, runs)?);
    gpu.wait_idle()?;

    let info = gpu.info();
    Ok(PrimitivesReport {
        device: info.name.clone(),
        driver: format!("{} {}", info.driver_name, info.driver_info),
        subgroup_size: info.limits.subgroup_size,
        variant: tuning.describe(),
        tuning,
        runs,
        host_cpu: host::cpu_model(),
        host_threads: rayon::current_num_threads(),
        host_cores_before,
        host_cores_after,
        rows,
        targets,
    })
}

/// Issue 3's sort target: on lavapipe a ratio to the single-thread CPU sort, on a GPU a
/// throughput (stated for 16M keys).
fn sort_target(gpu: &Gpu, n: usize, row: &BenchRow, single_ms: f64) -> TargetCheck {
    if gpu.info().is_cpu() {
        TargetCheck {
            target: format!("sort {n} pairs vs single-thread sort_unstable_by_key"),
            measured: single_ms / row.gpu_ms,
            required: 1.5,
            met: single_ms / row.gpu_ms >= 1.5,
        }
    } else {
        let gkeys = row.mkeys_per_s / 1e3;
        TargetCheck {
            target: format!("sort {n} pairs, Gkeys/s (GPU target at 16M keys)"),
            measured: gkeys,
            required: 5.0,
            met: gkeys >= 5.0,
        }
    }
}

/// Milliseconds of one single-thread `sort_unstable_by_key` of a copy of `pairs`.
fn cpu_sort_ms(pairs: &[(u32, u32)]) -> f64 {
    let mut p = pairs.to_vec();
    let t = Instant::now();
    p.sort_unstable_by_key(|x| x.0);
    let ms = t.elapsed().as_secs_f64() * 1e3;
    std::hint::black_box(&p);
    ms
}

/// Radix sort of key-value pairs, all 32 bits against `sort_unstable_by_key` (the
/// target) and rayon's parallel sort, then keys of 16 significant bits (half the
/// passes); each result checked against the CPU twin first.
fn bench_sort(
    gpu: &Gpu,
    tuning: &Tuning,
    n: usize,
    runs: usize,
) -> BenchResult<(Vec<BenchRow>, TargetCheck)> {
    let n32 = u32::try_from(n)?;
    let sort = RadixSort::new(gpu, tuning)?;
    let keys = random_u32s(n, 1);
    let values: Vec<u32> = (0..n as u32).collect();
    let kbuf = gpu.upload("bench-keys", &keys)?;
    let vbuf = gpu.upload("bench-values", &values)?;
    // Pristine copies: every timed sort starts from them (copied on the device before
    // the timestamp scope, so no host upload idles the GPU between runs).
    let kinit = gpu.upload("bench-keys-init", &keys)?;
    let vinit = gpu.upload("bench-values-init", &values)?;
    let restore = |rec: &mut Recorder| {
        rec.copy(&kinit, 0, &kbuf, 0, n as u64 * 4);
        rec.copy(&vinit, 0, &vbuf, 0, n as u64 * 4);
        rec.barrier();
        Ok(())
    };
    let scratch = sort.alloc_scratch(gpu, n32)?;
    let record_sort = |rec: &mut Recorder, bits: std::ops::Range<u32>| {
        sort.record(
            rec,
            n32,
            (&kbuf).into(),
            Some((&vbuf).into()),
            bits,
            &scratch,
        )
    };
    let verify = |keys: &[u32], bits: std::ops::Range<u32>, what: &str| -> BenchResult<()> {
        let mut rec = gpu.recorder(StreamKind::Main)?;
        record_sort(&mut rec, bits.clone())?;
        gpu.wait(&rec.submit(&[])?)?;
        let (ck, cv) = cpu::sort_pairs(keys, &values, bits);
        check(&format!("{what} keys"), &kbuf.read::<u32>()?, &ck)?;
        check(&format!("{what} values"), &vbuf.read::<u32>()?, &cv)
    };
    let mut rows = Vec::new();

    verify(&keys, 0..32, "radix sort")?;
    let pairs: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    // The target's two sides alternate run by run (see time_against).
    let (gpu_ms, wall_ms, single) = time_against(
        gpu,
        runs,
        restore,
        |rec| record_sort(rec, 0..32),
        || Ok(cpu_sort_ms(&pairs)),
    )?;
    let par = time_cpu(runs, || {
        let mut p = pairs.clone();
        let t = Instant::now();
        p.par_sort_unstable_by_key(|x| x.0);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        std::hint::black_box(&p);
        ms
    });
    let r = row(
        "sort_pairs (32 bits)",
        n,
        (gpu_ms, wall_ms),
        &[
            ("cpu sort_unstable_by_key", single),
            ("cpu rayon par_sort", par),
        ],
    );
    let target = sort_target(gpu, n, &r, single);
    rows.push(r);

    // Keys with 16 significant bits: the bit range halves the passes.
    let keys16: Vec<u32> = keys.iter().map(|k| k >> 16).collect();
    kinit.write(&keys16)?;
    let mut rec = gpu.recorder(StreamKind::Main)?;
    restore(&mut rec)?;
    gpu.wait(&rec.submit(&[])?)?;
    verify(&keys16, 0..16, "radix sort 16-bit")?;
    let pairs16: Vec<(u32, u32)> = keys16.iter().copied().zip(values.iter().copied()).collect();
    let single16 = time_cpu(runs, || cpu_sort_ms(&pairs16));
    let t = time_gpu(gpu, runs, restore, |rec| record_sort(rec, 0..16))?;
    rows.push(row(
        "sort_pairs (bits 0..16)",
        n,
        t,
        &[("cpu sort_unstable_by_key", single16)],
    ));
    Ok((rows, target))
}

/// Exclusive scan of `scan_n` values below 256 against a vkCmdCopyBuffer of the same
/// bytes (lavapipe's target) and the CPU scan; the copy's own row follows.
fn bench_scan(
    gpu: &Gpu,
    tuning: &Tuning,
    scan_n: usize,
    runs: usize,
) -> BenchResult<(Vec<BenchRow>, Option<TargetCheck>)> {
    let scan = VerifiedScan::new(gpu, tuning, scan_n, "bench-scan", "exclusive scan")?;
    let record_scan = |rec: &mut Recorder| scan.record(rec);
    let scan_cpu = time_cpu(runs, || {
        let t = Instant::now();
        std::hint::black_box(cpu::exclusive_scan(&scan.data));
        t.elapsed().as_secs_f64() * 1e3
    });
    // The copy and the scan alternate run by run (see time_against).
    let copy_once = |rec: &mut Recorder| {
        rec.copy(&scan.input, 0, &scan.output, 0, scan_n as u64 * 4);
        Ok(())
    };
    gpu_once(gpu, &no_prepare, &copy_once, false)?;
    let copy_walls = std::cell::RefCell::new(Vec::new());
    let (scan_gpu, scan_wall, copy_ms) = time_against(gpu, runs, no_prepare, record_scan, || {
        let (g, w) = gpu_once(gpu, &no_prepare, &copy_once, false)?;
        copy_walls.borrow_mut().push(w);
        Ok(g)
    })?;
    let copy_t = (copy_ms, median(copy_walls.into_inner(), EvenMedian::Upper));
    let r = row(
        "scan (exclusive)",
        scan_n,
        (scan_gpu, scan_wall),
        &[
            ("vkCmdCopyBuffer same bytes", copy_t.0),
            ("cpu scan", scan_cpu),
        ],
    );
    // The scan's target is lavapipe's; on a GPU the ratio stays in the row.
    let target = gpu.info().is_cpu().then(|| TargetCheck {
        target: format!("scan {scan_n} u32 vs vkCmdCopyBuffer bandwidth"),
        measured: copy_t.0 / r.gpu_ms,
        required: 0.5,
        met: copy_t.0 / r.gpu_ms >= 0.5,
    });
    Ok((
        vec![r, row("vkCmdCopyBuffer (reference)", scan_n, copy_t, &[])],
        target,
    ))
}

/// The values the reductions, compaction and gathers read, and the outputs they write.
struct Values {
    n: usize,
    host: Vec<u32>,
    buffer: Buffer,
    out: Buffer,
    out_count: Buffer,
}

impl Values {
    fn new(gpu: &Gpu, n: usize) -> BenchResult<Self> {
        let host = random_u32s(n, 4);
        Ok(Self {
            n,
            buffer: gpu.upload("bench-rbk-values", &host)?,
            host,
            out: device_buffer(gpu, "bench-rbk-out-a", n as u64 * 4)?,
            out_count: device_buffer(gpu, "bench-rbk-count", 4)?,
        })
    }
}

/// Sorted keys with runs of 1..=16 items (like PDACRT's per-ray hit candidates).
fn run_keys(n: usize) -> Vec<u32> {
    let mut keys = Vec::with_capacity(n);
    let lens = random_u32s(n, 3);
    let mut k = 0u32;
    while keys.len() < n {
        let len = (lens[keys.len()] % 16 + 1) as usize;
        keys.extend(std::iter::repeat_n(k, len.min(n - keys.len())));
        k += 1;
    }
    keys
}

/// Reduce-by-key (sum, arg-min) and run-length encoding over [`run_keys`], each against
/// its CPU twin.
fn bench_reduce_by_key(
    gpu: &Gpu,
    tuning: &Tuning,
    values: &Values,
    runs: usize,
) -> BenchResult<Vec<BenchRow>> {
    let n = values.n;
    let n32 = u32::try_from(n)?;
    let rbk = ReduceByKey::new(gpu, tuning)?;
    let rkeys = run_keys(n);
    let rvals = &values.host;
    let tvals: Vec<f32> = rvals.iter().map(|&v| (v >> 8) as f32 / 65536.0).collect();
    let ids: Vec<u32> = (0..n as u32).collect();
    let bk = gpu.upload("bench-rbk-keys", &rkeys)?;
    let bt = gpu.upload("bench-rbk-t", &tvals)?;
    let bi = gpu.upload("bench-rbk-ids", &ids)?;
    let ok = device_buffer(gpu, "bench-rbk-out-keys", n as u64 * 4)?;
    let ob = device_buffer(gpu, "bench-rbk-out-b", n as u64 * 4)?;
    let rs = device_buffer(gpu, "bench-rbk-scratch", rbk.scratch_bytes(n32))?;
    let (oa, oc) = (&values.out, &values.out_count);
    let outs = RunOutputs {
        keys: (&ok).into(),
        a: oa.into(),
        b: Some((&ob).into()),
        count: oc.into(),
    };
    let reductions: [(&str, Reduction); 3] = [
        (
            "reduce_by_key sum",
            Reduction::Sum {
                values: (&values.buffer).into(),
            },
        ),
        (
            "reduce_by_key arg-min",
            Reduction::ArgMin {
                t: (&bt).into(),
                ids: (&bi).into(),
            },
        ),
        ("run_length_encode", Reduction::Count),
    ];
    let mut rows = Vec::new();
    for (name, reduction) in reductions {
        let record = |rec: &mut Recorder| rbk.record(rec, n32, (&bk).into(), reduction, outs, &rs);
        let mut rec = gpu.recorder(StreamKind::Main)?;
        record(&mut rec)?;
        gpu.wait(&rec.submit(&[])?)?;
        let runs_n = oc.read::<u32>()?[0] as usize;
        let gk = &ok.read::<u32>()?[..runs_n.min(n)];
        let ga = &oa.read::<u32>()?[..runs_n.min(n)];
        match reduction {
            Reduction::Sum { .. } => {
                let (ck, cv) = cpu::reduce_by_key_sum(&rkeys, rvals);
                check(name, gk, &ck)?;
                check(name, ga, &cv)?;
            }
            Reduction::Count => {
                let (ck, cv) = cpu::run_length_encode(&rkeys);
                check(name, gk, &ck)?;
                check(name, ga, &cv)?;
            }
            Reduction::ArgMin { .. } => {
                let (ck, ct, ci) = cpu::reduce_by_key_argmin(&rkeys, &tvals, &ids);
                let gb = &ob.read::<u32>()?[..runs_n.min(n)];
                let ct: Vec<u32> = ct.iter().map(|t| t.to_bits()).collect();
                check(name, gk, &ck)?;
                check(name, ga, &ct)?;
                check(name, gb, &ci)?;
            }
        }
        let cpu_ms = time_cpu(runs, || {
            let t = Instant::now();
            match reduction {
                Reduction::Sum { .. } => {
                    std::hint::black_box(cpu::reduce_by_key_sum(&rkeys, rvals));
                }
                Reduction::Count => {
                    std::hint::black_box(cpu::run_length_encode(&rkeys));
                }
                Reduction::ArgMin { .. } => {
                    std::hint::black_box(cpu::reduce_by_key_argmin(&rkeys, &tvals, &ids));
                }
            }
            t.elapsed().as_secs_f64() * 1e3
        });
        let t = time_gpu(gpu, runs, no_prepare, record)?;
        rows.push(row(name, n, t, &[("cpu twin", cpu_ms)]));
    }
    Ok(rows)
}

/// Compaction of the values, half of them kept, against its CPU twin.
fn bench_compact(
    gpu: &Gpu,
    tuning: &Tuning,
    values: &Values,
    runs: usize,
) -> BenchResult<BenchRow> {
    let n = values.n;
    let n32 = u32::try_from(n)?;
    let compact = Compact::new(gpu, tuning)?;
    let flags: Vec<u32> = random_u32s(n, 5).iter().map(|x| x & 1).collect();
    let bf = gpu.upload("bench-flags", &flags)?;
    let cs = device_buffer(gpu, "bench-compact-scratch", compact.scratch_bytes(n32))?;
    let record = |rec: &mut Recorder| {
        compact.record(
            rec,
            n32,
            (&bf).into(),
            Kept::Values((&values.buffer).into()),
            (&values.out).into(),
            (&values.out_count).into(),
            &cs,
        )
    };
    let mut rec = gpu.recorder(StreamKind::Main)?;
    record(&mut rec)?;
    gpu.wait(&rec.submit(&[])?)?;
    let kept = values.out_count.read::<u32>()?[0] as usize;
    let expect = cpu::compact(&flags, &values.host);
    check(
        "compaction",
        &values.out.read::<u32>()?[..kept.min(n)],
        &expect,
    )?;
    let cpu_ms = time_cpu(runs, || {
        let t = Instant::now();
        std::hint::black_box(cpu::compact(&flags, &values.host));
        t.elapsed().as_secs_f64() * 1e3
    });
    let t = time_gpu(gpu, runs, no_prepare, record)?;
    Ok(row("compact (by flag)", n, t, &[("cpu twin", cpu_ms)]))
}

/// Gather and scatter of the values by a random permutation, against their CPU twins.
fn bench_gather(
    gpu: &Gpu,
    tuning: &Tuning,
    values: &Values,
    runs: usize,
) -> BenchResult<Vec<BenchRow>> {
    let n = values.n;
    let n32 = u32::try_from(n)?;
    let gather = Gather::new(gpu, tuning)?;
    let mut perm: Vec<u32> = (0..n as u32).collect();
    let shuffle = random_u32s(n, 6);
    for i in (1..n).rev() {
        perm.swap(i, shuffle[i] as usize % (i + 1));
    }
    let bp = gpu.upload("bench-perm", &perm)?;
    let gs = device_buffer(gpu, "bench-gather-scratch", gather.scratch_bytes(n32))?;
    let rvals = &values.host;
    let apply = |dir: Direction| match dir {
        Direction::Gather => cpu::gather(rvals, &perm),
        Direction::Scatter => {
            let mut o = vec![0; n];
            cpu::scatter(rvals, &perm, &mut o);
            o
        }
    };
    let mut rows = Vec::new();
    for (name, dir) in [
        ("gather", Direction::Gather),
        ("scatter", Direction::Scatter),
    ] {
        let record = |rec: &mut Recorder| {
            gather.record(
                rec,
                n32,
                dir,
                (&values.buffer).into(),
                (&bp).into(),
                (&values.out).into(),
                &gs,
            )
        };
        let mut rec = gpu.recorder(StreamKind::Main)?;
        record(&mut rec)?;
        gpu.wait(&rec.submit(&[])?)?;
        check(name, &values.out.read::<u32>()?, &apply(dir))?;
        let cpu_ms = time_cpu(runs, || {
            let t = Instant::now();
            std::hint::black_box(apply(dir));
            t.elapsed().as_secs_f64() * 1e3
        });
        let t = time_gpu(gpu, runs, no_prepare, record)?;
        rows.push(row(name, n, t, &[("cpu twin", cpu_ms)]));
    }
    Ok(rows)
}

/// Minimum over `runs` of the GPU ms (less sensitive than the median to other load on a
/// shared machine) of a full 32-bit key-value sort of `n` random keys with `tuning`
/// (verified first): the measurement behind [`Tuning::for_device`]'s choices.
pub fn time_sort(gpu: &Gpu, tuning: &Tuning, n: usize, runs: usize) -> BenchResult<f64> {
    let n32 = u32::try_from(n)?;
    let sort = RadixSort::new(gpu, tuning)?;
    let keys = random_u32s(n, 1);
    let values: Vec<u32> = (0..n as u32).collect();
    let kbuf = gpu.upload("sweep-keys", &keys)?;
    let vbuf = gpu.upload("sweep-values", &values)?;
    let kinit = gpu.upload("sweep-keys-init", &keys)?;
    let vinit = gpu.upload("sweep-values-init", &values)?;
    let scratch = sort.alloc_scratch(gpu, n32)?;
    let record = |rec: &mut Recorder| {
        sort.record(
            rec,
            n32,
            (&kbuf).into(),
            Some((&vbuf).into()),
            0..32,
            &scratch,
        )
    };
    let mut rec = gpu.recorder(StreamKind::Main)?;
    record(&mut rec)?;
    gpu.wait(&rec.submit(&[])?)?;
    let (ck, cv) = expected_sort(&keys, &values);
    check("sweep sort keys", &kbuf.read::<u32>()?, &ck)?;
    check("sweep sort values", &vbuf.read::<u32>()?, &cv)?;
    let restore = |rec: &mut Recorder| {
        rec.copy(&kinit, 0, &kbuf, 0, n as u64 * 4);
        rec.copy(&vinit, 0, &vbuf, 0, n as u64 * 4);
        rec.barrier();
        Ok(())
    };
    time_gpu_min(gpu, runs, restore, record)
}

/// The CPU twin's sort of the pairs [`time_sort`] makes for `n` (its keys and values
/// depend on `n` alone), kept for the next tuning: a sweep verifies every tuning, and
/// sorting 16M pairs on the CPU each time would take longer than the timings.
fn expected_sort(keys: &[u32], values: &[u32]) -> (Arc<Vec<u32>>, Arc<Vec<u32>>) {
    type Sorted = (usize, Arc<Vec<u32>>, Arc<Vec<u32>>);
    static LAST: Mutex<Option<Sorted>> = Mutex::new(None);
    let mut last = LAST.lock().unwrap_or_else(|e| e.into_inner());
    match last.as_ref() {
        Some((n, ck, cv)) if *n == keys.len() => (ck.clone(), cv.clone()),
        _ => {
            let (ck, cv) = cpu::sort_pairs(keys, values, 0..32);
            let (ck, cv) = (Arc::new(ck), Arc::new(cv));
            *last = Some((keys.len(), ck.clone(), cv.clone()));
            (ck, cv)
        }
    }
}

/// Minimum GPU ms over `runs` of an exclusive scan of `n` u32 with `tuning` (verified
/// first).
pub fn time_scan(gpu: &Gpu, tuning: &Tuning, n: usize, runs: usize) -> BenchResult<f64> {
    let scan = VerifiedScan::new(gpu, tuning, n, "sweep-scan", "sweep scan")?;
    time_gpu_min(gpu, runs, no_prepare, |rec: &mut Recorder| scan.record(rec))
}

/// An exclusive scan of `n` values below 256 with its buffers (named `prefix`-in, -out
/// and -scratch), run once and checked against the CPU scan (as `what`) before anything
/// times it.
struct VerifiedScan {
    scan: Scan,
    n: u32,
    data: Vec<u32>,
    input: Buffer,
    output: Buffer,
    scratch: Buffer,
}

impl VerifiedScan {
    fn new(gpu: &Gpu, tuning: &Tuning, n: usize, prefix: &str, what: &str) -> BenchResult<Self> {
        let n32 = u32::try_from(n)?;
        let scan = Scan::new(gpu, tuning)?;
        let data: Vec<u32> = random_u32s(n, 2).iter().map(|x| x & 0xFF).collect();
        let input = gpu.upload(&format!("{prefix}-in"), &data)?;
        let output = device_buffer(gpu, &format!("{prefix}-out"), n as u64 * 4)?;
        let scratch = device_buffer(gpu, &format!("{prefix}-scratch"), scan.scratch_bytes(n32))?;
        let verified = Self {
            scan,
            n: n32,
            data,
            input,
            output,
            scratch,
        };
        let mut rec = gpu.recorder(StreamKind::Main)?;
        verified.record(&mut rec)?;
        gpu.wait(&rec.submit(&[])?)?;
        check(
            what,
            &verified.output.read::<u32>()?,
            &cpu::exclusive_scan(&verified.data),
        )?;
        Ok(verified)
    }

    fn record(&self, rec: &mut Recorder) -> crate::vk::Result<()> {
        self.scan.record(
            rec,
            self.n,
            (&self.input).into(),
            (&self.output).into(),
            ScanKind::Exclusive,
            &self.scratch,
        )
    }
}

/// Minimum GPU ms over `runs` of a `vkCmdCopyBuffer` of `n` u32: the yardstick of the
/// scan target, for sweeps that set scan tunings against it.
pub fn time_copy(gpu: &Gpu, n: usize, runs: usize) -> BenchResult<f64> {
    let input = device_buffer(gpu, "sweep-copy-in", n as u64 * 4)?;
    let output = device_buffer(gpu, "sweep-copy-out", n as u64 * 4)?;
    time_gpu_min(gpu, runs, no_prepare, |rec: &mut Recorder| {
        rec.copy(&input, 0, &output, 0, n as u64 * 4);
        Ok(())
    })
}

/// Minimum ms over `runs` of `sort_unstable_by_key` on the (key, value) pairs that
/// [`time_sort`] sorts: the single-thread CPU reference of the sort target.
pub fn time_cpu_sort(n: usize, runs: usize) -> f64 {
    let keys = random_u32s(n, 1);
    let pairs: Vec<(u32, u32)> = keys.into_iter().zip(0..n as u32).collect();
    (0..runs.max(1))
        .map(|_| {
            let mut p = pairs.clone();
            let t = Instant::now();
            p.sort_unstable_by_key(|x| x.0);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            std::hint::black_box(&p);
            ms
        })
        .fold(f64::INFINITY, f64::min)
}
