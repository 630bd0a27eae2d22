//! Compute pipelines from embedded SPIR-V, with push descriptors and push constants.
//!
//! Every kernel binds its storage buffers at set 0, bindings 0..n, pushed at dispatch
//! time (VK_KHR_push_descriptor), so no descriptor pools or sets need managing. Scalars
//! travel as push constants. Specialization constant `i` takes `spec[i]`; by convention
//! constant 0 is the workgroup size (`layout(local_size_x_id = 0) in;`), so Rust holds
//! the one true value.

use ash::vk;

use super::device::Gpu;
use super::error::{CallContext, Result, VkError};
use crate::shaders::Kernel;

/// What a kernel needs from its pipeline.
#[derive(Clone, Debug)]
pub struct PipelineDesc<'a> {
    pub kernel: Kernel,
    /// Number of storage-buffer bindings (set 0, bindings 0..n).
    pub bindings: u32,
    /// Size of the push-constant block in bytes (0 for none).
    pub push_constant_bytes: u32,
    /// Values of specialization constants 0, 1, 2, ...
    pub spec: &'a [u32],
}

pub struct ComputePipeline {
    gpu: Gpu,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pub(crate) bindings: u32,
    /// Whether an acceleration structure follows the storage buffers.
    pub(crate) tlas_binding: bool,
    pub(crate) push_constant_bytes: u32,
    name: &'static str,
    /// Workgroup size along x (specialization constant 0).
    workgroup_size: u32,
    /// Set by the first dispatch (drivers such as lavapipe compile at first use).
    dispatched: std::sync::atomic::AtomicBool,
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
        let device = &gpu.0.raw;
        let words = ash::util::read_spv(&mut std::io::Cursor::new(desc.kernel.spirv))
            .map_err(|_| VkError::BadSpirv(desc.kernel.name))?;
        if full_subgroups {
            check_full_subgroups(gpu, desc)?;
        }
        let max_push = gpu.info().limits.max_push_constants_size;
        if desc.push_constant_bytes > max_push {
            return Err(VkError::Usage(format!(
                "kernel '{}' asks for {} push-constant bytes; the device allows {max_push}",
                desc.kernel.name, desc.push_constant_bytes
            )));
        }
        let mut bindings: Vec<_> = (0..desc.bindings)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        if tlas_binding {
            bindings.push(
                vk::DescriptorSetLayoutBinding::default()
                    .binding(desc.bindings)
                    .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE),
            );
        }
        let set_info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&bindings);
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .offset(0)
            .size(desc.push_constant_bytes)];
        let spec_entries: Vec<_> = (0..desc.spec.len() as u32)
            .map(|i| {
                vk::SpecializationMapEntry::default()
                    .constant_id(i)
                    .offset(i * 4)
                    .size(4)
            })
            .collect();
        let spec_data: &[u8] = bytemuck::cast_slice(desc.spec);
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&spec_entries)
            .data(spec_data);

        // SAFETY: valid device; every create info and the SPIR-V live across the calls;
        // objects are destroyed on the error paths and in Drop.
        unsafe {
            let set_layout = device
                .create_descriptor_set_layout(&set_info, None)
                .call("vkCreateDescriptorSetLayout")?;
            let set_layouts = [set_layout];
            let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            if desc.push_constant_bytes > 0 {
                layout_info = layout_info.push_constant_ranges(&ranges);
            }
            let layout = match device.create_pipeline_layout(&layout_info, None) {
                Ok(l) => l,
                Err(e) => {
                    device.destroy_descriptor_set_layout(set_layout, None);
                    return Err(VkError::Call {
                        call: "vkCreatePipelineLayout",
                        result: e,
                    });
                }
            };
            let module_info = vk::ShaderModuleCreateInfo::default().code(&words);
            let module = match device.create_shader_module(&module_info, None) {
                Ok(m) => m,
                Err(e) => {
                    device.destroy_pipeline_layout(layout, None);
                    device.destroy_descriptor_set_layout(set_layout, None);
                    return Err(VkError::Call {
                        call: "vkCreateShaderModule",
                        result: e,
                    });
                }
            };
            let mut stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            if !desc.spec.is_empty() {
                stage = stage.specialization_info(&spec_info);
            }
            if full_subgroups {
                stage = stage.flags(vk::PipelineShaderStageCreateFlags::REQUIRE_FULL_SUBGROUPS);
            }
            let info = vk::ComputePipelineCreateInfo::default()
                .stage(stage)
                .layout(layout);
            let result = device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None);
            device.destroy_shader_module(module, None);
            let raw = match result {
                Ok(p) => p[0],
                Err((_, e)) => {
                    device.destroy_pipeline_layout(layout, None);
                    device.destroy_descriptor_set_layout(set_layout, None);
                    return Err(VkError::Call {
                        call: "vkCreateComputePipelines",
                        result: e,
                    });
                }
            };
            gpu.set_object_name(raw, desc.kernel.name);
            Ok(Self {
                gpu: gpu.clone(),
                raw,
                layout,
                set_layout,
                bindings: desc.bindings,
                tlas_binding,
                push_constant_bytes: desc.push_constant_bytes,
                name: desc.kernel.name,
                workgroup_size: desc.spec.first().copied().unwrap_or(1),
                dispatched: Default::default(),
            })
        }
    }

    pub fn name(&self) -> &'static str {
        self.name
    }

    pub fn workgroup_size(&self) -> u32 {
        self.workgroup_size
    }

    /// Notes a dispatch; true for the first.
    pub(crate) fn mark_dispatched(&self) -> bool {
        !self
            .dispatched
            .swap(true, std::sync::atomic::Ordering::Relaxed)
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
        // SAFETY: pipelines are dropped only after the work using them completed.
        unsafe {
            device.destroy_pipeline(self.raw, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
