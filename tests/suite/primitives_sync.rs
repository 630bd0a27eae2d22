//! Every primitive once under synchronization validation: a missing barrier between
//! dependent passes would be reported as a hazard.

use crate::common;

use splitray::primitives::compact::Kept;
use splitray::primitives::gather::Direction;
use splitray::primitives::reduce_by_key::{Reduction, RunOutputs};
use splitray::primitives::{cpu, Compact, Gather, RadixSort, ReduceByKey, Scan, ScanKind, Tuning};
use splitray::vk::{Gpu, MemoryKind, StreamKind, StreamPlacement};

#[test]
fn primitives_are_hazard_free_under_synchronization_validation() {
    let gpu = common::gpu_with(StreamPlacement::Spread, true);
    let tuning = Tuning::for_device(gpu.info());
    println!("variant: {}", tuning.describe());
    chain(&gpu, &tuning, 5000);
    common::assert_clean(&gpu);
}

/// The variant meant for discrete GPUs, run here too so that it is at least correct
/// (and hazard-free) wherever the tests run.
#[test]
fn gpu_variant_is_correct_and_hazard_free() {
    let gpu = common::gpu_with(StreamPlacement::Spread, true);
    let tuning = Tuning::gpu(gpu.info().limits.subgroup_size).fit(gpu.info());
    println!("variant: {}", tuning.describe());
    for n in [1, 5000, 70_001] {
        chain(&gpu, &tuning, n);
    }
    common::assert_clean(&gpu);
}

fn chain(gpu: &Gpu, tuning: &Tuning, n: usize) {
    let tuning = *tuning;
    let keys = common::random_u32s(n, 1);
    let values: Vec<u32> = (0..n as u32).collect();
    let kb = gpu.upload("keys", &keys).unwrap();
    let vb = gpu.upload("values", &values).unwrap();
    let count = gpu.upload("count", &[n as u32]).unwrap();
    let dev = |name: &str, bytes: u64| gpu.create_buffer(name, bytes, MemoryKind::Device).unwrap();

    let sort = RadixSort::new(gpu, &tuning).unwrap();
    let scan = Scan::new(gpu, &tuning).unwrap();
    let rbk = ReduceByKey::new(gpu, &tuning).unwrap();
    let compact = Compact::new(gpu, &tuning).unwrap();
    let gather = Gather::new(gpu, &tuning).unwrap();
    let sort_scratch = sort.alloc_scratch(gpu, n as u32).unwrap();
    let scan_out = dev("scan-out", n as u64 * 4);
    let scan_scratch = dev("scan-scratch", scan.scratch_bytes(n as u32));
    let (ok, oa, ob, oc) = (
        dev("ok", n as u64 * 4),
        dev("oa", n as u64 * 4),
        dev("ob", n as u64 * 4),
        dev("oc", 4),
    );
    let rbk_scratch = dev("rbk-scratch", rbk.scratch_bytes(n as u32));
    let flags = dev("flags", n as u64 * 4);
    let kept = dev("kept", n as u64 * 4);
    let kept_count = dev("kept-count", 4);
    let compact_scratch = dev("compact-scratch", compact.scratch_bytes(n as u32));
    let gathered = dev("gathered", n as u64 * 4);
    let gather_scratch = dev("gather-scratch", gather.scratch_bytes(n as u32));

    // One command buffer chaining everything: sort (top 3 bits only, so runs form), scan
    // of the sorted values, run-length encoding of the sorted keys, compaction of the
    // run counts, gather by the sorted values (a permutation) — each consuming the
    // previous one's output, with only the barriers the primitives place themselves.
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    sort.record_indirect(
        &mut rec,
        &count,
        0,
        n as u32,
        (&kb).into(),
        Some((&vb).into()),
        29..32,
        &sort_scratch,
    )
    .unwrap();
    scan.record(
        &mut rec,
        n as u32,
        (&vb).into(),
        (&scan_out).into(),
        ScanKind::Exclusive,
        &scan_scratch,
    )
    .unwrap();
    let out = RunOutputs {
        keys: (&ok).into(),
        a: (&oa).into(),
        b: Some((&ob).into()),
        count: (&oc).into(),
    };
    rbk.record(
        &mut rec,
        n as u32,
        (&kb).into(),
        Reduction::Count,
        out,
        &rbk_scratch,
    )
    .unwrap();
    let m = n.min(8);
    rec.copy(&oa, 0, &flags, 0, m as u64 * 4);
    rec.barrier();
    compact
        .record(
            &mut rec,
            m as u32,
            (&flags).into(),
            Kept::Indices,
            (&kept).into(),
            (&kept_count).into(),
            &compact_scratch,
        )
        .unwrap();
    gather
        .record(
            &mut rec,
            n as u32,
            Direction::Gather,
            (&kb).into(),
            (&vb).into(),
            (&gathered).into(),
            &gather_scratch,
        )
        .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();

    let (ck, cv) = cpu::sort_pairs(&keys, &values, 29..32);
    assert_eq!(kb.read::<u32>().unwrap(), ck);
    assert_eq!(vb.read::<u32>().unwrap(), cv);
    assert_eq!(scan_out.read::<u32>().unwrap(), cpu::exclusive_scan(&cv));
    let (rk, rc) = cpu::run_length_encode(&ck);
    let runs = oc.read::<u32>().unwrap()[0] as usize;
    assert_eq!(&ok.read::<u32>().unwrap()[..runs], &rk[..]);
    assert_eq!(&oa.read::<u32>().unwrap()[..runs], &rc[..]);
    let counts8: Vec<u32> = oa.read::<u32>().unwrap()[..m].to_vec();
    let expect = cpu::compact_indices(&counts8);
    assert_eq!(kept_count.read::<u32>().unwrap()[0] as usize, expect.len());
    assert_eq!(&kept.read::<u32>().unwrap()[..expect.len()], &expect[..]);
    assert_eq!(gathered.read::<u32>().unwrap(), cpu::gather(&ck, &cv));
}
