//! GPU timestamps around named dispatch scopes.
//!
//! A [`Recorder`](super::Recorder) writes a timestamp pair around every named scope. The
//! query pools travel with the submission and are read back only once the stream's
//! timeline shows the work complete, so profiling never stalls the pipeline.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::time::Instant;

use ash::vk;
use serde::Serialize;

use super::device::{Gpu, StreamState, QUERIES_PER_POOL};
use super::error::{CallContext, Result};
use super::stream::StreamKind;

/// What a scope knows about the work inside it (dispatches fill it in; plain scopes
/// leave it empty).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ScopeInfo {
    /// Workgroups dispatched (x, y, z).
    pub workgroups: Option<[u32; 3]>,
    /// Items the dispatch covers, where the caller gave a count.
    pub items: Option<u64>,
    /// Bytes bound to the dispatch's storage-buffer bindings: an upper bound on what it
    /// reads and writes.
    pub bytes_bound: Option<u64>,
    /// The pipeline's first dispatch: on drivers that compile shaders at first use
    /// (lavapipe), its time includes the compilation.
    pub first_use: bool,
}

/// One timed scope.
#[derive(Clone, Debug, Serialize)]
pub struct ProfileRecord {
    pub stream: StreamKind,
    pub name: String,
    /// GPU clock at scope start and end in nanoseconds (for queue timelines).
    pub start_ns: f64,
    pub end_ns: f64,
    /// Nesting depth in its command buffer (0 = outermost). A command buffer's records
    /// are contiguous in a [`ProfileLog`], in the order their scopes began, so depths
    /// alone rebuild the nesting.
    pub depth: u32,
    /// The value the command buffer signals on its stream's timeline.
    pub submission: u64,
    pub info: ScopeInfo,
}

impl ProfileRecord {
    pub fn duration_ms(&self) -> f64 {
        (self.end_ns - self.start_ns) * 1e-6
    }
}

/// The timed scopes of one submitted command buffer, with the host time of its
/// submission (for timelines).
#[derive(Clone, Debug)]
pub struct GpuBatch {
    pub stream: StreamKind,
    pub submission: u64,
    pub submitted: Instant,
    pub records: Vec<ProfileRecord>,
}

/// Per-name totals.
#[derive(Clone, Debug, Serialize)]
pub struct KernelTime {
    pub name: String,
    pub count: usize,
    /// Time inside scopes of this name, nested scopes included.
    pub total_ms: f64,
    /// Time inside scopes of this name less the time of the scopes nested in them: the
    /// self times of all names add up to the GPU time.
    pub self_ms: f64,
    pub mean_ms: f64,
    pub max_ms: f64,
}

/// Everything timed since the log was last taken.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ProfileLog {
    pub records: Vec<ProfileRecord>,
}

impl ProfileLog {
    /// Totals per scope name, longest total first.
    pub fn summary(&self) -> Vec<KernelTime> {
        let self_ms = super::profile_tree::self_times_ms(&self.records);
        let mut by_name: BTreeMap<&str, (usize, f64, f64, f64)> = BTreeMap::new();
        for (r, own) in self.records.iter().zip(self_ms) {
            let e = by_name.entry(&r.name).or_default();
            let ms = r.duration_ms();
            e.0 += 1;
            e.1 += ms;
            e.2 = e.2.max(ms);
            e.3 += own;
        }
        let mut out: Vec<_> = by_name
            .into_iter()
            .map(|(name, (count, total_ms, max_ms, self_ms))| KernelTime {
                name: name.to_string(),
                count,
                total_ms,
                self_ms,
                mean_ms: total_ms / count as f64,
                max_ms,
            })
            .collect();
        out.sort_by(|a, b| b.total_ms.total_cmp(&a.total_ms));
        out
    }

    /// A printable table of [`ProfileLog::summary`].
    pub fn table(&self) -> String {
        Self::table_of(&self.summary())
    }

    /// A printable table of per-kernel totals.
    pub fn table_of(rows: &[KernelTime]) -> String {
        let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(6).max(6);
        let mut s = format!(
            "{:<width$}  {:>7}  {:>11}  {:>11}  {:>10}  {:>10}\n",
            "kernel", "count", "total ms", "self ms", "mean ms", "max ms"
        );
        for r in rows {
            let _ = writeln!(
                s,
                "{:<width$}  {:>7}  {:>11.3}  {:>11.3}  {:>10.4}  {:>10.4}",
                r.name, r.count, r.total_ms, r.self_ms, r.mean_ms, r.max_ms
            );
        }
        s
    }

    /// The scopes as a tree aggregated by path, with total and self times.
    pub fn tree(&self) -> super::ProfileTree {
        super::ProfileTree::from_records(&self.records)
    }

    pub fn extend(&mut self, other: ProfileLog) {
        self.records.extend(other.records);
    }
}

/// The timestamp queries of one command buffer.
#[derive(Default)]
pub(crate) struct QueryBatch {
    pub(crate) pools: Vec<vk::QueryPool>,
    /// In the order the scopes began.
    pub(crate) scopes: Vec<ScopeQueries>,
    pub(crate) next: u32,
}

/// One scope's queries: `None` where the queue writes no timestamps (or, for `end`,
/// while the scope is open).
pub(crate) struct ScopeQueries {
    pub(crate) name: String,
    pub(crate) begin: Option<u32>,
    pub(crate) end: Option<u32>,
    pub(crate) depth: u32,
    pub(crate) info: ScopeInfo,
}

impl QueryBatch {
    pub(crate) fn location(index: u32) -> (usize, u32) {
        (
            (index / QUERIES_PER_POOL) as usize,
            index % QUERIES_PER_POOL,
        )
    }
}

/// Reads a finished batch's timestamps into records.
pub(crate) fn read_batch(
    gpu: &Gpu,
    stream: &StreamState,
    batch: &QueryBatch,
    submission: u64,
) -> Result<Vec<ProfileRecord>> {
    if batch.scopes.is_empty() {
        return Ok(Vec::new());
    }
    let mut raw = vec![0u64; batch.pools.len() * QUERIES_PER_POOL as usize];
    for (i, &pool) in batch.pools.iter().enumerate() {
        let first = i as u32 * QUERIES_PER_POOL;
        let count = batch.next.saturating_sub(first).min(QUERIES_PER_POOL);
        if count == 0 {
            continue;
        }
        let dst = &mut raw[first as usize..(first + count) as usize];
        // SAFETY: the pool belongs to this device; the work that wrote these queries has
        // completed (its timeline value was reached), so the results are available.
        unsafe {
            gpu.0
                .raw
                .get_query_pool_results(pool, 0, dst, vk::QueryResultFlags::TYPE_64)
        }
        .call("vkGetQueryPoolResults")?;
    }
    let period = gpu.0.info.limits.timestamp_period_ns as f64;
    let mask = stream.timestamp_mask;
    Ok(batch
        .scopes
        .iter()
        .filter_map(|scope| {
            let t0 = raw[scope.begin? as usize] & mask;
            let t1 = raw[scope.end? as usize] & mask;
            // Masked subtraction handles a counter that wrapped inside the scope.
            let ticks = t1.wrapping_sub(t0) & mask;
            let start_ns = t0 as f64 * period;
            Some(ProfileRecord {
                stream: stream.kind,
                name: scope.name.clone(),
                start_ns,
                end_ns: start_ns + ticks as f64 * period,
                depth: scope.depth,
                submission,
                info: scope.info,
            })
        })
        .collect())
}
