//! Per-device choice of algorithm variant and tuning.
//!
//! All primitives use the same portable, barrier-light algorithms (no forward progress
//! between workgroups is ever assumed; no decoupled look-back): each invocation owns a
//! contiguous run of items and works through it sequentially, and workgroups cooperate
//! only through a few barriers per tile and through separate dispatches. What changes
//! per device is the shape, set by specialization constants:
//!
//! - **CPU devices (lavapipe/llvmpipe)** — variant `cpu-segments`: barrier-free
//!   segments. Every invocation owns one long contiguous segment (4112 scan items,
//!   32768 sort keys) that it reads and writes as `u64vec4`s (eight u32 per access;
//!   `uvec4`s without shaderInt64: [`Tuning::wide_accesses`]), with its own partial sum
//!   (scan) or its own column of 2^11 digit counters in shared memory (sort), and no
//!   kernel of the scan or sort has a workgroup barrier or a subgroup operation. The
//!   per-segment sums / digit histograms are written in an order (segment-major for the
//!   scan, digit-major across all segments for the sort) that one small scan turns into
//!   every segment's offset, so each segment then writes its output sequentially and
//!   stably. The sort uses 11-bit digits (3 passes for 32-bit keys; 2^11 counters × 4
//!   invocations × 4 bytes = 32 KiB of shared memory, the Vulkan minimum) and, for
//!   key-value sorts, ping-pongs through interleaved (key, value) pairs.
//!   Measured on lavapipe (Mesa 25.0.7, LLVM 15, 2 cores shared with other work;
//!   `tuning_sweep` in `tests/suite/primitives_bench.rs`, minimum over rounds that interleave
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
//!   per-invocation-run sort in the same sweep) and was dropped. 8192 keys per
//!   invocation and 2-invocation workgroups were slower. With 32768 keys per
//!   invocation a workgroup takes 131072 keys, so sorts below ~256K keys run on fewer
//!   workgroups than lavapipe has threads.
//!   64-bit accesses (2026-11-24, an AMD EPYC host): lavapipe makes one scalar access
//!   per component of a lane's load or store whatever the component's width, and its
//!   per-lane overhead (exec-mask test, descriptor and bounds reload) is paid once per
//!   lane per access, so four 64-bit components carry twice the bytes of a `uvec4` for
//!   the same cost. A per-invocation segment copy of 16M u32 took 9.5-13.0 ms with
//!   `uvec4`, 8.4-9.9 with `u64vec2` and 6.0-6.6 with `u64vec4` (a `vkCmdCopyBuffer` of
//!   the same bytes 5.3-6.3 ms); a segment sum 4.3-7.7 ms against 3.4-3.7 (minima of
//!   interleaved rounds, three runs; docs/PERFORMANCE.md). The scan of 16M
//!   items went from 14.5 to 11.6 ms (2048-item segments; sweep minima of 5 rounds),
//!   the sort of 4M pairs from 55.6 to 48.8 ms (CPU `sort_unstable_by_key` 78.0 ms).
//!   Reduce-by-key and compaction reuse the scan's segments: per-segment run-head or
//!   kept counts, one small scan of those, then each invocation writes its segment's
//!   runs (reducing a run to its end, so none is split and no atomic is needed) or kept
//!   items in order (reduce-by-key 2.1–3.5× and compaction 1.02–1.08× the general path,
//!   4M items, interleaved minima). Gathers move segments of the scan's length with
//!   64-bit index and output accesses (`gather.comp`, variant `seg64`); scatters and the
//!   general paths keep one SIMD subgroup per workgroup (`workgroup_size =
//!   subgroup_size`, queried, never assumed) with 256 items per invocation.
//! - **GPUs** — variant `gpu-multisplit` (`gpu-wide` where the sort must fall back):
//!   128-invocation workgroups (at least one subgroup) with short runs of 16 items for
//!   the scan-like kernels, for occupancy. The sort is a reduce-then-scan LSD sort
//!   with 8-bit digits over tiles of 512 invocations × 7 keys ([`Tuning::sort_multisplit`]):
//!   a histogram per tile counted with shared atomics, one scan of the digit-major
//!   histograms, and a scatter that ranks each subgroup's keys by ballots over the digit
//!   bits (warp-level multisplit), sorts the tile in shared memory and writes each digit's
//!   run coalesced. Still no forward-progress assumption (no decoupled look-back). Where
//!   a device lacks subgroup ballot and shuffle or full subgroups, the sort falls back to
//!   per-invocation runs with 4-bit digits (the per-invocation counter table of
//!   `2^bits × workgroup_size` words must stay small in shared memory). Measured on an
//!   NVIDIA H100 (2026-11-23, `bench primitives --n 16777216 --runs 9`): the multisplit
//!   sort sorts 16M pairs in 1.53 ms (10.9 Gkeys/s); the fallback took 25.2 ms in the
//!   benchmark as it stood before this variant and 5.13 ms in the shape sweep of
//!   [`Tuning::gpu`]. docs/PERFORMANCE.md has the figures.
//!
//! Both are checked against the device's shared-memory and workgroup limits.

use serde::Serialize;

use crate::vk::PhysicalDeviceInfo;

/// Whether `info`'s device can run the multisplit sort with `workgroup` invocations:
/// subgroup ballot, shuffle and arithmetic in compute shaders, and full subgroups of
/// any size it may choose.
pub fn multisplit_supported(info: &PhysicalDeviceInfo, workgroup: u32) -> bool {
    let c = &info.capabilities;
    c.subgroup_ballot_shuffle
        && c.subgroup_arithmetic
        && c.compute_full_subgroups
        && workgroup % info.limits.max_subgroup_size.max(1) == 0
        && workgroup <= info.limits.max_compute_work_group_invocations
}

/// Whether `info`'s device can run the `wide64` segment kernels
/// ([`Tuning::wide_accesses`]): shaderInt64 (enabled on the device where present), and
/// storage-buffer offsets that keep every binding's 64-bit components 8-byte aligned.
pub fn wide_accesses_supported(info: &PhysicalDeviceInfo) -> bool {
    info.capabilities.shader_int64 && info.limits.min_storage_buffer_offset_alignment % 8 == 0
}

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
    /// Multisplit tiles (GPUs): per-tile histograms with shared atomics, and a scatter
    /// that ranks keys with subgroup ballots, sorts the tile in shared memory and writes
    /// coalesced (`sort_ms_*.comp`). Digits of at most 8 bits. Used only where the device
    /// has subgroup ballot, shuffle and arithmetic and full subgroups, and
    /// `sort_workgroup_size` is a multiple of the largest subgroup size.
    pub sort_multisplit: bool,
    /// With `sort_segments`, key-value sorts ping-pong through interleaved (key, value)
    /// pairs (one `uvec2` store per key in the scatter instead of two scalar stores,
    /// and half the output streams); the scratch holds the pairs instead of separate
    /// keys and values (same bytes).
    pub sort_pairs: bool,
    /// Items per invocation of the barrier-free segment scan (0: off): every invocation
    /// of `workgroup_size` owns this many contiguous items with its own sum, so neither
    /// scan kernel needs a barrier or a subgroup operation. A multiple of 4 (`uvec4`
    /// accesses), of 8 for 64-bit accesses.
    pub scan_segment: u32,
    /// The segment kernels read and write 64-bit vector components (`u64vec4`, eight
    /// u32 per access instead of four per `uvec4`). lavapipe makes one scalar access
    /// per component of every lane's load or store, whatever the component's width,
    /// so this halves the accesses of the streaming kernels. Used only where the device
    /// has shaderInt64 and storage-buffer offsets are 8-byte aligned; segments are then
    /// a multiple of 8 items.
    pub wide_accesses: bool,
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
            sort_multisplit: false,
            sort_pairs: true,
            // Segments a little off a power of two: with 64-bit accesses, three sweeps
            // of 16M items (2026-11-24, AMD EPYC host, minima of 5 interleaved rounds
            // each) gave 4112 items 9.4-9.7 ms, 8208 9.1, 4096 10.4-11.1, 2064
            // 10.6-16.0, 2048 10.4-11.6, 1024 11.1-14.1, against a vkCmdCopyBuffer of
            // the same bytes of 6.3-6.7 ms. Power-of-two strides (16 KiB apart) let a
            // subgroup's eight lane streams alias in the cache. 4112 keeps two
            // workgroups, one per lavapipe thread, from 66K items on.
            scan_segment: 4112,
            wide_accesses: true,
        }
    }

    /// The variant for GPUs with subgroup ballot and shuffle and full subgroups: the
    /// multisplit sort, in tiles of 512 invocations × 7 keys. Shape sweep on an NVIDIA
    /// H100 (16M pairs, minimum of 3 rounds, two sweeps on 2026-11-23 agreeing within
    /// 1%): 512 × 7 1.54 ms, 384 × 10 1.58, 256 × 16 1.65, 256 × 18 1.66–1.67,
    /// 256 × 15 1.72, 128 × 16 1.74, 256 × 12 1.81, 256 × 8 2.10, 128 × 24 2.42; the
    /// per-invocation-run fallback 5.13 ms. Larger tiles overflow 48 KiB of shared
    /// memory at 512 invocations.
    pub fn gpu(subgroup_size: u32) -> Self {
        Self {
            variant: "gpu-multisplit",
            sort_workgroup_size: subgroup_size.clamp(512, 1024),
            sort_keys_per_invocation: 7,
            radix_bits: 8,
            sort_multisplit: true,
            ..Self::gpu_runs(subgroup_size)
        }
    }

    /// The variant for other GPUs: the sort in per-invocation runs of 8 keys with 4-bit
    /// digits, whose per-invocation counter tables stay small in shared memory.
    pub fn gpu_runs(subgroup_size: u32) -> Self {
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
            sort_multisplit: false,
            sort_pairs: false,
            scan_segment: 0,
            wide_accesses: false,
        }
    }

    /// Chooses the variant for a device and fits it to the device's limits.
    pub fn for_device(info: &PhysicalDeviceInfo) -> Self {
        let subgroup = info.limits.subgroup_size.max(1);
        let gpu = Self::gpu(subgroup);
        let t = if info.is_cpu() {
            Self::cpu(subgroup)
        } else if multisplit_supported(info, gpu.sort_workgroup_size) {
            gpu
        } else {
            Self::gpu_runs(subgroup)
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
        self.sort_multisplit &= multisplit_supported(info, self.sort_workgroup_size);
        if self.sort_multisplit {
            self.sort_rows = false;
            self.sort_segments = false;
        }
        self.sort_segments &= !self.sort_rows && self.sort_keys_per_invocation % 4 == 0;
        self.sort_pairs &= self.sort_segments;
        if self.scan_segment % 4 != 0 {
            self.scan_segment = 0;
        }
        self.wide_accesses &= wide_accesses_supported(info);
        let max_bits = if self.sort_segments { 11 } else { 8 };
        self.radix_bits = self.radix_bits.clamp(1, max_bits);
        let shared = info.limits.max_compute_shared_memory_size as u64;
        let max_subgroup = info.limits.max_subgroup_size.max(1);
        while self.sort_shared_bytes(info) > shared {
            let half = self.sort_workgroup_size / 2;
            if self.sort_multisplit && half >= 64 && half % max_subgroup == 0 {
                // Fewer subgroups (their counters dominate where subgroups are narrow);
                // more keys per invocation keep the tile about as long.
                self.sort_workgroup_size = half;
                self.sort_keys_per_invocation = (self.sort_keys_per_invocation * 2).min(16);
            } else if self.sort_multisplit && self.sort_keys_per_invocation > 1 {
                // A shorter tile; the workgroup must stay a multiple of the subgroup size.
                self.sort_keys_per_invocation -= 1;
            } else if self.radix_bits > 4 {
                self.radix_bits -= 1;
            } else if self.sort_workgroup_size > 1 {
                self.sort_workgroup_size /= 2;
            } else {
                self.radix_bits -= 1;
            }
        }
        self
    }

    /// Shared memory of the sort kernels on `info`'s device: for the multisplit
    /// scatter, one counter per digit per subgroup and the tile's keys and values; for
    /// the others, one counter per digit per invocation.
    pub fn sort_shared_bytes(&self, info: &PhysicalDeviceInfo) -> u64 {
        let radix = 1u64 << self.radix_bits;
        if self.sort_multisplit {
            let subgroups = self.sort_max_subgroups(info) as u64;
            let tile = self.sort_tile() as u64;
            (subgroups * radix + radix + subgroups + 2 * tile) * 4
        } else {
            radix * self.sort_workgroup_size as u64 * 4
        }
    }

    /// Most subgroups a sort workgroup can hold on `info`'s device (the multisplit
    /// scatter's per-subgroup counters).
    pub fn sort_max_subgroups(&self, info: &PhysicalDeviceInfo) -> u32 {
        self.sort_workgroup_size
            .div_ceil(info.limits.min_subgroup_size.max(1))
    }

    /// Items per workgroup of the scan-like kernels.
    pub fn tile(&self) -> u32 {
        self.workgroup_size * self.items_per_invocation
    }

    /// Keys per workgroup of the sort.
    pub fn sort_tile(&self) -> u32 {
        self.sort_workgroup_size * self.sort_keys_per_invocation
    }

    /// Whether segment kernels over segments of `segment` items run with 64-bit
    /// accesses on `info`'s device: asked for, supported, and segments of a multiple of 8.
    pub(crate) fn wide_segments(&self, info: &PhysicalDeviceInfo, segment: u32) -> bool {
        self.wide_accesses && segment > 0 && segment % 8 == 0 && wide_accesses_supported(info)
    }

    /// One line for logs and benchmark output.
    pub fn describe(&self) -> String {
        format!(
            "{} (workgroup {} x {} items, {}; sort workgroup {} x {} keys, {}-bit digits, {}{})",
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
            if self.sort_multisplit {
                "multisplit tiles"
            } else if self.sort_rows {
                "subgroup-row sort"
            } else if self.sort_segments && self.sort_pairs {
                "barrier-free segment sort, interleaved pairs"
            } else if self.sort_segments {
                "barrier-free segment sort"
            } else {
                "per-invocation-run sort"
            },
            if self.wide_accesses && (self.scan_segment > 0 || self.sort_segments) {
                "; 64-bit accesses in the segment kernels"
            } else {
                ""
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::{CapabilityInfo, LimitsInfo};

    fn device(shared_kib: u32, subgroups: (u32, u32), ballots: bool) -> PhysicalDeviceInfo {
        PhysicalDeviceInfo::synthetic(
            "discrete",
            LimitsInfo {
                max_storage_buffer_range: 1 << 32,
                max_compute_shared_memory_size: shared_kib << 10,
                max_compute_work_group_invocations: 1024,
                max_compute_work_group_count: [65535; 3],
                max_push_constants_size: 128,
                min_storage_buffer_offset_alignment: 64,
                timestamp_period_ns: 1.0,
                subgroup_size: subgroups.1,
                min_subgroup_size: subgroups.0,
                max_subgroup_size: subgroups.1,
                max_memory_allocation_size: 1 << 32,
                max_buffer_size: 1 << 40,
                device_local_bytes: 8 << 30,
            },
            CapabilityInfo {
                timeline_semaphore: true,
                synchronization2: true,
                maintenance4: true,
                buffer_device_address: true,
                push_descriptor: true,
                ray_query: false,
                subgroup_arithmetic: true,
                subgroup_ballot_shuffle: ballots,
                compute_full_subgroups: ballots,
                shader_int64: true,
                buffer_int64_atomics: true,
                host_query_reset: true,
            },
        )
    }

    /// The multisplit shape fits the device's shared memory, keeps its workgroup a
    /// multiple of every subgroup size the device may choose, and keeps 8-bit digits.
    fn assert_multisplit_fits(info: &PhysicalDeviceInfo) -> Tuning {
        let t = Tuning::for_device(info);
        assert!(t.sort_multisplit, "{}", t.describe());
        assert_eq!(t.radix_bits, 8, "{}", t.describe());
        assert_eq!(t.sort_workgroup_size % info.limits.max_subgroup_size, 0);
        let shared = info.limits.max_compute_shared_memory_size as u64;
        assert!(t.sort_shared_bytes(info) <= shared, "{}", t.describe());
        t
    }

    #[test]
    fn gpus_with_ballots_get_the_multisplit_sort_within_their_shared_memory() {
        // NVIDIA (the measured default), AMD RDNA (wave32 or wave64), Intel (SIMD8..32),
        // and a small-shared-memory GPU with narrow subgroups.
        let nvidia = assert_multisplit_fits(&device(48, (32, 32), true));
        assert_eq!(
            (nvidia.sort_workgroup_size, nvidia.sort_keys_per_invocation),
            (512, 7)
        );
        assert_multisplit_fits(&device(64, (32, 64), true));
        assert_multisplit_fits(&device(64, (8, 32), true));
        let small = assert_multisplit_fits(&device(32, (8, 8), true));
        assert!(small.sort_tile() >= 1024, "{}", small.describe());
    }

    #[test]
    fn gpus_without_ballots_fall_back_to_per_invocation_runs() {
        let t = Tuning::for_device(&device(48, (32, 32), false));
        assert!(!t.sort_multisplit && !t.sort_segments && !t.sort_rows);
        assert_eq!(t.variant, "gpu-wide");
        assert!(t.sort_shared_bytes(&device(48, (32, 32), false)) <= 48 << 10);
    }
}
