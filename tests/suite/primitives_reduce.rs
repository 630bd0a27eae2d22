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

/// Arg-min of `t` (with `ids`) per run of `keys` on the GPU: (unique keys, f32 bits of
/// the smallest t, its id).
fn argmin_on_gpu(
    gpu: &Gpu,
    rbk: &ReduceByKey,
    keys: &[u32],
    t: &[f32],
    ids: &[u32],
) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let n = keys.len();
    let kb = gpu.upload("keys", keys).unwrap();
    let tb = gpu.upload("t", t).unwrap();
    let ib = gpu.upload("ids", ids).unwrap();
    let o = outs(gpu, n);
    let scratch = gpu
        .create_buffer("scratch", rbk.scratch_bytes(n as u32), MemoryKind::Device)
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
        n as u32,
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
    let r = o.count.read::<u32>().unwrap()[0] as usize;
    assert!(r <= n, "{r} runs for {n} items");
    let read = |b: &Buffer| b.read::<u32>().unwrap()[..r].to_vec();
    (read(&o.keys), read(&o.a), read(&o.b))
}

/// The arg-min orders t by `f32::total_cmp` (−NaN < −inf < … < −0 < +0 < … < +inf <
/// +NaN), then the smaller id, on the general path and on segments that runs cross:
/// equal t at several ids, signed zeros and NaNs, infinities and a subnormal (1e-40,
/// which a float comparison flushing subnormals would tie with 0).
#[test]
fn reduce_by_key_arg_min_ties_pick_the_smaller_id() {
    let gpu = common::gpu();
    // One run; equal smallest t (and -0 below +0) at several ids.
    let rbk = ReduceByKey::new(&gpu, &Tuning::for_device(gpu.info())).unwrap();
    let (keys, t, ids) = argmin_on_gpu(
        &gpu,
        &rbk,
        &[3u32; 6],
        &[1.0f32, 0.0, -0.0, 5.0, -0.0, 2.0],
        &[10u32, 1, 7, 0, 4, 2],
    );
    assert_eq!(
        (keys, t, ids),
        (vec![3], vec![(-0.0f32).to_bits()], vec![4])
    );

    let neg_nan = f32::from_bits(f32::NAN.to_bits() | 0x8000_0000);
    assert!(neg_nan.is_nan() && neg_nan.is_sign_negative());
    // In increasing total order.
    let specials = [
        neg_nan,
        f32::NEG_INFINITY,
        f32::MIN,
        -1.0,
        -1e-40,
        -0.0,
        0.0,
        1e-40,
        f32::MIN_POSITIVE,
        1.0,
        f32::MAX,
        f32::INFINITY,
        f32::NAN,
    ];
    // First one run per special: it at id 9, every special above it, then it again at
    // id 2 twice (a tie of t and of id), so the run's minimum is (it, 2).
    let (mut keys, mut t, mut ids) = (vec![], vec![], vec![]);
    for (k, &s) in specials.iter().enumerate() {
        let run: Vec<f32> = [s]
            .into_iter()
            .chain(specials[k + 1..].iter().copied())
            .chain([s, s])
            .collect();
        keys.extend(std::iter::repeat_n(k as u32, run.len()));
        ids.extend(
            [9].into_iter()
                .chain(std::iter::repeat_n(0, run.len() - 3))
                .chain([2, 2]),
        );
        t.extend(run);
    }
    let (_, designed_t, designed_ids) = cpu::reduce_by_key_argmin(&keys, &t, &ids);
    assert_eq!(
        designed_t.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
        specials.map(f32::to_bits),
        "the CPU twin orders t by total_cmp"
    );
    assert_eq!(designed_ids, vec![2; specials.len()]);
    // Then runs of 1 to 40 items, each drawing t from four specials of its own (ties in
    // most runs) with ids that repeat.
    let n = 5000;
    let r = common::random_u32s(3 * n, 81);
    let mut key = specials.len() as u32;
    while keys.len() < n {
        let len = (r[keys.len()] % 40 + 1) as usize;
        for _ in 0..len.min(n - keys.len()) {
            let i = keys.len();
            let pick = (key as usize + (r[n + i] % 4) as usize * 3) % specials.len();
            keys.push(key);
            t.push(specials[pick]);
            ids.push(r[2 * n + i] % 64);
        }
        key += 1 + r[keys.len() - 1] % 2;
    }
    for (segment, tuning) in common::segment_tunings(&gpu) {
        let rbk = ReduceByKey::new(&gpu, &tuning).unwrap();
        for m in [1usize, 7, 100, n] {
            let (k, gt, gi) = argmin_on_gpu(&gpu, &rbk, &keys[..m], &t[..m], &ids[..m]);
            let (ck, ct, ci) = cpu::reduce_by_key_argmin(&keys[..m], &t[..m], &ids[..m]);
            let ct: Vec<u32> = ct.iter().map(|x| x.to_bits()).collect();
            let what = format!("segment {segment}, n = {m}");
            assert_eq!(k, ck, "{what}: keys");
            let bad: Vec<_> = (0..k.len())
                .filter(|&j| gt[j] != ct[j] || gi[j] != ci[j])
                .take(4)
                .map(|j| {
                    (
                        j,
                        f32::from_bits(gt[j]),
                        gi[j],
                        f32::from_bits(ct[j]),
                        ci[j],
                    )
                })
                .collect();
            assert!(
                bad.is_empty(),
                "{what}: (run, gpu t, id, cpu t, id) {bad:?}"
            );
        }
    }
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
