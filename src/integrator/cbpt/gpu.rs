//! The combination on the GPU (§4, Fig. 3): a step's linking vertices go up on the
//! transfer stream, then visibility, camera shading and light shading run in batches of
//! a fixed number of segments. Two result buffers alternate: batch k computes into one
//! while batch k − 1's results download from the other on the transfer stream into the
//! host memory zone of batch k − 1; batch k + 1 waits (a timeline semaphore) until
//! batch k − 1's download has released its buffer. Nothing of size O(N_C·N_L) is ever
//! uploaded: each thread finds its two vertices from its index.
//!
//! Visibility goes through the [`Tracer`] interface, so any tracer serves: a kernel
//! writes each segment's shadow ray, the tracer answers occlusion queries, a second
//! kernel packs the answers 32 to a word.
//!
//! Two population couples can be in flight (Algorithm 2): each has its own vertex
//! buffers and host zones (`Slot`, the white and black of Fig. 4), so step t's upload
//! and batches can be submitted while step t − 1's are still running.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};

use super::layout::{CombinationData, GpuVertex, Kinds, Tables, SHADING_PLANES};
use super::pipeline::Evaluator;
use crate::bidir::scene::SHADOW_RAY_REACH;
use crate::bidir::CpuScene;
use crate::integrator::{IntegratorError, SceneFrame};
use crate::shaders;
use crate::trace::{Hit, Query, Ray, Tracer};
use crate::vk::{
    self, compute_pipeline, Buffer, ComputePipeline, Gpu, MemoryKind, Recorder, StreamKind,
    TimelinePoint,
};

const WORKGROUP: u32 = 64;

/// `CbptPush` in cbpt.glsl (32 bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct CbptPush {
    pub first: u32,
    pub count: u32,
    /// Vertices per row: V_L (camera-vertex major kernels) or V_C (light shading).
    pub inner: u32,
    /// Floats per result plane: the batch capacity.
    pub plane: u32,
    pub ray_epsilon: f32,
    pub shadow_reach: f32,
    pub pad0: u32,
    pub pad1: u32,
}

/// The three kinds of combination data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Visibility,
    Camera,
    Light,
}

/// One batch of a step: segments `first..first + count` of `kind`, downloaded into
/// host readback buffer `zone` of the step's slot from byte `at` (its zone).
#[derive(Clone, Copy, Debug)]
struct Batch {
    kind: Kind,
    first: u64,
    count: u32,
    zone: usize,
    at: u64,
}

impl Batch {
    /// Bytes of its results: the packed words, or five planes of `count` floats, which
    /// its zone holds back to back.
    fn bytes(&self) -> u64 {
        match self.kind {
            Kind::Visibility => self.count.div_ceil(32) as u64 * 4,
            Kind::Camera | Kind::Light => self.count as u64 * 4 * SHADING_PLANES as u64,
        }
    }
}

/// A population couple's memory: its linking vertices on the GPU (and their staging)
/// and the host memory its batches download into (the step's combination data, in
/// readback buffers of at most [`ZONE_BUFFER_BYTES`], grown as steps need).
#[derive(Default)]
struct Slot {
    staging: [Option<Buffer>; 2],
    vertices: [Option<Buffer>; 2],
    zones: Vec<Buffer>,
    busy: bool,
}

/// The most bytes of one readback buffer of host zones (or one batch's, if more).
const ZONE_BUFFER_BYTES: u64 = 64 << 20;

/// A step uploaded: `done` marks its upload (`None`: it has no segment).
pub struct GpuUploaded(GpuPending);

/// A step launched: `done` marks its last download (the transfer stream runs in
/// order; `None`: it has no segment).
pub struct GpuPending {
    slot: usize,
    tables: Arc<Tables>,
    batches: Vec<Batch>,
    done: Option<TimelinePoint>,
}

struct Kernels {
    rays: ComputePipeline,
    pack: ComputePipeline,
    camera: ComputePipeline,
    light: ComputePipeline,
}

/// The GPU combination of §4 (see the module docs).
pub struct GpuCombiner {
    gpu: Gpu,
    tracer: Box<dyn Tracer>,
    kernels: Kernels,
    bsdfs: Buffer,
    /// Segments per batch (a multiple of 32).
    batch: u32,
    ray_epsilon: f32,
    /// What [`Evaluator::start`] computes (everything, but for benchmarks of one kind).
    pub kinds: Kinds,
    results: [Buffer; 2],
    /// The download that last read each result buffer.
    released: [Option<TimelinePoint>; 2],
    /// Batches submitted so far: batch k uses result buffer k mod 2.
    submitted: u64,
    rays: Buffer,
    hits: Buffer,
    slots: [Slot; 2],
    next_slot: usize,
}

/// Bytes of a GPU result buffer: five planes of `batch` floats (visibility needs far
/// less).
fn result_bytes(batch: u32) -> u64 {
    batch as u64 * SHADING_PLANES as u64 * 4
}

impl GpuCombiner {
    /// The combination for `scene` on `gpu`, visibility through `tracer`, in batches of
    /// `batch` segments (a multiple of 32).
    pub fn new(
        gpu: &Gpu,
        tracer: Box<dyn Tracer>,
        scene: &CpuScene,
        batch: u32,
    ) -> Result<Self, IntegratorError> {
        if batch == 0 || batch % 32 != 0 {
            return Err(IntegratorError::Usage(format!(
                "cbpt: a batch of {batch} segments is not a positive multiple of 32"
            )));
        }
        // Compiled for the scene's layer kinds alone: lavapipe compiles a kernel at its
        // first dispatch, and the kinds a scene lacks are most of the shading kernels'
        // code.
        let bsdf_kinds = crate::bsdf::layer_kinds(&scene.tables.bsdfs);
        let constants = crate::bsdf::kernel_constants(WORKGROUP, 1, bsdf_kinds);
        let pipeline = |kernel, bindings| {
            compute_pipeline(
                gpu,
                kernel,
                bindings,
                size_of::<CbptPush>() as u32,
                &constants,
            )
        };
        let kernels = Kernels {
            rays: pipeline(shaders::INTEGRATOR_CBPT_VISIBILITY_RAYS, 3)?,
            pack: pipeline(shaders::INTEGRATOR_CBPT_VISIBILITY_PACK, 3)?,
            camera: pipeline(shaders::INTEGRATOR_CBPT_CAMERA_SHADING, 4)?,
            light: pipeline(shaders::INTEGRATOR_CBPT_LIGHT_SHADING, 4)?,
        };
        let results = |k: usize| {
            gpu.create_buffer(
                &format!("cbpt results {k}"),
                result_bytes(batch),
                MemoryKind::Device,
            )
        };
        Ok(Self {
            gpu: gpu.clone(),
            tracer,
            kernels,
            bsdfs: gpu.upload("cbpt bsdfs", &scene.tables.bsdfs)?,
            batch,
            ray_epsilon: scene.ray_epsilon,
            kinds: Kinds::ALL,
            results: [results(0)?, results(1)?],
            released: [None, None],
            submitted: 0,
            rays: gpu.create_buffer(
                "cbpt rays",
                (batch as usize * size_of::<Ray>()) as u64,
                MemoryKind::Device,
            )?,
            hits: gpu.create_buffer(
                "cbpt hits",
                (batch as usize * size_of::<Hit>()) as u64,
                MemoryKind::Device,
            )?,
            slots: Default::default(),
            next_slot: 0,
        })
    }

    /// Moves the combination to another frame of an animated scene: the tracer's
    /// geometry in the changed ranges and the ray offset of the posed scene (`scene`,
    /// already built for it); the BSDF table does not move. Called between steps only:
    /// the GPU is waited for first, so no batch of the old pose is still tracing. A slot
    /// still marked busy belonged to a step whose call ended in an error (a call that
    /// returns finishes all of its steps): its pending data went with that call, so the
    /// slot is free.
    pub fn move_to_frame(&mut self, frame: &SceneFrame<'_>, scene: &CpuScene) -> vk::Result<()> {
        self.gpu.wait_idle()?;
        if frame.geometry_changed() {
            self.tracer
                .update_geometry(frame.triangles, frame.changed)?;
        }
        self.ray_epsilon = scene.ray_epsilon;
        for slot in &mut self.slots {
            slot.busy = false;
        }
        Ok(())
    }

    pub fn tracer_name(&self) -> &'static str {
        self.tracer.name()
    }

    pub fn batch(&self) -> u32 {
        self.batch
    }

    /// Puts `tables` on the GPU in `slot`'s buffers; the point marks them there.
    fn upload_vertices(&mut self, slot: usize, tables: &Tables) -> vk::Result<TimelinePoint> {
        let gpu = self.gpu.clone();
        let s = &mut self.slots[slot];
        let mut rec = gpu.recorder(StreamKind::Transfer)?;
        rec.begin_scope("cbpt upload")?;
        for (k, records) in [&tables.camera, &tables.light].into_iter().enumerate() {
            let bytes = std::mem::size_of_val(records.as_slice()) as u64;
            let fits = |b: &Option<Buffer>| b.as_ref().is_some_and(|b| b.size() >= bytes);
            if !fits(&s.staging[k]) || !fits(&s.vertices[k]) {
                // Room for growth, so that steps of slowly varying size reuse the buffers.
                let size = (bytes + bytes / 2).max(size_of::<GpuVertex>() as u64);
                let name = ["cbpt camera vertices", "cbpt light vertices"][k];
                s.staging[k] = Some(gpu.create_buffer(name, size, MemoryKind::Upload)?);
                s.vertices[k] = Some(gpu.create_buffer(name, size, MemoryKind::Device)?);
            }
            let (staging, vertices) = (s.staging[k].as_ref(), s.vertices[k].as_ref());
            let (staging, vertices) = (staging.expect("made"), vertices.expect("made"));
            staging.write(records)?;
            rec.copy(staging, 0, vertices, 0, bytes);
        }
        rec.end_scope()?;
        rec.submit(&[])
    }

    /// Places each batch's zone in the readback buffers of `slot` (batches back to back,
    /// a new buffer where one is full) and makes or grows the buffers to fit.
    fn place_zones(&mut self, slot: usize, batches: &mut [Batch]) -> vk::Result<()> {
        let cap = ZONE_BUFFER_BYTES.max(result_bytes(self.batch));
        let mut sizes = vec![0u64];
        for b in batches.iter_mut() {
            let used = *sizes.last().expect("one");
            if used > 0 && used + b.bytes() > cap {
                sizes.push(0);
            }
            b.zone = sizes.len() - 1;
            b.at = sizes[b.zone];
            sizes[b.zone] += b.bytes();
        }
        let zones = &mut self.slots[slot].zones;
        for (k, &need) in sizes.iter().enumerate() {
            if zones.get(k).is_some_and(|z| z.size() >= need) {
                continue;
            }
            // Room for growth, so that steps of slowly varying size reuse the buffers.
            let size = (need + need / 4).min(cap).max(need);
            let zone = self.gpu.create_buffer(
                &format!("cbpt host zones {slot}.{k}"),
                size,
                MemoryKind::Readback,
            )?;
            if k < zones.len() {
                zones[k] = zone;
            } else {
                zones.push(zone);
            }
        }
        Ok(())
    }

    /// Records and submits one batch; returns its download's point.
    fn submit_batch(
        &mut self,
        slot: usize,
        tables: &Tables,
        b: &Batch,
        uploaded: &TimelinePoint,
    ) -> vk::Result<TimelinePoint> {
        let r = (self.submitted % 2) as usize;
        self.submitted += 1;
        let mut push = CbptPush {
            first: b.first as u32,
            count: b.count,
            inner: tables.light.len() as u32,
            plane: self.batch,
            ray_epsilon: self.ray_epsilon,
            shadow_reach: SHADOW_RAY_REACH,
            ..Default::default()
        };
        let s = &self.slots[slot];
        let camera = s.vertices[0].as_ref().expect("uploaded");
        let light = s.vertices[1].as_ref().expect("uploaded");
        let released: Vec<&TimelinePoint> = self.released[r].iter().collect();
        let computed = match b.kind {
            Kind::Visibility => {
                let mut rec = self.gpu.recorder(StreamKind::Main)?;
                rec.dispatch_items(
                    &self.kernels.rays,
                    &[camera.into(), light.into(), (&self.rays).into()],
                    &push,
                    b.count as u64,
                )?;
                let rays = rec.submit(&[uploaded])?;
                let traced = self.tracer.trace(
                    &self.rays,
                    &self.hits,
                    b.count,
                    Query::Occlusion,
                    &[&rays],
                )?;
                let mut rec = self.gpu.recorder(StreamKind::Main)?;
                rec.dispatch_items(
                    &self.kernels.pack,
                    &[
                        (&self.rays).into(),
                        (&self.hits).into(),
                        (&self.results[r]).into(),
                    ],
                    &push,
                    b.count.div_ceil(32) as u64,
                )?;
                let mut waits = released;
                waits.push(&traced);
                rec.submit(&waits)?
            }
            Kind::Camera | Kind::Light => {
                let kernel = if b.kind == Kind::Camera {
                    &self.kernels.camera
                } else {
                    push.inner = tables.camera.len() as u32;
                    &self.kernels.light
                };
                let mut rec = self.gpu.recorder(StreamKind::Main)?;
                rec.dispatch_items(
                    kernel,
                    &[
                        camera.into(),
                        light.into(),
                        (&self.bsdfs).into(),
                        (&self.results[r]).into(),
                    ],
                    &push,
                    b.count as u64,
                )?;
                let mut waits = released;
                waits.push(uploaded);
                rec.submit(&waits)?
            }
        };
        let mut rec = self.gpu.recorder(StreamKind::Transfer)?;
        rec.begin_scope("cbpt download")?;
        self.record_download(&mut rec, slot, r, b);
        rec.end_scope()?;
        let downloaded = rec.submit(&[&computed])?;
        self.released[r] = Some(downloaded.clone());
        Ok(downloaded)
    }

    /// Copies batch `b`'s results from result buffer `r` into its host zone.
    fn record_download(&self, rec: &mut Recorder, slot: usize, r: usize, b: &Batch) {
        let zone = &self.slots[slot].zones[b.zone];
        let results = &self.results[r];
        match b.kind {
            Kind::Visibility => rec.copy(results, 0, zone, b.at, b.bytes()),
            Kind::Camera | Kind::Light => {
                let (gpu_plane, n) = (self.batch as u64 * 4, b.count as u64 * 4);
                for p in 0..SHADING_PLANES as u64 {
                    rec.copy(results, p * gpu_plane, zone, b.at + p * n, n);
                }
            }
        }
    }

    /// The batches of a step: visibility, then camera shading, then light shading.
    fn batches(&self, tables: &Tables) -> Vec<Batch> {
        let mut out = Vec::new();
        let kinds = [
            (Kind::Visibility, self.kinds.visibility, tables.segments()),
            (Kind::Camera, self.kinds.camera, tables.segments()),
            (Kind::Light, self.kinds.light, tables.light_segments()),
        ];
        for (kind, on, total) in kinds {
            if !on {
                continue;
            }
            for first in (0..total).step_by(self.batch as usize) {
                out.push(Batch {
                    kind,
                    first,
                    count: (total - first).min(self.batch as u64) as u32,
                    zone: 0,
                    at: 0,
                });
            }
        }
        out
    }
}

impl Evaluator for GpuCombiner {
    type Uploaded = GpuUploaded;
    type Pending = GpuPending;

    /// Takes the next slot, places the step's host zones and uploads its linking
    /// vertices on the transfer stream.
    fn upload(&mut self, tables: Arc<Tables>) -> Result<GpuUploaded, IntegratorError> {
        let _span = tracing::info_span!("cbpt upload", segments = tables.segments()).entered();
        let slot = self.next_slot;
        if self.slots[slot].busy {
            return Err(IntegratorError::Usage(
                "cbpt: a third population couple started before the first finished".into(),
            ));
        }
        if tables.segments().max(tables.light_segments()) > u32::MAX as u64 {
            return Err(IntegratorError::Usage(format!(
                "cbpt: a step of {} linking segments is more than the kernels index (2^32); \
                 lower --cbpt-nc or --cbpt-nl",
                tables.segments()
            )));
        }
        let mut batches = self.batches(&tables);
        let mut done = None;
        if !batches.is_empty() {
            self.place_zones(slot, &mut batches)?;
            done = Some(self.upload_vertices(slot, &tables)?);
        }
        self.slots[slot].busy = true;
        self.next_slot = 1 - slot;
        Ok(GpuUploaded(GpuPending {
            slot,
            tables,
            batches,
            done,
        }))
    }

    /// Submits the step's batches after its upload; the pending step then waits for
    /// its last download.
    fn launch(&mut self, uploaded: GpuUploaded) -> Result<GpuPending, IntegratorError> {
        let mut step = uploaded.0;
        let _span = tracing::info_span!("cbpt launch", batches = step.batches.len()).entered();
        if let Some(uploaded) = step.done.take() {
            let mut last = uploaded.clone();
            for b in &step.batches {
                last = self.submit_batch(step.slot, &step.tables, b, &uploaded)?;
            }
            step.done = Some(last);
        }
        Ok(step)
    }

    fn finish(&mut self, p: GpuPending) -> Result<CombinationData, IntegratorError> {
        if let Some(done) = &p.done {
            let _span = tracing::info_span!("cbpt gpu wait").entered();
            self.gpu.wait(done)?;
        }
        let _span = tracing::info_span!("cbpt download copy").entered();
        let mut data = CombinationData::zeroed(&p.tables);
        for b in &p.batches {
            let zone = &self.slots[p.slot].zones[b.zone];
            let (first, n) = (b.first as usize, b.count as usize);
            match b.kind {
                Kind::Visibility => {
                    let words = &mut data.visibility[first / 32..(first + n).div_ceil(32)];
                    zone.read_mapped_into(b.at, words)?;
                }
                Kind::Camera | Kind::Light => {
                    let shading = if b.kind == Kind::Camera {
                        &mut data.camera
                    } else {
                        &mut data.light
                    };
                    for (k, out) in shading.planes_mut(first, n).into_iter().enumerate() {
                        zone.read_mapped_into(b.at + (k * n * 4) as u64, out)?;
                    }
                }
            }
        }
        self.slots[p.slot].busy = false;
        Ok(data)
    }
}

impl Drop for GpuCombiner {
    fn drop(&mut self) {
        // Batches may still be running (a render stopped by an error): the buffers they
        // use must outlive them.
        let _ = self.gpu.wait_idle();
    }
}
