//! The committed Mitsuba 3 references and the comparison of `tests/suite/common/reference.rs`
//! (no GPU): every reference is consistent with its manifest entry and still matches
//! its scene as splitray resolves it, and the comparison accepts an estimate with only
//! the reference's own noise while it rejects a 1.5% bias and one biased block.
use crate::common;

use common::reference::{compare_images, reference_dir, Reference, BLOCK, BLOCK_Z};

fn manifest_names() -> Vec<String> {
    let path = reference_dir().join("references.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let manifest: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&text).unwrap();
    manifest.keys().cloned().collect()
}

#[test]
fn every_reference_matches_its_scene_and_manifest() {
    let names = manifest_names();
    for name in [
        "cornell_path_64",
        "glossy_path_64",
        "mirror_path_64",
        "fixture_ptracer_64",
    ] {
        assert!(
            names.iter().any(|n| n == name),
            "{name} missing from the manifest"
        );
    }
    for name in &names {
        let reference = Reference::load(name);
        let scene = reference.scene();
        assert_eq!(
            (scene.film.width, scene.film.height),
            (reference.info.width, reference.info.height)
        );
        let mean = reference
            .mean
            .iter()
            .flatten()
            .map(|&v| v as f64)
            .sum::<f64>()
            / (3 * reference.mean.len()) as f64;
        let recorded = reference.info.image_mean;
        assert!(
            ((mean - recorded) / recorded).abs() < 1e-5,
            "{name}: EXR mean {mean} but the manifest says {recorded}"
        );
        assert!(
            reference
                .stderr
                .iter()
                .flatten()
                .all(|&s| s >= 0.0 && s.is_finite()),
            "{name}: a standard error is negative or not finite"
        );
        assert!(
            reference.info.image_mean_stderr / recorded < 0.002,
            "{name}: the image mean's own standard error is {:.3}%, too large to test 1% against",
            reference.info.image_mean_stderr / recorded * 100.0
        );
    }
}

/// Standard normal deviates (Box–Muller on the harness's uniforms).
fn normals(n: usize, seed: u64) -> Vec<f64> {
    let u = common::uniforms(2 * n, seed);
    (0..n)
        .map(|i| {
            let u1 = (u[2 * i] as f64).max(1e-12);
            let u2 = u[2 * i + 1] as f64;
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        })
        .collect()
}

#[test]
fn comparison_accepts_noise_and_rejects_bias() {
    let reference = Reference::load("cornell_path_64");
    let width = reference.info.width as usize;
    let (mean, se) = (&reference.mean, &reference.stderr);

    // An estimate with the reference's own error: the reference plus Gaussian noise of
    // its standard error, claiming that standard error.
    let noise = normals(3 * mean.len(), 7);
    let noisy: Vec<[f32; 3]> = mean
        .iter()
        .zip(se)
        .enumerate()
        .map(|(p, (m, s))| std::array::from_fn(|c| m[c] + s[c] * noise[3 * p + c] as f32))
        .collect();
    let c = compare_images("self", width, (&noisy, se), (mean, se));
    assert!(c.failures().is_empty(), "{}", c.summary());
    assert!(c.relative_error().abs() < 1e-3, "{}", c.summary());

    // The same, 1.5% too bright everywhere: the image mean fails.
    let bright: Vec<[f32; 3]> = noisy.iter().map(|m| m.map(|v| v * 1.015)).collect();
    let c = compare_images("bright", width, (&bright, se), (mean, se));
    assert!(
        c.failures().iter().any(|f| f.contains("image mean")),
        "{}",
        c.summary()
    );

    // One 8×8 block too bright by (BLOCK_Z + 1.5) σ of its sum in every channel, spread
    // evenly (≈ 0.75 σ per pixel): the block test fails, the image mean and the pixel
    // test do not see it.
    let mut block = noisy.clone();
    let (bx, by) = (3 * BLOCK, 4 * BLOCK);
    for c in 0..3 {
        let var: f64 = (by..by + BLOCK)
            .flat_map(|y| (bx..bx + BLOCK).map(move |x| (x, y)))
            .map(|(x, y)| 2.0 * (se[y * width + x][c] as f64).powi(2))
            .sum();
        let shift = ((BLOCK_Z + 1.5) * var.sqrt() / (BLOCK * BLOCK) as f64) as f32;
        for y in by..by + BLOCK {
            for x in bx..bx + BLOCK {
                block[y * width + x][c] += shift;
            }
        }
    }
    let c = compare_images("block", width, (&block, se), (mean, se));
    let failures = c.failures();
    assert_eq!(failures.len(), 1, "{}", c.summary());
    assert!(failures[0].contains("block at (24, 32)"), "{failures:?}");
}

#[test]
fn blocks_cover_sizes_that_are_not_multiples_of_eight() {
    // 10 × 9 pixels: blocks of 8×8, 2×8, 8×1 and 2×1; a bias only in the last pixel.
    let (w, h) = (10, 9);
    let zero = vec![[0.0f32; 3]; w * h];
    let se = vec![[0.1f32; 3]; w * h];
    let mut image = zero.clone();
    image[w * h - 1] = [1.0; 3];
    let c = compare_images("edge", w, (&image, &se), (&zero, &se));
    assert_eq!(c.worst_block, (8, 8));
    assert_eq!(c.worst_pixel, (9, 8));
    assert!((c.block_max_z - 5.0).abs() < 1e-4, "{}", c.summary());
}
