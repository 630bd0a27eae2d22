//! The Vulkan runtime: validation canary, buffer round trips, dispatch grids, streams
//! ordered by timeline semaphores, profiler.

use crate::common;

use splitray::shaders;
use splitray::vk::{
    Buffer, BufferAccess, ComputePipeline, Gpu, MemoryKind, PipelineDesc, StreamKind,
    StreamPlacement,
};

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct CopyPush {
    n: u32,
    add: u32,
}

fn copy_pipeline(gpu: &Gpu, workgroup: u32) -> ComputePipeline {
    ComputePipeline::new(
        gpu,
        &PipelineDesc {
            kernel: shaders::TEST_COPY_WORDS,
            bindings: 2,
            push_constant_bytes: 8,
            spec: &[workgroup],
        },
    )
    .unwrap()
}

#[test]
fn validation_canary_is_caught_and_reported() {
    let gpu = common::gpu();
    assert!(gpu.validation_messages().is_empty());
    splitray::vk::provoke_validation_error(&gpu);
    let messages = gpu.validation_messages();
    assert!(
        messages
            .iter()
            .any(|m| m.id_name.contains("VUID-VkBufferCreateInfo-usage")),
        "the invalid call went unreported: {messages:?}"
    );
}

#[test]
fn upload_readback_round_trips_at_awkward_sizes() {
    let gpu = common::gpu();
    for n in [0usize, 1, 2, 3, 255, 256, 257, 1000, 65_537, 1_000_003] {
        let data = common::random_u32s(n, n as u64);
        let buffer = gpu.upload("round-trip", &data).unwrap();
        assert_eq!(buffer.read::<u32>().unwrap(), data, "n = {n}");
    }
    // Byte-granular sizes survive too (the Vulkan buffer is padded, the logical size not).
    let bytes: Vec<u8> = (0..13u8).collect();
    let b = gpu.upload("bytes", &bytes).unwrap();
    assert_eq!(b.size(), 13);
    assert_eq!(b.read::<u8>().unwrap(), bytes);
    common::assert_clean(&gpu);
}

#[test]
fn dispatch_covers_every_item_including_folded_2d_grids() {
    let gpu = common::gpu();
    let max_x = gpu.info().limits.max_compute_work_group_count[0] as usize;
    // With 1-wide workgroups, max_x + 5 items need a second row of workgroups. Where
    // that many words exceed one storage-buffer binding (maxComputeWorkGroupCount[0] is
    // 2^31 - 1 on NVIDIA), no u32-indexed launch can ever fold, so the case is moot.
    let fold = max_x + 5;
    let foldable = (fold as u64) * 4 <= gpu.info().limits.max_storage_buffer_range;
    if !foldable {
        println!("no folded grid: {fold} words exceed one storage-buffer binding");
    }
    let cases = [
        (64u32, 0usize),
        (64, 1),
        (64, 1000),
        (1, fold),
        (256, 1 << 20),
    ];
    for (workgroup, n) in cases.into_iter().filter(|&(_, n)| foldable || n != fold) {
        let pipeline = copy_pipeline(&gpu, workgroup);
        let src = common::random_u32s(n, 7);
        let a = gpu.upload("src", &src).unwrap();
        let b = gpu.zeroed::<u32>("dst", n).unwrap();
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        let push = CopyPush {
            n: n as u32,
            add: 3,
        };
        rec.dispatch_items(&pipeline, &[(&a).into(), (&b).into()], &push, n as u64)
            .unwrap();
        let done = rec.submit(&[]).unwrap();
        gpu.wait(&done).unwrap();
        let out = b.read::<u32>().unwrap();
        assert!(
            out.iter().zip(&src).all(|(o, s)| *o == s.wrapping_add(3)),
            "workgroup {workgroup}, n {n}"
        );
    }
    common::assert_clean(&gpu);
}

/// A chain main → aux0 → aux1 → transfer → main, each step on its own stream and
/// ordered only by timeline semaphores: the result is right only if every wait holds.
fn stream_chain(gpu: &Gpu) {
    let n = 300_001usize;
    let pipeline = copy_pipeline(gpu, 128);
    let src = common::random_u32s(n, 42);
    let a = gpu.upload("a", &src).unwrap();
    let b = gpu.zeroed::<u32>("b", n).unwrap();
    let c = gpu.zeroed::<u32>("c", n).unwrap();
    let d = gpu.zeroed::<u32>("d", n).unwrap();
    let push = CopyPush {
        n: n as u32,
        add: 1,
    };

    let mut rec = gpu.recorder(StreamKind::Aux0).unwrap();
    rec.dispatch_items(&pipeline, &[(&a).into(), (&b).into()], &push, n as u64)
        .unwrap();
    let p0 = rec.submit(&[]).unwrap();

    let mut rec = gpu.recorder(StreamKind::Aux1).unwrap();
    rec.dispatch_items(&pipeline, &[(&b).into(), (&c).into()], &push, n as u64)
        .unwrap();
    let p1 = rec.submit(&[&p0]).unwrap();

    let mut rec = gpu.recorder(StreamKind::Transfer).unwrap();
    rec.copy(&c, 0, &d, 0, (n * 4) as u64);
    let p2 = rec.submit(&[&p1]).unwrap();

    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch_items(&pipeline, &[(&d).into(), (&a).into()], &push, n as u64)
        .unwrap();
    let p3 = rec.submit(&[&p2]).unwrap();
    gpu.wait(&p3).unwrap();

    let out = a.read::<u32>().unwrap();
    assert!(out.iter().zip(&src).all(|(o, s)| *o == s.wrapping_add(3)));
    assert!(gpu.completed_value(StreamKind::Aux1).unwrap() >= p1.value);
}

#[test]
fn streams_forced_onto_one_queue_are_ordered_by_timelines_under_sync_validation() {
    let gpu = common::gpu_with(StreamPlacement::SingleQueue, true);
    assert!(gpu.stream_mapping().is_single_queue());
    stream_chain(&gpu);
    common::assert_clean(&gpu);
}

#[test]
fn streams_on_their_default_queues_are_ordered_by_timelines_under_sync_validation() {
    let gpu = common::gpu_with(StreamPlacement::Spread, true);
    stream_chain(&gpu);
    common::assert_clean(&gpu);
}

/// Recorders reuse finished command buffers: two hundred submissions, each waited for,
/// allocate one, and bursts of twenty in flight at once at most twenty. (Allocating a
/// buffer per submission from a reused pool left every earlier one allocated there, and
/// each pool reset walked them all: on NVIDIA long renders slowed down pass by pass.)
#[test]
fn finished_command_buffers_are_reused() {
    let gpu = common::gpu();
    let n = 1000usize;
    let pipeline = copy_pipeline(&gpu, 64);
    let a = gpu.upload("a", &vec![0u32; n]).unwrap();
    let b = gpu.zeroed::<u32>("b", n).unwrap();
    let push = CopyPush {
        n: n as u32,
        add: 1,
    };
    // a → b → a, adding 1 each time: 2 per submission.
    let submit = || {
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.dispatch_items(&pipeline, &[(&a).into(), (&b).into()], &push, n as u64)
            .unwrap();
        rec.barrier();
        rec.dispatch_items(&pipeline, &[(&b).into(), (&a).into()], &push, n as u64)
            .unwrap();
        rec.submit(&[]).unwrap()
    };
    let before = gpu.command_buffers_allocated();
    for _ in 0..200 {
        gpu.wait(&submit()).unwrap();
    }
    let serial = gpu.command_buffers_allocated() - before;
    assert!(
        serial <= 1,
        "200 submissions one at a time allocated {serial}"
    );
    for _ in 0..5 {
        let points: Vec<_> = (0..20).map(|_| submit()).collect();
        gpu.wait(points.last().unwrap()).unwrap();
    }
    let bursts = gpu.command_buffers_allocated() - before;
    assert!(bursts <= 20, "bursts of 20 in flight allocated {bursts}");
    let out = a.read::<u32>().unwrap();
    assert!(
        out.iter().all(|&v| v == 2 * 300),
        "the work ran: {}",
        out[0]
    );
    common::assert_clean(&gpu);
}

#[test]
fn profiler_times_named_dispatches_without_stalling() {
    let gpu = common::gpu();
    let pipeline = copy_pipeline(&gpu, 64);
    let n = 1 << 16;
    let a = gpu.upload("a", &vec![1u32; n]).unwrap();
    let b = gpu.zeroed::<u32>("b", n).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.begin_scope("outer").unwrap();
    for _ in 0..3 {
        rec.dispatch_items(
            &pipeline,
            &[(&a).into(), (&b).into()],
            &CopyPush {
                n: n as u32,
                add: 0,
            },
            n as u64,
        )
        .unwrap();
        rec.barrier();
    }
    rec.end_scope().unwrap();
    let point = rec.submit(&[]).unwrap();
    gpu.wait(&point).unwrap();
    let log = gpu.take_profile();
    let summary = log.summary();
    let copy = summary
        .iter()
        .find(|k| k.name == "test_copy_words")
        .unwrap();
    assert_eq!(copy.count, 3);
    let outer = summary.iter().find(|k| k.name == "outer").unwrap();
    assert!(outer.total_ms >= copy.total_ms * 0.99, "{}", log.table());
    assert!(log.records.iter().all(|r| r.end_ns >= r.start_ns));
    common::assert_clean(&gpu);
}

#[test]
fn peak_memory_is_tracked() {
    let gpu = common::gpu();
    let (before, _) = gpu.memory_bytes();
    {
        let _a = gpu.zeroed::<u32>("a", 1 << 20).unwrap();
        let (now, peak) = gpu.memory_bytes();
        assert!(now >= before + (4 << 20));
        assert!(peak >= now);
    }
    let (after, peak) = gpu.memory_bytes();
    assert_eq!(after, before);
    assert!(peak >= before + (4 << 20));
    common::assert_clean(&gpu);
}

#[test]
fn oversized_buffers_are_refused_with_the_limit_named() {
    let gpu = common::gpu();
    // One storage binding is no limit: a buffer past it is made (and bound by address).
    let binding = gpu.info().limits.max_storage_buffer_range;
    if common::holds_past_one_binding(&gpu, binding + 4, "a buffer past one binding") {
        let past_binding = gpu
            .create_buffer("past-binding", binding + 4, MemoryKind::Device)
            .unwrap();
        assert_eq!(past_binding.size(), binding + 4);
    }
    // One allocation is: the smaller of maxBufferSize and maxMemoryAllocationSize.
    let (limit, which) = gpu.max_buffer_bytes();
    let l = &gpu.info().limits;
    assert_eq!(limit, l.max_buffer_size.min(l.max_memory_allocation_size));
    let err = gpu
        .create_buffer("huge", limit + 1, MemoryKind::Device)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("'huge'") && err.contains(which) && err.contains(&limit.to_string()),
        "{err}"
    );
    assert!(
        gpu.check_buffer_size("film", limit).is_ok()
            && gpu.check_buffer_size("film", limit + 1).is_err()
    );
    common::assert_clean(&gpu);
}

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct RangePush {
    n: u32,
    add: u32,
    first: u32,
}

/// Runs test_copy_words_by_address over words `first..first + n` of `src` into `dst`.
fn copy_range(
    gpu: &Gpu,
    pipeline: &ComputePipeline,
    src: &Buffer,
    dst: &Buffer,
    first: u32,
    n: u32,
) {
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    let push = RangePush { n, add: 1, first };
    rec.dispatch_items(pipeline, &[src.into(), dst.into()], &push, n as u64)
        .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
}

#[test]
fn buffers_past_one_storage_binding_are_read_and_written_by_address() {
    // Both ways a device may take buffers: by address only, and (lavapipe's default)
    // as descriptors where they fit, by address where they do not.
    for access in [
        BufferAccess::Addresses,
        BufferAccess::DescriptorsWhereTheyFit,
    ] {
        let gpu = common::gpu_with_access(access);
        let pipeline = ComputePipeline::new(
            &gpu,
            &PipelineDesc {
                kernel: shaders::TEST_COPY_WORDS_BY_ADDRESS,
                bindings: 2,
                push_constant_bytes: 12,
                spec: &[64],
            },
        )
        .unwrap();
        // Small buffers: the descriptor twin where the device prefers it.
        let small: Vec<u32> = (0..1000).collect();
        let src = gpu.upload("small-src", &small).unwrap();
        let dst = gpu.zeroed::<u32>("small-dst", small.len()).unwrap();
        copy_range(&gpu, &pipeline, &src, &dst, 0, 1000);
        let got = dst.read::<u32>().unwrap();
        assert!(
            got.iter().zip(&small).all(|(g, s)| *g == s + 1),
            "{access:?}"
        );

        // Past one binding: the words around the binding's end and the buffer's last.
        let binding_words = (gpu.info().limits.max_storage_buffer_range / 4) as u32;
        let words = binding_words + 4096;
        if !common::holds_past_one_binding(&gpu, words as u64 * 4, "copies past one binding") {
            common::assert_clean(&gpu);
            continue;
        }
        let src = gpu
            .create_buffer("big-src", words as u64 * 4, MemoryKind::Device)
            .unwrap();
        let dst = gpu.zeroed::<u32>("big-dst", words as usize).unwrap();
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.fill(&src, 7);
        gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
        let first = binding_words - 2048;
        copy_range(&gpu, &pipeline, &src, &dst, first, 6144);
        let got = dst.read::<u32>().unwrap();
        let (before, rest) = got.split_at(first as usize);
        assert!(
            before.iter().all(|&w| w == 0),
            "{access:?}: wrote before the range"
        );
        assert!(rest.iter().all(|&w| w == 8), "{access:?}: past the binding");
        common::assert_clean(&gpu);
    }
}

#[test]
fn synchronization_validation_catches_a_missing_barrier() {
    // Proves the ordering tests above are meaningful: the same chain inside one command
    // buffer without a barrier is a read-after-write hazard that the layer reports.
    let gpu = common::gpu_with(StreamPlacement::SingleQueue, true);
    let pipeline = copy_pipeline(&gpu, 64);
    let n = 4096usize;
    let a = gpu.upload("a", &vec![1u32; n]).unwrap();
    let b = gpu.zeroed::<u32>("b", n).unwrap();
    let c = gpu.zeroed::<u32>("c", n).unwrap();
    let push = CopyPush {
        n: n as u32,
        add: 1,
    };
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch_items(&pipeline, &[(&a).into(), (&b).into()], &push, n as u64)
        .unwrap();
    rec.dispatch_items(&pipeline, &[(&b).into(), (&c).into()], &push, n as u64)
        .unwrap();
    let point = rec.submit(&[]).unwrap();
    gpu.wait(&point).unwrap();
    let messages = gpu.validation_messages();
    assert!(
        messages
            .iter()
            .any(|m| m.id_name.contains("SYNC-HAZARD-READ")),
        "missing barrier went unreported: {messages:?}"
    );
}

/// A test process's devices are opened one test at a time (tests/suite/common/turn.rs: the
/// validation layer cannot take a device opened or closed beside another thread's
/// calls): a thread's second device joins its turn, another thread's waits until both
/// are closed.
#[test]
fn test_devices_take_turns() {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::Duration;
    let first = common::gpu();
    // Opened in the turn `first` holds: waiting for it would never end.
    let second = common::gpu_with(StreamPlacement::SingleQueue, false);
    let other_opened = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let other = scope.spawn(|| {
            let gpu = common::gpu();
            other_opened.store(true, Ordering::SeqCst);
            common::assert_clean(&gpu);
        });
        // Opening a device takes lavapipe tens of milliseconds: were the turn not
        // waited for, the other thread would be done by now.
        let assert_still_waiting = |beside: &str| {
            std::thread::sleep(Duration::from_millis(300));
            let opened = other_opened.load(Ordering::SeqCst);
            assert!(!opened, "opened beside {beside}");
        };
        assert_still_waiting("two devices");
        common::assert_clean(&second);
        drop(second);
        assert_still_waiting("a device");
        common::assert_clean(&first);
        drop(first);
        other.join().expect("the other thread's device");
    });
    assert!(other_opened.load(Ordering::SeqCst));
}
