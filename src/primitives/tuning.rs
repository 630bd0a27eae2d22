//! Per-device choice of algorithm variant and tuning.
//!
//! All primitives use the same portable, barrier-light algorithms (no forward progress
//! between workgroups is ever assumed; no decoupled look-back): each invocation owns a
//! contiguous run of items and works through it sequentially, and workgroups cooperate
//! only through a few barriers per tile and through separate dispatches. What changes
//! per device is the shape, set by specialization constants:
//!
//! - **CPU devices (lavapipe/llvmpipe)** — variant `cpu-segments`: barrier-free
//!   segments. Every invocation owns one long contiguous segment (4096 scan items,
//!   32768 sort keys) that it reads and writes as `uvec4`s, with its own partial sum
//!   (scan) or its own column of 2^11 digit counters in shared memory (sort), and no
//!   kernel of the scan or sort has a workgroup barrier or a subgroup operation. The
//!   per-segment sums / digit histograms are written in an order (segment-major for the
//!   scan, digit-major across all segments for the sort) that one small scan turns into
//!   every segment's offset, so each segment then writes its output sequentially and
//!   stably. The sort uses 11-bit digits (3 passes for 32-bit keys; 2^11 counters × 4
//!   invocations × 4 bytes = 32 KiB of shared memory, the Vulkan minimum) and, for
//!   key-value sorts, ping-pongs through interleaved (key, value) pairs.
//!   Measured on lavapipe (Mesa 25.0.7, LLVM 15, 2 cores shared with other work;
//!   `tuning_sweep` in `tests/primitives_bench.rs`, minimum over rounds that interleave
//!   the tunings and the CPU reference; 2026-11-22, load average 3–7): a lane's buffer
//!   or shared-memory access costs about as much as a scalar access, and barriers and
//!   subgroup operations cost extra, so per-invocation segments with `uvec4` accesses
//!   win. Scan of 16M u32: segments of 4096 items 31.9 ms, 1024 33.3 ms, 16384 33.9 ms,
//!   the previous subgroup-row scan 43.8 ms, per-invocation runs with barriers 55.8 ms
//!   (load 4.7). One-invocation workgroups that never name their invocation (hoping
//!   lavapipe would emit uniform scalar code) were 2x slower than the subgroup rows.
//!   Sort of 4M pairs: 4 × 16384 keys with 11-bit digits 95.6 ms against 154.2 ms for
//!   the previous 8 × 16384 8-bit per-invocation-run sort (with barriers) and 172.6 ms
//!   for 8-bit segments (load 3.5); 4 × 32768 with pairs 122.5 / 183.1 ms against
//!   147.7 / 238.0 ms for 4 × 16384 with pairs (two sweeps, load 5.3); interleaved
//!   pairs against separate arrays within noise for 11-bit digits, 0.9x the time for
//!   8-bit. Shared-memory `atomicAdd` for the counters instead of a load and a store
//!   measured slower (8 × 16384 8-bit segments 256 ms, against 152 ms for the previous
//!   per-invocation-run sort in the same sweep) and was dropped. 8192 keys per invocation and 2-invocation workgroups were slower. With
//!   32768 keys per invocation a workgroup takes 131072 keys, so sorts below ~256K keys
//!   run on fewer workgroups than lavapipe has threads.
//!   Reduce-by-key and compaction reuse the scan's segments: per-segment run-head or
//!   kept counts, one small scan of those, then each invocation writes its segment's
//!   runs (reducing a run to its end, so none is split and no atomic is needed) or kept
//!   items in order (reduce-by-key 2.1–3.5× and compaction 1.02–1.08× the general path,
//!   4M items, interleaved minima). Gather and the general paths keep one SIMD subgroup
//!   per workgroup (`workgroup_size = subgroup_size`, queried, never assumed) with 256
//!   items per invocation.
//! - **GPUs** — variant `gpu-wide`: 128-invocation workgroups (at least one subgroup),
//!   short runs (8 to 16 items) for occupancy, and 4-bit digits so the per-invocation
//!   counter table (`2^bits × workgroup_size` words) stays small in shared memory.
//!
//! Both are checked against the device's shared-memory and workgroup limits.

use serde::Serialize;

use crate::vk::PhysicalDeviceInfo;

/// Shapes of the primitives' kernels (specialization constants).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Tuning {
    /// Variant name, printed by the benchmark.
    pub variant: &'static str,
    /// Workgroup size of the scan, compaction, reduce-by-key and gather kernels.
    pub workgroup_size: u32,
    /// Items per invocation of those kernels.
    pub items_per_invocation: u32,
    /// Workgroup size of the radix sort's histogram and scatter kernels.
    pub sort_workgroup_size: u32,
    /// Keys per invocation in the radix sort.
    pub sort_keys_per_invocation: u32,
    /// Digit width of one radix sort pass, in bits (1..=8; up to 11 for the segment
    /// sort, whose counters are per invocation and never summed inside a workgroup).
    pub radix_bits: u32,
    /// Scan rows of one subgroup with `subgroupInclusiveAdd` (coalesced, barrier-free)
    /// instead of per-invocation runs. Used only where the device has subgroup
    /// arithmetic and `workgroup_size` equals the subgroup size (checked again when the
    /// pipelines are made).
    pub subgroup_rows: bool,
    /// Sort in coalesced rows of one subgroup (ranks within a row through shared
    /// memory, ordered by subgroup barriers) instead of per-invocation runs. Used only
    /// where `sort_workgroup_size` equals the subgroup size.
    pub sort_rows: bool,
    /// Barrier-free segment sort: every invocation's keys are one segment with its own
    /// digit histogram, scanned digit-major across all segments, so neither the count
    /// nor the scatter kernel needs a workgroup barrier. Used only where
    /// `sort_keys_per_invocation` is a multiple of 4 and `sort_rows` is off.
    pub sort_segments: bool,
    /// With `sort_segments`, key-value sorts ping-pong through interleaved (key, value)
    /// pairs (one `uvec2` store per key in the scatter instead of two scalar stores,
    /// and half the output streams); the scratch holds the pairs instead of separate
    /// keys and values (same bytes).
    pub sort_pairs: bool,
    /// Items per invocation of the barrier-free segment scan (0: off): every invocation
    /// of `workgroup_size` owns this many contiguous items with its own sum, so neither
    /// scan kernel needs a barrier or a subgroup operation. A multiple of 4 (`uvec4`
    /// accesses).
    pub scan_segment: u32,
}

impl Tuning {
    /// The variant for CPU implementations of Vulkan.
    pub fn cpu(subgroup_size: u32) -> Self {
        let w = subgroup_size.clamp(4, 64);
        Self {
            variant: "cpu-segments",
            workgroup_size: w,
            items_per_invocation: 256,
            // 2^11 counters x 4 invocations x 4 bytes = 32 KiB, the least shared memory
            // Vulkan guarantees; fit() narrows the digits where a device has less.
            sort_workgroup_size: 4,
            sort_keys_per_invocation: 32768,
            radix_bits: 11,
            subgroup_rows: true,
            sort_rows: false,
            sort_segments: true,
            sort_pairs: true,
            // Quiet-machine sweep (load 0.2, 16M items, min of 5): 1024 → 17.5 ms,
            // 2048 → 16.7, 4096 → 25.4, 8192 → 16.4, 16384 → 30.3 (vkCmdCopyBuffer of
            // the same bytes 13.3). 4096-item (16 KiB) strides seem to alias in the
            // cache across a subgroup's lanes; 2048 is as fast as the best and keeps
            // more invocations busy on small inputs.
            scan_segment: 2048,
        }
    }

    /// The variant for GPUs.
    pub fn gpu(subgroup_size: u32) -> Self {
        let w = subgroup_size.clamp(128, 1024);
        Self {
            variant: "gpu-wide",
            workgroup_size: w,
            items_per_invocation: 16,
            sort_workgroup_size: w,
            sort_keys_per_invocation: 8,
            radix_bits: 4,
            subgroup_rows: false,
            sort_rows: false,
            sort_segments: false,
            sort_pairs: false,
            scan_segment: 0,
        }
    }

    /// Chooses the variant for a device and fits it to the device's limits.
    pub fn for_device(info: &PhysicalDeviceInfo) -> Self {
        let subgroup = info.limits.subgroup_size.max(1);
        let t = if info.is_cpu() {
            Self::cpu(subgroup)
        } else {
            Self::gpu(subgroup)
        };
        t.fit(info)
    }

    /// Shrinks the shapes until they fit the device's limits.
    pub fn fit(mut self, info: &PhysicalDeviceInfo) -> Self {
        let max_inv = info.limits.max_compute_work_group_invocations.max(1);
        self.workgroup_size = self.workgroup_size.clamp(1, max_inv);
        self.sort_workgroup_size = self.sort_workgroup_size.clamp(1, max_inv);
        self.items_per_invocation = self.items_per_invocation.max(1);
        self.sort_keys_per_invocation = self.sort_keys_per_invocation.max(1);
        self.subgroup_rows &= info.capabilities.subgroup_arithmetic
            && self.workgroup_size == info.limits.subgroup_size
            && self.items_per_invocation % 4 == 0;
        self.sort_rows &= self.sort_workgroup_size == info.limits.subgroup_size;
        self.sort_segments &= !self.sort_rows && self.sort_keys_per_invocation % 4 == 0;
        self.sort_pairs &= self.sort_segments;
        if self.scan_segment % 4 != 0 {
            self.scan_segment = 0;
        }
        let max_bits = if self.sort_segments { 11 } else { 8 };
        self.radix_bits = self.radix_bits.clamp(1, max_bits);
        let shared = info.limits.max_compute_shared_memory_size as u64;
        while self.sort_shared_bytes() > shared {
            if self.radix_bits > 4 {
                self.radix_bits -= 1;
            } else if self.sort_workgroup_size > 1 {
                self.sort_workgroup_size /= 2;
            } else {
                self.radix_bits -= 1;
            }
        }
        self
    }

    /// Shared memory of the sort kernels: one counter per digit per invocation.
    pub fn sort_shared_bytes(&self) -> u64 {
        (1u64 << self.radix_bits) * self.sort_workgroup_size as u64 * 4
    }

    /// Items per workgroup of the scan-like kernels.
    pub fn tile(&self) -> u32 {
        self.workgroup_size * self.items_per_invocation
    }

    /// Keys per workgroup of the sort.
    pub fn sort_tile(&self) -> u32 {
        self.sort_workgroup_size * self.sort_keys_per_invocation
    }

    /// One line for logs and benchmark output.
    pub fn describe(&self) -> String {
        format!(
            "{} (workgroup {} x {} items, {}; sort workgroup {} x {} keys, {}-bit digits, {})",
            self.variant,
            self.workgroup_size,
            self.items_per_invocation,
            if self.scan_segment > 0 {
                format!("segment scan of {} items per invocation", self.scan_segment)
            } else if self.subgroup_rows {
                "subgroup-row scan".to_string()
            } else {
                "per-invocation-run scan".to_string()
            },
            self.sort_workgroup_size,
            self.sort_keys_per_invocation,
            self.radix_bits,
            if self.sort_rows {
                "subgroup-row sort"
            } else if self.sort_segments && self.sort_pairs {
                "barrier-free segment sort, interleaved pairs"
            } else if self.sort_segments {
                "barrier-free segment sort"
            } else {
                "per-invocation-run sort"
            }
        )
    }
}
