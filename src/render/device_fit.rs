//! Whether a render fits the device, checked before any work: the buffers that grow with
//! the scene and the film, each against the most one buffer may hold (the smaller of
//! maxBufferSize and maxMemoryAllocationSize: 2 GiB on lavapipe) and together against
//! the device-local memory. One storage binding (maxStorageBufferRange) is no limit:
//! kernels take larger buffers by address (glsl/common/address.glsl).
//!
//! Only the buffers whose sizes are known before tracing are counted: PDACRT's level
//! lists grow with the rays and the scene's depth complexity, and are refused by name
//! when they are allocated.

use super::{RenderError, RenderOptions};
use crate::integrator::IntegratorKind;
use crate::scene::Scene;
use crate::trace::GpuTriangle;
use crate::vk::{fmt_bytes, Gpu};

/// A buffer a render will allocate, and its size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedBuffer {
    pub name: &'static str,
    pub bytes: u64,
}

/// The largest buffers `options` makes for `scene` that live through the integrator's
/// passes (the AOV pass's own film buffers come and go before it, and are no larger).
pub fn planned_buffers(scene: &Scene, options: &RenderOptions) -> Vec<PlannedBuffer> {
    let triangles = scene.triangles.len() as u64;
    let pixels = options.width as u64 * options.height as u64;
    let vec4 = 16;
    let triangle_bytes = triangles * size_of::<GpuTriangle>() as u64;
    let mut buffers = vec![
        PlannedBuffer {
            name: "triangles",
            bytes: triangle_bytes,
        },
        PlannedBuffer {
            name: "aov-normal",
            bytes: pixels * vec4,
        },
    ];
    let gpu_film = match options.integrator {
        IntegratorKind::Pt => vec!["pt-accum", "pt-accum2"],
        IntegratorKind::Bpt | IntegratorKind::Light => vec![],
        _ => vec!["accum"],
    };
    if !gpu_film.is_empty() {
        // The shading kernels' own copy of the triangles and their materials.
        buffers.push(PlannedBuffer {
            name: "shade-triangles",
            bytes: triangle_bytes,
        });
        buffers.push(PlannedBuffer {
            name: "triangle-material",
            bytes: triangles * 4,
        });
    }
    for name in gpu_film {
        buffers.push(PlannedBuffer {
            name,
            bytes: pixels * vec4,
        });
    }
    buffers
}

/// Refuses a render whose buffers cannot exist on `gpu`, naming the buffer (or the
/// largest ones) and the sizes.
pub fn check(gpu: &Gpu, scene: &Scene, options: &RenderOptions) -> Result<(), RenderError> {
    let buffers = planned_buffers(scene, options);
    let (limit, which) = gpu.max_buffer_bytes();
    let too_large: Vec<String> = buffers
        .iter()
        .filter(|b| b.bytes > limit)
        .map(|b| format!("'{}' of {} bytes ({})", b.name, b.bytes, fmt_bytes(b.bytes)))
        .collect();
    if !too_large.is_empty() {
        return Err(RenderError::Options(format!(
            "scene '{}' at {}x{} ({} triangles) needs {}: more than one buffer can hold on \
             device '{}', {limit} bytes ({}, its {which})",
            scene.name,
            options.width,
            options.height,
            scene.triangles.len(),
            too_large.join(", "),
            gpu.info().name,
            fmt_bytes(limit)
        )));
    }
    let total: u64 = buffers.iter().map(|b| b.bytes).sum();
    let memory = gpu.info().limits.device_local_bytes;
    if total > memory {
        let list: Vec<String> = buffers
            .iter()
            .filter(|b| b.bytes > 0)
            .map(|b| format!("{} {}", b.name, fmt_bytes(b.bytes)))
            .collect();
        return Err(RenderError::Options(format!(
            "scene '{}' at {}x{} ({} triangles) needs {} ({}) in GPU buffers, more than \
             device '{}' has: {} of device-local memory",
            scene.name,
            options.width,
            options.height,
            scene.triangles.len(),
            fmt_bytes(total),
            list.join(", "),
            gpu.info().name,
            fmt_bytes(memory)
        )));
    }
    Ok(())
}
