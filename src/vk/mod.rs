//! The Vulkan layer: the only module with `unsafe` and raw `ash`.
//!
//! Above it, the engine speaks in safe types: [`Gpu`] (device, allocator, streams),
//! [`Buffer`], [`ComputePipeline`], [`Recorder`] (command recording) and
//! [`TimelinePoint`] (cross-stream order), plus the [`ProfileLog`] of GPU times, and,
//! where the device offers ray queries, [`AccelerationStructure`]; with the `window`
//! feature, a window's `Surface` and `Swapchain` for previews.

mod accel;
mod buffer;
mod clock;
mod command;
mod device;
mod error;
mod instance;
mod physical;
mod pipeline;
mod profile_tree;
mod profiler;
mod reflect;
mod stream;
#[cfg(feature = "window")]
mod swapchain;
mod validation;

pub use accel::{AccelerationStructure, VERTEX_STRIDE};
pub use buffer::{Buffer, BufferSlice, BufferUsage, MemoryKind};
pub use clock::ClockCalibration;
pub use command::{grid_for, Recorder};
pub use device::{Gpu, GpuDesc};
pub use error::{fmt_bytes, Result, VkError};
pub use instance::{validation_layer_available, Instance, InstanceDesc};
pub use physical::{
    enumerate, select, CapabilityInfo, LimitsInfo, PhysicalDeviceInfo, QueueFamilyInfo,
};
pub use pipeline::{
    compute_pipeline, compute_pipeline_full_subgroups, BufferAccess, ComputePipeline, PipelineDesc,
};
pub use profile_tree::{ProfileNode, ProfileTree};
pub use profiler::{GpuBatch, KernelTime, ProfileLog, ProfileRecord, ScopeInfo};
pub use stream::{QueueSlot, StreamKind, StreamMapping, StreamPlacement, TimelinePoint};
#[cfg(feature = "window")]
pub use swapchain::{surface_extensions, PixelOrder, PresentTarget, Presented, Surface, Swapchain};
pub use validation::{ValidationMessage, SUPPRESSED};

/// Deliberately breaks a valid-usage rule so tests can prove the validation layer and
/// the message collection are live: creates a buffer with no usage flags
/// (VUID-VkBufferCreateInfo-usage-requiredbitmask), which drivers tolerate.
#[doc(hidden)]
pub fn provoke_validation_error(gpu: &Gpu) {
    let info = ash::vk::BufferCreateInfo::default()
        .size(16)
        .usage(ash::vk::BufferUsageFlags::empty());
    // SAFETY: intentionally invalid usage flags, but well-formed structures; the buffer,
    // if created, is destroyed at once and never bound or used.
    unsafe {
        if let Ok(b) = gpu.0.raw.create_buffer(&info, None) {
            gpu.0.raw.destroy_buffer(b, None);
        }
    }
}
