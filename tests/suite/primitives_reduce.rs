//! Reduce-by-key (sum, arg-min) and run-length encoding against their CPU twins.

use crate::common;

use splitray::primitives::reduce_by_key::{Reduction, RunOutputs};
use splitray::primitives::{cpu, ReduceByKey, Tuning};
use splitray::vk::{Buffer, Gpu, MemoryKind, StreamKind};

const SENTINEL: u32 = 0xDEAD_BEEF;

/// Sorted keys with runs whose lengths come from `run_len`.
fn runs(n: usize, seed: u64, max_run: u32) -> Vec<u32> {
    let r = common::random_u32s(n, seed);
    let mut keys = Vec::with_capacity(n);
    let mut k = 5u32;
    while keys.len() < n {
        let len = (r[keys.len()] % max_run + 1) as usize;
        keys.extend(std::iter::repeat_n(k, len.min(n - keys.len())));
        k += 1 + r[keys.len() - 1] % 3;
    }
    keys
}

fn key_patterns(n: usize) -> Vec<(&'static str, Vec<u32>)> {
    vec![
        ("short runs", runs(n, n as u64, 4)),
        ("long runs", runs(n, n as u64 + 1, 3000)),
        ("all equal", vec![9; n]),
        ("all distinct", (0..n as u32).collect()),
    ]
}

struct Outs {
    keys: Buffer,
    a: Buffer,
    b: Buffer,
    count: Buffer,
}

fn outs(gpu: &Gpu, n: usize) -> Outs {
    let pad = vec![SENTINEL; n + 4];
    Outs {
        keys: gpu.upload("out-keys", &pad).unwrap(),
        a: gpu.upload("out-a", &pad).unwrap(),
        b: gpu.upload("out-b", &pad).unwrap(),
        count: gpu.upload("out-count", &[SENTINEL; 2]).unwrap(),
    }
}

fn check_all(gpu: &Gpu, rbk: &ReduceByKey, keys: &[u32], what: &str, indirect: Option<u32>) {
    let n = keys.len();
    let values = common::random_u32s(n, 77);
    let t: Vec<f32> = values
        .iter()
        .map(|&v| ((v >> 4) % 64) as f32 * 0.25 - 4.0)
        .collect();
    let ids: Vec<u32> = values.iter().map(|&v| v % 1000).collect();
    let kb = gpu.upload("keys", keys).unwrap();
    let vb = gpu.upload("values", &values).unwrap();
    let tb = gpu.upload("t", &t).unwrap();
    let ib = gpu.upload("ids", &ids).unwrap();
    let cap = indirect.unwrap_or(n as u32);
    let scratch = gpu
        .create_buffer("scratch", rbk.scratch_bytes(cap), MemoryKind::Device)
        .unwrap();
    let m = n;
    for mode in 0..3 {
        let o = outs(gpu, n);
        let out = RunOutputs {
            keys: (&o.keys).into(),
            a: (&o.a).into(),
            b: Some((&o.b).into()),
            count: o.count.slice(0, 4),
        };
        let reduction = match mode {
            0 => Reduction::Sum {
                values: (&vb).into(),
            },
            1 => Reduction::Count,
            _ => Reduction::ArgMin {
                t: (&tb).into(),
                ids: (&ib).into(),
            },
        };
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        match indirect {
            None => {
                rbk.record(&mut rec, n as u32, (&kb).into(), reduction, out, &scratch)
                    .unwrap();
                gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
            }
            Some(cap) => {
                let staging = gpu.upload("n", &[n as u32]).unwrap();
                let count = gpu.upload("count", &[0u32; 4]).unwrap();
                rec.copy(&staging, 0, &count, 8, 4);
                rec.barrier();
                rbk.record_indirect(
                    &mut rec,
                    &count,
                    8,
                    cap,
                    (&kb).into(),
                    reduction,
                    out,
                    &scratch,
                )
                .unwrap();
                gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
            }
        }
        let c = o.count.read::<u32>().unwrap();
        assert_eq!(c[1], SENTINEL);
        let r = c[0] as usize;
        let gk = o.keys.read::<u32>().unwrap();
        let ga = o.a.read::<u32>().unwrap();
        let gb = o.b.read::<u32>().unwrap();
        assert!(r <= m, "{what}: {r} runs for {m} items");
        assert!(
            gk[r..].iter().all(|&x| x == SENTINEL),
            "{what}: keys past the run count"
        );
        assert!(
            ga[r..].iter().all(|&x| x == SENTINEL),
            "{what}: values past the run count"
        );
        match mode {
            0 => {
                let (ck, cv) = cpu::reduce_by_key_sum(keys, &values);
                assert!(gk[..r] == ck[..] && ga[..r] == cv[..], "{what}: sum");
            }
            1 => {
                let (ck, cv) = cpu::run_length_encode(keys);
                assert!(
                    gk[..r] == ck[..] && ga[..r] == cv[..],
                    "{what}: run lengths"
                );
            }
            _ => {
                let (ck, ct, ci) = cpu::reduce_by_key_argmin(keys, &t, &ids);
                let ct: Vec<u32> = ct.iter().map(|x| x.to_bits()).collect();
                assert!(gk[..r] == ck[..], "{what}: arg-min keys");
                assert!(ga[..r] == ct[..], "{what}: arg-min t");
                assert!(gb[..r] == ci[..], "{what}: arg-min ids");
            }
        }
    }
}

#[test]
fn reduce_by_key_matches_cpu_at_awkward_sizes() {
    let gpu = common::gpu();
    let rbk = ReduceByKey::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    for n in common::ISSUE_SIZES {
        check_all(&gpu, &rbk, &runs(n, n as u64, 8), &format!("n = {n}"), None);
    }
    common::assert_clean(&gpu);
}

#[test]
fn reduce_by_key_adversarial_keys() {
    let gpu = common::gpu();
    let rbk = ReduceByKey::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    for n in [257usize, 65_537, 1_000_003] {
        for (name, keys) in key_patterns(n) {
            check_all(&gpu, &rbk, &keys, &format!("{name} n = {n}"), None);
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn reduce_by_key_arg_min_ties_pick_the_smaller_id() {
    let gpu = common::gpu();
    let rbk = ReduceByKey::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    // One run; equal smallest t (and -0 below +0) at several ids.
    let keys = vec![3u32; 6];
    let t = [1.0f32, 0.0, -0.0, 5.0, -0.0, 2.0];
    let ids = [10u32, 1, 7, 0, 4, 2];
    let kb = gpu.upload("keys", &keys).unwrap();
    let tb = gpu.upload("t", &t).unwrap();
    let ib = gpu.upload("ids", &ids).unwrap();
    let o = outs(&gpu, 6);
    let scratch = gpu
        .create_buffer("scratch", rbk.scratch_bytes(6), MemoryKind::Device)
        .unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    let out = RunOutputs {
        keys: (&o.keys).into(),
        a: (&o.a).into(),
        b: Some((&o.b).into()),
        count: o.count.slice(0, 4),
    };
    rbk.record(
        &mut rec,
        6,
        (&kb).into(),
        Reduction::ArgMin {
            t: (&tb).into(),
            ids: (&ib).into(),
        },
        out,
        &scratch,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    assert_eq!(o.count.read::<u32>().unwrap()[0], 1);
    assert_eq!(o.a.read::<f32>().unwrap()[0].to_bits(), (-0.0f32).to_bits());
    assert_eq!(o.b.read::<u32>().unwrap()[0], 4);
    common::assert_clean(&gpu);
}

#[test]
fn reduce_by_key_indirect_reads_n_written_on_the_gpu() {
    let gpu = common::gpu();
    let rbk = ReduceByKey::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    for n in [0usize, 1, 257, 65_537] {
        // Capacity larger than n: work past n would show in the outputs.
        check_all(
            &gpu,
            &rbk,
            &runs(n, 3, 8),
            &format!("indirect n = {n}"),
            Some(70_000),
        );
    }
    common::assert_clean(&gpu);
}

/// Both paths on every device: the general one (flags, scan, atomics) and the segment
/// variant with segments short enough that runs cross many of them.
#[test]
fn reduce_by_key_general_path_and_short_segments() {
    let gpu = common::gpu();
    for (segment, tuning) in common::segment_tunings(&gpu) {
        let rbk = ReduceByKey::new(&gpu, &tuning).unwrap();
        for n in [0usize, 1, 5, 257, 65_537] {
            for (name, keys) in key_patterns(n) {
                check_all(
                    &gpu,
                    &rbk,
                    &keys,
                    &format!("segment {segment}: {name} n = {n}"),
                    None,
                );
            }
            check_all(
                &gpu,
                &rbk,
                &runs(n, 9, 8),
                &format!("segment {segment}: indirect n = {n}"),
                Some(70_000),
            );
        }
    }
    common::assert_clean(&gpu);
}
