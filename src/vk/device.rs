//! The logical device and everything that lives as long as it: allocator, streams,
//! profiler log. [`Gpu`] is a cheap, cloneable handle to it.

use std::collections::VecDeque;
use std::ffi::{c_char, CStr};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use ash::{ext, khr, vk};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::clock::Calibrator;
use super::error::{CallContext, Result, VkError};
use super::instance::{Instance, InstanceDesc};
use super::physical::{self, PhysicalDeviceInfo, QueueFamilyInfo};
use super::pipeline::BufferAccess;
use super::profiler::{GpuBatch, ProfileLog, QueryBatch};
use super::stream::{
    QueueSlot, StreamKind, StreamMapping, StreamPlacement, TimelineHandle, TimelinePoint,
};

/// How to open a device.
#[derive(Clone, Debug, Default)]
pub struct GpuDesc {
    pub instance: InstanceDesc,
    /// Device index or name substring; `None` picks the best (see [`physical::select`]).
    pub device: Option<String>,
    pub placement: StreamPlacement,
    /// How kernels with a descriptor twin take their buffers; `None`: the device's
    /// default ([`BufferAccess::for_device`]), or `SPLITRAY_BUFFER_ACCESS`
    /// (`descriptors` or `addresses`) where it is set.
    pub buffer_access: Option<BufferAccess>,
}

/// Bytes allocated through the allocator: now and at the peak.
#[derive(Debug, Default)]
pub(crate) struct MemoryCounters {
    current: AtomicU64,
    peak: AtomicU64,
}

impl MemoryCounters {
    /// Counts an allocation; returns the bytes allocated now.
    pub(crate) fn add(&self, bytes: u64) -> u64 {
        let now = self.current.fetch_add(bytes, Ordering::Relaxed) + bytes;
        self.peak.fetch_max(now, Ordering::Relaxed);
        now
    }
    /// Counts a release; returns the bytes allocated now.
    pub(crate) fn sub(&self, bytes: u64) -> u64 {
        self.current.fetch_sub(bytes, Ordering::Relaxed) - bytes
    }
}

/// VK_KHR_acceleration_structure entry points and limits, when enabled.
pub(crate) struct AccelSupport {
    pub(crate) loader: khr::acceleration_structure::Device,
    /// minAccelerationStructureScratchOffsetAlignment.
    pub(crate) scratch_alignment: u64,
}

impl AccelSupport {
    /// The loader and the scratch alignment of a device opened with ray queries.
    fn new(instance: &Instance, info: &PhysicalDeviceInfo, raw: &ash::Device) -> Self {
        let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut as_props);
        // SAFETY: valid physical device that offers VK_KHR_acceleration_structure.
        unsafe {
            instance
                .raw
                .get_physical_device_properties2(info.raw, &mut props2)
        };
        Self {
            loader: khr::acceleration_structure::Device::new(&instance.raw, raw),
            scratch_alignment: (as_props.min_acceleration_structure_scratch_offset_alignment
                as u64)
                .max(1),
        }
    }
}

/// A command pool with the one command buffer ever allocated from it. Resetting the
/// pool returns that buffer to the initial state, ready to record again; allocating a
/// fresh buffer at each reuse instead would leave every earlier one allocated in the
/// pool (a reset recycles buffers, it does not free them), and each reset would then
/// walk all of them: on NVIDIA's driver a long render slowed down pass by pass.
#[derive(Clone, Copy)]
pub(crate) struct CommandSlot {
    pub(crate) pool: vk::CommandPool,
    pub(crate) cmd: vk::CommandBuffer,
}

/// A submitted command buffer that may still run.
pub(crate) struct InFlight {
    pub(crate) value: u64,
    pub(crate) slot: CommandSlot,
    pub(crate) queries: QueryBatch,
    /// When the host submitted it (timelines align GPU clocks at submission where the
    /// device cannot calibrate them).
    pub(crate) submitted: Instant,
}

pub(crate) struct StreamState {
    pub(crate) kind: StreamKind,
    pub(crate) family: u32,
    /// Index into `GpuInner::queues`.
    pub(crate) queue: usize,
    pub(crate) timeline: Arc<TimelineHandle>,
    /// 0 when the queue family cannot write timestamps.
    pub(crate) timestamp_mask: u64,
    pub(crate) state: Mutex<StreamInner>,
}

#[derive(Default)]
pub(crate) struct StreamInner {
    pub(crate) last_value: u64,
    pub(crate) in_flight: VecDeque<InFlight>,
    pub(crate) free_slots: Vec<CommandSlot>,
    pub(crate) free_query_pools: Vec<vk::QueryPool>,
}

pub(crate) struct GpuInner {
    pub(crate) instance: Arc<Instance>,
    pub(crate) info: PhysicalDeviceInfo,
    pub(crate) raw: ash::Device,
    pub(crate) push_descriptor: khr::push_descriptor::Device,
    /// Present when the device was opened with ray queries (see [`Gpu::ray_query`]).
    pub(crate) accel: Option<AccelSupport>,
    pub(crate) debug_utils: Option<ext::debug_utils::Device>,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) memory: MemoryCounters,
    /// Command buffers allocated since the device opened (one per command pool).
    pub(crate) command_buffers: AtomicU64,
    pub(crate) mapping: StreamMapping,
    /// One entry per distinct queue; submissions to a queue are serialised by its mutex.
    pub(crate) queues: Vec<Mutex<vk::Queue>>,
    pub(crate) streams: Vec<StreamState>,
    pub(crate) profile: Mutex<ProfileLog>,
    /// Every harvested command buffer's scopes while a timeline is kept
    /// ([`Gpu::start_timeline`]); `None` otherwise, so that nothing is kept for nothing.
    pub(crate) timeline: Mutex<Option<Vec<GpuBatch>>>,
    /// Present where the device offers VK_KHR/EXT_calibrated_timestamps.
    pub(crate) calibrator: Option<Calibrator>,
    pub(crate) buffer_access: BufferAccess,
    /// Opened with VK_KHR_swapchain ([`Gpu::new_for_presentation`]).
    pub(crate) present: bool,
}

/// The device handle every other object holds.
#[derive(Clone)]
pub struct Gpu(pub(crate) Arc<GpuInner>);

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
            .field("device", &self.0.info.name)
            .finish()
    }
}

pub(crate) const QUERIES_PER_POOL: u32 = 512;

impl Gpu {
    /// Creates the instance, picks a device and opens it with every stream.
    ///
    /// With validation on, do not open or drop a `Gpu` while another thread uses
    /// another one: the validation layer of Debian 12 (1.3.239) keeps all instances' and
    /// devices' state in one unsynchronised map, and such a process crashes now and then
    /// (the tests take turns for this: tests/suite/common/turn.rs).
    pub fn new(desc: &GpuDesc) -> Result<Self> {
        let _span = tracing::info_span!("open device").entered();
        let instance = Instance::new(desc.instance)?;
        let devices = physical::enumerate(&instance)?;
        let info = physical::select(&devices, desc.device.as_deref())?;
        let buffer_access = buffer_access_for(desc, &info)?;
        Self::open(instance, info, desc.placement, buffer_access, false)
    }

    /// [`Gpu::new`] for a device that also presents to windows: the instance gets the
    /// window system's `surface_extensions` (see `vk::surface_extensions`) and the device
    /// VK_KHR_swapchain, which it must offer.
    pub fn new_for_presentation(desc: &GpuDesc, surface_extensions: &[&CStr]) -> Result<Self> {
        let _span = tracing::info_span!("open device").entered();
        let instance = Instance::with_extensions(desc.instance, surface_extensions)?;
        let devices = physical::enumerate(&instance)?;
        let info = physical::select(&devices, desc.device.as_deref())?;
        // SAFETY: a plain query on a physical device of this instance.
        let extensions = unsafe { instance.raw.enumerate_device_extension_properties(info.raw) }
            .call("vkEnumerateDeviceExtensionProperties")?;
        let has_swapchain = extensions.iter().any(|e| {
            e.extension_name_as_c_str()
                .is_ok_and(|n| n == khr::swapchain::NAME)
        });
        if !has_swapchain {
            return Err(VkError::MissingFeature {
                device: info.name.clone(),
                what: "VK_KHR_swapchain (to present to a window)".into(),
            });
        }
        let buffer_access = buffer_access_for(desc, &info)?;
        Self::open(instance, info, desc.placement, buffer_access, true)
    }

    fn open(
        instance: Arc<Instance>,
        info: PhysicalDeviceInfo,
        placement: StreamPlacement,
        buffer_access: BufferAccess,
        present: bool,
    ) -> Result<Self> {
        let mapping = StreamMapping::plan(&info, placement);
        let raw = create_logical_device(&instance, &info, &mapping, present)?;
        let allocator = match create_allocator(&instance, &raw, &info) {
            Ok(allocator) => allocator,
            Err(e) => return Err(destroy_unowned_device(&raw, e)),
        };
        let queue_slots = distinct_queue_slots(&mapping);
        let queues = queue_slots
            .iter()
            // SAFETY: each (family, index) is one of the mapping's, all requested by
            // create_logical_device.
            .map(|s| Mutex::new(unsafe { raw.get_device_queue(s.family, s.index) }))
            .collect();
        let streams = match create_streams(&raw, &info, &mapping, &queue_slots) {
            Ok(streams) => streams,
            Err(e) => {
                // The allocator frees its memory through the device: it goes first.
                drop(allocator);
                return Err(destroy_unowned_device(&raw, e));
            }
        };
        let push_descriptor = khr::push_descriptor::Device::new(&instance.raw, &raw);
        let accel = info
            .capabilities
            .ray_query
            .then(|| AccelSupport::new(&instance, &info, &raw));
        let calibrator = info
            .calibration
            .map(|extension| Calibrator::new(&instance, &raw, extension));
        let debug_utils = instance
            .has_debug_utils()
            .then(|| ext::debug_utils::Device::new(&instance.raw, &raw));
        let gpu = Gpu(Arc::new(GpuInner {
            instance,
            info,
            raw,
            push_descriptor,
            accel,
            debug_utils,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            memory: MemoryCounters::default(),
            command_buffers: AtomicU64::new(0),
            mapping,
            queues,
            streams,
            profile: Mutex::new(ProfileLog::default()),
            timeline: Mutex::new(None),
            calibrator,
            buffer_access,
            present,
        }));
        for s in &gpu.0.streams {
            gpu.set_object_name(s.timeline.raw, &format!("timeline:{}", s.kind.name()));
        }
        Ok(gpu)
    }

    pub fn info(&self) -> &PhysicalDeviceInfo {
        &self.0.info
    }

    /// Whether the device was opened with ray queries and acceleration structures
    /// (VK_KHR_ray_query, VK_KHR_acceleration_structure, bufferDeviceAddress).
    pub fn ray_query(&self) -> bool {
        self.0.accel.is_some()
    }

    /// How kernels with a descriptor twin take their buffers on this device.
    pub fn buffer_access(&self) -> BufferAccess {
        self.0.buffer_access
    }

    /// Whether the device was opened to present to windows ([`Gpu::new_for_presentation`]).
    pub fn presents(&self) -> bool {
        self.0.present
    }

    pub fn stream_mapping(&self) -> &StreamMapping {
        &self.0.mapping
    }

    pub fn instance(&self) -> &Instance {
        &self.0.instance
    }

    /// Errors and warnings the validation layer has reported so far.
    pub fn validation_messages(&self) -> Vec<super::ValidationMessage> {
        self.0.instance.validation_log().messages()
    }

    /// Bytes currently allocated and the peak since the device opened (or the last reset).
    pub fn memory_bytes(&self) -> (u64, u64) {
        let m = &self.0.memory;
        (
            m.current.load(Ordering::Relaxed),
            m.peak.load(Ordering::Relaxed),
        )
    }

    /// Command buffers allocated since the device opened. Recorders reuse finished
    /// command buffers, so this is the most ever in flight at once, not the number of
    /// submissions.
    pub fn command_buffers_allocated(&self) -> u64 {
        self.0.command_buffers.load(Ordering::Relaxed)
    }

    /// Restarts peak tracking from the current allocation level.
    pub fn reset_peak_memory(&self) {
        let m = &self.0.memory;
        m.peak
            .store(m.current.load(Ordering::Relaxed), Ordering::Relaxed);
    }

    /// Names a Vulkan object for validation messages and debuggers.
    pub(crate) fn set_object_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(du) = &self.0.debug_utils {
            let Ok(cname) = std::ffi::CString::new(name) else {
                return;
            };
            let info = vk::DebugUtilsObjectNameInfoEXT::default()
                .object_handle(handle)
                .object_name(&cname);
            // SAFETY: the handle belongs to this device. Naming is best effort.
            let _ = unsafe { du.set_debug_utils_object_name(&info) };
        }
    }

    pub(crate) fn stream(&self, kind: StreamKind) -> &StreamState {
        &self.0.streams[kind.index()]
    }

    /// Blocks until `point` has been reached.
    pub fn wait(&self, point: &TimelinePoint) -> Result<()> {
        let _span = tracing::info_span!(
            "wait",
            what = %self.awaited(point),
            stream = point.stream.name(),
            value = point.value
        )
        .entered();
        let semaphores = [point.semaphore.raw];
        let values = [point.value];
        let info = vk::SemaphoreWaitInfo::default()
            .semaphores(&semaphores)
            .values(&values);
        // SAFETY: the semaphore belongs to this device.
        unsafe { self.0.raw.wait_semaphores(&info, u64::MAX) }.call("vkWaitSemaphores")?;
        self.reclaim(point.stream)
    }

    /// What a host wait waits for, as a timeline names it: the stream, the value and the
    /// last outermost scope of the command buffer that signals it (when still in flight).
    fn awaited(&self, point: &TimelinePoint) -> String {
        let st = self.stream(point.stream).state.lock().unwrap();
        let last_scope = st
            .in_flight
            .iter()
            .find(|f| f.value == point.value)
            .and_then(|f| f.queries.scopes.iter().rev().find(|s| s.depth == 0));
        match last_scope {
            Some(scope) => format!("{}@{} ({})", point.stream.name(), point.value, scope.name),
            None => format!("{}@{}", point.stream.name(), point.value),
        }
    }

    /// The value a stream's timeline has reached.
    pub fn completed_value(&self, kind: StreamKind) -> Result<u64> {
        // SAFETY: the semaphore belongs to this device.
        unsafe {
            self.0
                .raw
                .get_semaphore_counter_value(self.stream(kind).timeline.raw)
        }
        .call("vkGetSemaphoreCounterValue")
    }

    /// Waits for every stream to drain.
    pub fn wait_idle(&self) -> Result<()> {
        for kind in StreamKind::ALL {
            let last = self.stream(kind).state.lock().unwrap().last_value;
            let point = self.timeline_point(kind, last);
            self.wait(&point)?;
        }
        Ok(())
    }

    pub(crate) fn timeline_point(&self, kind: StreamKind, value: u64) -> TimelinePoint {
        TimelinePoint {
            semaphore: self.stream(kind).timeline.clone(),
            value,
            stream: kind,
        }
    }

    /// Recycles finished command pools and harvests their timestamps. Never blocks on
    /// the GPU: only submissions whose timeline value has been reached are touched.
    pub fn reclaim(&self, kind: StreamKind) -> Result<()> {
        let done = self.completed_value(kind)?;
        let stream = self.stream(kind);
        let mut finished = Vec::new();
        {
            let mut st = stream.state.lock().unwrap();
            while st.in_flight.front().is_some_and(|f| f.value <= done) {
                finished.push(st.in_flight.pop_front().unwrap());
            }
        }
        for f in finished {
            let records = super::profiler::read_batch(self, stream, &f.queries, f.value)?;
            // SAFETY: the pool's command buffers have completed (timeline reached).
            unsafe {
                self.0
                    .raw
                    .reset_command_pool(f.slot.pool, vk::CommandPoolResetFlags::empty())
            }
            .call("vkResetCommandPool")?;
            if let Some(batches) = self.0.timeline.lock().unwrap().as_mut() {
                batches.push(GpuBatch {
                    stream: kind,
                    submission: f.value,
                    submitted: f.submitted,
                    records: records.clone(),
                });
            }
            self.0.profile.lock().unwrap().records.extend(records);
            let mut st = stream.state.lock().unwrap();
            st.free_slots.push(f.slot);
            st.free_query_pools.extend(f.queries.pools);
        }
        Ok(())
    }

    /// Starts keeping every finished command buffer's scopes and submission time for a
    /// timeline (until [`Gpu::take_timeline`]), independently of [`Gpu::take_profile`].
    pub fn start_timeline(&self) {
        *self.0.timeline.lock().unwrap() = Some(Vec::new());
    }

    /// Stops keeping command buffers for a timeline and returns those kept, in the order
    /// they were harvested. Wait for the streams first ([`Gpu::wait_idle`]) so that all
    /// finished work is in.
    pub fn take_timeline(&self) -> Vec<GpuBatch> {
        self.0.timeline.lock().unwrap().take().unwrap_or_default()
    }

    /// Takes the per-dispatch GPU times collected so far (after [`Gpu::wait_idle`] or
    /// waits, so that finished work has been harvested).
    pub fn take_profile(&self) -> ProfileLog {
        std::mem::take(&mut *self.0.profile.lock().unwrap())
    }
}

impl Drop for GpuInner {
    fn drop(&mut self) {
        // SAFETY: last handle gone: nothing else uses the device. Wait, then destroy
        // children before the device, and the allocator before the device.
        unsafe {
            let _ = self.raw.device_wait_idle();
            for s in &mut self.streams {
                let st = s.state.get_mut().unwrap();
                for f in st.in_flight.drain(..) {
                    self.raw.destroy_command_pool(f.slot.pool, None);
                    for q in f.queries.pools {
                        self.raw.destroy_query_pool(q, None);
                    }
                }
                for slot in st.free_slots.drain(..) {
                    self.raw.destroy_command_pool(slot.pool, None);
                }
                for q in st.free_query_pools.drain(..) {
                    self.raw.destroy_query_pool(q, None);
                }
                self.raw.destroy_semaphore(s.timeline.raw, None);
            }
            ManuallyDrop::drop(&mut self.allocator);
            self.raw.destroy_device(None);
        }
    }
}

/// Queue priorities, all equal; a family's queue create info takes the first `count`.
static QUEUE_PRIORITIES: [f32; 16] = [1.0; 16];

/// Opens the logical device with the queues of `mapping`, the extensions and features
/// splitray uses where the device offers them, and VK_KHR_swapchain when it `present`s.
fn create_logical_device(
    instance: &Instance,
    info: &PhysicalDeviceInfo,
    mapping: &StreamMapping,
    present: bool,
) -> Result<ash::Device> {
    let queue_infos: Vec<_> = mapping
        .queues_per_family()
        .iter()
        .map(|&(family, count)| {
            vk::DeviceQueueCreateInfo::default()
                .queue_family_index(family)
                .queue_priorities(&QUEUE_PRIORITIES[..count as usize])
        })
        .collect();
    let extensions = device_extensions(info, present);
    let ray_query = info.capabilities.ray_query;
    let int64_atomics = info.capabilities.buffer_int64_atomics;
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
        .timeline_semaphore(true)
        .buffer_device_address(true)
        .shader_buffer_int64_atomics(int64_atomics)
        .host_query_reset(info.capabilities.host_query_reset);
    let f10 = vk::PhysicalDeviceFeatures::default().shader_int64(info.capabilities.shader_int64);
    let full_subgroups = info.capabilities.compute_full_subgroups;
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
        .synchronization2(true)
        .maintenance4(true)
        .subgroup_size_control(full_subgroups)
        .compute_full_subgroups(full_subgroups);
    let mut accel_features =
        vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
    let mut rq_features = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
    let mut create_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_extension_names(&extensions)
        .enabled_features(&f10)
        .push_next(&mut f12)
        .push_next(&mut f13);
    if ray_query {
        create_info = create_info
            .push_next(&mut accel_features)
            .push_next(&mut rq_features);
    }
    // SAFETY: the physical device came from this instance; the create info lives here.
    unsafe { instance.raw.create_device(info.raw, &create_info, None) }.call("vkCreateDevice")
}

/// The device extensions to enable: push descriptors always, the swapchain to present,
/// calibrated timestamps and ray queries where the device offers them.
fn device_extensions(info: &PhysicalDeviceInfo, present: bool) -> Vec<*const c_char> {
    let mut extensions = vec![khr::push_descriptor::NAME.as_ptr()];
    if present {
        extensions.push(khr::swapchain::NAME.as_ptr());
    }
    if let Some(calibration) = info.calibration {
        extensions.push(calibration.name().as_ptr());
    }
    // Ray queries (and what they need) are enabled only where the device offers
    // them all; elsewhere the device is opened exactly as without them.
    if info.capabilities.ray_query {
        extensions.extend([
            khr::acceleration_structure::NAME.as_ptr(),
            khr::ray_query::NAME.as_ptr(),
            khr::deferred_host_operations::NAME.as_ptr(),
        ]);
    }
    extensions
}

fn create_allocator(
    instance: &Instance,
    raw: &ash::Device,
    info: &PhysicalDeviceInfo,
) -> Result<Allocator> {
    Allocator::new(&AllocatorCreateDesc {
        instance: instance.raw.clone(),
        device: raw.clone(),
        physical_device: info.raw,
        debug_settings: Default::default(),
        buffer_device_address: true,
        allocation_sizes: Default::default(),
    })
    .map_err(|error| VkError::Alloc {
        name: "allocator".into(),
        error,
    })
}

/// The distinct queues of `mapping`, in slot order.
fn distinct_queue_slots(mapping: &StreamMapping) -> Vec<QueueSlot> {
    let mut queue_slots = Vec::new();
    for s in mapping.slots {
        if !queue_slots.contains(&s) {
            queue_slots.push(s);
        }
    }
    queue_slots
}

/// Every stream with its timeline semaphore, on its queue (an index into `queue_slots`).
fn create_streams(
    raw: &ash::Device,
    info: &PhysicalDeviceInfo,
    mapping: &StreamMapping,
    queue_slots: &[QueueSlot],
) -> Result<Vec<StreamState>> {
    let mut streams: Vec<StreamState> = Vec::new();
    for kind in StreamKind::ALL {
        let slot = mapping.slot(kind);
        let sem = match create_timeline_semaphore(raw) {
            Ok(sem) => sem,
            Err(e) => {
                for s in &streams {
                    // SAFETY: created above on `raw`, never used.
                    unsafe { raw.destroy_semaphore(s.timeline.raw, None) };
                }
                return Err(e);
            }
        };
        let family = &info.queue_families[slot.family as usize];
        let bits = timestamp_bits(family, info.capabilities.host_query_reset);
        streams.push(StreamState {
            kind,
            family: slot.family,
            queue: queue_slots.iter().position(|s| *s == slot).unwrap(),
            timeline: Arc::new(TimelineHandle { raw: sem }),
            timestamp_mask: timestamp_mask(bits),
            state: Mutex::new(StreamInner::default()),
        });
    }
    Ok(streams)
}

/// Destroys a device that `Gpu::open` created but could not finish (no `GpuInner` owns
/// it yet, so nothing else will), and hands back the error that stopped it.
fn destroy_unowned_device(raw: &ash::Device, error: VkError) -> VkError {
    // SAFETY: nothing was submitted to the device and every child object made on it has
    // been destroyed by the caller.
    unsafe { raw.destroy_device(None) };
    error
}

fn create_timeline_semaphore(raw: &ash::Device) -> Result<vk::Semaphore> {
    let mut type_info = vk::SemaphoreTypeCreateInfo::default()
        .semaphore_type(vk::SemaphoreType::TIMELINE)
        .initial_value(0);
    let sem_info = vk::SemaphoreCreateInfo::default().push_next(&mut type_info);
    // SAFETY: valid device.
    unsafe { raw.create_semaphore(&sem_info, None) }.call("vkCreateSemaphore")
}

/// The timestamp bits a stream on `family` gets. A query must be reset before it is
/// written: from the host where the device can (`host_query_reset`), else in the command
/// buffer, which a family without graphics or compute cannot record
/// (VUID-vkCmdResetQueryPool-commandBuffer-cmdpool), so such a stream goes untimed.
fn timestamp_bits(family: &QueueFamilyInfo, host_query_reset: bool) -> u32 {
    if host_query_reset || family.graphics || family.compute {
        family.timestamp_valid_bits
    } else {
        0
    }
}

/// The bits of a timestamp that a queue family writes (`timestamp_valid_bits`) as a mask.
fn timestamp_mask(bits: u32) -> u64 {
    match bits {
        0 => 0,
        64.. => u64::MAX,
        b => (1u64 << b) - 1,
    }
}

/// How kernels with a descriptor twin take their buffers: the description's choice, else
/// `SPLITRAY_BUFFER_ACCESS`, else the device's default ([`BufferAccess::for_device`]).
fn buffer_access_for(desc: &GpuDesc, info: &PhysicalDeviceInfo) -> Result<BufferAccess> {
    let from_env = std::env::var("SPLITRAY_BUFFER_ACCESS").ok();
    match (desc.buffer_access, from_env.as_deref()) {
        (Some(access), _) => Ok(access),
        (None, None | Some("")) => Ok(BufferAccess::for_device(info)),
        (None, Some(s)) => BufferAccess::parse(s).ok_or_else(|| {
            VkError::Usage(format!(
                "SPLITRAY_BUFFER_ACCESS={s}: expected `descriptors` or `addresses`"
            ))
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn family(graphics: bool, compute: bool, bits: u32) -> QueueFamilyInfo {
        QueueFamilyInfo {
            index: 0,
            count: 1,
            graphics,
            compute,
            transfer: true,
            timestamp_valid_bits: bits,
        }
    }

    #[test]
    fn transfer_only_families_are_timed_only_with_host_resets() {
        let transfer_only = family(false, false, 64);
        assert_eq!(timestamp_bits(&transfer_only, true), 64);
        assert_eq!(timestamp_bits(&transfer_only, false), 0);
        for (graphics, compute) in [(true, true), (false, true), (true, false)] {
            let f = family(graphics, compute, 36);
            assert_eq!(timestamp_bits(&f, false), 36);
            assert_eq!(timestamp_bits(&f, true), 36);
        }
        assert_eq!(timestamp_bits(&family(true, true, 0), true), 0);
        assert_eq!(timestamp_mask(timestamp_bits(&transfer_only, false)), 0);
        assert_eq!(timestamp_mask(36), (1 << 36) - 1);
        assert_eq!(timestamp_mask(64), u64::MAX);
    }
}
