//! The per-path buffers of a wavefront of paths, shared by the light pass and the camera
//! pass (which run one after the other), and the shadow-ray buffers that the camera
//! pass fills with one direct-lighting and N connection rays per path, and light tracing
//! with one ray per cache vertex of a batch.

use super::gpu::{Contribution, LvcVertex, VisibilityTally, WalkState};
use crate::integrator::pt::MaterialSort;
use crate::primitives::compact::Kept;
use crate::primitives::{Compact, Tuning};
use crate::trace::{Hit, Ray};
use crate::vk::{self, Buffer, Gpu, MemoryKind, Recorder, TimelinePoint};

/// Slots the connections' region may start after the direct-lighting slots (it starts
/// at a storage-buffer offset the device can bind: up to 2 KiB of 32-byte slots).
const ALIGNMENT_SLACK: usize = 64;

/// Where the tally lies in the readback buffer, after the two counts.
const TALLY_READBACK_OFFSET: u64 = 8;
const TALLY_BYTES: u64 = size_of::<VisibilityTally>() as u64;

pub struct Wavefront {
    /// Paths it holds.
    pub capacity: u32,
    /// Shadow rays it holds: (1 + N) per path, and room for the connections' region to
    /// start at an aligned offset.
    pub shadow_capacity: u32,
    /// Two of the ray and active lists: compaction gathers survivors from one into the
    /// other.
    pub rays: [Buffer; 2],
    pub active: [Buffer; 2],
    pub hits: Buffer,
    /// Per path (by id): the walk's state.
    pub paths: Buffer,
    pub keys: Buffer,
    pub order: Buffer,
    /// Per live path: the vertex it reached this bounce.
    pub vertices: Buffer,
    /// Light pass: the vertex goes to the cache.
    pub stored: Buffer,
    pub alive: Buffer,
    pub kept: Buffer,
    pub kept_vertices: Buffer,
    /// Camera pass: per live path its emitter hit, per path (by id) its radiance.
    pub emitted: Buffer,
    pub radiance: Buffer,
    pub shadow_rays: Buffer,
    pub shadow_hits: Buffer,
    pub contributions: Buffer,
    /// The two counts of a light bounce (vertices marked, paths alive), or the
    /// survivors of a camera bounce, on the device and for the host.
    pub count_marked: Buffer,
    pub count_alive: Buffer,
    /// A camera bounce's [`VisibilityTally`].
    pub tally: Buffer,
    /// The two counts (bytes 0–7) and the tally (from `TALLY_READBACK_OFFSET`).
    pub counts_readback: Buffer,
    pub compact: Compact,
    compact_scratch: Buffer,
    pub(crate) sorter: Option<MaterialSort>,
}

impl Wavefront {
    /// Buffers for `capacity` paths with `connections` connection rays each.
    pub fn new(gpu: &Gpu, capacity: u32, connections: u32, sort: bool) -> vk::Result<Self> {
        let c = capacity.max(1) as usize;
        let shadow = (1 + connections as usize) * c + ALIGNMENT_SLACK;
        let tuning = Tuning::for_device(gpu.info());
        let compact = Compact::new(gpu, &tuning)?;
        let compact_scratch = gpu.create_buffer(
            "lvc-compact-scratch",
            compact.scratch_bytes(c as u32),
            MemoryKind::Device,
        )?;
        let sorter = sort
            .then(|| MaterialSort::new(gpu, &tuning, c as u32))
            .transpose()?;
        Ok(Self {
            capacity: c as u32,
            shadow_capacity: shadow as u32,
            rays: [
                gpu.zeroed::<Ray>("lvc-rays-0", c)?,
                gpu.zeroed::<Ray>("lvc-rays-1", c)?,
            ],
            active: [
                gpu.zeroed::<u32>("lvc-active-0", c)?,
                gpu.zeroed::<u32>("lvc-active-1", c)?,
            ],
            hits: gpu.zeroed::<Hit>("lvc-hits", c)?,
            paths: gpu.zeroed::<WalkState>("lvc-paths", c)?,
            keys: gpu.zeroed::<u32>("lvc-keys", c)?,
            order: gpu.zeroed::<u32>("lvc-order", c)?,
            vertices: gpu.zeroed::<LvcVertex>("lvc-vertices", c)?,
            stored: gpu.zeroed::<u32>("lvc-stored", c)?,
            alive: gpu.zeroed::<u32>("lvc-alive", c)?,
            kept: gpu.zeroed::<u32>("lvc-kept", c)?,
            kept_vertices: gpu.zeroed::<u32>("lvc-kept-vertices", c)?,
            emitted: gpu.zeroed::<Contribution>("lvc-emitted", c)?,
            radiance: gpu.zeroed::<[f32; 4]>("lvc-radiance", c)?,
            shadow_rays: gpu.zeroed::<Ray>("lvc-shadow-rays", shadow)?,
            shadow_hits: gpu.zeroed::<Hit>("lvc-shadow-hits", shadow)?,
            contributions: gpu.zeroed::<Contribution>("lvc-contributions", shadow)?,
            count_marked: gpu.zeroed::<u32>("lvc-count-marked", 1)?,
            count_alive: gpu.zeroed::<u32>("lvc-count-alive", 1)?,
            tally: gpu.zeroed::<VisibilityTally>("lvc-tally", 1)?,
            counts_readback: gpu.create_buffer(
                "lvc-counts",
                TALLY_READBACK_OFFSET + TALLY_BYTES,
                MemoryKind::Readback,
            )?,
            compact,
            compact_scratch,
            sorter,
        })
    }

    /// Records the compaction of the first `n` of `flags` into `out` (indices of the
    /// kept items, in order) with their count in `count`.
    pub fn record_compact(
        &self,
        rec: &mut Recorder,
        n: u32,
        flags: &Buffer,
        out: &Buffer,
        count: &Buffer,
    ) -> vk::Result<()> {
        self.compact.record(
            rec,
            n,
            flags.into(),
            Kept::Indices,
            out.into(),
            count.into(),
            &self.compact_scratch,
        )
    }

    /// Records the copy of the two counts to the host-visible buffer.
    pub fn record_counts_readback(&self, rec: &mut Recorder) {
        rec.copy(&self.count_marked, 0, &self.counts_readback, 0, 4);
        rec.copy(&self.count_alive, 0, &self.counts_readback, 4, 4);
    }

    /// Records the copy of the camera bounce's tally to the host-visible buffer.
    pub fn record_tally_readback(&self, rec: &mut Recorder) {
        rec.copy(
            &self.tally,
            0,
            &self.counts_readback,
            TALLY_READBACK_OFFSET,
            TALLY_BYTES,
        );
    }

    /// A camera bounce's survivors (at most `n`) and tally, in one read of what the
    /// readbacks recorded in the submission that ends at `done` left.
    pub fn read_camera_counts(
        &self,
        n: u32,
        done: &TimelinePoint,
    ) -> vk::Result<(u32, VisibilityTally)> {
        let words = self.counts_readback.read_after::<u32>(done)?;
        let at = (TALLY_READBACK_OFFSET / 4) as usize;
        let tally = bytemuck::cast_slice::<u32, VisibilityTally>(&words[at..at + 4])[0];
        Ok((words[1].min(n), tally))
    }

    /// (vertices marked, paths alive), each at most `n`, as the readback recorded in the
    /// submission that ends at `done` left them.
    pub fn read_counts(&self, n: u32, done: &TimelinePoint) -> vk::Result<(u32, u32)> {
        let c = self.counts_readback.read_after::<u32>(done)?;
        Ok((c[0].min(n), c[1].min(n)))
    }
}
