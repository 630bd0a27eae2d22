//! Buffers allocated through gpu-allocator, with upload and readback.
//!
//! Every engine buffer is a storage buffer that can also be copied, filled, read as
//! indirect arguments and addressed from kernels by its device address (so it may be
//! larger than one storage binding: see [`super::reflect`]). On devices whose memory is
//! host-visible (lavapipe, integrated GPUs), device buffers are allocated mapped and
//! transfers are plain copies; elsewhere they go through staging buffers on the main
//! stream.
//!
//! One buffer holds at most [`Gpu::max_buffer_bytes`]: the smaller of the device's
//! maxBufferSize and maxMemoryAllocationSize (each buffer is one allocation).

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::device::Gpu;
use super::error::{CallContext, Result, VkError};

/// Where a buffer lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryKind {
    /// Fastest memory for the GPU (mapped too when the device is host-visible anyway).
    Device,
    /// Host-written, GPU-read.
    Upload,
    /// GPU-written, host-read.
    Readback,
}

/// Extra uses of a buffer beyond the storage/transfer/indirect/device-address ones every
/// buffer has. All need a device opened with ray queries ([`Gpu::ray_query`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BufferUsage {
    /// ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY: vertices or instances of a build.
    pub accel_build_input: bool,
    /// ACCELERATION_STRUCTURE_STORAGE: backs an acceleration structure.
    pub accel_storage: bool,
}

impl BufferUsage {
    /// Vertices or instances read by an acceleration-structure build.
    pub const ACCEL_BUILD_INPUT: Self = Self {
        accel_build_input: true,
        accel_storage: false,
    };

    fn flags(self) -> vk::BufferUsageFlags {
        let mut f = vk::BufferUsageFlags::empty();
        if self.accel_build_input {
            f |= vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR;
        }
        if self.accel_storage {
            f |= vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR;
        }
        f
    }
}

/// A buffer and its memory. Dropping it frees both: the caller must make sure the GPU
/// is done with it (wait on the timeline point of the last submission using it).
pub struct Buffer {
    gpu: Gpu,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    /// The device address of its first byte.
    address: vk::DeviceAddress,
    /// Size in bytes as requested (the Vulkan buffer is at least 4 bytes).
    size: u64,
    name: String,
}

impl std::fmt::Debug for Buffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Buffer")
            .field("name", &self.name)
            .field("size", &self.size)
            .finish()
    }
}

/// A byte range of a buffer, for binding to a kernel.
#[derive(Clone, Copy, Debug)]
pub struct BufferSlice<'a> {
    pub buffer: &'a Buffer,
    pub offset: u64,
    pub size: u64,
}

impl<'a> From<&'a Buffer> for BufferSlice<'a> {
    fn from(buffer: &'a Buffer) -> Self {
        buffer.slice(0, buffer.size())
    }
}

impl Gpu {
    /// Whether device-local memory is also host-visible, so no staging is needed.
    pub fn unified_memory(&self) -> bool {
        self.0.info.is_cpu()
    }

    /// The most bytes one buffer may hold, and the limit that sets it: each buffer is one
    /// allocation, so the smaller of maxBufferSize and maxMemoryAllocationSize.
    pub fn max_buffer_bytes(&self) -> (u64, &'static str) {
        let limits = &self.0.info.limits;
        if limits.max_memory_allocation_size < limits.max_buffer_size {
            (limits.max_memory_allocation_size, "maxMemoryAllocationSize")
        } else {
            (limits.max_buffer_size, "maxBufferSize")
        }
    }

    /// Refuses a buffer of `size` bytes that one buffer cannot hold on this device, naming
    /// it and the limit: for callers that check their buffers before any work.
    pub fn check_buffer_size(&self, name: &str, size: u64) -> Result<()> {
        let (limit, which) = self.max_buffer_bytes();
        if size.max(4).next_multiple_of(4) > limit {
            return Err(VkError::BufferTooLarge {
                name: name.to_string(),
                size,
                limit,
                which,
            });
        }
        Ok(())
    }

    /// Allocates a buffer of `size` bytes (contents undefined).
    pub fn create_buffer(&self, name: &str, size: u64, kind: MemoryKind) -> Result<Buffer> {
        self.create_buffer_with(name, size, kind, BufferUsage::default())
    }

    /// Allocates a buffer with extra `usage` (device address, acceleration structures).
    pub fn create_buffer_with(
        &self,
        name: &str,
        size: u64,
        kind: MemoryKind,
        usage: BufferUsage,
    ) -> Result<Buffer> {
        if usage != BufferUsage::default() && !self.ray_query() {
            return Err(VkError::Usage(format!(
                "buffer '{name}' needs {usage:?}, which this device was not opened with \
                 (it needs VK_KHR_acceleration_structure)"
            )));
        }
        self.check_buffer_size(name, size)?;
        // Vulkan forbids empty buffers; round up so vkCmdFillBuffer's 4-byte rule holds.
        let vk_size = size.max(4).next_multiple_of(4);
        let families: Vec<u32> = {
            let mut f: Vec<u32> = self.0.streams.iter().map(|s| s.family).collect();
            f.sort_unstable();
            f.dedup();
            f
        };
        let mut info = vk::BufferCreateInfo::default().size(vk_size).usage(
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::INDIRECT_BUFFER
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                | usage.flags(),
        );
        // Streams on several queue families share buffers without ownership transfers.
        info = if families.len() > 1 {
            info.sharing_mode(vk::SharingMode::CONCURRENT)
                .queue_family_indices(&families)
        } else {
            info.sharing_mode(vk::SharingMode::EXCLUSIVE)
        };
        let device = &self.0.raw;
        // SAFETY: valid device and create info.
        let raw = unsafe { device.create_buffer(&info, None) }.call("vkCreateBuffer")?;
        // SAFETY: raw was just created on this device.
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let location = match kind {
            MemoryKind::Device if self.unified_memory() => MemoryLocation::CpuToGpu,
            MemoryKind::Device => MemoryLocation::GpuOnly,
            MemoryKind::Upload => MemoryLocation::CpuToGpu,
            MemoryKind::Readback => MemoryLocation::GpuToCpu,
        };
        let allocation = self
            .0
            .allocator
            .lock()
            .unwrap()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(error) => {
                // SAFETY: unused buffer of this device.
                unsafe { device.destroy_buffer(raw, None) };
                return Err(VkError::Alloc {
                    name: name.to_string(),
                    error,
                });
            }
        };
        // SAFETY: memory and offset come from the allocator for this buffer's requirements.
        unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }
            .call("vkBindBufferMemory")?;
        let now = self.0.memory.add(allocation.size());
        crate::timeline_counter!("GPU memory", "bytes", now);
        // `RUST_LOG=splitray::vk=trace` lists every allocation: what makes up a peak.
        log::trace!("alloc {name} {} bytes, {now} in all", allocation.size());
        self.set_object_name(raw, name);
        let address_info = vk::BufferDeviceAddressInfo::default().buffer(raw);
        // SAFETY: raw is bound to memory and was created with SHADER_DEVICE_ADDRESS usage
        // on a device opened with bufferDeviceAddress.
        let address = unsafe { device.get_buffer_device_address(&address_info) };
        Ok(Buffer {
            gpu: self.clone(),
            raw,
            allocation: Some(allocation),
            address,
            size,
            name: name.to_string(),
        })
    }

    /// Creates a device buffer holding `data`. Returns once the data is on the GPU.
    pub fn upload<T: bytemuck::Pod>(&self, name: &str, data: &[T]) -> Result<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let buffer = self.create_buffer(name, bytes.len() as u64, MemoryKind::Device)?;
        buffer.write(data)?;
        Ok(buffer)
    }

    /// Creates a device buffer of `len` elements of `T`, all zero bytes.
    pub fn zeroed<T: bytemuck::Pod>(&self, name: &str, len: usize) -> Result<Buffer> {
        let buffer = self.create_buffer(name, (len * size_of::<T>()) as u64, MemoryKind::Device)?;
        let mut rec = self.recorder(super::StreamKind::Main)?;
        rec.fill(&buffer, 0);
        let point = rec.submit(&[])?;
        self.wait(&point)?;
        Ok(buffer)
    }
}

impl Buffer {
    /// The device the buffer lives on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of whole `T` elements the buffer holds.
    pub fn element_count<T>(&self) -> usize {
        self.size as usize / size_of::<T>()
    }

    /// The device address of the buffer's first byte.
    pub(crate) fn device_address(&self) -> vk::DeviceAddress {
        self.address
    }

    pub fn slice(&self, offset: u64, size: u64) -> BufferSlice<'_> {
        BufferSlice {
            buffer: self,
            offset,
            size,
        }
    }

    fn mapped(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .map(|s| &mut s[..size])
    }

    /// Writes `data` at the start of the buffer: a copy into mapped memory, or through a
    /// staging buffer. The GPU must not be using the buffer. Waits for completion.
    pub fn write<T: bytemuck::Pod>(&self, data: &[T]) -> Result<()> {
        self.write_at(0, data)
    }

    /// Copies `out.len()` elements from byte `offset` of a host-visible buffer (a
    /// readback buffer) with no GPU synchronisation at all: the caller has waited for the
    /// timeline point of the work that wrote them (every submission ends with a host
    /// barrier). Unlike [`Buffer::read`], it never waits on a stream, so a thread can
    /// read one batch's results while the GPU computes the next.
    pub fn read_mapped_into<T: bytemuck::Pod>(&self, offset: u64, out: &mut [T]) -> Result<()> {
        let bytes = std::mem::size_of_val(out);
        if offset + bytes as u64 > self.size {
            return Err(VkError::Usage(format!(
                "read of {bytes} bytes at {offset} from buffer '{}' of {} bytes",
                self.name, self.size
            )));
        }
        let Some(ptr) = self.allocation.as_ref().and_then(|a| a.mapped_ptr()) else {
            return Err(VkError::Usage(format!(
                "buffer '{}' is not host-visible",
                self.name
            )));
        };
        // SAFETY: mapped, host-coherent (gpu-allocator's host locations), the range lies
        // within the allocation (checked above), the caller has waited for the writes,
        // and `out` is a distinct host allocation.
        unsafe {
            std::ptr::copy_nonoverlapping(
                (ptr.as_ptr() as *const u8).add(offset as usize),
                bytemuck::cast_slice_mut::<T, u8>(out).as_mut_ptr(),
                bytes,
            )
        };
        Ok(())
    }

    /// Reads the whole buffer back as `T`s. Runs after all work already submitted to the
    /// main stream; work on other streams must be waited for first.
    pub fn read<T: bytemuck::Pod>(&self) -> Result<Vec<T>> {
        let n = self.element_count::<T>();
        let bytes = n * size_of::<T>();
        let mut out = vec![T::zeroed(); n];
        if bytes == 0 {
            return Ok(out);
        }
        let _span =
            tracing::info_span!("readback", what = %self.name, bytes = bytes as u64).entered();
        if let Some(ptr) = self.allocation.as_ref().and_then(|a| a.mapped_ptr()) {
            // Order the read after main-stream work that may write this buffer.
            let rec = self.gpu.recorder(super::StreamKind::Main)?;
            let point = rec.submit(&[])?;
            self.gpu.wait(&point)?;
            // SAFETY: mapped, host-coherent, at least `bytes` long; the GPU is done with it
            // (the main stream drained and every submission ends with a host barrier).
            unsafe {
                std::ptr::copy_nonoverlapping(
                    ptr.as_ptr() as *const u8,
                    bytemuck::cast_slice_mut::<T, u8>(&mut out).as_mut_ptr(),
                    bytes,
                )
            };
            return Ok(out);
        }
        let mut staging =
            self.gpu
                .create_buffer("staging-readback", bytes as u64, MemoryKind::Readback)?;
        let mut rec = self.gpu.recorder(super::StreamKind::Main)?;
        rec.copy(self, 0, &staging, 0, bytes as u64);
        let point = rec.submit(&[])?;
        self.gpu.wait(&point)?;
        bytemuck::cast_slice_mut::<T, u8>(&mut out)
            .copy_from_slice(&staging.mapped().expect("readback memory is mapped")[..bytes]);
        Ok(out)
    }
}

impl Buffer {
    /// Writes `data` into the buffer from element `first` on (elements of `T`), leaving
    /// the rest as it is: the in-place update of part of a table. The GPU must not be
    /// using the buffer. Waits for completion.
    pub fn write_at<T: bytemuck::Pod>(&self, first: usize, data: &[T]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let offset = (first * size_of::<T>()) as u64;
        if offset + bytes.len() as u64 > self.size {
            return Err(VkError::Usage(format!(
                "write of {} bytes at offset {offset} into buffer '{}' of {} bytes",
                bytes.len(),
                self.name,
                self.size
            )));
        }
        if bytes.is_empty() {
            return Ok(());
        }
        let _span =
            tracing::info_span!("upload", what = %self.name, bytes = bytes.len() as u64).entered();
        if let Some(ptr) = self.allocation.as_ref().and_then(|a| a.mapped_ptr()) {
            // SAFETY: the allocation is mapped and at least `size` bytes long, the range
            // lies within it (checked above), and the GPU is not using the buffer (the
            // caller's contract); the ranges cannot overlap.
            unsafe {
                std::ptr::copy_nonoverlapping(
                    bytes.as_ptr(),
                    (ptr.as_ptr() as *mut u8).add(offset as usize),
                    bytes.len(),
                )
            };
            return Ok(());
        }
        let mut staging =
            self.gpu
                .create_buffer("staging-upload", bytes.len() as u64, MemoryKind::Upload)?;
        staging
            .mapped()
            .expect("upload memory is mapped")
            .copy_from_slice(bytes);
        let mut rec = self.gpu.recorder(super::StreamKind::Main)?;
        rec.copy(&staging, 0, self, offset, bytes.len() as u64);
        let point = rec.submit(&[])?;
        self.gpu.wait(&point)
    }

    /// Reads the whole buffer back as `T`s once `point` is reached: for a buffer that only
    /// work up to `point` writes (a copy of a film another stream keeps writing), so that
    /// the read waits for nothing else. Falls back to [`Buffer::read`] where the buffer
    /// is not host-visible.
    pub fn read_after<T: bytemuck::Pod>(&self, point: &super::TimelinePoint) -> Result<Vec<T>> {
        self.gpu.wait(point)?;
        let Some(ptr) = self.allocation.as_ref().and_then(|a| a.mapped_ptr()) else {
            return self.read();
        };
        let n = self.element_count::<T>();
        let mut out = vec![T::zeroed(); n];
        let bytes = n * size_of::<T>();
        // SAFETY: mapped, host-coherent, at least `bytes` long; the work writing it ended
        // at `point` (every submission ends with a host-visibility barrier), and the
        // caller's contract is that nothing later writes it.
        unsafe {
            std::ptr::copy_nonoverlapping(
                ptr.as_ptr() as *const u8,
                bytemuck::cast_slice_mut::<T, u8>(&mut out).as_mut_ptr(),
                bytes,
            )
        };
        Ok(out)
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(allocation) = self.allocation.take() {
            let now = self.gpu.0.memory.sub(allocation.size());
            crate::timeline_counter!("GPU memory", "bytes", now);
            log::trace!(
                "free {} {} bytes, {now} in all",
                self.name,
                allocation.size()
            );
            let _ = self.gpu.0.allocator.lock().unwrap().free(allocation);
        }
        // SAFETY: the caller guarantees the GPU no longer uses this buffer.
        unsafe { self.gpu.0.raw.destroy_buffer(self.raw, None) };
    }
}
