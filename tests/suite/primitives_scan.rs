//! Prefix scan against its CPU twin: awkward sizes, adversarial inputs, in place,
//! inclusive and exclusive, and the indirect variant with n set on the GPU.

use crate::common;

use splitray::primitives::{cpu, scan::SMALL_SCAN_MAX, Scan, ScanKind, Tuning};
use splitray::vk::{Gpu, MemoryKind, StreamKind};

const SIZES: [usize; 9] = [0, 1, 2, 255, 256, 257, 1000, 65_537, 1_000_003];
const SENTINEL: u32 = 0xDEAD_BEEF;

fn run_scan(gpu: &Gpu, scan: &Scan, data: &[u32], kind: ScanKind, in_place: bool) -> Vec<u32> {
    let n = data.len();
    let input = gpu.upload("in", data).unwrap();
    let output = gpu.upload("out", &vec![SENTINEL; n + 3]).unwrap();
    let scratch = gpu
        .create_buffer("scratch", scan.scratch_bytes(n as u32), MemoryKind::Device)
        .unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    let out = if in_place { &input } else { &output };
    scan.record(
        &mut rec,
        n as u32,
        (&input).into(),
        out.into(),
        kind,
        &scratch,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let result = out.read::<u32>().unwrap();
    if !in_place {
        assert_eq!(&result[n..], &[SENTINEL; 3], "wrote past n = {n}");
    }
    result[..n].to_vec()
}

fn expected(data: &[u32], kind: ScanKind) -> Vec<u32> {
    match kind {
        ScanKind::Exclusive => cpu::exclusive_scan(data),
        ScanKind::Inclusive => cpu::inclusive_scan(data),
    }
}

#[test]
fn scan_matches_cpu_at_awkward_sizes() {
    let gpu = common::gpu();
    let tuning = Tuning::for_device(gpu.info());
    println!("variant: {}", tuning.describe());
    let scan = Scan::new(&gpu, &tuning).unwrap();
    // Both sides of the one-workgroup scan's limit, then the three-pass scan.
    let limit = SMALL_SCAN_MAX as usize;
    for n in SIZES.into_iter().chain([limit, limit + 1, 1 << 22]) {
        let data = common::random_u32s(n, n as u64);
        for kind in [ScanKind::Exclusive, ScanKind::Inclusive] {
            assert_eq!(
                run_scan(&gpu, &scan, &data, kind, false),
                expected(&data, kind),
                "n = {n}, {kind:?}"
            );
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn scan_adversarial_inputs_and_in_place() {
    let gpu = common::gpu();
    let scan = Scan::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    for n in [257usize, 65_537, 1_000_003] {
        let patterns: [(&str, Vec<u32>); 4] = [
            ("zeros", vec![0; n]),
            ("ones", vec![1; n]),
            ("max", vec![u32::MAX; n]),
            ("ramp", (0..n as u32).collect()),
        ];
        for (name, data) in patterns {
            let kind = ScanKind::Exclusive;
            assert_eq!(
                run_scan(&gpu, &scan, &data, kind, false),
                expected(&data, kind),
                "{name} n = {n}"
            );
            let kind = ScanKind::Inclusive;
            assert_eq!(
                run_scan(&gpu, &scan, &data, kind, true),
                expected(&data, kind),
                "{name} in place n = {n}"
            );
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn scan_shapes_other_than_the_device_default() {
    // Small and large tiles: one workgroup, many, and tile sums longer than a workgroup.
    let gpu = common::gpu();
    let sg = gpu.info().limits.subgroup_size;
    // (workgroup, items per invocation, subgroup rows, segment-scan items per
    // invocation, 64-bit accesses where the device has them)
    for (w, k, rows, seg, wide) in [
        (1, 1, false, 0, false),
        (4, 3, false, 0, false),
        (32, 8, false, 0, false),
        (64, 64, false, 0, false),
        (sg, 5, true, 0, false),
        (sg, 8, true, 0, false),
        (sg, 256, true, 0, false),
        (sg, 64, false, 0, false),
        (1, 1, false, 4, false),
        (3, 1, false, 8, false),
        (3, 1, false, 8, true),
        (sg, 256, true, 4096, false),
        (sg, 256, true, 4096, true),
        (64, 1, false, 12, true),
        (5, 1, false, 24, true),
        (sg, 256, true, 6, false),
    ] {
        let tuning = Tuning {
            workgroup_size: w,
            items_per_invocation: k,
            subgroup_rows: rows,
            scan_segment: seg,
            wide_accesses: wide,
            ..Tuning::for_device(gpu.info())
        };
        let scan = Scan::new(&gpu, &tuning).unwrap();
        for n in [0usize, 1, 1000, 65_537] {
            let data = common::random_u32s(n, 9);
            // Exclusive out of place, inclusive in place.
            for (kind, in_place) in [(ScanKind::Exclusive, false), (ScanKind::Inclusive, true)] {
                assert_eq!(
                    run_scan(&gpu, &scan, &data, kind, in_place),
                    expected(&data, kind),
                    "w {w} k {k} rows {rows} segment {seg} wide {wide} n {n} {kind:?}"
                );
            }
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn scan_indirect_reads_n_written_on_the_gpu() {
    let gpu = common::gpu();
    let scan = Scan::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    let max_n = 70_000u32;
    let scratch = gpu
        .create_buffer("scratch", scan.scratch_bytes(max_n), MemoryKind::Device)
        .unwrap();
    let data = common::random_u32s(max_n as usize, 5);
    let input = gpu.upload("in", &data).unwrap();
    for n in [0u32, 1, 257, 65_537, max_n, max_n + 50] {
        // n travels through a GPU copy into word 3 of the count buffer.
        let staging = gpu.upload("n", &[n]).unwrap();
        let count = gpu.upload("count", &[7u32; 4]).unwrap();
        let output = gpu
            .upload("out", &vec![SENTINEL; max_n as usize + 8])
            .unwrap();
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.copy(&staging, 0, &count, 12, 4);
        rec.barrier();
        scan.record_indirect(
            &mut rec,
            &count,
            12,
            max_n,
            (&input).into(),
            (&output).into(),
            ScanKind::Inclusive,
            &scratch,
        )
        .unwrap();
        gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
        let m = n.min(max_n) as usize;
        let out = output.read::<u32>().unwrap();
        assert_eq!(&out[..m], &cpu::inclusive_scan(&data[..m])[..], "n = {n}");
        assert!(
            out[m..].iter().all(|&x| x == SENTINEL),
            "wrote past n = {n}"
        );
    }
    common::assert_clean(&gpu);
}
