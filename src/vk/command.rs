//! Command recording: dispatches, barriers, copies, timestamp scopes, submission.

use std::sync::atomic::Ordering;

use ash::vk;

use super::accel::AccelerationStructure;
use super::buffer::{Buffer, BufferSlice};
use super::device::{CommandSlot, Gpu, InFlight, StreamState, QUERIES_PER_POOL};
use super::error::{CallContext, Result, VkError};
use super::pipeline::{ComputePipeline, Variant};
use super::profiler::{QueryBatch, ScopeInfo, ScopeQueries};
use super::stream::{StreamKind, TimelinePoint};

/// Records one command buffer for one stream. Every dispatch is named (debug label and
/// timestamp scope under the kernel's name, or the innermost [`Recorder::begin_scope`]
/// name if one is open). Nothing runs until [`Recorder::submit`].
pub struct Recorder {
    gpu: Gpu,
    stream: StreamKind,
    /// The pool and its command buffer, being recorded.
    slot: CommandSlot,
    queries: QueryBatch,
    /// Indices into `queries.scopes` of the scopes still open, outermost first.
    open_scopes: Vec<usize>,
    submitted: bool,
    /// Host time spent recording, for timelines: from [`Gpu::recorder`] to submission.
    span: tracing::Span,
}

/// Workgroup counts for `n` items in groups of `workgroup_size`, folded into y when x
/// would exceed the device limit. Kernels recover the linear index with
/// `linear_group_id()` from `glsl/common/grid.glsl`.
pub fn grid_for(gpu: &Gpu, n: u64, workgroup_size: u32) -> [u32; 3] {
    let groups = n.div_ceil(workgroup_size as u64);
    let max_x = gpu.info().limits.max_compute_work_group_count[0] as u64;
    if groups <= max_x {
        [groups as u32, 1, 1]
    } else {
        let y = groups.div_ceil(max_x);
        [groups.div_ceil(y) as u32, y as u32, 1]
    }
}

impl Gpu {
    /// Starts recording a command buffer for `stream`.
    pub fn recorder(&self, stream: StreamKind) -> Result<Recorder> {
        let span = tracing::info_span!("record", what = stream.name());
        self.reclaim(stream)?;
        let state = self.stream(stream);
        let device = &self.0.raw;
        let reused = state.state.lock().unwrap().free_slots.pop();
        // A reused slot was reset when its last submission finished (Gpu::reclaim).
        let slot = match reused {
            Some(slot) => slot,
            None => self.new_command_slot(state.family)?,
        };
        let cmd = slot.cmd;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the command buffer is in the initial state (new, or its pool reset).
        unsafe { device.begin_command_buffer(cmd, &begin) }.call("vkBeginCommandBuffer")?;
        Ok(Recorder {
            gpu: self.clone(),
            stream,
            slot,
            queries: QueryBatch::default(),
            open_scopes: Vec::new(),
            submitted: false,
            span,
        })
    }

    /// A new command pool of queue family `family` with its one command buffer.
    fn new_command_slot(&self, family: u32) -> Result<CommandSlot> {
        let device = &self.0.raw;
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device and family.
        let pool =
            unsafe { device.create_command_pool(&info, None) }.call("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool was just created; the recorder owns it until its submission
        // completes.
        match unsafe { device.allocate_command_buffers(&alloc) }.call("vkAllocateCommandBuffers") {
            Ok(cmds) => {
                self.0.command_buffers.fetch_add(1, Ordering::Relaxed);
                Ok(CommandSlot { pool, cmd: cmds[0] })
            }
            Err(e) => {
                // SAFETY: nothing was allocated from or submitted with the pool.
                unsafe { device.destroy_command_pool(pool, None) };
                Err(e)
            }
        }
    }
}

impl Recorder {
    pub fn stream(&self) -> StreamKind {
        self.stream
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    fn device(&self) -> &ash::Device {
        &self.gpu.0.raw
    }

    /// The command buffer being recorded (for sibling modules such as `accel`).
    pub(crate) fn raw_cmd(&self) -> vk::CommandBuffer {
        self.slot.cmd
    }

    /// Allocates the next timestamp query and writes it.
    fn timestamp(&mut self) -> Result<Option<u32>> {
        if self.gpu.stream(self.stream).timestamp_mask == 0 {
            return Ok(None);
        }
        let index = self.queries.next;
        let (pool_index, query) = QueryBatch::location(index);
        if pool_index == self.queries.pools.len() {
            let reused = self
                .gpu
                .stream(self.stream)
                .state
                .lock()
                .unwrap()
                .free_query_pools
                .pop();
            let pool = match reused {
                Some(p) => p,
                None => {
                    let info = vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(QUERIES_PER_POOL);
                    // SAFETY: valid device.
                    unsafe { self.device().create_query_pool(&info, None) }
                        .call("vkCreateQueryPool")?
                }
            };
            self.reset_query_pool(pool);
            self.queries.pools.push(pool);
        }
        let pool = self.queries.pools[pool_index];
        // SAFETY: recording; the query was reset before this command buffer's submission.
        unsafe {
            self.device().cmd_write_timestamp2(
                self.slot.cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                pool,
                query,
            )
        };
        self.queries.next += 1;
        Ok(Some(index))
    }

    /// Resets every query of `pool` before this command buffer writes any: from the host
    /// where the device allows it (the pool is new, or came back from a command buffer
    /// that completed or never ran, so the GPU is not using it), else recorded here.
    fn reset_query_pool(&self, pool: vk::QueryPool) {
        if self.gpu.info().capabilities.host_query_reset {
            // SAFETY: hostQueryReset is enabled; no pending submission uses `pool`.
            unsafe { self.device().reset_query_pool(pool, 0, QUERIES_PER_POOL) };
        } else {
            // SAFETY: recording on a graphics or compute family (others write no
            // timestamps without host resets); the reset precedes every write to the pool.
            unsafe {
                self.device()
                    .cmd_reset_query_pool(self.slot.cmd, pool, 0, QUERIES_PER_POOL)
            };
        }
    }

    fn label_begin(&self, name: &str) {
        if let Some(du) = &self.gpu.0.debug_utils {
            if let Ok(cname) = std::ffi::CString::new(name) {
                let label = vk::DebugUtilsLabelEXT::default().label_name(&cname);
                // SAFETY: recording.
                unsafe { du.cmd_begin_debug_utils_label(self.slot.cmd, &label) };
            }
        }
    }

    fn label_end(&self) {
        if let Some(du) = &self.gpu.0.debug_utils {
            // SAFETY: recording; paired with label_begin.
            unsafe { du.cmd_end_debug_utils_label(self.slot.cmd) };
        }
    }

    /// Opens a named scope: a debug label and a timestamp pair around everything
    /// recorded until the matching [`Recorder::end_scope`].
    pub fn begin_scope(&mut self, name: &str) -> Result<()> {
        self.begin_scope_with(name, ScopeInfo::default())
    }

    fn begin_scope_with(&mut self, name: &str, info: ScopeInfo) -> Result<()> {
        self.label_begin(name);
        let begin = self.timestamp()?;
        self.open_scopes.push(self.queries.scopes.len());
        self.queries.scopes.push(ScopeQueries {
            name: name.to_string(),
            begin,
            end: None,
            depth: self.open_scopes.len() as u32 - 1,
            info,
        });
        Ok(())
    }

    pub fn end_scope(&mut self) -> Result<()> {
        let index = self
            .open_scopes
            .pop()
            .ok_or_else(|| VkError::Usage("end_scope without begin_scope".into()))?;
        let end = self.timestamp()?;
        self.label_end();
        self.queries.scopes[index].end = end;
        Ok(())
    }

    /// Records a dispatch of `groups` workgroups of `variant` (bound) inside a scope
    /// under the kernel's name.
    fn dispatch_scope(
        &mut self,
        (pipeline, variant): (&ComputePipeline, &Variant),
        bindings: &[BufferSlice<'_>],
        groups: [u32; 3],
        items: Option<u64>,
    ) -> Result<()> {
        let info = ScopeInfo {
            workgroups: Some(groups),
            items,
            bytes_bound: Some(bindings.iter().map(|b| b.size).sum()),
            first_use: variant.mark_dispatched(),
        };
        self.begin_scope_with(pipeline.name(), info)?;
        // SAFETY: recording with a bound compute pipeline and pushed descriptors (the
        // callers bind first); for ray-query kernels the acceleration structure is alive
        // (borrowed by the caller) and built earlier on the timeline.
        unsafe {
            self.device()
                .cmd_dispatch(self.slot.cmd, groups[0], groups[1], groups[2])
        };
        self.end_scope()
    }

    fn bind<'p>(
        &mut self,
        pipeline: &'p ComputePipeline,
        bindings: &[BufferSlice<'_>],
        push: &[u8],
    ) -> Result<&'p Variant> {
        self.bind_with(pipeline, bindings, None, push)
    }

    /// Binds the form of `pipeline` that suits `bindings` (its descriptor twin where every
    /// buffer fits a binding and the device prefers it), its descriptors and its push
    /// constants with the buffer addresses; returns that form.
    fn bind_with<'p>(
        &mut self,
        pipeline: &'p ComputePipeline,
        bindings: &[BufferSlice<'_>],
        tlas: Option<&AccelerationStructure>,
        push: &[u8],
    ) -> Result<&'p Variant> {
        check_arguments(pipeline, bindings, tlas, push)?;
        let variant = pipeline.variant_for(bindings)?;
        self.check_descriptor_ranges(pipeline, variant, bindings)?;
        let descriptors = &variant.passing.descriptors;
        let infos = descriptor_buffer_infos(descriptors, bindings);
        let mut writes: Vec<_> = infos
            .iter()
            .zip(descriptors)
            .map(|(info, &binding)| {
                vk::WriteDescriptorSet::default()
                    .dst_binding(binding)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        let push = push_with_addresses(variant, bindings, push);
        let tlas_handles = tlas.map(|t| [t.raw]);
        let mut tlas_write = vk::WriteDescriptorSetAccelerationStructureKHR::default();
        if let Some(handles) = &tlas_handles {
            tlas_write = tlas_write.acceleration_structures(handles);
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_binding(pipeline.bindings)
                    .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1)
                    .push_next(&mut tlas_write),
            );
        }
        self.record_bind(variant, &writes, &push);
        Ok(variant)
    }

    /// Fails where a buffer that `variant` takes as a descriptor is larger than one
    /// storage binding holds on this device.
    fn check_descriptor_ranges(
        &self,
        pipeline: &ComputePipeline,
        variant: &Variant,
        bindings: &[BufferSlice<'_>],
    ) -> Result<()> {
        let max_range = self.gpu.info().limits.max_storage_buffer_range;
        if let Some(&b) = variant
            .passing
            .descriptors
            .iter()
            .find(|&&b| bindings[b as usize].size > max_range)
        {
            let slice = &bindings[b as usize];
            return Err(VkError::Usage(format!(
                "kernel '{}' binds buffer '{}' ({} bytes) as descriptor {b}, more than one \
                 storage binding holds on this device (maxStorageBufferRange, {max_range} \
                 bytes): the kernel must take it by address (glsl/common/address.glsl)",
                pipeline.name(),
                slice.buffer.name(),
                slice.size
            )));
        }
        Ok(())
    }

    /// Records the binding of `variant`, the push of its descriptor `writes` and of its
    /// `push` constants.
    fn record_bind(&self, variant: &Variant, writes: &[vk::WriteDescriptorSet<'_>], push: &[u8]) {
        // SAFETY: recording; the pipeline and buffers are alive; counts were checked.
        unsafe {
            let d = self.device();
            d.cmd_bind_pipeline(self.slot.cmd, vk::PipelineBindPoint::COMPUTE, variant.raw);
            if !writes.is_empty() {
                self.gpu.0.push_descriptor.cmd_push_descriptor_set(
                    self.slot.cmd,
                    vk::PipelineBindPoint::COMPUTE,
                    variant.layout,
                    0,
                    writes,
                );
            }
            if !push.is_empty() {
                d.cmd_push_constants(
                    self.slot.cmd,
                    variant.layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    push,
                );
            }
        }
    }

    /// Records a dispatch of `groups` workgroups, timed under the kernel's name.
    pub fn dispatch<P: bytemuck::Pod>(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[BufferSlice<'_>],
        push: &P,
        groups: [u32; 3],
    ) -> Result<()> {
        self.dispatch_counted(pipeline, bindings, bytemuck::bytes_of(push), groups, None)
    }

    /// [`Recorder::dispatch`] for `items` items where the caller counted them.
    fn dispatch_counted(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[BufferSlice<'_>],
        push: &[u8],
        groups: [u32; 3],
        items: Option<u64>,
    ) -> Result<()> {
        let max = self.gpu.info().limits.max_compute_work_group_count;
        if groups.iter().zip(max).any(|(g, m)| *g > m) {
            return Err(VkError::Usage(format!(
                "kernel '{}': {groups:?} workgroups exceed the device's {max:?}",
                pipeline.name()
            )));
        }
        let variant = self.bind(pipeline, bindings, push)?;
        if groups.contains(&0) {
            return Ok(());
        }
        self.dispatch_scope((pipeline, variant), bindings, groups, items)
    }

    /// Dispatches enough workgroups for `n` items of a kernel made with
    /// [`ComputePipeline::with_acceleration_structure`], binding `tlas` after the buffers.
    pub fn dispatch_with_tlas<P: bytemuck::Pod>(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[BufferSlice<'_>],
        tlas: &AccelerationStructure,
        push: &P,
        n: u64,
    ) -> Result<()> {
        let groups = grid_for(&self.gpu, n, pipeline.workgroup_size());
        let variant = self.bind_with(pipeline, bindings, Some(tlas), bytemuck::bytes_of(push))?;
        if groups.contains(&0) {
            return Ok(());
        }
        self.dispatch_scope((pipeline, variant), bindings, groups, Some(n))
    }

    /// Dispatches enough workgroups for `n` items (see [`grid_for`]).
    pub fn dispatch_items<P: bytemuck::Pod>(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[BufferSlice<'_>],
        push: &P,
        n: u64,
    ) -> Result<()> {
        let groups = grid_for(&self.gpu, n, pipeline.workgroup_size());
        self.dispatch_counted(
            pipeline,
            bindings,
            bytemuck::bytes_of(push),
            groups,
            Some(n),
        )
    }

    /// Records a dispatch whose workgroup counts are read from `args` at `offset`
    /// (three u32s) when it runs, so counts computed on the GPU need no host round trip.
    pub fn dispatch_indirect<P: bytemuck::Pod>(
        &mut self,
        pipeline: &ComputePipeline,
        bindings: &[BufferSlice<'_>],
        push: &P,
        args: &Buffer,
        offset: u64,
    ) -> Result<()> {
        let variant = self.bind(pipeline, bindings, bytemuck::bytes_of(push))?;
        let info = ScopeInfo {
            bytes_bound: Some(bindings.iter().map(|b| b.size).sum()),
            first_use: variant.mark_dispatched(),
            ..Default::default()
        };
        self.begin_scope_with(pipeline.name(), info)?;
        // SAFETY: recording; args is an indirect-capable buffer of this device.
        unsafe {
            self.device()
                .cmd_dispatch_indirect(self.slot.cmd, args.raw, offset)
        };
        self.end_scope()
    }

    /// Makes every earlier compute or transfer write visible to every later compute,
    /// transfer or indirect-argument read or write on this stream.
    pub fn barrier(&mut self) {
        let barrier = vk::MemoryBarrier2::default()
            .src_stage_mask(
                vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER,
            )
            .src_access_mask(
                vk::AccessFlags2::SHADER_STORAGE_WRITE | vk::AccessFlags2::TRANSFER_WRITE,
            )
            .dst_stage_mask(
                vk::PipelineStageFlags2::COMPUTE_SHADER
                    | vk::PipelineStageFlags2::ALL_TRANSFER
                    | vk::PipelineStageFlags2::DRAW_INDIRECT,
            )
            .dst_access_mask(
                vk::AccessFlags2::SHADER_STORAGE_READ
                    | vk::AccessFlags2::SHADER_STORAGE_WRITE
                    | vk::AccessFlags2::TRANSFER_READ
                    | vk::AccessFlags2::TRANSFER_WRITE
                    | vk::AccessFlags2::INDIRECT_COMMAND_READ,
            );
        self.memory_barrier(barrier);
    }

    pub(crate) fn memory_barrier(&mut self, barrier: vk::MemoryBarrier2<'_>) {
        let barriers = [barrier];
        let dep = vk::DependencyInfo::default().memory_barriers(&barriers);
        // SAFETY: recording.
        unsafe { self.device().cmd_pipeline_barrier2(self.slot.cmd, &dep) };
    }

    /// Copies `size` bytes between buffers.
    pub fn copy(
        &mut self,
        src: &Buffer,
        src_offset: u64,
        dst: &Buffer,
        dst_offset: u64,
        size: u64,
    ) {
        if size == 0 {
            return;
        }
        let region = [vk::BufferCopy {
            src_offset,
            dst_offset,
            size,
        }];
        // SAFETY: recording; both buffers are alive and the region lies within them
        // (checked by validation in tests).
        unsafe {
            self.device()
                .cmd_copy_buffer(self.slot.cmd, src.raw, dst.raw, &region)
        };
    }

    /// Writes a few bytes (at most 64 KiB, a multiple of 4) into a buffer from the
    /// command stream itself (vkCmdUpdateBuffer): no staging, ordered like a transfer.
    pub fn update<T: bytemuck::Pod>(
        &mut self,
        buffer: &Buffer,
        offset: u64,
        data: &[T],
    ) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.is_empty() {
            return Ok(());
        }
        if bytes.len() > 65536
            || bytes.len() % 4 != 0
            || offset % 4 != 0
            || offset + bytes.len() as u64 > buffer.size()
        {
            return Err(VkError::Usage(format!(
                "update of {} bytes at {offset} into '{}' ({} bytes): needs ≤ 64 KiB, 4-byte aligned, in range",
                bytes.len(),
                buffer.name(),
                buffer.size()
            )));
        }
        // SAFETY: recording; size and alignment checked above.
        unsafe {
            self.device()
                .cmd_update_buffer(self.slot.cmd, buffer.raw, offset, bytes)
        };
        Ok(())
    }

    /// Fills `size` bytes of `buffer` from `offset` with a repeated u32.
    pub fn fill_range(
        &mut self,
        buffer: &Buffer,
        offset: u64,
        size: u64,
        value: u32,
    ) -> Result<()> {
        if size == 0 {
            return Ok(());
        }
        if offset % 4 != 0 || size % 4 != 0 || offset + size > buffer.size() {
            return Err(VkError::Usage(format!(
                "fill of {size} bytes at {offset} into '{}' ({} bytes): needs 4-byte alignment, in range",
                buffer.name(),
                buffer.size()
            )));
        }
        // SAFETY: recording; alignment and range checked above.
        unsafe {
            self.device()
                .cmd_fill_buffer(self.slot.cmd, buffer.raw, offset, size, value)
        };
        Ok(())
    }

    /// Fills the whole buffer with a repeated u32.
    pub fn fill(&mut self, buffer: &Buffer, value: u32) {
        // SAFETY: recording; the Vulkan buffer size is a multiple of 4.
        unsafe {
            self.device()
                .cmd_fill_buffer(self.slot.cmd, buffer.raw, 0, vk::WHOLE_SIZE, value)
        };
    }

    /// Ends recording and submits: the submission waits for this stream's previous one
    /// and for every point in `waits`, and signals the returned point when done.
    pub fn submit(self, waits: &[&TimelinePoint]) -> Result<TimelinePoint> {
        self.submit_signalling(waits, None)
    }

    /// [`Recorder::submit`] that also signals the binary semaphore `binary` (a swapchain
    /// image's "rendered" semaphore, which presenting waits for).
    pub(crate) fn submit_signalling(
        mut self,
        waits: &[&TimelinePoint],
        binary: Option<vk::Semaphore>,
    ) -> Result<TimelinePoint> {
        self.end_recording()?;
        let gpu = self.gpu.clone();
        let stream = gpu.stream(self.stream);
        let mut state = stream.state.lock().unwrap();
        let value = state.last_value + 1;
        let _span = tracing::info_span!(
            "submit",
            what = %format_args!("{}@{value}", self.stream.name()),
            stream = self.stream.name(),
            value
        )
        .entered();
        let mut wait_infos: Vec<vk::SemaphoreSubmitInfo> = waits
            .iter()
            .map(|p| semaphore_submit_info(p.semaphore.raw, p.value))
            .collect();
        if state.last_value > 0 {
            wait_infos.push(semaphore_submit_info(stream.timeline.raw, state.last_value));
        }
        let mut signal = vec![semaphore_submit_info(stream.timeline.raw, value)];
        if let Some(semaphore) = binary {
            // A binary semaphore ignores the value.
            signal.push(semaphore_submit_info(semaphore, 0));
        }
        let submitted = self.queue_submit(stream, &wait_infos, &signal)?;
        state.last_value = value;
        state.in_flight.push_back(InFlight {
            value,
            slot: self.slot,
            queries: std::mem::take(&mut self.queries),
            submitted,
        });
        self.submitted = true;
        Ok(gpu.timeline_point(self.stream, value))
    }

    /// Closes the scopes still open, makes the results visible to the host and ends the
    /// command buffer.
    fn end_recording(&mut self) -> Result<()> {
        while !self.open_scopes.is_empty() {
            self.end_scope()?;
        }
        // Make results visible to the host (mapped readback) once the timeline is reached.
        self.memory_barrier(
            vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ),
        );
        // SAFETY: recording started in Gpu::recorder.
        unsafe { self.device().end_command_buffer(self.slot.cmd) }.call("vkEndCommandBuffer")?;
        // Recording ends here; the submission is a span of its own.
        drop(std::mem::replace(&mut self.span, tracing::Span::none()));
        Ok(())
    }

    /// Submits the recorded command buffer to `stream`'s queue, waiting for `waits` and
    /// signalling `signal`; returns when the host submitted it.
    fn queue_submit(
        &self,
        stream: &StreamState,
        waits: &[vk::SemaphoreSubmitInfo<'_>],
        signal: &[vk::SemaphoreSubmitInfo<'_>],
    ) -> Result<std::time::Instant> {
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.slot.cmd)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(signal);
        let submitted = std::time::Instant::now();
        let queue = self.gpu.0.queues[stream.queue].lock().unwrap();
        // SAFETY: the queue is externally synchronised by its mutex; the command
        // buffer is executable; semaphores belong to this device.
        unsafe {
            self.device()
                .queue_submit2(*queue, &[submit], vk::Fence::null())
        }
        .call("vkQueueSubmit2")?;
        Ok(submitted)
    }
}

/// A wait for, or signal of, `semaphore` reaching `value`, covering all commands.
fn semaphore_submit_info(semaphore: vk::Semaphore, value: u64) -> vk::SemaphoreSubmitInfo<'static> {
    vk::SemaphoreSubmitInfo::default()
        .semaphore(semaphore)
        .value(value)
        .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
}

/// Fails unless `bindings`, `tlas` and `push` are what `pipeline` takes.
fn check_arguments(
    pipeline: &ComputePipeline,
    bindings: &[BufferSlice<'_>],
    tlas: Option<&AccelerationStructure>,
    push: &[u8],
) -> Result<()> {
    if pipeline.tlas_binding != tlas.is_some() {
        return Err(VkError::Usage(format!(
            "kernel '{}' {} an acceleration structure, {} given",
            pipeline.name(),
            if pipeline.tlas_binding {
                "takes"
            } else {
                "takes no"
            },
            if tlas.is_some() { "one" } else { "none" }
        )));
    }
    for (what, takes, given) in [
        ("buffers", pipeline.bindings, bindings.len()),
        (
            "push-constant bytes",
            pipeline.push_constant_bytes,
            push.len(),
        ),
    ] {
        if given as u32 != takes {
            return Err(VkError::Usage(format!(
                "kernel '{}' takes {takes} {what}, {given} given",
                pipeline.name()
            )));
        }
    }
    Ok(())
}

/// The buffer infos of the bindings a kernel takes as `descriptors`.
fn descriptor_buffer_infos(
    descriptors: &[u32],
    bindings: &[BufferSlice<'_>],
) -> Vec<[vk::DescriptorBufferInfo; 1]> {
    descriptors
        .iter()
        .map(|&b| {
            let b = &bindings[b as usize];
            // An empty range is invalid; bind 4 bytes the kernel will not read.
            let range = if b.size == 0 {
                4
            } else {
                b.size.next_multiple_of(4)
            };
            [vk::DescriptorBufferInfo::default()
                .buffer(b.buffer.raw)
                .offset(b.offset)
                .range(range)]
        })
        .collect()
}

/// The push-constant bytes of a dispatch: the caller's values, then the device address
/// of each buffer the kernel takes by address at its offset (see [`super::reflect`]).
fn push_with_addresses(variant: &Variant, bindings: &[BufferSlice<'_>], values: &[u8]) -> Vec<u8> {
    let mut push = vec![0u8; variant.passing.push_bytes as usize];
    push[..values.len()].copy_from_slice(values);
    for &(binding, offset) in &variant.passing.addresses {
        let slice = &bindings[binding as usize];
        let address = slice.buffer.device_address() + slice.offset;
        push[offset as usize..offset as usize + 8].copy_from_slice(&address.to_le_bytes());
    }
    push
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.submitted {
            return;
        }
        // Abandoned without submitting (an error path): nothing of it ever ran.
        // SAFETY: the pool and query pools were never submitted.
        unsafe {
            let _ = self.gpu.0.raw.end_command_buffer(self.slot.cmd);
            let _ = self
                .gpu
                .0
                .raw
                .reset_command_pool(self.slot.pool, vk::CommandPoolResetFlags::empty());
        }
        let mut st = self.gpu.stream(self.stream).state.lock().unwrap();
        st.free_slots.push(self.slot);
        st.free_query_pools.append(&mut self.queries.pools);
    }
}
