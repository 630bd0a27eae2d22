//! Per-device choice of algorithm variant and tuning.
//!
//! All primitives use the same portable, barrier-light algorithms (no forward progress
//! between workgroups is ever assumed; no decoupled look-back): each invocation owns a
//! contiguous run of items and works through it sequentially, and workgroups cooperate
//! only through a few barriers per tile and through separate dispatches. What changes
//! per device is the shape, set by specialization constants:
//!
//! - **CPU devices (lavapipe/llvmpipe)** — variant `cpu-segments`: a workgroup is one
//!   SIMD subgroup (`workgroup_size = subgroup_size`, queried, never assumed), each
//!   invocation owns long runs (256 scan items, 16384 sort keys) read as `uvec4`s, the scan
//!   runs in coalesced subgroup rows (`subgroupInclusiveAdd`, where the device has
//!   subgroup arithmetic), and the sort uses 8-bit digits (4 passes for 32-bit keys).
//!   Measured on lavapipe (Mesa 25, `tuning_sweep` in `tests/primitives_bench.rs`): every
//!   per-lane buffer or shared-memory access costs about as much as a scalar access, so
//!   fewer, wider accesses win; the subgroup-row sort (ranks through shared memory and
//!   subgroup barriers) was 2-3x slower than per-invocation runs and is off; wider
//!   workgroups and 4- or 6-bit digits were slower too; long runs win (4M keys: 16384
//!   keys per invocation 178 ms, 4096 232 ms, 1024 199 ms, 256 355 ms — the per-tile
//!   work of clearing, summing and scanning 256 × 8 shared counters is amortised, and
//!   the histogram of digits by tile that must be scanned shrinks). With 4M keys that
//!   is still 32 workgroups, enough for lavapipe's threads.
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
            scan_segment: 4096,
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
            if self.subgroup_rows {
                "subgroup-row scan"
            } else {
                "per-invocation-run scan"
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
