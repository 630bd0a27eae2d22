//! First-hit AOVs of every render: one pass of rays through the pixel centres, traced by
//! the render's tracer, gives per pixel the distance to the first hit along the unit
//! ray (`+inf` on a miss), the hit triangle (`u32::MAX` on a miss) and the geometric
//! normal facing the viewer. Independent of the integrator, so a pt, bpt or cbpt image
//! carries the same AOVs as a `primary` one.
//!
//! Stages per chunk of pixels: `camera_rays` (unjittered) → trace → `write_aovs`.

use super::gpu_types::FrameParams;
use crate::scene::CameraFrame;
use crate::shaders;
use crate::trace::{Hit, Query, Ray, Tracer};
use crate::vk::{self, compute_pipeline, Buffer, Gpu, StreamKind};

const WORKGROUP: u32 = 64;
/// Rays per chunk: bounds the ray and hit buffers whatever the film size.
const CHUNK: usize = 1 << 20;

/// The AOVs of a film, in pixel order (row 0 at the top).
#[derive(Clone, Debug, PartialEq)]
pub struct Aovs {
    pub depth: Vec<f32>,
    pub triangle_id: Vec<u32>,
    pub normal: Vec<[f32; 3]>,
}

/// Traces one ray through each pixel centre of `camera`'s film and returns its AOVs.
/// `triangles` is the scene's triangle buffer (`GpuTriangle`s) the tracer was built on.
pub fn render_aovs(
    gpu: &Gpu,
    tracer: &mut dyn Tracer,
    triangles: &Buffer,
    camera: &CameraFrame,
) -> vk::Result<Aovs> {
    let size = size_of::<FrameParams>() as u32;
    let camera_rays =
        compute_pipeline(gpu, shaders::INTEGRATOR_CAMERA_RAYS, 1, size, &[WORKGROUP])?;
    let write_aovs = compute_pipeline(gpu, shaders::INTEGRATOR_WRITE_AOVS, 6, size, &[WORKGROUP])?;
    let pixels = camera.width as usize * camera.height as usize;
    let chunk = pixels.clamp(1, CHUNK);
    let rays = gpu.zeroed::<Ray>("aov-rays", chunk)?;
    let hits = gpu.zeroed::<Hit>("aov-hits", chunk)?;
    let depth = gpu.zeroed::<f32>("aov-depth", pixels)?;
    let triangle_id = gpu.zeroed::<u32>("aov-triangle-id", pixels)?;
    let normal = gpu.zeroed::<[f32; 4]>("aov-normal", pixels)?;

    let mut frame = FrameParams::new(camera);
    for offset in (0..pixels).step_by(chunk) {
        let count = chunk.min(pixels - offset) as u32;
        frame.pixel_offset = offset as u32;
        frame.pixel_count = count;
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(&camera_rays, &[(&rays).into()], &frame, count as u64)?;
        let generated = rec.submit(&[])?;
        let traced = tracer.trace(&rays, &hits, count, Query::ClosestHit, &[&generated])?;
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.dispatch_items(
            &write_aovs,
            &[
                (&rays).into(),
                (&hits).into(),
                triangles.into(),
                (&depth).into(),
                (&triangle_id).into(),
                (&normal).into(),
            ],
            &frame,
            count as u64,
        )?;
        // The next chunk reuses the ray and hit buffers.
        gpu.wait(&rec.submit(&[&traced])?)?;
    }
    Ok(Aovs {
        depth: depth.read()?,
        triangle_id: triangle_id.read()?,
        normal: normal
            .read::<[f32; 4]>()?
            .iter()
            .map(|n| [n[0], n[1], n[2]])
            .collect(),
    })
}
