//! Radix sort against a stable CPU sort: awkward sizes, adversarial keys, bit ranges,
//! stability, keys only, other tunings, and the indirect variant.

use crate::common;

use splitray::primitives::{cpu, RadixSort, SortScratch, Tuning};
use splitray::vk::{Gpu, StreamKind};

const SENTINEL: u32 = 0xDEAD_BEEF;

fn patterns(n: usize) -> Vec<(&'static str, Vec<u32>)> {
    let r = common::random_u32s(n, n as u64 + 11);
    let mut sorted = r.clone();
    sorted.sort_unstable();
    let mut reverse = sorted.clone();
    reverse.reverse();
    vec![
        ("all equal", vec![0x1234_5678; n]),
        ("sorted", sorted),
        ("reverse", reverse),
        (
            "high bits only",
            r.iter().map(|k| k & 0xF000_0000).collect(),
        ),
        ("low bits only", r.iter().map(|k| k & 0x3).collect()),
        // The largest key in every digit (a histogram's last bucket takes everything),
        // and alternating with the smallest (two buckets, every item moving).
        ("all u32::MAX", vec![u32::MAX; n]),
        (
            "u32::MAX and 0 alternating",
            (0..n)
                .map(|i| if i % 2 == 0 { u32::MAX } else { 0 })
                .collect(),
        ),
        ("random", r),
    ]
}

/// Sorts (keys, index) pairs on the GPU; checks against the CPU twin, that values are
/// increasing within equal keys (stability), and that nothing past n was touched.
fn check_sort(
    gpu: &Gpu,
    sort: &RadixSort,
    scratch: &SortScratch,
    keys: &[u32],
    bits: std::ops::Range<u32>,
    what: &str,
) {
    let n = keys.len();
    let values: Vec<u32> = (0..n as u32).collect();
    let mut kpad = keys.to_vec();
    kpad.extend([SENTINEL; 5]);
    let mut vpad = values.clone();
    vpad.extend([SENTINEL; 5]);
    let kb = gpu.upload("keys", &kpad).unwrap();
    let vb = gpu.upload("values", &vpad).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    sort.record(
        &mut rec,
        n as u32,
        (&kb).into(),
        Some((&vb).into()),
        bits.clone(),
        scratch,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let gk = kb.read::<u32>().unwrap();
    let gv = vb.read::<u32>().unwrap();
    assert_eq!(&gk[n..], &[SENTINEL; 5], "{what}: keys past n");
    assert_eq!(&gv[n..], &[SENTINEL; 5], "{what}: values past n");
    let (ck, cv) = cpu::sort_pairs(keys, &values, bits.clone());
    assert!(gk[..n] == ck[..], "{what}: keys differ from the CPU twin");
    for i in 1..n {
        let (a, b) = (cpu::key_bits(gk[i - 1], &bits), cpu::key_bits(gk[i], &bits));
        assert!(
            a < b || (a == b && gv[i - 1] < gv[i]),
            "{what}: unstable or unsorted at {i}"
        );
    }
    assert!(gv[..n] == cv[..], "{what}: values differ from the CPU twin");
}

#[test]
fn sort_matches_cpu_at_awkward_sizes() {
    let gpu = common::gpu();
    let tuning = Tuning::for_device(gpu.info());
    println!("variant: {}", tuning.describe());
    let sort = RadixSort::new(&gpu, &tuning).unwrap();
    let scratch = sort.alloc_scratch(&gpu, 1 << 22).unwrap();
    for n in common::ISSUE_SIZES {
        let keys = common::random_u32s(n, n as u64);
        check_sort(
            &gpu,
            &sort,
            &scratch,
            &keys,
            0..32,
            &format!("random n = {n}"),
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn sort_adversarial_keys() {
    let gpu = common::gpu();
    let sort = RadixSort::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    let scratch = sort.alloc_scratch(&gpu, 1_000_003).unwrap();
    for n in [2usize, 257, 65_537, 1_000_003] {
        for (name, keys) in patterns(n) {
            check_sort(
                &gpu,
                &sort,
                &scratch,
                &keys,
                0..32,
                &format!("{name} n = {n}"),
            );
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn sort_bit_ranges() {
    // PDACRT-style keys: node index in the high bits, a 2-bit code in the low bits; only
    // the significant bits are sorted. Odd pass counts exercise the copy home; an empty
    // range is a no-op.
    let gpu = common::gpu();
    let sort = RadixSort::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    let scratch = sort.alloc_scratch(&gpu, 100_000).unwrap();
    check_bit_ranges(&gpu, &sort, &scratch);
    let r = common::random_u32s(1000, 3);
    check_sort(&gpu, &sort, &scratch, &r, 5..5, "empty range");
    common::assert_clean(&gpu);
}

/// PDACRT-style keys (a node index above a 2-bit code) sorted by their 14 significant
/// bits, and partial ranges of random keys: 3 passes (an odd count on 8- and 11-bit
/// digits), a range in the middle, and one bit.
fn check_bit_ranges(gpu: &Gpu, sort: &RadixSort, scratch: &SortScratch) {
    let r = common::random_u32s(100_000, 3);
    let pdacrt: Vec<u32> = r.iter().map(|k| ((k >> 20) << 2) | (k & 3)).collect();
    let what = |range: &str| format!("{} {range}", sort.tuning().describe());
    check_sort(
        gpu,
        sort,
        scratch,
        &pdacrt,
        0..14,
        &what("node|code keys, bits 0..14"),
    );
    check_sort(gpu, sort, scratch, &r, 0..24, &what("random, bits 0..24"));
    check_sort(gpu, sort, scratch, &r, 8..20, &what("random, bits 8..20"));
    check_sort(gpu, sort, scratch, &r, 31..32, &what("random, top bit"));
}

/// Sorts keys without values.
fn check_keys_alone(gpu: &Gpu, sort: &RadixSort) {
    let scratch = sort.alloc_scratch(gpu, 65_537).unwrap();
    let keys = common::random_u32s(65_537, 8);
    let kb = gpu.upload("keys", &keys).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    sort.record(&mut rec, 65_537, (&kb).into(), None, 0..32, &scratch)
        .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let mut expect = keys.clone();
    expect.sort_unstable();
    let what = sort.tuning().describe();
    assert_eq!(kb.read::<u32>().unwrap(), expect, "{what}: keys alone");
}

#[test]
fn sort_keys_only_and_other_tunings() {
    let gpu = common::gpu();
    let base = Tuning::for_device(gpu.info());
    let sg = gpu.info().limits.subgroup_size;
    // (workgroup, keys per invocation, digit bits, subgroup rows, barrier-free segments,
    // interleaved pairs, 64-bit accesses where the device has them: segments of a
    // multiple of 8 keys)
    for (w, k, bits, rows, segments, pairs, wide) in [
        (1, 1, 8, false, false, false, false),
        (8, 3, 4, false, false, false, false),
        (32, 16, 6, false, false, false, false),
        (64, 8, 5, false, false, false, false),
        (sg, 7, 8, true, false, false, false),
        (sg, 256, 8, false, false, false, false),
        (sg, 256, 8, false, true, false, false),
        (sg, 256, 8, false, true, false, true),
        (sg, 256, 8, false, true, true, false),
        (sg, 256, 8, false, true, true, true),
        (4, 12, 6, false, true, true, true),
        (4, 64, 11, false, true, true, false),
        (4, 64, 11, false, true, true, true),
        (sg, 7, 8, false, true, true, true),
        (1, 4, 3, false, true, false, false),
        (2, 8, 10, false, true, true, true),
        (3, 24, 9, false, true, false, true),
    ] {
        let tuning = Tuning {
            sort_workgroup_size: w,
            sort_keys_per_invocation: k,
            radix_bits: bits,
            sort_rows: rows,
            sort_segments: segments,
            sort_pairs: pairs,
            wide_accesses: wide,
            ..base
        }
        .fit(gpu.info());
        let sort = RadixSort::new(&gpu, &tuning).unwrap();
        let scratch = sort.alloc_scratch(&gpu, 70_000).unwrap();
        for n in [0usize, 1, 1000, 65_537] {
            let keys = common::random_u32s(n, 4);
            check_sort(
                &gpu,
                &sort,
                &scratch,
                &keys,
                0..32,
                &format!("{} n = {n}", tuning.describe()),
            );
        }
    }
    // Keys alone.
    check_keys_alone(&gpu, &RadixSort::new(&gpu, &base).unwrap());
    common::assert_clean(&gpu);
}

/// The multisplit tile sort (the GPU variant) in shapes that fit any device offering it,
/// lavapipe included: every awkward size and adversarial pattern, bit ranges, keys alone
/// and the indirect count. Tiles of 64 × 5 keys make small inputs cross many tiles and
/// leave partial subgroups of keys in the last tile; 192 invocations are not a power of
/// two; 7-bit digits take 5 passes for 32-bit keys (an odd count: the copy home).
#[test]
fn sort_multisplit_tiles() {
    let gpu = common::gpu();
    let info = gpu.info();
    let max_sg = info.limits.max_subgroup_size;
    // (workgroup, keys per invocation, digit bits)
    let shapes: Vec<(u32, u32, u32)> = [(64u32, 5u32, 8u32), (128, 12, 8), (192, 3, 8), (64, 8, 7)]
        .into_iter()
        .map(|(w, k, bits)| (w.next_multiple_of(max_sg), k, bits))
        .collect();
    if !splitray::primitives::tuning::multisplit_supported(info, shapes[0].0) {
        println!(
            "skipped: '{}' lacks subgroup ballot/shuffle/arithmetic or full subgroups",
            info.name
        );
        return;
    }
    let base = Tuning::gpu(info.limits.subgroup_size);
    for (i, &(w, k, bits)) in shapes.iter().enumerate() {
        let tuning = Tuning {
            sort_workgroup_size: w,
            sort_keys_per_invocation: k,
            radix_bits: bits,
            ..base
        }
        .fit(info);
        assert!(tuning.sort_multisplit, "{}", tuning.describe());
        println!("variant: {}", tuning.describe());
        let sort = RadixSort::new(&gpu, &tuning).unwrap();
        let scratch = sort.alloc_scratch(&gpu, 1 << 22).unwrap();
        // The first shape takes the whole suite; the others the sizes around their tile.
        let sizes: &[usize] = if i == 0 {
            &[0, 1, 2, 255, 256, 257, 1000, 65_537, 1_000_003, 1 << 22]
        } else {
            &[1, 1000, 65_537]
        };
        for &n in sizes {
            let keys = common::random_u32s(n, n as u64 + 5);
            let what = format!("{} random n = {n}", tuning.describe());
            check_sort(&gpu, &sort, &scratch, &keys, 0..32, &what);
        }
        if i > 0 {
            continue;
        }
        for n in [257usize, 65_537, 1_000_003] {
            for (name, keys) in patterns(n) {
                let what = format!("{} {name} n = {n}", tuning.describe());
                check_sort(&gpu, &sort, &scratch, &keys, 0..32, &what);
            }
        }
        check_bit_ranges(&gpu, &sort, &scratch);
        check_keys_alone(&gpu, &sort);
        check_indirect(&gpu, &sort, 70_000);
    }
    common::assert_clean(&gpu);
}

#[test]
fn sort_indirect_reads_n_written_on_the_gpu() {
    let gpu = common::gpu();
    let sort = RadixSort::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    check_indirect(&gpu, &sort, 70_000);
    common::assert_clean(&gpu);
}

/// Sorts with n written on the GPU, for n around `max_n` and past it (clamped).
fn check_indirect(gpu: &Gpu, sort: &RadixSort, max_n: u32) {
    let scratch = sort.alloc_scratch(gpu, max_n).unwrap();
    let keys = common::random_u32s(max_n as usize, 21);
    let values: Vec<u32> = (0..max_n).collect();
    for n in [0u32, 1, 257, 65_537, max_n, max_n + 9] {
        let staging = gpu.upload("n", &[n]).unwrap();
        let count = gpu.upload("count", &[0u32; 2]).unwrap();
        let kb = gpu.upload("keys", &keys).unwrap();
        let vb = gpu.upload("values", &values).unwrap();
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.copy(&staging, 0, &count, 4, 4);
        rec.barrier();
        sort.record_indirect(
            &mut rec,
            &count,
            4,
            max_n,
            (&kb).into(),
            Some((&vb).into()),
            0..32,
            &scratch,
        )
        .unwrap();
        gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
        let m = n.min(max_n) as usize;
        let (ck, cv) = cpu::sort_pairs(&keys[..m], &values[..m], 0..32);
        let gk = kb.read::<u32>().unwrap();
        let gv = vb.read::<u32>().unwrap();
        assert!(gk[..m] == ck[..] && gv[..m] == cv[..], "n = {n}");
        assert!(
            gk[m..] == keys[m..] && gv[m..] == values[m..],
            "touched past n = {n}"
        );
    }
}
