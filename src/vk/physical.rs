//! Physical devices: what they are, what they offer, and which one to use.

use std::ffi::CStr;

use ash::{ext, khr, vk};
use serde::Serialize;

use super::error::{CallContext, Result, VkError};
use super::instance::Instance;

/// One queue family, as `splitray info` reports it.
#[derive(Clone, Debug, Serialize)]
pub struct QueueFamilyInfo {
    pub index: u32,
    pub count: u32,
    pub graphics: bool,
    pub compute: bool,
    pub transfer: bool,
    pub timestamp_valid_bits: u32,
}

/// Limits that shape splitray's kernels.
#[derive(Clone, Debug, Serialize)]
pub struct LimitsInfo {
    pub max_storage_buffer_range: u64,
    pub max_compute_shared_memory_size: u32,
    pub max_compute_work_group_invocations: u32,
    pub max_compute_work_group_count: [u32; 3],
    pub max_push_constants_size: u32,
    pub min_storage_buffer_offset_alignment: u64,
    pub timestamp_period_ns: f32,
    pub subgroup_size: u32,
    /// The range a compute subgroup's size may take (Vulkan 1.3 subgroup size control):
    /// SPIR-V 1.6 modules may run with any size in it unless a size is required.
    pub min_subgroup_size: u32,
    pub max_subgroup_size: u32,
    pub max_memory_allocation_size: u64,
    /// maxBufferSize (Vulkan 1.3): the largest VkBuffer.
    pub max_buffer_size: u64,
    /// Bytes of the largest device-local memory heap.
    pub device_local_bytes: u64,
}

/// Optional capabilities that later methods use when present.
#[derive(Clone, Debug, Serialize)]
pub struct CapabilityInfo {
    pub timeline_semaphore: bool,
    pub synchronization2: bool,
    pub maintenance4: bool,
    pub buffer_device_address: bool,
    pub push_descriptor: bool,
    /// VK_KHR_ray_query + VK_KHR_acceleration_structure + VK_KHR_deferred_host_operations
    /// with the rayQuery, accelerationStructure and bufferDeviceAddress features: when
    /// true, the device is opened with all of them enabled.
    pub ray_query: bool,
    pub subgroup_arithmetic: bool,
    /// Subgroup ballot and shuffle operations in compute shaders (the radix sort's
    /// multisplit ranking).
    pub subgroup_ballot_shuffle: bool,
    /// The computeFullSubgroups feature: pipelines can require every subgroup of a
    /// workgroup to be full (enabled on the device when present).
    pub compute_full_subgroups: bool,
    pub shader_int64: bool,
    /// shaderInt64 with shaderBufferInt64Atomics (64-bit atomicMin on storage buffers);
    /// enabled on the device when present (PDACRT's atomic flush uses it).
    pub buffer_int64_atomics: bool,
    /// The hostQueryReset feature (Vulkan 1.2): timestamp query pools are reset from the
    /// host, so a queue family without graphics or compute (a transfer-only one, where
    /// vkCmdResetQueryPool is not allowed) still times its commands. Enabled when present.
    pub host_query_reset: bool,
}

/// Everything `splitray info` says about a device.
#[derive(Clone, Debug, Serialize)]
pub struct PhysicalDeviceInfo {
    pub index: usize,
    pub name: String,
    pub device_type: String,
    pub api_version: String,
    pub driver_name: String,
    pub driver_info: String,
    pub queue_families: Vec<QueueFamilyInfo>,
    pub limits: LimitsInfo,
    pub capabilities: CapabilityInfo,
    /// Time domains that VK_KHR/EXT_calibrated_timestamps can sample together with the
    /// device's timestamps ("device", "clock-monotonic", ...); empty where neither
    /// extension is offered. With "device" and a host domain, GPU timelines are placed
    /// on the host clock by calibration rather than at submission.
    pub calibrated_time_domains: Vec<String>,
    #[serde(skip)]
    pub(crate) calibration: Option<CalibrationExtension>,
    #[serde(skip)]
    pub(crate) raw: vk::PhysicalDevice,
    #[serde(skip)]
    pub(crate) api_version_raw: u32,
    #[serde(skip)]
    type_rank: u32,
}

impl PhysicalDeviceInfo {
    /// A device description that no Vulkan device stands behind, for unit tests of
    /// choices made from limits and capabilities.
    #[cfg(test)]
    pub(crate) fn synthetic(
        device_type: &str,
        limits: LimitsInfo,
        capabilities: CapabilityInfo,
    ) -> Self {
        Self {
            index: 0,
            name: format!("synthetic {device_type}"),
            device_type: device_type.into(),
            api_version: "1.3.0".into(),
            driver_name: String::new(),
            driver_info: String::new(),
            queue_families: Vec::new(),
            limits,
            capabilities,
            calibrated_time_domains: Vec::new(),
            calibration: None,
            raw: vk::PhysicalDevice::null(),
            api_version_raw: vk::API_VERSION_1_3,
            type_rank: 0,
        }
    }

    /// True for a CPU implementation such as lavapipe.
    pub fn is_cpu(&self) -> bool {
        self.device_type == "cpu"
    }

    /// The missing requirements, named; empty when the device can run splitray.
    pub fn missing_requirements(&self) -> Vec<String> {
        let mut missing = Vec::new();
        if self.api_version_raw < vk::API_VERSION_1_3 {
            missing.push(format!("Vulkan 1.3 (it offers {})", self.api_version));
        }
        let c = &self.capabilities;
        for (ok, what) in [
            (c.timeline_semaphore, "the timelineSemaphore feature"),
            (c.synchronization2, "the synchronization2 feature"),
            (c.maintenance4, "the maintenance4 feature"),
            (c.push_descriptor, "the VK_KHR_push_descriptor extension"),
            (c.buffer_device_address, "the bufferDeviceAddress feature"),
        ] {
            if !ok {
                missing.push(what.to_string());
            }
        }
        if !self.queue_families.iter().any(|q| q.compute) {
            missing.push("a compute queue".into());
        }
        missing
    }
}

/// Which calibrated-timestamps extension a device offers (the EXT one where both are:
/// they are the same functions, and validation layers older than the KHR promotion, such
/// as Debian 12's 1.3.239, warn that they do not know the KHR name, a warning that fails
/// every validated run on drivers offering both, NVIDIA's among them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CalibrationExtension {
    Khr,
    Ext,
}

impl CalibrationExtension {
    pub(crate) fn name(self) -> &'static CStr {
        match self {
            Self::Khr => khr::calibrated_timestamps::NAME,
            Self::Ext => ext::calibrated_timestamps::NAME,
        }
    }
}

/// The name `splitray info` and timeline metadata give a time domain.
pub(crate) fn time_domain_name(domain: vk::TimeDomainKHR) -> String {
    match domain {
        vk::TimeDomainKHR::DEVICE => "device".into(),
        vk::TimeDomainKHR::CLOCK_MONOTONIC => "clock-monotonic".into(),
        vk::TimeDomainKHR::CLOCK_MONOTONIC_RAW => "clock-monotonic-raw".into(),
        vk::TimeDomainKHR::QUERY_PERFORMANCE_COUNTER => "query-performance-counter".into(),
        other => format!("time-domain-{}", other.as_raw()),
    }
}

/// The time domains a device can calibrate, through whichever extension it offers.
fn calibrateable_domains(
    instance: &Instance,
    pd: vk::PhysicalDevice,
    exts: &[vk::ExtensionProperties],
) -> (Option<CalibrationExtension>, Vec<vk::TimeDomainKHR>) {
    let extension = if has_extension(exts, ext::calibrated_timestamps::NAME) {
        CalibrationExtension::Ext
    } else if has_extension(exts, khr::calibrated_timestamps::NAME) {
        CalibrationExtension::Khr
    } else {
        return (None, Vec::new());
    };
    // SAFETY: valid physical device of this instance, which offers the extension.
    let domains = unsafe {
        match extension {
            CalibrationExtension::Khr => {
                khr::calibrated_timestamps::Instance::new(&instance.entry, &instance.raw)
                    .get_physical_device_calibrateable_time_domains(pd)
            }
            CalibrationExtension::Ext => {
                ext::calibrated_timestamps::Instance::new(&instance.entry, &instance.raw)
                    .get_physical_device_calibrateable_time_domains(pd)
            }
        }
    };
    // A device that cannot list its domains is treated as one without calibration.
    match domains {
        Ok(d) if d.contains(&vk::TimeDomainKHR::DEVICE) => (Some(extension), d),
        _ => (None, Vec::new()),
    }
}

fn name_of(chars: &[std::ffi::c_char]) -> String {
    // SAFETY: Vulkan guarantees NUL termination within the fixed-size array.
    unsafe { CStr::from_ptr(chars.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

fn has_extension(exts: &[vk::ExtensionProperties], name: &CStr) -> bool {
    exts.iter()
        .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name))
}

/// Lists every physical device with its properties.
pub fn enumerate(instance: &Instance) -> Result<Vec<PhysicalDeviceInfo>> {
    // SAFETY: valid instance.
    let devices =
        unsafe { instance.raw.enumerate_physical_devices() }.call("vkEnumeratePhysicalDevices")?;
    devices
        .iter()
        .enumerate()
        .map(|(index, &pd)| describe(instance, index, pd))
        .collect()
}

/// Everything about physical device `pd`, the `index`th of its instance.
fn describe(
    instance: &Instance,
    index: usize,
    pd: vk::PhysicalDevice,
) -> Result<PhysicalDeviceInfo> {
    let raw_instance = &instance.raw;
    let mut props11 = vk::PhysicalDeviceVulkan11Properties::default();
    let mut props12 = vk::PhysicalDeviceVulkan12Properties::default();
    let mut props13 = vk::PhysicalDeviceVulkan13Properties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut props11)
        .push_next(&mut props12)
        .push_next(&mut props13);
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut features2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f12)
        .push_next(&mut f13);
    // SAFETY: valid physical device; the chains live on this stack frame.
    let (families, exts, memory) = unsafe {
        raw_instance.get_physical_device_properties2(pd, &mut props2);
        raw_instance.get_physical_device_features2(pd, &mut features2);
        (
            raw_instance.get_physical_device_queue_family_properties(pd),
            raw_instance
                .enumerate_device_extension_properties(pd)
                .call("vkEnumerateDeviceExtensionProperties")?,
            raw_instance.get_physical_device_memory_properties(pd),
        )
    };
    let p = props2.properties;
    let f10 = features2.features;
    let ray_query = ray_query_supported(instance, pd, &exts, &f12);
    let (device_type, type_rank) = device_type_and_rank(p.device_type);
    let v = p.api_version;
    let (calibration, domains) = calibrateable_domains(instance, pd, &exts);
    Ok(PhysicalDeviceInfo {
        index,
        name: name_of(&p.device_name),
        device_type: device_type.into(),
        api_version: format!(
            "{}.{}.{}",
            vk::api_version_major(v),
            vk::api_version_minor(v),
            vk::api_version_patch(v)
        ),
        driver_name: name_of(&props12.driver_name),
        driver_info: name_of(&props12.driver_info),
        queue_families: queue_family_infos(&families),
        limits: limits_info(&p.limits, &props11, &props13, &memory),
        capabilities: capability_info(&exts, &f10, &f12, &f13, &props11, ray_query),
        calibrated_time_domains: domains.into_iter().map(time_domain_name).collect(),
        calibration,
        raw: pd,
        api_version_raw: v,
        type_rank,
    })
}

/// Ray queries need three extensions and three features; the feature structures of the
/// two KHR extensions are only chained where the extensions exist.
fn ray_query_supported(
    instance: &Instance,
    pd: vk::PhysicalDevice,
    exts: &[vk::ExtensionProperties],
    f12: &vk::PhysicalDeviceVulkan12Features<'_>,
) -> bool {
    let ray_query_exts = has_extension(exts, khr::ray_query::NAME)
        && has_extension(exts, khr::acceleration_structure::NAME)
        && has_extension(exts, khr::deferred_host_operations::NAME);
    ray_query_exts && f12.buffer_device_address == vk::TRUE && {
        let mut accel = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
        let mut rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
        let mut features2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut accel)
            .push_next(&mut rq);
        // SAFETY: valid physical device; the extensions of both structures exist.
        unsafe {
            instance
                .raw
                .get_physical_device_features2(pd, &mut features2)
        };
        accel.acceleration_structure == vk::TRUE && rq.ray_query == vk::TRUE
    }
}

/// The name `splitray info` gives a device type, and its rank in the default choice
/// ([`select`]: lower first).
fn device_type_and_rank(device_type: vk::PhysicalDeviceType) -> (&'static str, u32) {
    match device_type {
        vk::PhysicalDeviceType::DISCRETE_GPU => ("discrete", 0),
        vk::PhysicalDeviceType::INTEGRATED_GPU => ("integrated", 1),
        vk::PhysicalDeviceType::VIRTUAL_GPU => ("virtual", 2),
        vk::PhysicalDeviceType::CPU => ("cpu", 3),
        _ => ("other", 4),
    }
}

fn queue_family_infos(families: &[vk::QueueFamilyProperties]) -> Vec<QueueFamilyInfo> {
    families
        .iter()
        .enumerate()
        .map(|(i, q)| QueueFamilyInfo {
            index: i as u32,
            count: q.queue_count,
            graphics: q.queue_flags.contains(vk::QueueFlags::GRAPHICS),
            compute: q.queue_flags.contains(vk::QueueFlags::COMPUTE),
            transfer: q.queue_flags.intersects(
                vk::QueueFlags::TRANSFER | vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS,
            ),
            timestamp_valid_bits: q.timestamp_valid_bits,
        })
        .collect()
}

fn limits_info(
    limits: &vk::PhysicalDeviceLimits,
    props11: &vk::PhysicalDeviceVulkan11Properties<'_>,
    props13: &vk::PhysicalDeviceVulkan13Properties<'_>,
    memory: &vk::PhysicalDeviceMemoryProperties,
) -> LimitsInfo {
    LimitsInfo {
        max_storage_buffer_range: limits.max_storage_buffer_range as u64,
        max_compute_shared_memory_size: limits.max_compute_shared_memory_size,
        max_compute_work_group_invocations: limits.max_compute_work_group_invocations,
        max_compute_work_group_count: limits.max_compute_work_group_count,
        max_push_constants_size: limits.max_push_constants_size,
        min_storage_buffer_offset_alignment: limits.min_storage_buffer_offset_alignment,
        timestamp_period_ns: limits.timestamp_period,
        subgroup_size: props11.subgroup_size,
        // A device without subgroup size control reports zeros: then the one
        // size it has is the range.
        min_subgroup_size: if props13.min_subgroup_size > 0 {
            props13.min_subgroup_size
        } else {
            props11.subgroup_size
        },
        max_subgroup_size: props13.max_subgroup_size.max(props11.subgroup_size),
        max_memory_allocation_size: props11.max_memory_allocation_size,
        max_buffer_size: props13.max_buffer_size,
        device_local_bytes: memory
            .memory_heaps_as_slice()
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .max()
            .unwrap_or(0),
    }
}

fn capability_info(
    exts: &[vk::ExtensionProperties],
    f10: &vk::PhysicalDeviceFeatures,
    f12: &vk::PhysicalDeviceVulkan12Features<'_>,
    f13: &vk::PhysicalDeviceVulkan13Features<'_>,
    props11: &vk::PhysicalDeviceVulkan11Properties<'_>,
    ray_query: bool,
) -> CapabilityInfo {
    CapabilityInfo {
        timeline_semaphore: f12.timeline_semaphore == vk::TRUE,
        synchronization2: f13.synchronization2 == vk::TRUE,
        maintenance4: f13.maintenance4 == vk::TRUE,
        buffer_device_address: f12.buffer_device_address == vk::TRUE,
        push_descriptor: has_extension(exts, khr::push_descriptor::NAME),
        ray_query,
        subgroup_arithmetic: props11
            .subgroup_supported_operations
            .contains(vk::SubgroupFeatureFlags::ARITHMETIC),
        subgroup_ballot_shuffle: props11
            .subgroup_supported_stages
            .contains(vk::ShaderStageFlags::COMPUTE)
            && props11.subgroup_supported_operations.contains(
                vk::SubgroupFeatureFlags::BASIC
                    | vk::SubgroupFeatureFlags::BALLOT
                    | vk::SubgroupFeatureFlags::SHUFFLE,
            ),
        compute_full_subgroups: f13.compute_full_subgroups == vk::TRUE
            && f13.subgroup_size_control == vk::TRUE,
        shader_int64: f10.shader_int64 == vk::TRUE,
        buffer_int64_atomics: f10.shader_int64 == vk::TRUE
            && f12.shader_buffer_int64_atomics == vk::TRUE,
        host_query_reset: f12.host_query_reset == vk::TRUE,
    }
}

/// Picks a device: `selector` (an index, or else a case-insensitive name substring: a
/// number is always an index, so that a missing device is not mistaken for one whose
/// name holds that number), else the
/// `SPLITRAY_DEVICE` environment variable, else discrete > integrated > virtual > CPU
/// among the devices that meet splitray's requirements.
pub fn select(
    devices: &[PhysicalDeviceInfo],
    selector: Option<&str>,
) -> Result<PhysicalDeviceInfo> {
    if devices.is_empty() {
        return Err(VkError::NoDevice(
            " (install mesa-vulkan-drivers for the lavapipe CPU device)".into(),
        ));
    }
    // An empty SPLITRAY_DEVICE is an unset one, as shells make it easy to leave it so;
    // the command line refuses an empty `--device`.
    let env = std::env::var("SPLITRAY_DEVICE").ok();
    let named = match (selector, env.as_deref()) {
        (Some(sel), _) => Some((sel, format!("--device {sel}"))),
        (None, Some(sel)) if !sel.is_empty() => Some((sel, format!("SPLITRAY_DEVICE={sel}"))),
        _ => None,
    };
    let chosen = match named {
        Some((sel, how)) => {
            let found = match sel.parse::<usize>() {
                Ok(index) => devices.get(index),
                Err(_) => {
                    let lower = sel.to_lowercase();
                    devices
                        .iter()
                        .find(|d| d.name.to_lowercase().contains(&lower))
                }
            };
            found.ok_or(VkError::UnknownDevice(how))?
        }
        None => devices
            .iter()
            .filter(|d| d.missing_requirements().is_empty())
            .min_by_key(|d| (d.type_rank, d.index))
            .unwrap_or(&devices[0]),
    };
    let missing = chosen.missing_requirements();
    if let Some(first) = missing.first() {
        return Err(VkError::MissingFeature {
            device: chosen.name.clone(),
            what: if missing.len() == 1 {
                first.clone()
            } else {
                missing.join(", ")
            },
        });
    }
    Ok(chosen.clone())
}
