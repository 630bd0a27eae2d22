//! GPU timestamps around named dispatch scopes.
//!
//! A [`Recorder`](super::Recorder) writes a timestamp pair around every named scope. The
//! query pools travel with the submission and are read back only once the stream's
//! timeline shows the work complete, so profiling never stalls the pipeline.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use ash::vk;
use serde::Serialize;

use super::device::{Gpu, StreamState, QUERIES_PER_POOL};
use super::error::{CallContext, Result};
use super::stream::StreamKind;

/// One timed scope.
#[derive(Clone, Debug, Serialize)]
pub struct ProfileRecord {
    pub stream: StreamKind,
    pub name: String,
    /// GPU clock at scope start and end in nanoseconds (for queue timelines).
    pub start_ns: f64,
    pub end_ns: f64,
}

impl ProfileRecord {
    pub fn duration_ms(&self) -> f64 {
        (self.end_ns - self.start_ns) * 1e-6
    }
}

/// Per-name totals.
#[derive(Clone, Debug, Serialize)]
pub struct KernelTime {
    pub name: String,
    pub count: usize,
    pub total_ms: f64,
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
        let mut by_name: BTreeMap<&str, (usize, f64, f64)> = BTreeMap::new();
        for r in &self.records {
            let e = by_name.entry(&r.name).or_default();
            let ms = r.duration_ms();
            e.0 += 1;
            e.1 += ms;
            e.2 = e.2.max(ms);
        }
        let mut out: Vec<_> = by_name
            .into_iter()
            .map(|(name, (count, total_ms, max_ms))| KernelTime {
                name: name.to_string(),
                count,
                total_ms,
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
            "{:<width$}  {:>7}  {:>11}  {:>10}  {:>10}\n",
            "kernel", "count", "total ms", "mean ms", "max ms"
        );
        for r in rows {
            let _ = writeln!(
                s,
                "{:<width$}  {:>7}  {:>11.3}  {:>10.4}  {:>10.4}",
                r.name, r.count, r.total_ms, r.mean_ms, r.max_ms
            );
        }
        s
    }

    pub fn extend(&mut self, other: ProfileLog) {
        self.records.extend(other.records);
    }
}

/// The timestamp queries of one command buffer.
#[derive(Default)]
pub(crate) struct QueryBatch {
    pub(crate) pools: Vec<vk::QueryPool>,
    /// (name, index of the begin query, index of the end query).
    pub(crate) scopes: Vec<(String, u32, u32)>,
    pub(crate) next: u32,
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
        .map(|(name, begin, end)| {
            let t0 = raw[*begin as usize] & mask;
            let t1 = raw[*end as usize] & mask;
            // Masked subtraction handles a counter that wrapped inside the scope.
            let ticks = t1.wrapping_sub(t0) & mask;
            let start_ns = t0 as f64 * period;
            ProfileRecord {
                stream: stream.kind,
                name: name.clone(),
                start_ns,
                end_ns: start_ns + ticks as f64 * period,
            }
        })
        .collect())
}
