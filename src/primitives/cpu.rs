//! CPU twins of the GPU primitives: plain, obviously correct Rust that the tests and the
//! benchmark compare the GPU results with, bit for bit.

use std::cmp::Ordering;

/// `out[i] = x[0] + .. + x[i-1]` (wrapping).
pub fn exclusive_scan(x: &[u32]) -> Vec<u32> {
    let mut run = 0u32;
    x.iter()
        .map(|&v| {
            let out = run;
            run = run.wrapping_add(v);
            out
        })
        .collect()
}

/// `out[i] = x[0] + .. + x[i]` (wrapping).
pub fn inclusive_scan(x: &[u32]) -> Vec<u32> {
    let mut run = 0u32;
    x.iter()
        .map(|&v| {
            run = run.wrapping_add(v);
            run
        })
        .collect()
}

/// The bits `[begin, end)` of `key`.
pub fn key_bits(key: u32, bits: &std::ops::Range<u32>) -> u32 {
    let width = bits.end.saturating_sub(bits.start);
    if width == 0 {
        return 0;
    }
    let mask = if width >= 32 {
        u32::MAX
    } else {
        (1 << width) - 1
    };
    (key >> bits.start) & mask
}

/// Stable sort of (key, value) pairs by the key bits `[begin, end)`.
pub fn sort_pairs(
    keys: &[u32],
    values: &[u32],
    bits: std::ops::Range<u32>,
) -> (Vec<u32>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    pairs.sort_by_key(|&(k, _)| key_bits(k, &bits));
    pairs.into_iter().unzip()
}

/// Runs of equal keys: (unique keys, wrapping sums of their values).
pub fn reduce_by_key_sum(keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut out_k = Vec::new();
    let mut out_v: Vec<u32> = Vec::new();
    for (i, (&k, &v)) in keys.iter().zip(values).enumerate() {
        if i == 0 || keys[i - 1] != k {
            out_k.push(k);
            out_v.push(0);
        }
        let last = out_v.last_mut().unwrap();
        *last = last.wrapping_add(v);
    }
    (out_k, out_v)
}

/// Runs of equal keys: (unique keys, counts).
pub fn run_length_encode(keys: &[u32]) -> (Vec<u32>, Vec<u32>) {
    reduce_by_key_sum(keys, &vec![1; keys.len()])
}

/// The order of arg-min: t by `f32::total_cmp`, then the smaller id.
pub fn argmin_order(a: (f32, u32), b: (f32, u32)) -> Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

/// Runs of equal keys: (unique keys, smallest t, its id), see [`argmin_order`].
pub fn reduce_by_key_argmin(
    keys: &[u32],
    t: &[f32],
    ids: &[u32],
) -> (Vec<u32>, Vec<f32>, Vec<u32>) {
    let mut out_k = Vec::new();
    let mut best: Vec<(f32, u32)> = Vec::new();
    for i in 0..keys.len() {
        let cand = (t[i], ids[i]);
        if i == 0 || keys[i - 1] != keys[i] {
            out_k.push(keys[i]);
            best.push(cand);
        } else {
            let b = best.last_mut().unwrap();
            if argmin_order(cand, *b) == Ordering::Less {
                *b = cand;
            }
        }
    }
    let (t, id) = best.into_iter().unzip();
    (out_k, t, id)
}

/// Stable compaction: the items whose flag is non-zero, in order.
pub fn compact(flags: &[u32], values: &[u32]) -> Vec<u32> {
    flags
        .iter()
        .zip(values)
        .filter(|(&f, _)| f != 0)
        .map(|(_, &v)| v)
        .collect()
}

/// The indices whose flag is non-zero, in order.
pub fn compact_indices(flags: &[u32]) -> Vec<u32> {
    (0..flags.len() as u32)
        .filter(|&i| flags[i as usize] != 0)
        .collect()
}

/// `out[i] = src[idx[i]]`, 0 for indices out of range.
pub fn gather(src: &[u32], idx: &[u32]) -> Vec<u32> {
    idx.iter()
        .map(|&i| src.get(i as usize).copied().unwrap_or(0))
        .collect()
}

/// `out[idx[i]] = src[i]` into `out` (indices out of range skipped).
pub fn scatter(src: &[u32], idx: &[u32], out: &mut [u32]) {
    for (&v, &i) in src.iter().zip(idx) {
        if let Some(o) = out.get_mut(i as usize) {
            *o = v;
        }
    }
}
