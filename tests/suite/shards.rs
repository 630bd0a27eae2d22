//! Shards: the shards of one image, written as EXRs and merged, hold the samples of one
//! render of the same passes — equal to it up to the rounding of the films' f32 sums —
//! and an independent render agrees with the merged image by a z-test on the merged
//! standard error; `merge` refuses parts that do not belong together, naming the file.
//! (Each render builds its integrator's pipelines anew, and lavapipe compiles a shader
//! at its first dispatch: the tests keep their renders few.)
use crate::common;

use std::path::{Path, PathBuf};

use splitray::film::{write_outputs, FilmSums};
use splitray::integrator::IntegratorKind;
use splitray::render::merge::merge_parts;
use splitray::render::{
    render_from, RenderControl, RenderOptions, RenderOutput, RenderPlan, Shard,
};
use splitray::scene::{builtin, Scene};
use splitray::vk::Gpu;

/// f32's unit roundoff.
const U: f64 = 1.0 / (1u64 << 24) as f64;

fn options(scene: &Scene, kind: IntegratorKind, spp: u32, seed: u64) -> RenderOptions {
    RenderOptions::resolve(
        scene,
        Some(24),
        Some(16),
        Some(spp),
        Some(seed),
        Some(kind),
        None,
    )
    .unwrap()
}

fn render(gpu: &Gpu, scene: &Scene, opts: &RenderOptions, shard: Shard) -> RenderOutput {
    render_from(
        gpu,
        scene,
        opts,
        RenderPlan {
            shard,
            ..Default::default()
        },
        RenderControl {
            progress: &mut |_| {},
            stop: &|| false,
            abandon: &|| false,
        },
    )
    .unwrap()
}

fn write_part(dir: &Path, name: &str, out: &RenderOutput) -> PathBuf {
    let path = dir.join(name);
    write_outputs(&path, &out.film, &out.metadata).unwrap();
    path
}

/// Checks `|a − b| ≤ bound(pixel, channel)` everywhere.
fn assert_within(what: &str, a: &[[f64; 3]], b: &[[f64; 3]], bound: impl Fn(usize, usize) -> f64) {
    assert_eq!(a.len(), b.len());
    for (p, (x, y)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            let d = (x[c] - y[c]).abs();
            assert!(
                d <= bound(p, c),
                "{what}: pixel {p}[{c}]: {} vs {}",
                x[c],
                y[c]
            );
        }
    }
}

#[test]
fn merged_shards_equal_one_render_of_the_same_passes() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let dir = tempfile::tempdir().unwrap();
    const PASSES: u32 = 8;
    // `bpt`, `light` and `cbpt` splat light-tracing samples: each shard normalises its
    // splats by its own passes' light subpaths, so merged shards still hold one render's
    // passes.
    for kind in [
        IntegratorKind::Pt,
        IntegratorKind::Ao,
        IntegratorKind::Bpt,
        IntegratorKind::Light,
        IntegratorKind::Cbpt,
    ] {
        // A pass of cbpt holds four samples per pixel.
        let per_pass = if kind == IntegratorKind::Cbpt { 4 } else { 1 };
        let opts = options(&scene, kind, PASSES * per_pass, 7);
        let whole = render(&gpu, &scene, &opts, Shard::WHOLE);
        // Shards may come from devices whose material-sorting defaults differ: pt's
        // middle shard sorts, the others do not (sorting never changes the image).
        let shards: Vec<RenderOutput> = (0..3)
            .map(|i| {
                let mut shard_opts = opts.clone();
                if kind == IntegratorKind::Pt {
                    shard_opts.sort_materials = Some(i == 1);
                }
                render(&gpu, &scene, &shard_opts, Shard::new(i, 3).unwrap())
            })
            .collect();
        let blocks: Vec<(u32, u32)> = shards
            .iter()
            .map(|s| (s.first_pass, s.sums.passes))
            .collect();
        assert_eq!(blocks, [(0, 2), (2, 3), (5, 3)], "{kind}");
        // Shard 0 is the first block of the one-process render, bit for bit.
        let first_block = render(
            &gpu,
            &scene,
            &options(&scene, kind, 2 * per_pass, 7),
            Shard::WHOLE,
        );
        assert!(
            shards[0].sums == first_block.sums,
            "{kind}: shard 0 differs"
        );

        let paths: Vec<PathBuf> = shards
            .iter()
            .enumerate()
            .map(|(i, s)| write_part(dir.path(), &format!("{kind}-{i}.exr"), s))
            .collect();
        let merged = merge_parts(&paths).unwrap();
        assert_eq!(merged.record.passes.to_string(), "0..8", "{kind}");
        assert_eq!(merged.record.fingerprint, whole.record.fingerprint);
        assert_eq!(
            (merged.sums.passes, merged.metadata.spp),
            (PASSES, PASSES * per_pass)
        );
        assert!(merged.missing_shards.is_empty());

        // The EXRs lose only the rounding of each part's mean and standard error to f32
        // against the exact (f64) sum of the parts' films: at most u·Σ|Σᵢ| for the sums
        // and 2u·ΣΣᵢ² for the squares (Σ² = n·m² + n(n−1)·se² with m, se rounded once).
        let mut exact = shards[0].sums.clone();
        for s in &shards[1..] {
            exact.merge(&s.sums).unwrap();
        }
        let abs_sum =
            |p: usize, c: usize| -> f64 { shards.iter().map(|s| s.sums.sum[p][c].abs()).sum() };
        assert_within("sums", &merged.sums.sum, &exact.sum, |p, c| {
            U * abs_sum(p, c) * (1.0 + 1e-9)
        });
        if let (Some(q), Some(qe)) = (&merged.sums.sum_sq, &exact.sum_sq) {
            assert_within("squares", q, qe, |p, c| 2.01 * U * qe[p][c]);
        }

        // Against the one-process render the samples are the same; the sums differ by
        // the order in which f32 films added them: recursive summation of n non-negative
        // terms errs by at most (n−1)·u·Σ, so the two differ by at most 2·P·u·Σ.
        let p = PASSES as f64;
        assert_within(
            "merged vs one render",
            &merged.sums.sum,
            &whole.sums.sum,
            |i, c| 2.0 * p * U * whole.sums.sum[i][c].abs().max(merged.sums.sum[i][c].abs()),
        );
        check_stderr(&merged.sums, &whole.sums, kind);
        assert!(merged.film.stderr == merged.sums.stderr(), "{kind}");
        if matches!(
            kind,
            IntegratorKind::Pt | IntegratorKind::Bpt | IntegratorKind::Cbpt
        ) {
            let other = render(
                &gpu,
                &scene,
                &options(&scene, kind, PASSES * per_pass, 8),
                Shard::WHOLE,
            );
            z_test(&merged.sums, &other.sums);
        }
    }
    common::assert_clean(&gpu);
}

/// The merged standard error is the one-process render's up to the same rounding. With
/// the sums off by at most εs·Σ and the squares by εq·Σ² (the films' f32 summation on
/// both sides, and the parts' EXR rounding: εs = (2P+1)·u, εq = (2P+2)·u), the variance
/// of the mean, (Σ²/N − m²)/(N−1), moves by at most (εq·Σ²/N + 2εs·m²)/(N−1); each
/// standard error is rounded to f32 too (2u·se² on se²).
fn check_stderr(merged: &FilmSums, whole: &FilmSums, kind: IntegratorKind) {
    let (Some(a), Some(b), Some(q)) = (merged.stderr(), whole.stderr(), &whole.sum_sq) else {
        assert!(merged.sum_sq.is_none() && whole.sum_sq.is_none(), "{kind}");
        return;
    };
    let n = whole.passes as f64;
    let (eps_s, eps_q) = ((2.0 * n + 1.0) * U, (2.0 * n + 2.0) * U);
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        for c in 0..3 {
            let m = whole.sum[i][c] / n;
            let (x, y) = (x[c] as f64, y[c] as f64);
            let bound =
                (eps_q * q[i][c] / n + 2.0 * eps_s * m * m) / (n - 1.0) + 2.0 * U * (x * x + y * y);
            assert!(
                (x * x - y * y).abs() <= bound,
                "{kind}: stderr {i}[{c}]: {x} vs {y}"
            );
        }
    }
}

/// The merged image against an independent render (another seed) of as many passes,
/// by the merged standard error and the other render's.
fn z_test(merged: &FilmSums, other: &FilmSums) {
    let (ma, mb) = (merged.mean(), other.mean());
    let (sa, sb) = (merged.stderr().unwrap(), other.stderr().unwrap());
    let mut z2 = Vec::new();
    for i in 0..ma.len() {
        for c in 0..3 {
            let se = ((sa[i][c] as f64).powi(2) + (sb[i][c] as f64).powi(2)).sqrt();
            if se > 0.0 {
                z2.push(((ma[i][c] - mb[i][c]) as f64 / se).powi(2));
            }
        }
    }
    assert!(z2.len() > 500, "{} channel values with light", z2.len());
    // Two independent means of 8 passes each: z follows Welch's t with about 14
    // degrees of freedom, E[z²] ≈ 1.17. Over ~10³ channel values (correlated within a
    // pixel) its mean stays within [0.7, 1.7], and |z| > 5 is rare (t₁₄: 0.02 %).
    let mean_z2 = z2.iter().sum::<f64>() / z2.len() as f64;
    let far = z2.iter().filter(|&&v| v > 25.0).count();
    assert!((0.7..1.7).contains(&mean_z2), "mean z² = {mean_z2}");
    assert!(
        far * 100 <= z2.len(),
        "{far} of {} beyond 5 standard errors",
        z2.len()
    );
}

fn merge_error(paths: &[&Path], culprit: &Path) -> String {
    let err = match merge_parts(paths) {
        Ok(_) => panic!("{paths:?} merged"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains(&*culprit.to_string_lossy()), "{err}");
    err
}

#[test]
fn merge_refuses_parts_that_do_not_belong_together_naming_the_file() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ao = options(&scene, IntegratorKind::Ao, 4, 7);
    let half = |i| Shard::new(i, 2).unwrap();
    let a0 = write_part(d, "a0.exr", &render(&gpu, &scene, &ao, half(0)));
    let a1 = write_part(d, "a1.exr", &render(&gpu, &scene, &ao, half(1)));
    assert!(merge_parts(&[&a0, &a1]).is_ok());

    let twice = d.join("a0-again.exr");
    std::fs::copy(&a0, &twice).unwrap();
    let err = merge_error(&[&a0, &a1, &twice], &twice);
    assert!(
        err.contains("is shard 0/2, and so is") && err.contains("a0.exr"),
        "{err}"
    );

    let seed = write_part(
        d,
        "seed.exr",
        &render(
            &gpu,
            &scene,
            &options(&scene, IntegratorKind::Ao, 4, 8),
            half(1),
        ),
    );
    assert!(merge_error(&[&a0, &seed], &seed).contains("seed 8 in"));

    let mut wide = ao.clone();
    wide.width = 16;
    let size = write_part(d, "size.exr", &render(&gpu, &scene, &wide, half(1)));
    assert!(merge_error(&[&a0, &size], &size).contains("is 16x16"));

    let primary = options(&scene, IntegratorKind::Primary, 4, 7);
    let other = write_part(d, "primary.exr", &render(&gpu, &scene, &primary, half(1)));
    assert!(merge_error(&[&a0, &other], &other).contains("integrator primary in"));

    // Shard 1/2 of 2 passes is pass 1, which shard 0/2 of 4 passes holds too.
    let overlap = write_part(
        d,
        "overlap.exr",
        &render(
            &gpu,
            &scene,
            &options(&scene, IntegratorKind::Ao, 2, 7),
            half(1),
        ),
    );
    assert!(merge_error(&[&a0, &overlap], &overlap).contains("holds passes 1..2"));

    let film = splitray::film::Film::from_mean_rgb(24, 16, &vec![[1.0; 3]; 24 * 16]).unwrap();
    let foreign = d.join("foreign.exr");
    splitray::film::write_exr(&foreign, &film, &Default::default()).unwrap();
    assert!(merge_error(&[&a0, &foreign], &foreign).contains("not a part of a splitray render"));

    let bytes = std::fs::read(&a1).unwrap();
    let truncated = d.join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    assert!(merge_error(&[&a0, &truncated], &truncated).contains("EXR"));

    let missing = d.join("missing.exr");
    assert!(merge_error(&[&a0, &missing], &missing).contains("No such file"));
    common::assert_clean(&gpu);
}
