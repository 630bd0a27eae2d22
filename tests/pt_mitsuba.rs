//! `pt` on the Cornell box against Mitsuba 3's `path` integrator on the identical scene
//! (tests/data/reference/cornell_pt_64_{mean,stderr}.exr, made by
//! tools/mitsuba_reference.py: 16 independent renders of 512 spp, 64×64, max_depth −1,
//! rr_depth 5, box filter).
//!
//! The test, and why:
//! - **image mean within 1%**: the mean over all pixels and channels of splitray's image
//!   against the reference's. Both estimates carry ≈ 0.1% noise at these sample counts,
//!   so 1% catches any systematic error (a wrong MIS weight, a missing cosine, a
//!   one-sided/two-sided mismatch, a wrong camera) with a wide margin.
//! - **per-pixel z-test**: for each pixel and channel, z = (splitray − reference) /
//!   √(se_splitray² + se_reference²), with splitray's standard error from its own
//!   per-pixel sample variance and the reference's from its 16 independent runs. For
//!   Gaussian z, |z| > 3 has probability 0.27%; we require under 2% of the 64·64·3
//!   values beyond 3. Why not 0.27%: at 256 spp a pixel's samples are very skewed (rare
//!   paths that reach the light carry most of the value), so a low sample mean comes
//!   with a low sample variance and z has a heavier, one-sided tail: measured ≈ 0.9–1.2%
//!   across seeds, nearly all below the reference, while the image means agree to
//!   0.01–0.3%. (An independent variance estimate from a second render just moves the
//!   excess to the other side.)
//! - **8×8-block z-test**: the same statistic over sums of 64 pixels, which are close
//!   to Gaussian: every block and channel within 4.5 σ (192 tests; a false alarm has
//!   probability ≈ 1e-3). Any regional bias (a corner, the light's edges, one wall)
//!   shows here long before it moves the image mean.
mod common;

use std::path::Path;

use splitray::integrator::pt::{render_pt, PtOptions, PtScene};
use splitray::scene::builtin;
use splitray::trace::TracerKind;

const SIZE: u32 = 64;
const SPP: u32 = 256;

/// An RGB EXR as rows of [r, g, b], top row first.
fn read_rgb(path: &Path) -> Vec<[f32; 3]> {
    let image = exr::prelude::read_first_flat_layer_from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let layer = &image.layer_data;
    assert_eq!(layer.size.0 as u32, SIZE);
    assert_eq!(layer.size.1 as u32, SIZE);
    let channel = |name: &str| -> Vec<f32> {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("{}: no channel {name}", path.display()))
            .sample_data
            .values_as_f32()
            .collect()
    };
    let (r, g, b) = (channel("R"), channel("G"), channel("B"));
    (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect()
}

#[test]
fn cornell_box_matches_mitsuba() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/reference");
    let ref_mean = read_rgb(&dir.join("cornell_pt_64_mean.exr"));
    let ref_se = read_rgb(&dir.join("cornell_pt_64_stderr.exr"));

    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let pt = PtScene::new(&scene);
    // The default tracer, PDACRT.
    let mut tracer = TracerKind::default().create(&gpu, &pt.triangles).unwrap();
    let camera = scene.camera.frame(SIZE, SIZE);
    let options = PtOptions {
        spp: SPP,
        seed: 1,
        max_depth: -1,
        rr_depth: 5,
        ..Default::default()
    };
    let out = render_pt(&gpu, tracer.as_mut(), &pt, &camera, &options, &mut |_| {}).unwrap();
    drop(tracer);
    common::assert_clean(&gpu);
    let (mean, se) = out.mean_and_stderr();

    // 8×8-pixel blocks: sums of 64 pixels are close to Gaussian, so a block z-test is
    // exact enough for a tight bound, and it catches any regional bias.
    let mut zblock_max = 0.0f64;
    for by in 0..(SIZE / 8) as usize {
        for bx in 0..(SIZE / 8) as usize {
            for c in 0..3 {
                let (mut d, mut v) = (0.0f64, 0.0f64);
                for y in by * 8..by * 8 + 8 {
                    for x in bx * 8..bx * 8 + 8 {
                        let p = y * SIZE as usize + x;
                        d += mean[p][c] as f64 - ref_mean[p][c] as f64;
                        v += (se[p][c] as f64).powi(2) + (ref_se[p][c] as f64).powi(2);
                    }
                }
                zblock_max = zblock_max.max(d.abs() / v.sqrt().max(1e-12));
            }
        }
    }

    let avg = |img: &[[f32; 3]]| -> f64 {
        img.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * img.len()) as f64
    };
    let (ours, theirs) = (avg(&mean), avg(&ref_mean));
    let diff = (ours - theirs) / theirs;

    let mut beyond = 0usize;
    let mut beyond4 = 0usize;
    let mut below = 0usize;
    let mut zmax = 0.0f64;
    let mut worst = 0usize;
    for p in 0..mean.len() {
        for c in 0..3 {
            let d = mean[p][c] as f64 - ref_mean[p][c] as f64;
            let s = ((se[p][c] as f64).powi(2) + (ref_se[p][c] as f64).powi(2)).sqrt();
            let z = if s > 0.0 {
                d.abs() / s
            } else if d == 0.0 {
                0.0
            } else {
                f64::INFINITY
            };
            if z > 3.0 {
                beyond += 1;
                below += (d < 0.0) as usize;
            }
            if z > 4.0 {
                beyond4 += 1;
            }
            if z > zmax {
                zmax = z;
                worst = p;
            }
        }
    }
    let total = mean.len() * 3;
    let fraction = beyond as f64 / total as f64;
    eprintln!(
        "pt vs Mitsuba: image mean {ours:.6} vs {theirs:.6} ({:+.3}%), {beyond} of {total} \
         pixel channels with |z| > 3 ({:.2}%; {below} of them below the reference), \
         {beyond4} with |z| > 4, max |z| {zmax:.2} at pixel ({}, {})",
        diff * 100.0,
        fraction * 100.0,
        worst % SIZE as usize,
        worst / SIZE as usize
    );
    assert!(
        diff.abs() < 0.01,
        "image mean differs by {:.3}%",
        diff * 100.0
    );
    eprintln!("8x8 blocks: max |z| {zblock_max:.2}");
    assert!(
        fraction < 0.02,
        "{:.2}% of pixel channels beyond 3 sigma",
        fraction * 100.0
    );
    assert!(
        zblock_max < 4.5,
        "an 8x8 block differs by {zblock_max:.2} sigma"
    );
}
