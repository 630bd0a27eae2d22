//! Compute pipelines from embedded SPIR-V, with push descriptors and push constants.
//!
//! Every kernel takes its storage buffers as bindings 0..n. Those it declares as
//! descriptors (set 0, binding b) are pushed at dispatch time (VK_KHR_push_descriptor),
//! so no descriptor pools or sets need managing; the others it takes by device address,
//! in buffer references that end its push-constant block (see [`super::reflect`]), so
//! they may be larger than one storage binding (maxStorageBufferRange). Callers bind
//! buffers alike either way. Scalars travel as push constants. Specialization constant
//! `i` takes `spec[i]`; by convention constant 0 is the workgroup size
//! (`layout(local_size_x_id = 0) in;`), so Rust holds the one true value.
//!
//! A kernel that takes buffers by address also has a descriptor twin (the same source
//! compiled with `SPLITRAY_DESCRIPTORS`, glsl/common/address.glsl). Where the device
//! reads descriptors faster ([`BufferAccess`]), a dispatch whose buffers each fit one
//! storage binding runs the twin, and only larger ones go by address: on lavapipe,
//! addresses cost PDACRT's load-bound ray filter 3.4x its time (docs/PERFORMANCE.md).

use std::sync::atomic::{AtomicBool, Ordering};

use ash::vk;

use super::buffer::BufferSlice;
use super::device::Gpu;
use super::error::{CallContext, Result, VkError};
use super::reflect;
use crate::shaders::Kernel;

/// What a kernel needs from its pipeline.
#[derive(Clone, Debug)]
pub struct PipelineDesc<'a> {
    pub kernel: Kernel,
    /// Number of storage buffers the kernel takes (bindings 0..n; by descriptor or by
    /// address, as the kernel declares).
    pub bindings: u32,
    /// Bytes of push-constant values the caller gives (0 for none); buffer addresses
    /// follow them.
    pub push_constant_bytes: u32,
    /// Values of specialization constants 0, 1, 2, ...
    pub spec: &'a [u32],
}

/// How kernels with a descriptor twin take their buffers on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BufferAccess {
    /// As descriptors wherever every buffer of a dispatch fits one storage binding, by
    /// address otherwise. The default on CPU devices: lavapipe turns each lane's load
    /// through an address into a gather of 64-bit pointers.
    DescriptorsWhereTheyFit,
    /// Always by address: the default on GPUs, whose loads cost the same either way.
    Addresses,
}

impl BufferAccess {
    /// The default for a device (see the variants).
    pub fn for_device(info: &super::PhysicalDeviceInfo) -> Self {
        if info.is_cpu() {
            Self::DescriptorsWhereTheyFit
        } else {
            Self::Addresses
        }
    }

    /// `descriptors` or `addresses` (as `SPLITRAY_BUFFER_ACCESS` takes them).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "descriptors" => Some(Self::DescriptorsWhereTheyFit),
            "addresses" => Some(Self::Addresses),
            _ => None,
        }
    }
}

/// One compiled form of a kernel: its pipeline, its layouts and how it takes its
/// buffers.
pub(crate) struct Variant {
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    /// Which bindings go as descriptors and which by address, and the push range.
    pub(crate) passing: reflect::BufferPassing,
    /// Set by the first dispatch (drivers such as lavapipe compile at first use).
    dispatched: AtomicBool,
}

impl Variant {
    /// Notes a dispatch; true for the first.
    pub(crate) fn mark_dispatched(&self) -> bool {
        !self.dispatched.swap(true, Ordering::Relaxed)
    }
}

pub struct ComputePipeline {
    gpu: Gpu,
    /// The kernel as written (buffers by address where it takes them so); `None` where
    /// its addresses do not fit the device's push constants but its twin does.
    primary: Option<Variant>,
    /// The descriptor twin, where the kernel has one and the device prefers it.
    twin: Option<Variant>,
    pub(crate) bindings: u32,
    /// Whether an acceleration structure follows the storage buffers.
    pub(crate) tlas_binding: bool,
    /// Bytes of push-constant values the caller gives (the addresses follow).
    pub(crate) push_constant_bytes: u32,
    name: &'static str,
    /// Workgroup size along x (specialization constant 0).
    workgroup_size: u32,
}

/// [`ComputePipeline::new`] with the description's fields as arguments: the form every
/// kernel owner uses.
pub fn compute_pipeline(
    gpu: &Gpu,
    kernel: Kernel,
    bindings: u32,
    push_constant_bytes: u32,
    spec: &[u32],
) -> Result<ComputePipeline> {
    pipeline_of(gpu, kernel, bindings, push_constant_bytes, spec, false)
}

/// As [`compute_pipeline`], for a kernel whose work partition counts on every subgroup
/// of its workgroup being full (`gl_NumSubgroups * gl_SubgroupSize` equals the
/// workgroup size), as ranking by subgroup ballots does. SPIR-V 1.6 modules may run with
/// any subgroup size in the device's range, so the workgroup size (`spec[0]`) must be a
/// multiple of `maxSubgroupSize`, and the device must offer `computeFullSubgroups`.
pub fn compute_pipeline_full_subgroups(
    gpu: &Gpu,
    kernel: Kernel,
    bindings: u32,
    push_constant_bytes: u32,
    spec: &[u32],
) -> Result<ComputePipeline> {
    pipeline_of(gpu, kernel, bindings, push_constant_bytes, spec, true)
}

fn pipeline_of(
    gpu: &Gpu,
    kernel: Kernel,
    bindings: u32,
    push_constant_bytes: u32,
    spec: &[u32],
    full_subgroups: bool,
) -> Result<ComputePipeline> {
    let desc = PipelineDesc {
        kernel,
        bindings,
        push_constant_bytes,
        spec,
    };
    ComputePipeline::create(gpu, &desc, false, full_subgroups)
}

impl std::fmt::Debug for ComputePipeline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ComputePipeline")
            .field("name", &self.name)
            .finish()
    }
}

impl ComputePipeline {
    pub fn new(gpu: &Gpu, desc: &PipelineDesc<'_>) -> Result<Self> {
        Self::create(gpu, desc, false, false)
    }

    /// A kernel that also reads an acceleration structure (a TLAS, for ray queries) at
    /// set 0, binding `desc.bindings` — right after its storage buffers. Dispatch it with
    /// [`Recorder::dispatch_with_tlas`](super::Recorder::dispatch_with_tlas). Needs a
    /// device opened with ray queries.
    pub fn with_acceleration_structure(gpu: &Gpu, desc: &PipelineDesc<'_>) -> Result<Self> {
        if !gpu.ray_query() {
            return Err(VkError::Usage(format!(
                "kernel '{}' uses ray queries, which device '{}' does not offer \
                 (it needs VK_KHR_ray_query and VK_KHR_acceleration_structure)",
                desc.kernel.name,
                gpu.info().name
            )));
        }
        Self::create(gpu, desc, true, false)
    }

    fn create(
        gpu: &Gpu,
        desc: &PipelineDesc<'_>,
        tlas_binding: bool,
        full_subgroups: bool,
    ) -> Result<Self> {
        let _span = tracing::info_span!("create pipeline", what = desc.kernel.name).entered();
        if full_subgroups {
            check_full_subgroups(gpu, desc)?;
        }
        let prepare = |spirv| Prepared::new(desc, spirv, tlas_binding, full_subgroups);
        let primary = prepare(desc.kernel.spirv)?;
        let twin = desc.kernel.descriptor_twin.map(prepare).transpose()?;
        let max_push = gpu.info().limits.max_push_constants_size;
        let primary_fits = primary.passing.push_bytes <= max_push;
        if let Some(p) = [Some(&primary), twin.as_ref()]
            .into_iter()
            .flatten()
            .filter(|p| p.passing.push_bytes > max_push)
            .find(|p| p.passing.addresses.is_empty() || twin.is_none())
        {
            return Err(VkError::Usage(format!(
                "kernel '{}' needs {} push-constant bytes ({} of values, {} buffer addresses); \
                 the device allows {max_push}",
                desc.kernel.name,
                p.passing.push_bytes,
                desc.push_constant_bytes,
                p.passing.addresses.len()
            )));
        }
        let twin_wanted =
            !primary_fits || gpu.buffer_access() == BufferAccess::DescriptorsWhereTheyFit;
        let primary = primary_fits.then(|| primary.build(gpu)).transpose()?;
        let twin = twin
            .filter(|_| twin_wanted)
            .map(|t| t.build(gpu))
            .transpose()?;
        Ok(Self {
            gpu: gpu.clone(),
            primary,
            twin,
            bindings: desc.bindings,
            tlas_binding,
            push_constant_bytes: desc.push_constant_bytes,
            name: desc.kernel.name,
            workgroup_size: desc.spec.first().copied().unwrap_or(1),
        })
    }

    pub fn name(&self) -> &'static str {
        self.name
    }

    pub fn workgroup_size(&self) -> u32 {
        self.workgroup_size
    }

    /// The form that runs a dispatch over `bindings`: the descriptor twin where there is
    /// one and every buffer fits one storage binding, else the kernel as written. Errors
    /// name the buffer when neither form can take the dispatch.
    pub(crate) fn variant_for(&self, bindings: &[BufferSlice<'_>]) -> Result<&Variant> {
        let max_range = self.gpu.info().limits.max_storage_buffer_range;
        let too_large = bindings.iter().find(|b| b.size > max_range);
        match (&self.twin, &self.primary, too_large) {
            (Some(twin), _, None) => Ok(twin),
            (_, Some(primary), _) => Ok(primary),
            (_, None, Some(slice)) => Err(VkError::Usage(format!(
                "kernel '{}' cannot take buffer '{}' ({} bytes): it is more than one storage \
                 binding holds (maxStorageBufferRange, {max_range} bytes), and the kernel's \
                 buffer addresses do not fit this device's push constants",
                self.name,
                slice.buffer.name(),
                slice.size
            ))),
            (None, None, _) => unreachable!("a pipeline has at least one form"),
        }
    }
}

/// One form of a kernel, read and matched to its bindings, before its pipeline exists.
struct Prepared<'a, 'd> {
    desc: &'a PipelineDesc<'d>,
    words: Vec<u32>,
    passing: reflect::BufferPassing,
    tlas_binding: bool,
    full_subgroups: bool,
}

impl<'a, 'd> Prepared<'a, 'd> {
    fn new(
        desc: &'a PipelineDesc<'d>,
        spirv: &[u8],
        tlas_binding: bool,
        full_subgroups: bool,
    ) -> Result<Self> {
        let name = desc.kernel.name;
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|_| VkError::BadSpirv(name))?;
        let interface = reflect::kernel_interface(&words).ok_or(VkError::BadSpirv(name))?;
        let passing = reflect::buffer_passing(&interface, desc.bindings, desc.push_constant_bytes)
            .map_err(|e| VkError::Usage(format!("kernel '{name}' {e}")))?;
        Ok(Self {
            desc,
            words,
            passing,
            tlas_binding,
            full_subgroups,
        })
    }

    /// Creates the pipeline of this form.
    fn build(self, gpu: &Gpu) -> Result<Variant> {
        let device = &gpu.0.raw;
        let (set_layout, layout) =
            create_layouts(device, &self.set_layout_bindings(), self.passing.push_bytes)?;
        let raw = match self.create_pipeline(device, layout) {
            Ok(raw) => raw,
            Err(e) => {
                // SAFETY: both layouts were just created, and no pipeline uses them.
                unsafe {
                    device.destroy_pipeline_layout(layout, None);
                    device.destroy_descriptor_set_layout(set_layout, None);
                }
                return Err(e);
            }
        };
        gpu.set_object_name(raw, self.desc.kernel.name);
        Ok(Variant {
            raw,
            layout,
            set_layout,
            passing: self.passing,
            dispatched: AtomicBool::new(false),
        })
    }

    /// The pushed descriptors of this form: its storage buffers taken as descriptors,
    /// then the acceleration structure where it reads one.
    fn set_layout_bindings(&self) -> Vec<vk::DescriptorSetLayoutBinding<'static>> {
        let mut bindings: Vec<_> = self
            .passing
            .descriptors
            .iter()
            .map(|&b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        if self.tlas_binding {
            bindings.push(
                vk::DescriptorSetLayoutBinding::default()
                    .binding(self.desc.bindings)
                    .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE),
            );
        }
        bindings
    }

    /// Creates the compute pipeline of this form's SPIR-V, with its specialization
    /// constants, over `layout`.
    fn create_pipeline(
        &self,
        device: &ash::Device,
        layout: vk::PipelineLayout,
    ) -> Result<vk::Pipeline> {
        let spec_entries: Vec<_> = (0..self.desc.spec.len() as u32)
            .map(|i| {
                vk::SpecializationMapEntry::default()
                    .constant_id(i)
                    .offset(i * 4)
                    .size(4)
            })
            .collect();
        let spec_data: &[u8] = bytemuck::cast_slice(self.desc.spec);
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&spec_entries)
            .data(spec_data);
        let module_info = vk::ShaderModuleCreateInfo::default().code(&self.words);
        // SAFETY: valid device and layout; every create info and the SPIR-V live across
        // the calls; the module is destroyed once the pipeline is created from it.
        unsafe {
            let module = device
                .create_shader_module(&module_info, None)
                .call("vkCreateShaderModule")?;
            let mut stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            if !self.desc.spec.is_empty() {
                stage = stage.specialization_info(&spec_info);
            }
            if self.full_subgroups {
                stage = stage.flags(vk::PipelineShaderStageCreateFlags::REQUIRE_FULL_SUBGROUPS);
            }
            let info = vk::ComputePipelineCreateInfo::default()
                .stage(stage)
                .layout(layout);
            let result = device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None);
            device.destroy_shader_module(module, None);
            match result {
                Ok(p) => Ok(p[0]),
                Err((_, e)) => Err(VkError::Call {
                    call: "vkCreateComputePipelines",
                    result: e,
                }),
            }
        }
    }
}

/// Creates the push-descriptor set layout of `bindings` and the pipeline layout over it
/// with `push_bytes` of push constants.
fn create_layouts(
    device: &ash::Device,
    bindings: &[vk::DescriptorSetLayoutBinding<'_>],
    push_bytes: u32,
) -> Result<(vk::DescriptorSetLayout, vk::PipelineLayout)> {
    let set_info = vk::DescriptorSetLayoutCreateInfo::default()
        .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
        .bindings(bindings);
    let ranges = [vk::PushConstantRange::default()
        .stage_flags(vk::ShaderStageFlags::COMPUTE)
        .offset(0)
        .size(push_bytes)];
    // SAFETY: valid device; every create info lives across the calls; the set layout is
    // destroyed on the error path, and the caller owns both layouts otherwise.
    unsafe {
        let set_layout = device
            .create_descriptor_set_layout(&set_info, None)
            .call("vkCreateDescriptorSetLayout")?;
        let set_layouts = [set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_bytes > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        match device.create_pipeline_layout(&layout_info, None) {
            Ok(layout) => Ok((set_layout, layout)),
            Err(e) => {
                device.destroy_descriptor_set_layout(set_layout, None);
                Err(VkError::Call {
                    call: "vkCreatePipelineLayout",
                    result: e,
                })
            }
        }
    }
}

/// Whether `desc` can require full subgroups on `gpu` (see
/// [`compute_pipeline_full_subgroups`]).
fn check_full_subgroups(gpu: &Gpu, desc: &PipelineDesc<'_>) -> Result<()> {
    let info = gpu.info();
    let workgroup = desc.spec.first().copied().unwrap_or(1);
    if !info.capabilities.compute_full_subgroups {
        return Err(VkError::Usage(format!(
            "kernel '{}' needs full subgroups, which device '{}' does not offer",
            desc.kernel.name, info.name
        )));
    }
    if workgroup % info.limits.max_subgroup_size != 0 {
        return Err(VkError::Usage(format!(
            "kernel '{}': workgroup size {workgroup} is not a multiple of the largest \
             subgroup size {}, so its subgroups cannot all be full",
            desc.kernel.name, info.limits.max_subgroup_size
        )));
    }
    Ok(())
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        let device = &self.gpu.0.raw;
        for variant in self.primary.iter().chain(&self.twin) {
            // SAFETY: pipelines are dropped only after the work using them completed.
            unsafe {
                device.destroy_pipeline(variant.raw, None);
                device.destroy_pipeline_layout(variant.layout, None);
                device.destroy_descriptor_set_layout(variant.set_layout, None);
            }
        }
    }
}
