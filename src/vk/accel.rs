//! Acceleration structures (VK_KHR_acceleration_structure) for ray queries.
//!
//! [`AccelerationStructure`] is either a bottom-level structure over one geometry of
//! non-indexed opaque triangles, or a top-level structure with one identity instance of
//! such a BLAS. Builds are recorded on a [`Recorder`]: the structure may be used by the
//! commands recorded after it (a barrier follows every build) and by later submissions.
//! Each structure owns its storage, its build scratch and (TLAS) its instance buffer, all
//! freed on drop — after the GPU is done with it, like any [`Buffer`].

use ash::vk;

use super::buffer::{Buffer, BufferUsage, MemoryKind};
use super::command::Recorder;
use super::device::{AccelSupport, Gpu};
use super::error::{CallContext, Result, VkError};

/// Bytes per vertex of a triangle geometry: three packed f32 (R32G32B32_SFLOAT).
pub const VERTEX_STRIDE: u64 = 12;

/// A built (or recorded-to-be-built) acceleration structure.
pub struct AccelerationStructure {
    gpu: Gpu,
    pub(crate) raw: vk::AccelerationStructureKHR,
    address: vk::DeviceAddress,
    storage: Buffer,
    /// Build scratch, and update scratch too for an updatable structure.
    scratch: Buffer,
    _instances: Option<Buffer>,
    top_level: bool,
    primitives: u32,
    /// Built with ALLOW_UPDATE: [`AccelerationStructure::update_triangles`] may refit it.
    updatable: bool,
}

impl std::fmt::Debug for AccelerationStructure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AccelerationStructure")
            .field("name", &self.storage.name())
            .field("top_level", &self.top_level)
            .field("primitives", &self.primitives)
            .field("bytes", &self.storage.size())
            .finish()
    }
}

fn const_address(buffer: &Buffer) -> vk::DeviceOrHostAddressConstKHR {
    vk::DeviceOrHostAddressConstKHR {
        device_address: buffer.device_address(),
    }
}

impl AccelerationStructure {
    /// Records the build of a bottom-level structure over `triangle_count` non-indexed,
    /// opaque triangles: `vertices` holds 3 × `triangle_count` vertices of three packed
    /// f32 ([`VERTEX_STRIDE`] bytes each) and was created with
    /// [`BufferUsage::ACCEL_BUILD_INPUT`]. `vertices` must stay alive until the recorded
    /// build has run. Primitive index `i` is the triangle at vertices `3i..3i+3`.
    pub fn build_triangles(
        rec: &mut Recorder,
        name: &str,
        vertices: &Buffer,
        triangle_count: u32,
    ) -> Result<Self> {
        Self::build_triangles_with(rec, name, vertices, triangle_count, false)
    }

    /// [`Self::build_triangles`] with ALLOW_UPDATE, so that
    /// [`Self::update_triangles`] can refit it when the vertices move.
    pub fn build_triangles_updatable(
        rec: &mut Recorder,
        name: &str,
        vertices: &Buffer,
        triangle_count: u32,
    ) -> Result<Self> {
        Self::build_triangles_with(rec, name, vertices, triangle_count, true)
    }

    fn build_triangles_with(
        rec: &mut Recorder,
        name: &str,
        vertices: &Buffer,
        triangle_count: u32,
        updatable: bool,
    ) -> Result<Self> {
        let geometry = triangle_geometry(name, vertices, triangle_count)?;
        Self::build(rec, name, false, geometry, triangle_count, None, updatable)
    }

    /// Records an in-place update (a refit: the same triangles, moved) of a bottom-level
    /// structure built by [`Self::build_triangles_updatable`], from `vertices` (the same
    /// layout and count as its build's). The hierarchy keeps its topology, so it traces
    /// slower the further the triangles moved from where it was built. The GPU must be
    /// done with earlier uses of the structure; a barrier follows, as after a build.
    pub fn update_triangles(&self, rec: &mut Recorder, vertices: &Buffer) -> Result<()> {
        let name = self.storage.name().to_string();
        if self.top_level || !self.updatable {
            return Err(VkError::Usage(format!(
                "acceleration structure '{name}' was not built as an updatable BLAS"
            )));
        }
        let accel = self.gpu.0.accel.as_ref().expect("built with the extension");
        let geometries = [triangle_geometry(&name, vertices, self.primitives)?];
        let build_info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
            .flags(build_flags(true))
            .mode(vk::BuildAccelerationStructureModeKHR::UPDATE)
            .src_acceleration_structure(self.raw)
            .dst_acceleration_structure(self.raw)
            .geometries(&geometries)
            .scratch_data(self.scratch_data(accel));
        let ranges =
            [vk::AccelerationStructureBuildRangeInfoKHR::default()
                .primitive_count(self.primitives)];
        rec.begin_scope(&format!("update-blas:{name}"))?;
        // SAFETY: recording; the structure (source and destination, allowed to be the
        // same for an update), its scratch (sized for updates at creation) and the
        // caller's vertices are alive; geometry and count are those of its build.
        unsafe {
            accel
                .loader
                .cmd_build_acceleration_structures(rec.raw_cmd(), &[build_info], &[&ranges])
        };
        rec.end_scope()?;
        rec.memory_barrier(after_build_barrier());
        Ok(())
    }

    /// Records the build of a top-level structure holding one instance of `blas` with
    /// the identity transform, mask 0xFF, forced opaque. `blas` must outlive it.
    pub fn build_single_instance(
        rec: &mut Recorder,
        name: &str,
        blas: &AccelerationStructure,
    ) -> Result<Self> {
        if blas.top_level {
            return Err(VkError::Usage(format!(
                "TLAS '{name}': the instanced structure must be bottom-level"
            )));
        }
        // VkAccelerationStructureInstanceKHR, 64 bytes: a 3×4 row-major transform, then
        // customIndex:24 | mask:8, sbtOffset:24 | flags:8, and the BLAS address.
        let mut words = [0u32; 16];
        for diagonal in [0, 5, 10] {
            words[diagonal] = 1.0f32.to_bits();
        }
        words[12] = 0xFF << 24;
        let flags = vk::GeometryInstanceFlagsKHR::FORCE_OPAQUE
            | vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE;
        words[13] = (flags.as_raw() & 0xFF) << 24;
        words[14] = blas.address as u32;
        words[15] = (blas.address >> 32) as u32;
        let instances = rec.gpu().create_buffer_with(
            &format!("{name}:instances"),
            64,
            MemoryKind::Upload,
            BufferUsage::ACCEL_BUILD_INPUT,
        )?;
        instances.write(&words)?;
        let data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(const_address(&instances));
        let geometry = vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { instances: data })
            .flags(vk::GeometryFlagsKHR::OPAQUE);
        Self::build(rec, name, true, geometry, 1, Some(instances), false)
    }

    fn build(
        rec: &mut Recorder,
        name: &str,
        top_level: bool,
        geometry: vk::AccelerationStructureGeometryKHR<'_>,
        primitives: u32,
        instances: Option<Buffer>,
        updatable: bool,
    ) -> Result<Self> {
        let gpu = rec.gpu().clone();
        let accel = enabled_support(&gpu, name)?;
        let ty = if top_level {
            vk::AccelerationStructureTypeKHR::TOP_LEVEL
        } else {
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL
        };
        let geometries = [geometry];
        let build_info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(ty)
            .flags(build_flags(updatable))
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometries);
        let sizes = build_sizes(accel, &build_info, primitives);
        let storage = gpu.create_buffer_with(
            name,
            sizes.acceleration_structure_size,
            MemoryKind::Device,
            BufferUsage {
                accel_build_input: false,
                accel_storage: true,
            },
        )?;
        let scratch = create_scratch(&gpu, accel, name, &sizes, updatable)?;
        let (raw, address) = create_structure(&gpu, accel, name, &storage, &sizes, ty)?;
        // From here on Drop destroys `raw`.
        let built = Self {
            gpu: gpu.clone(),
            raw,
            address,
            storage,
            scratch,
            _instances: instances,
            top_level,
            primitives,
            updatable,
        };
        built.record_build(rec, accel, name, build_info)?;
        Ok(built)
    }

    /// Records the build of this structure, just created for `build_info`'s geometry, and
    /// the barrier after it.
    fn record_build(
        &self,
        rec: &mut Recorder,
        accel: &AccelSupport,
        name: &str,
        build_info: vk::AccelerationStructureBuildGeometryInfoKHR<'_>,
    ) -> Result<()> {
        let build_info = build_info
            .dst_acceleration_structure(self.raw)
            .scratch_data(self.scratch_data(accel));
        let ranges = [vk::AccelerationStructureBuildRangeInfoKHR::default()
            .primitive_count(self.primitives)
            .primitive_offset(0)
            .first_vertex(0)
            .transform_offset(0)];
        rec.begin_scope(&format!(
            "build-{}:{name}",
            if self.top_level { "tlas" } else { "blas" }
        ))?;
        // SAFETY: recording; the destination, scratch and input buffers are alive (the
        // first two owned by `self`, the inputs the caller's contract) and sized by
        // vkGetAccelerationStructureBuildSizesKHR for this very geometry and count.
        unsafe {
            accel
                .loader
                .cmd_build_acceleration_structures(rec.raw_cmd(), &[build_info], &[&ranges])
        };
        rec.end_scope()?;
        rec.memory_barrier(after_build_barrier());
        Ok(())
    }

    /// The scratch's address rounded up to the device's alignment ([`create_scratch`]
    /// over-allocates for it).
    fn scratch_data(&self, accel: &AccelSupport) -> vk::DeviceOrHostAddressKHR {
        vk::DeviceOrHostAddressKHR {
            device_address: self
                .scratch
                .device_address()
                .next_multiple_of(accel.scratch_alignment),
        }
    }

    pub fn is_top_level(&self) -> bool {
        self.top_level
    }

    /// Triangles (BLAS) or instances (TLAS).
    pub fn primitive_count(&self) -> u32 {
        self.primitives
    }

    /// Bytes of the structure's storage (not counting scratch).
    pub fn size(&self) -> u64 {
        self.storage.size()
    }
}

/// The device's acceleration-structure support, or an error naming the structure where
/// the device was opened without it.
fn enabled_support<'g>(gpu: &'g Gpu, name: &str) -> Result<&'g AccelSupport> {
    gpu.0.accel.as_ref().ok_or_else(|| {
        VkError::Usage(format!(
            "acceleration structure '{name}': device '{}' was not opened with \
             VK_KHR_acceleration_structure",
            gpu.info().name
        ))
    })
}

/// The storage and scratch sizes the driver asks for the build of `build_info`.
fn build_sizes(
    accel: &AccelSupport,
    build_info: &vk::AccelerationStructureBuildGeometryInfoKHR<'_>,
    primitives: u32,
) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    // SAFETY: valid device with the extension enabled; the build info and its
    // geometry array live on the caller's frame.
    unsafe {
        accel.loader.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            build_info,
            &[primitives],
            &mut sizes,
        )
    };
    sizes
}

/// The build scratch, and room for updates where the structure is `updatable`.
fn create_scratch(
    gpu: &Gpu,
    accel: &AccelSupport,
    name: &str,
    sizes: &vk::AccelerationStructureBuildSizesInfoKHR<'_>,
    updatable: bool,
) -> Result<Buffer> {
    // Scratch: over-allocate by the alignment and round the address up.
    let align = accel.scratch_alignment;
    let scratch_size = match updatable {
        true => sizes.build_scratch_size.max(sizes.update_scratch_size),
        false => sizes.build_scratch_size,
    };
    gpu.create_buffer(
        &format!("{name}:scratch"),
        scratch_size + align,
        MemoryKind::Device,
    )
}

/// Creates and names the structure at the start of `storage`; returns it and its
/// device address.
fn create_structure(
    gpu: &Gpu,
    accel: &AccelSupport,
    name: &str,
    storage: &Buffer,
    sizes: &vk::AccelerationStructureBuildSizesInfoKHR<'_>,
    ty: vk::AccelerationStructureTypeKHR,
) -> Result<(vk::AccelerationStructureKHR, vk::DeviceAddress)> {
    let create_info = vk::AccelerationStructureCreateInfoKHR::default()
        .buffer(storage.raw)
        .offset(0)
        .size(sizes.acceleration_structure_size)
        .ty(ty);
    // SAFETY: the storage buffer has ACCELERATION_STRUCTURE_STORAGE usage and room
    // for the size the driver asked for; offset 0 is 256-byte aligned.
    let raw = unsafe {
        accel
            .loader
            .create_acceleration_structure(&create_info, None)
    }
    .call("vkCreateAccelerationStructureKHR")?;
    gpu.set_object_name(raw, name);
    let address_info =
        vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw);
    // SAFETY: raw was just created on this device.
    let address = unsafe {
        accel
            .loader
            .get_acceleration_structure_device_address(&address_info)
    };
    Ok((raw, address))
}

/// Fast trace, and ALLOW_UPDATE where the structure will be refitted (the flags of an
/// update must be its build's).
fn build_flags(updatable: bool) -> vk::BuildAccelerationStructureFlagsKHR {
    let flags = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE;
    match updatable {
        true => flags | vk::BuildAccelerationStructureFlagsKHR::ALLOW_UPDATE,
        false => flags,
    }
}

/// Later builds (a TLAS over this BLAS, an update) and kernels read the structure.
fn after_build_barrier() -> vk::MemoryBarrier2<'static> {
    vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR)
        .src_access_mask(vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR)
        .dst_stage_mask(
            vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR
                | vk::PipelineStageFlags2::COMPUTE_SHADER,
        )
        .dst_access_mask(
            vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR
                | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
        )
}

/// The one opaque, non-indexed triangle geometry of a BLAS over `vertices`.
fn triangle_geometry<'a>(
    name: &str,
    vertices: &Buffer,
    triangle_count: u32,
) -> Result<vk::AccelerationStructureGeometryKHR<'a>> {
    let needed = triangle_count as u64 * 3 * VERTEX_STRIDE;
    if vertices.size() < needed {
        return Err(VkError::Usage(format!(
            "BLAS '{name}': {triangle_count} triangles need {needed} vertex bytes, \
             buffer '{}' has {}",
            vertices.name(),
            vertices.size()
        )));
    }
    let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
        .vertex_format(vk::Format::R32G32B32_SFLOAT)
        .vertex_data(const_address(vertices))
        .vertex_stride(VERTEX_STRIDE)
        .max_vertex((triangle_count * 3).saturating_sub(1))
        .index_type(vk::IndexType::NONE_KHR);
    Ok(vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
        .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
        .flags(vk::GeometryFlagsKHR::OPAQUE))
}

impl Drop for AccelerationStructure {
    fn drop(&mut self) {
        if let Some(accel) = &self.gpu.0.accel {
            // SAFETY: the caller guarantees the GPU no longer uses the structure; its
            // storage buffer is dropped after this (field order).
            unsafe { accel.loader.destroy_acceleration_structure(self.raw, None) };
        }
    }
}
