//! Independent references and the comparison every integrator's image is checked with.
//!
//! A reference is a Mitsuba 3 render of one of splitray's scenes made by
//! `tools/mitsuba_reference.py` (its docstring says how the scene is mapped):
//! `tests/data/reference/NAME_{mean,stderr}.exr` (float32 RGB, the mean of K independent
//! runs and its per-pixel standard error), `NAME.scene.json` (the scene it was rendered
//! from, as `splitray export-scene` wrote it) and NAME's entry in `references.json`
//! (scene, Mitsuba integrator, max_depth, rr_depth, film size, samples).
//!
//! Use:
//! ```ignore
//! let reference = common::reference::Reference::load("glossy_path_64");
//! let scene = reference.scene();          // film = the reference's; fails if stale
//! // … render `scene` with max_depth = reference.info.max_depth,
//! //   rr_depth = reference.info.rr_depth, into a per-pixel mean and standard error …
//! reference.compare(&mean, &stderr).assert_agrees("bpt, 64 spp");
//! ```
//! [`compare_images`] applies the same tests to any two estimates, e.g. two of
//! splitray's integrators against each other. [`Comparison::summary`] is the one line
//! to quote; [`Comparison::failures`] says what failed, for tests that expect a failure.
//!
//! The comparison, and why:
//! - **image mean within 1%** ([`MEAN_TOLERANCE`]): the mean over all pixels and channels
//!   of the image against the reference's. Both estimates carry ≈ 0.1–0.3% noise at the
//!   sample counts used, so 1% catches any systematic error (a wrong MIS weight, a
//!   missing cosine, a one-sided/two-sided mismatch, a wrong camera) with a wide margin.
//! - **per-pixel z-test** ([`PIXEL_Z`], [`PIXEL_FRACTION`]): for each pixel and channel,
//!   z = (image − reference) / √(se_image² + se_reference²), with the image's standard
//!   error from its own per-pixel sample variance and the reference's from its K
//!   independent runs. For Gaussian z, |z| > 3 has probability 0.27%; we require under
//!   2% of the values beyond 3. Why not 0.27%: at a few hundred spp a pixel's samples
//!   are very skewed (rare paths that reach the light carry most of the value), so a
//!   low sample mean comes with a low sample variance and z has a heavier, one-sided
//!   tail: measured ≈ 0.9–1.2% for `pt` on the Cornell box across seeds, nearly all
//!   below the reference, while the image means agree to 0.01–0.3%. (An independent
//!   variance estimate from a second render just moves the excess to the other side.)
//!   The tail grows where an integrator finds a caustic only by chance: see
//!   `tests/suite/pt_mitsuba.rs` for the sample counts `pt` needs on each scene.
//! - **8×8-block z-test** ([`BLOCK`], [`BLOCK_Z`]): the same statistic over sums of 64
//!   pixels, which are close to Gaussian: every block and channel within 4.5 σ (192
//!   tests on 64×64; a false alarm has probability ≈ 1e-3). Any regional bias (a corner,
//!   the light's edges, one wall) shows here long before it moves the image mean.
use std::path::{Path, PathBuf};

use serde::Deserialize;
use splitray::scene::{FilmSize, Scene};
use splitray::scene_export::{export, SceneExport};

/// Largest relative difference of the image means.
pub const MEAN_TOLERANCE: f64 = 0.01;
/// A pixel channel is an outlier beyond this |z|.
pub const PIXEL_Z: f64 = 3.0;
/// Largest fraction of outlier pixel channels.
pub const PIXEL_FRACTION: f64 = 0.02;
/// Side of the pixel blocks of the block z-test.
pub const BLOCK: usize = 8;
/// Largest |z| of any block and channel.
pub const BLOCK_Z: f64 = 4.5;

/// The folder of the references: `SPLITRAY_REFERENCE_DIR` (to try references made with
/// `tools/mitsuba_reference.py --out DIR` before committing them), else the committed
/// `tests/data/reference/`.
pub fn reference_dir() -> PathBuf {
    match std::env::var_os("SPLITRAY_REFERENCE_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/reference"),
    }
}

/// A reference's entry in `references.json`.
#[derive(Clone, Debug, Deserialize)]
pub struct ReferenceInfo {
    /// A built-in scene name or a scene file relative to the repository root.
    pub scene: String,
    /// Mitsuba's integrator: `path` or `ptracer` (light tracing).
    pub integrator: String,
    /// Mitsuba's max_depth (splitray's `pt` counts depth the same way; −1: unbounded).
    pub max_depth: i32,
    pub rr_depth: u32,
    pub width: u32,
    pub height: u32,
    /// K: the independent runs behind the standard error.
    pub runs: u32,
    pub spp_per_run: u32,
    pub mitsuba: String,
    pub variant: String,
    pub conductor_shadowing: String,
    pub seconds: f64,
    pub image_mean: f64,
    pub image_mean_stderr: f64,
    pub median_relative_stderr: f64,
}

/// A loaded reference: its manifest entry, mean image and per-pixel standard error
/// (rows of [r, g, b], top row first).
pub struct Reference {
    pub name: String,
    pub info: ReferenceInfo,
    pub mean: Vec<[f32; 3]>,
    pub stderr: Vec<[f32; 3]>,
}

impl Reference {
    /// Loads reference `name` (see the module docs); panics naming the file on any problem.
    pub fn load(name: &str) -> Self {
        let dir = reference_dir();
        let manifest_path = dir.join("references.json");
        let text = std::fs::read_to_string(&manifest_path)
            .unwrap_or_else(|e| panic!("{}: {e}", manifest_path.display()));
        let mut manifest: std::collections::BTreeMap<String, ReferenceInfo> =
            serde_json::from_str(&text)
                .unwrap_or_else(|e| panic!("{}: {e}", manifest_path.display()));
        let info = manifest.remove(name).unwrap_or_else(|| {
            panic!(
                "{}: no reference '{name}' (known: {:?})",
                manifest_path.display(),
                manifest.keys().collect::<Vec<_>>()
            )
        });
        let size = (info.width, info.height);
        let mean = read_rgb(&dir.join(format!("{name}_mean.exr")), size);
        let stderr = read_rgb(&dir.join(format!("{name}_stderr.exr")), size);
        Self {
            name: name.to_string(),
            info,
            mean,
            stderr,
        }
    }

    /// The scene the reference was rendered from, on the reference's film. Panics when
    /// the scene no longer resolves to the committed `NAME.scene.json` (a scene file,
    /// the MTL mapping or a BSDF mapping changed): the reference is then stale.
    pub fn scene(&self) -> Scene {
        let spec = &self.info.scene;
        let mut scene = match splitray::scene::builtin(spec) {
            Some(s) => s,
            None => {
                let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(spec);
                splitray::scene::load(path.to_str().expect("UTF-8 path"))
                    .unwrap_or_else(|e| panic!("reference '{}': {e}", self.name))
            }
        };
        scene.film = FilmSize {
            width: self.info.width,
            height: self.info.height,
        };
        let path = reference_dir().join(format!("{}.scene.json", self.name));
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let committed: SceneExport =
            serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let today = export(&scene, scene.film);
        if let Some(difference) = first_difference(&committed, &today) {
            panic!(
                "reference '{}' is stale: {} no longer matches the scene '{spec}' as splitray \
                 resolves it ({difference}); regenerate it with \
                 `tools/mitsuba_reference.py {}`",
                self.name,
                path.display(),
                self.name
            );
        }
        scene
    }

    /// Compares an image (per-pixel mean and standard error, rows of [r, g, b], top row
    /// first, at the reference's size) with the reference.
    pub fn compare(&self, mean: &[[f32; 3]], stderr: &[[f32; 3]]) -> Comparison {
        let (w, h) = (self.info.width as usize, self.info.height as usize);
        assert_eq!(mean.len(), w * h, "image size differs from the reference's");
        assert_eq!(
            stderr.len(),
            w * h,
            "stderr size differs from the reference's"
        );
        compare_images(&self.name, w, (mean, stderr), (&self.mean, &self.stderr))
    }
}

/// Where two exports first differ, in words, or `None` when they are equal.
fn first_difference(committed: &SceneExport, today: &SceneExport) -> Option<String> {
    if committed == today {
        return None;
    }
    if committed.triangles.len() != today.triangles.len() {
        return Some(format!(
            "{} triangles committed, {} today",
            committed.triangles.len(),
            today.triangles.len()
        ));
    }
    if let Some(i) =
        (0..today.triangles.len()).find(|&i| committed.triangles[i] != today.triangles[i])
    {
        return Some(format!("triangle {i} differs"));
    }
    if let Some(i) = (0..committed.materials.len().min(today.materials.len()))
        .find(|&i| committed.materials[i] != today.materials[i])
    {
        return Some(format!(
            "material {i} ('{}') differs",
            committed.materials[i].name
        ));
    }
    if committed.materials.len() != today.materials.len() {
        return Some("the material count differs".to_string());
    }
    Some("the camera, film, lights or header differ".to_string())
}

/// An RGB EXR of `size` as rows of [r, g, b], top row first (read by splitray's reader,
/// which keeps the stored values bit for bit).
pub fn read_rgb(path: &Path, size: (u32, u32)) -> Vec<[f32; 3]> {
    let (film, _) = splitray::film::read_exr(path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (film.width(), film.height()),
        size,
        "{}: size differs from the manifest's",
        path.display()
    );
    film.mean_rgb_buffer()
}

/// The figures of one comparison (see the module docs for the tests).
#[derive(Clone, Debug)]
pub struct Comparison {
    pub reference: String,
    /// Image means (all pixels and channels) of the image and the reference.
    pub mean: f64,
    pub reference_mean: f64,
    /// Pixel channels with |z| > [`PIXEL_Z`], how many of them below the reference, and
    /// how many beyond 4.
    pub beyond: usize,
    pub beyond_below: usize,
    pub beyond4: usize,
    pub total: usize,
    pub max_z: f64,
    /// (x, y) of the pixel with the largest |z|.
    pub worst_pixel: (usize, usize),
    /// Largest |z| of the [`BLOCK`]×[`BLOCK`] block sums, and that block's (x, y) corner.
    pub block_max_z: f64,
    pub worst_block: (usize, usize),
}

/// z of a difference `d` with variance `v` (0 for 0 / 0, ∞ for a difference without
/// variance).
fn z_score(d: f64, v: f64) -> f64 {
    if v > 0.0 {
        d.abs() / v.sqrt()
    } else if d == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// Compares `(mean, stderr)` of an image of width `width` with a reference's.
pub fn compare_images(
    reference: &str,
    width: usize,
    (mean, se): (&[[f32; 3]], &[[f32; 3]]),
    (ref_mean, ref_se): (&[[f32; 3]], &[[f32; 3]]),
) -> Comparison {
    let height = mean.len() / width;
    let diff = |p: usize, c: usize| mean[p][c] as f64 - ref_mean[p][c] as f64;
    let var = |p: usize, c: usize| (se[p][c] as f64).powi(2) + (ref_se[p][c] as f64).powi(2);

    let (mut beyond, mut beyond_below, mut beyond4) = (0, 0, 0);
    let (mut max_z, mut worst) = (0.0f64, 0usize);
    for p in 0..mean.len() {
        for c in 0..3 {
            let z = z_score(diff(p, c), var(p, c));
            if z > PIXEL_Z {
                beyond += 1;
                beyond_below += (diff(p, c) < 0.0) as usize;
            }
            beyond4 += (z > 4.0) as usize;
            if z > max_z {
                max_z = z;
                worst = p;
            }
        }
    }

    let (mut block_max_z, mut worst_block) = (0.0f64, (0, 0));
    for by in (0..height).step_by(BLOCK) {
        for bx in (0..width).step_by(BLOCK) {
            for c in 0..3 {
                let (mut d, mut v) = (0.0f64, 0.0f64);
                for y in by..(by + BLOCK).min(height) {
                    for x in bx..(bx + BLOCK).min(width) {
                        d += diff(y * width + x, c);
                        v += var(y * width + x, c);
                    }
                }
                let z = z_score(d, v);
                if z > block_max_z {
                    block_max_z = z;
                    worst_block = (bx, by);
                }
            }
        }
    }

    let average = |img: &[[f32; 3]]| -> f64 {
        img.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * img.len()) as f64
    };
    Comparison {
        reference: reference.to_string(),
        mean: average(mean),
        reference_mean: average(ref_mean),
        beyond,
        beyond_below,
        beyond4,
        total: 3 * mean.len(),
        max_z,
        worst_pixel: (worst % width, worst / width),
        block_max_z,
        worst_block,
    }
}

impl Comparison {
    /// (image mean − reference mean) / reference mean.
    pub fn relative_error(&self) -> f64 {
        (self.mean - self.reference_mean) / self.reference_mean
    }

    /// Fraction of pixel channels with |z| > [`PIXEL_Z`].
    pub fn fraction_beyond(&self) -> f64 {
        self.beyond as f64 / self.total as f64
    }

    /// The tests this comparison fails, in words (empty: it agrees).
    pub fn failures(&self) -> Vec<String> {
        // Written as "passes" tests so that a NaN fails each of them.
        let mean_passes = self.relative_error().abs() < MEAN_TOLERANCE;
        let pixels_pass = self.fraction_beyond() < PIXEL_FRACTION;
        let blocks_pass = self.block_max_z < BLOCK_Z;
        let mut failures = Vec::new();
        if !mean_passes {
            failures.push(format!(
                "image mean differs by {:+.3}% (tolerance {}%)",
                self.relative_error() * 100.0,
                MEAN_TOLERANCE * 100.0
            ));
        }
        if !pixels_pass {
            failures.push(format!(
                "{:.2}% of pixel channels beyond {PIXEL_Z} sigma (at most {}%)",
                self.fraction_beyond() * 100.0,
                PIXEL_FRACTION * 100.0
            ));
        }
        if !blocks_pass {
            failures.push(format!(
                "the {BLOCK}x{BLOCK} block at ({}, {}) differs by {:.2} sigma (at most {BLOCK_Z})",
                self.worst_block.0, self.worst_block.1, self.block_max_z
            ));
        }
        failures
    }

    /// One line with every figure, for logs and notes.
    pub fn summary(&self) -> String {
        format!(
            "vs {}: image mean {:.6} vs {:.6} ({:+.3}%); {} of {} pixel channels with |z| > {PIXEL_Z} \
             ({:.2}%, {} below the reference), {} with |z| > 4, max |z| {:.2} at pixel ({}, {}); \
             {BLOCK}x{BLOCK} blocks: max |z| {:.2} at ({}, {})",
            self.reference,
            self.mean,
            self.reference_mean,
            self.relative_error() * 100.0,
            self.beyond,
            self.total,
            self.fraction_beyond() * 100.0,
            self.beyond_below,
            self.beyond4,
            self.max_z,
            self.worst_pixel.0,
            self.worst_pixel.1,
            self.block_max_z,
            self.worst_block.0,
            self.worst_block.1
        )
    }

    /// Prints `what: summary` and panics with the failures, if any.
    pub fn assert_agrees(&self, what: &str) {
        eprintln!("{what} {}", self.summary());
        let failures = self.failures();
        assert!(
            failures.is_empty(),
            "{what} disagrees with {}: {}",
            self.reference,
            failures.join("; ")
        );
    }
}
