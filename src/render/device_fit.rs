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

impl PlannedBuffer {
    fn new(name: &'static str, bytes: u64) -> Self {
        PlannedBuffer { name, bytes }
    }
}

/// What a render is, for the messages: its scene's name, triangle count and film size.
#[derive(Clone, Debug)]
pub struct RenderSize<'a> {
    pub scene: &'a str,
    pub triangles: u64,
    pub width: u32,
    pub height: u32,
}

impl RenderSize<'_> {
    fn describe(&self) -> String {
        format!(
            "scene '{}' at {}x{} ({} triangles)",
            self.scene, self.width, self.height, self.triangles
        )
    }
}

/// What one device allows: the most bytes one buffer holds (and the limit that sets it)
/// and its device-local memory.
#[derive(Clone, Debug)]
pub struct DeviceCapacity {
    pub device: String,
    pub max_buffer: u64,
    pub max_buffer_limit: &'static str,
    pub memory: u64,
}

impl DeviceCapacity {
    pub fn of(gpu: &Gpu) -> Self {
        let (max_buffer, max_buffer_limit) = gpu.max_buffer_bytes();
        DeviceCapacity {
            device: gpu.info().name.clone(),
            max_buffer,
            max_buffer_limit,
            memory: gpu.info().limits.device_local_bytes,
        }
    }
}

/// The largest buffers a render of `size` with `integrator` makes that live through the
/// integrator's passes (the AOV pass's own film buffers come and go before it, and are
/// no larger).
pub fn planned_buffers(size: &RenderSize<'_>, integrator: IntegratorKind) -> Vec<PlannedBuffer> {
    let triangles = size.triangles;
    let pixels = size.width as u64 * size.height as u64;
    let vec4 = 16;
    let triangle_bytes = triangles * size_of::<GpuTriangle>() as u64;
    let mut buffers = vec![
        PlannedBuffer::new("triangles", triangle_bytes),
        PlannedBuffer::new("aov-normal", pixels * vec4),
    ];
    let gpu_film = match integrator {
        IntegratorKind::Pt => vec!["pt-accum", "pt-accum2"],
        // Films on the host; cbpt's GPU buffers are batch-sized.
        IntegratorKind::Bpt | IntegratorKind::Light | IntegratorKind::Cbpt => vec![],
        _ => vec!["accum"],
    };
    if !gpu_film.is_empty() {
        // The shading kernels' own copy of the triangles and their materials.
        buffers.push(PlannedBuffer::new("shade-triangles", triangle_bytes));
        buffers.push(PlannedBuffer::new("triangle-material", triangles * 4));
    }
    // Films hold a sum and its remainder per pixel (film::compensated).
    let film = 2 * pixels * vec4;
    for name in gpu_film {
        buffers.push(PlannedBuffer::new(name, film));
    }
    if integrator.lvc_variant().is_some() {
        // The splat film holds at least one pass of fixed-point words per pixel.
        let splat = pixels * crate::integrator::lvc::fixed::FIXED_WORDS as u64 * 4;
        for (name, bytes) in [
            ("lvc-accum", film),
            ("lvc-accum2", film),
            ("lvc-splat-film", splat),
        ] {
            buffers.push(PlannedBuffer::new(name, bytes));
        }
    }
    buffers
}

/// Refuses a render whose buffers cannot exist on `gpu`, naming the buffer (or the
/// largest ones) and the sizes.
pub fn check(gpu: &Gpu, scene: &Scene, options: &RenderOptions) -> Result<(), RenderError> {
    let size = RenderSize {
        scene: &scene.name,
        triangles: scene.triangles.len() as u64,
        width: options.width,
        height: options.height,
    };
    let buffers = planned_buffers(&size, options.integrator);
    fits(&size, &buffers, &DeviceCapacity::of(gpu)).map_err(RenderError::Options)
}

/// Whether `buffers` fit `device`: each within its largest buffer, all together within its
/// memory; else the message naming the buffers and the sizes.
pub fn fits(
    size: &RenderSize<'_>,
    buffers: &[PlannedBuffer],
    device: &DeviceCapacity,
) -> Result<(), String> {
    let limit = device.max_buffer;
    let too_large: Vec<String> = buffers
        .iter()
        .filter(|b| b.bytes > limit)
        .map(|b| format!("'{}' of {} bytes ({})", b.name, b.bytes, fmt_bytes(b.bytes)))
        .collect();
    if !too_large.is_empty() {
        return Err(format!(
            "{} needs {}: more than one buffer can hold on device '{}', {limit} bytes ({}, \
             its {})",
            size.describe(),
            too_large.join(", "),
            device.device,
            fmt_bytes(limit),
            device.max_buffer_limit
        ));
    }
    let total: u64 = buffers.iter().map(|b| b.bytes).sum();
    if total > device.memory {
        let list: Vec<String> = buffers
            .iter()
            .filter(|b| b.bytes > 0)
            .map(|b| format!("'{}' {}", b.name, fmt_bytes(b.bytes)))
            .collect();
        return Err(format!(
            "{} needs {total} bytes ({}: {}) in GPU buffers, more than device '{}' has: {} \
             bytes ({}) of device-local memory",
            size.describe(),
            fmt_bytes(total),
            list.join(", "),
            device.device,
            device.memory,
            fmt_bytes(device.memory)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(max_buffer: u64, memory: u64) -> DeviceCapacity {
        DeviceCapacity {
            device: "test device".into(),
            max_buffer,
            max_buffer_limit: "maxBufferSize",
            memory,
        }
    }

    fn size(triangles: u64, side: u32) -> RenderSize<'static> {
        RenderSize {
            scene: "big",
            triangles,
            width: side,
            height: side,
        }
    }

    #[test]
    fn a_triangle_buffer_past_the_largest_buffer_is_named_with_its_size() {
        let big = size(100_000_000, 64);
        let buffers = planned_buffers(&big, IntegratorKind::Primary);
        let err = fits(&big, &buffers, &device(2 << 30, 1 << 40)).unwrap_err();
        let bytes = (100_000_000 * size_of::<GpuTriangle>()).to_string();
        for part in [
            "scene 'big' at 64x64 (100000000 triangles)",
            "'triangles' of",
            "'shade-triangles' of",
            &bytes,
            "2147483648 bytes",
            "maxBufferSize",
            "test device",
        ] {
            assert!(err.contains(part), "missing {part:?} in: {err}");
        }
        assert!(!err.contains("aov-normal"), "{err}");
    }

    #[test]
    fn buffers_past_the_device_memory_together_are_listed_with_the_total() {
        // Each buffer fits one buffer; together they do not fit the memory.
        let big = size(20_000_000, 8192);
        let buffers = planned_buffers(&big, IntegratorKind::Pt);
        let total: u64 = buffers.iter().map(|b| b.bytes).sum();
        let err = fits(&big, &buffers, &device(2 << 30, total - 1)).unwrap_err();
        for part in [
            total.to_string(),
            (total - 1).to_string(),
            "'pt-accum'".into(),
            "'triangles'".into(),
            "device-local memory".into(),
        ] {
            assert!(err.contains(&part), "missing {part:?} in: {err}");
        }
        assert!(fits(&big, &buffers, &device(2 << 30, total)).is_ok());
    }

    #[test]
    fn films_past_one_binding_are_no_limit() {
        // 4096²: 512 MiB of vec4 sums and remainders and 384 MiB of six-word splats, past
        // a 128 MiB binding, within a 2 GiB buffer: the kernels take them by address.
        let large = size(1000, 4096);
        for kind in [
            IntegratorKind::Pt,
            IntegratorKind::LvcBdpt,
            IntegratorKind::CisLbdpt,
        ] {
            let buffers = planned_buffers(&large, kind);
            assert!(buffers.iter().any(|b| b.bytes > 128 << 20), "{kind}");
            assert!(fits(&large, &buffers, &device(2 << 30, 1 << 40)).is_ok());
        }
        // Past the largest buffer (256 MiB here), they are refused by name.
        let buffers = planned_buffers(&large, IntegratorKind::CisLbdpt);
        let err = fits(&large, &buffers, &device(256 << 20, 1 << 40)).unwrap_err();
        for part in ["'lvc-accum' of", "'lvc-accum2' of", "268435456 bytes"] {
            assert!(err.contains(part), "missing {part:?} in: {err}");
        }
    }

    #[test]
    fn the_buffers_grow_with_the_film_and_the_scene() {
        let b = planned_buffers(&size(1000, 100), IntegratorKind::Pt);
        let bytes = |name: &str| b.iter().find(|p| p.name == name).map(|p| p.bytes);
        assert_eq!(bytes("triangles"), Some(48_000));
        // A sum and its remainder per pixel.
        assert_eq!(bytes("pt-accum"), Some(320_000));
        assert_eq!(bytes("pt-accum2"), Some(320_000));
        assert_eq!(bytes("triangle-material"), Some(4000));
        // The CPU integrators (and cbpt, which combines on the CPU) keep their film on
        // the host.
        for kind in [
            IntegratorKind::Bpt,
            IntegratorKind::Light,
            IntegratorKind::Cbpt,
        ] {
            let host = planned_buffers(&size(1000, 100), kind);
            assert!(host.iter().all(|p| !p.name.contains("accum")), "{kind}");
        }
    }
}
