//! Stream compaction, gather and scatter against their CPU twins.

use crate::common;

use splitray::primitives::compact::Kept;
use splitray::primitives::gather::Direction;
use splitray::primitives::{cpu, Compact, Gather, Tuning};
use splitray::vk::{Gpu, MemoryKind, StreamKind};

const SENTINEL: u32 = 0xDEAD_BEEF;

fn flag_patterns(n: usize) -> Vec<(&'static str, Vec<u32>)> {
    let r = common::random_u32s(n, n as u64 + 1);
    vec![
        ("random", r.iter().map(|x| x & 1).collect()),
        (
            "random values as flags",
            r.iter().map(|x| x & 0x8000_0003).collect(),
        ),
        ("none", vec![0; n]),
        ("all", vec![1; n]),
        ("sparse", r.iter().map(|x| (x % 1000 == 0) as u32).collect()),
    ]
}

/// Compacts on the GPU (directly or with n set on the GPU) and checks both outputs.
fn check_compact(
    gpu: &Gpu,
    compact: &Compact,
    flags: &[u32],
    what: &str,
    indirect_cap: Option<u32>,
) {
    let n = flags.len();
    let values = common::random_u32s(n, 5);
    let fb = gpu.upload("flags", flags).unwrap();
    let vb = gpu.upload("values", &values).unwrap();
    let cap = indirect_cap.unwrap_or(n as u32);
    let scratch = gpu
        .create_buffer("scratch", compact.scratch_bytes(cap), MemoryKind::Device)
        .unwrap();
    for indices in [false, true] {
        let out = gpu.upload("out", &vec![SENTINEL; n + 4]).unwrap();
        let count = gpu.upload("count", &[SENTINEL; 2]).unwrap();
        let kept = if indices {
            Kept::Indices
        } else {
            Kept::Values((&vb).into())
        };
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        match indirect_cap {
            None => {
                compact
                    .record(
                        &mut rec,
                        n as u32,
                        (&fb).into(),
                        kept,
                        (&out).into(),
                        count.slice(0, 4),
                        &scratch,
                    )
                    .unwrap();
                gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
            }
            Some(cap) => {
                let staging = gpu.upload("n", &[n as u32]).unwrap();
                let nb = gpu.upload("n-on-gpu", &[0u32; 2]).unwrap();
                rec.copy(&staging, 0, &nb, 4, 4);
                rec.barrier();
                compact
                    .record_indirect(
                        &mut rec,
                        &nb,
                        4,
                        cap,
                        (&fb).into(),
                        kept,
                        (&out).into(),
                        count.slice(0, 4),
                        &scratch,
                    )
                    .unwrap();
                gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
            }
        }
        let expect = if indices {
            cpu::compact_indices(flags)
        } else {
            cpu::compact(flags, &values)
        };
        let c = count.read::<u32>().unwrap();
        assert_eq!(c[0] as usize, expect.len(), "{what}: count");
        assert_eq!(c[1], SENTINEL);
        let o = out.read::<u32>().unwrap();
        assert!(
            o[..expect.len()] == expect[..],
            "{what}: kept items (indices {indices})"
        );
        assert!(
            o[expect.len()..].iter().all(|&x| x == SENTINEL),
            "{what}: wrote past the count"
        );
    }
}

#[test]
fn compact_matches_cpu_at_awkward_sizes() {
    let gpu = common::gpu();
    let compact = Compact::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    for n in common::ISSUE_SIZES {
        let flags: Vec<u32> = common::random_u32s(n, n as u64)
            .iter()
            .map(|x| x & 1)
            .collect();
        check_compact(&gpu, &compact, &flags, &format!("n = {n}"), None);
    }
    common::assert_clean(&gpu);
}

#[test]
fn compact_adversarial_flags_and_indirect() {
    let gpu = common::gpu();
    let compact = Compact::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    for n in [257usize, 1_000_003] {
        for (name, flags) in flag_patterns(n) {
            check_compact(&gpu, &compact, &flags, &format!("{name} n = {n}"), None);
        }
    }
    for n in [0usize, 1, 257, 65_537] {
        let flags: Vec<u32> = common::random_u32s(n, 3).iter().map(|x| x & 1).collect();
        check_compact(
            &gpu,
            &compact,
            &flags,
            &format!("indirect n = {n}"),
            Some(70_000),
        );
    }
    common::assert_clean(&gpu);
}

/// Both paths on every device: the general one (a full position scan) and the segment
/// variant, here with segments of a few items so that many of them meet each pattern.
#[test]
fn compact_general_path_and_short_segments() {
    let gpu = common::gpu();
    for (segment, tuning) in common::segment_tunings(&gpu) {
        let compact = Compact::new(&gpu, &tuning).unwrap();
        for n in [0usize, 1, 5, 257, 65_537] {
            for (name, flags) in flag_patterns(n) {
                let what = format!("segment {segment}: {name} n = {n}");
                check_compact(&gpu, &compact, &flags, &what, None);
            }
            let flags: Vec<u32> = common::random_u32s(n, 3).iter().map(|x| x & 1).collect();
            let what = format!("segment {segment}: indirect n = {n}");
            check_compact(&gpu, &compact, &flags, &what, Some(70_000));
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn gather_and_scatter_match_cpu() {
    let gpu = common::gpu();
    let base = Tuning::for_device(gpu.info());
    // The device's kernel and the other one: subgroup rows, or segments with 64-bit
    // accesses (where the device has them).
    let other = if base.wide_accesses && base.scan_segment > 0 {
        Tuning {
            wide_accesses: false,
            ..base
        }
    } else {
        Tuning {
            wide_accesses: true,
            scan_segment: 4112,
            ..base
        }
        .fit(gpu.info())
    };
    for tuning in [base, other] {
        let gather = Gather::new(&gpu, &tuning).unwrap();
        let scratch = gpu
            .create_buffer("scratch", gather.scratch_bytes(0), MemoryKind::Device)
            .unwrap();
        for n in common::ISSUE_SIZES.into_iter().chain([7]) {
            let what = format!("{} n = {n}", tuning.describe());
            let src = common::random_u32s(n, 1);
            // A permutation; for gather a few indices past the source, for scatter a
            // few past the output (n + 4 words), which both must skip: just past the
            // end, and near the top of u32 (u32::MAX, 0xFFFF_FFF0), where a bounds
            // test on index + 1, index + 16 or on byte offsets would wrap around.
            let r = common::random_u32s(n, 2);
            let mut perm: Vec<u32> = (0..n as u32).collect();
            for i in (1..n).rev() {
                perm.swap(i, r[i] as usize % (i + 1));
            }
            let mut wild_gather = perm.clone();
            let mut wild_scatter = perm.clone();
            for (k, i) in (0..n).step_by(97).enumerate() {
                let (gather_past, scatter_past) = match k % 4 {
                    0 | 1 => (n as u32 + (i as u32 % 3), n as u32 + 4 + (i as u32 % 3)),
                    2 => (u32::MAX, u32::MAX),
                    _ => (0xFFFF_FFF0, 0xFFFF_FFF0),
                };
                wild_gather[i] = gather_past;
                wild_scatter[i] = scatter_past;
            }
            let sb = gpu.upload("src", &src).unwrap();
            for (dir, idx) in [
                (Direction::Gather, &wild_gather),
                (Direction::Scatter, &perm),
                (Direction::Scatter, &wild_scatter),
            ] {
                let ib = gpu.upload("idx", idx).unwrap();
                let out = gpu.upload("out", &vec![SENTINEL; n + 4]).unwrap();
                let mut rec = gpu.recorder(StreamKind::Main).unwrap();
                gather
                    .record(
                        &mut rec,
                        n as u32,
                        dir,
                        (&sb).into(),
                        (&ib).into(),
                        (&out).into(),
                        &scratch,
                    )
                    .unwrap();
                gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
                let mut expect = vec![SENTINEL; n + 4];
                match dir {
                    Direction::Gather => {
                        expect[..n].copy_from_slice(&cpu::gather(&src, idx));
                    }
                    Direction::Scatter => cpu::scatter(&src, idx, &mut expect),
                }
                let o = out.read::<u32>().unwrap();
                assert!(o == expect, "{dir:?} {what}");
            }
        }
    }
    let gather = Gather::new(&gpu, &base).unwrap();
    let scratch = gpu
        .create_buffer("scratch", gather.scratch_bytes(0), MemoryKind::Device)
        .unwrap();
    // Indirect: n from the GPU, larger buffers.
    let n = 1000u32;
    let src = common::random_u32s(2000, 4);
    let idx: Vec<u32> = (0..2000u32).rev().collect();
    let sb = gpu.upload("src", &src).unwrap();
    let ib = gpu.upload("idx", &idx).unwrap();
    let out = gpu.upload("out", &vec![SENTINEL; 2000]).unwrap();
    let count = gpu.upload("count", &[n]).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    gather
        .record_indirect(
            &mut rec,
            &count,
            0,
            2000,
            Direction::Gather,
            (&sb).into(),
            (&ib).into(),
            (&out).into(),
            &scratch,
        )
        .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let o = out.read::<u32>().unwrap();
    assert_eq!(&o[..1000], &cpu::gather(&src, &idx[..1000])[..]);
    assert!(o[1000..].iter().all(|&x| x == SENTINEL));
    common::assert_clean(&gpu);
}
