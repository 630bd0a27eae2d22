//! The film (or an AOV) as 8-bit pixels on screen: the `display/tonemap` kernel
//! ([`Tonemapper`]) and its CPU twin ([`tonemap_cpu`]).
//!
//! Colour is what the PNG writer makes of the film (`film::png_out`): estimate × exposure,
//! clamped, sRGB-encoded to 8 bits, magenta where the estimate is not finite. Subnormal
//! sums, weights and estimates count as zero (devices may flush them or not; this way
//! all show the same; at exposure 1 they encode as 0 anyway, as in the PNG). The sRGB
//! step is a table ([`srgb8_thresholds`]): for each 8-bit value k, the smallest linear
//! value the PNG writer encodes as k or more, found by bisection over the `f32`s in
//! [0, 1]; a pixel's value is the number of thresholds at or below it. The kernel and the
//! twin both search that table, so they agree with each other and with the PNG writer
//! without evaluating `pow` (whose GPU precision is loose) at all.
//!
//! The AOV views: depth (near bright, the farthest hit 25, misses black), normals
//! (components from [-1, 1] to 0..255), triangle ids (a colour per triangle from a PCG
//! hash). Every view is scaled into a rectangle of the output ([`fit`]) by nearest
//! neighbour in integer arithmetic, on a grey background.

use std::sync::OnceLock;

use bytemuck::{Pod, Zeroable};

use crate::film::png_out::{tonemap_pixel, PreviewSettings, NON_FINITE_COLOR};
use crate::integrator::aov::Aovs;
use crate::shaders;
use crate::vk::{self, compute_pipeline, Buffer, ComputePipeline, Gpu, Recorder};

const WORKGROUP: u32 = 64;

/// The grey around the film where the output's shape differs from the film's.
pub const BACKGROUND: [u8; 3] = [24, 24, 24];

/// What a view shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum View {
    /// The render, tone-mapped as the PNG is.
    #[default]
    Colour,
    Depth,
    Normal,
    TriangleId,
}

impl View {
    pub const ALL: [View; 4] = [View::Colour, View::Depth, View::Normal, View::TriangleId];

    /// The next view in [`View::ALL`] (wrapping).
    pub fn next(self) -> Self {
        let i = Self::ALL.iter().position(|v| *v == self).unwrap_or(0);
        Self::ALL[(i + 1) % Self::ALL.len()]
    }

    pub fn name(self) -> &'static str {
        match self {
            View::Colour => "colour",
            View::Depth => "depth",
            View::Normal => "normal",
            View::TriangleId => "triangle id",
        }
    }

    fn mode(self) -> u32 {
        self as u32
    }
}

/// Push constants of the kernel (`ToneParams` in glsl/display/tonemap.comp).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct ToneParams {
    pub film_width: u32,
    pub film_height: u32,
    pub out_width: u32,
    pub out_height: u32,
    /// x, y, width, height of the film's rectangle in the output ([`fit`]).
    pub view_rect: [u32; 4],
    pub exposure: f32,
    pub mode: u32,
    /// 1: pack B, G, R, A from the low byte up; 0: R, G, B, A.
    pub bgra: u32,
    pub depth_near: f32,
    pub depth_scale: f32,
    pub pad: [u32; 3],
}

const _: () = assert!(size_of::<ToneParams>() == 64);

impl ToneParams {
    /// `view` of a `film`-sized film into an `out`-sized output (the film fitted into it),
    /// with `exposure` for colour and the film's [`depth_range`].
    pub fn new(
        film: [u32; 2],
        out: [u32; 2],
        view: View,
        exposure: f32,
        bgra: bool,
        (depth_near, depth_scale): (f32, f32),
    ) -> Self {
        Self {
            film_width: film[0],
            film_height: film[1],
            out_width: out[0],
            out_height: out[1],
            view_rect: fit(film, out),
            exposure,
            mode: view.mode(),
            bgra: bgra as u32,
            depth_near,
            depth_scale,
            pad: [0; 3],
        }
    }

    pub fn out_pixels(&self) -> usize {
        self.out_width as usize * self.out_height as usize
    }
}

/// Where a `film`-sized image goes in an `out`-sized output: as large as fits with its
/// aspect kept, magnified by a whole factor when it is smaller (sharp square pixels),
/// centred. `[x, y, width, height]`; all zero when either size is empty.
pub fn fit(film: [u32; 2], out: [u32; 2]) -> [u32; 4] {
    if film.contains(&0) || out.contains(&0) {
        return [0; 4];
    }
    let scale = (out[0] as f64 / film[0] as f64).min(out[1] as f64 / film[1] as f64);
    let scale = if scale >= 1.0 { scale.floor() } else { scale };
    let w = ((film[0] as f64 * scale).round() as u32).clamp(1, out[0]);
    let h = ((film[1] as f64 * scale).round() as u32).clamp(1, out[1]);
    [(out[0] - w) / 2, (out[1] - h) / 2, w, h]
}

/// The depth view's range: the nearest finite depth and 1 / (farthest − nearest)
/// (0 where all hits are at one depth or there are none).
pub fn depth_range(depth: &[f32]) -> (f32, f32) {
    let finite = depth.iter().copied().filter(|d| d.is_finite());
    let (near, far) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| {
        (lo.min(d), hi.max(d))
    });
    if near.is_finite() && far > near {
        (near, 1.0 / (far - near))
    } else if near.is_finite() {
        (near, 0.0)
    } else {
        (0.0, 0.0)
    }
}

/// The PNG writer's 8-bit encoding of one linear channel (exposure 1).
fn png_encode(x: f32) -> u8 {
    tonemap_pixel([x, 0.0, 0.0], &PreviewSettings::default())[0]
}

/// `t[k]` (k = 1..=255): the smallest `f32` in [0, 1] that the PNG writer encodes as k
/// or more; `t[0] = 0` is never read.
pub fn srgb8_thresholds() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [0.0f32; 256];
        for (k, slot) in t.iter_mut().enumerate().skip(1) {
            // Non-negative f32s order as their bit patterns: bisect over those in [0, 1].
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if png_encode(f32::from_bits(mid)) as usize >= k {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *slot = f32::from_bits(lo);
        }
        t
    })
}

/// The kernel's sRGB encoding of linear `x` in [0, 1] (`encode_srgb8`).
pub fn encode_srgb8(x: f32, thresholds: &[f32; 256]) -> u8 {
    let mut k = 0usize;
    let mut step = 128;
    while step > 0 {
        if thresholds[k + step] <= x {
            k += step;
        }
        step >>= 1;
    }
    k as u8
}

fn unorm8(x: f32) -> u32 {
    (x * 255.0 + 0.5) as u32
}

/// Zero for subnormal numbers (the kernel's `flush`: devices may flush them or not).
fn flush(x: f32) -> f32 {
    if x.abs() < f32::MIN_POSITIVE {
        0.0
    } else {
        x
    }
}

fn colour(s: [f32; 4], exposure: f32, thresholds: &[f32; 256]) -> [u8; 3] {
    let s = s.map(flush);
    let mean = if s[3] > 0.0 {
        [s[0] / s[3], s[1] / s[3], s[2] / s[3]].map(flush)
    } else {
        [0.0; 3]
    };
    if mean.iter().any(|c| !c.is_finite()) {
        return NON_FINITE_COLOR;
    }
    mean.map(|m| {
        let mut x = (m * exposure).max(0.0);
        if x.is_infinite() {
            x = f32::MAX;
        }
        encode_srgb8(x.min(1.0), thresholds)
    })
}

fn depth_view(d: f32, near: f32, scale: f32) -> [u8; 3] {
    if !d.is_finite() {
        return [0; 3];
    }
    let v = (1.0 - (d - near) * scale).clamp(0.0, 1.0);
    [(25 + (v * 230.0 + 0.5) as u32) as u8; 3]
}

fn normal_view(n: [f32; 3]) -> [u8; 3] {
    if n == [0.0; 3] {
        return [0; 3];
    }
    n.map(|c| unorm8((c * 0.5 + 0.5).clamp(0.0, 1.0)) as u8)
}

/// The triangle view's colour of triangle `id` (black for a miss).
pub fn triangle_colour(id: u32) -> [u8; 3] {
    if id == u32::MAX {
        return [0; 3];
    }
    let state = id.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    let h = (word >> 22) ^ word;
    [h, h >> 8, h >> 16].map(|b| (64 + (b & 255) * 3 / 4) as u8)
}

/// Packs an RGB pixel as the kernel does.
pub fn pack(rgb: [u8; 3], bgra: bool) -> u32 {
    let [a, b, c] = if bgra { [rgb[2], rgb[1], rgb[0]] } else { rgb };
    a as u32 | (b as u32) << 8 | (c as u32) << 16 | 0xFF00_0000
}

/// The CPU twin of the kernel: `film` holds one `[sum r, g, b, weight]` per pixel and
/// `aovs` the film's AOVs; returns the output's packed pixels, row 0 at the top.
pub fn tonemap_cpu(params: &ToneParams, film: &[[f32; 4]], aovs: &Aovs) -> Vec<u32> {
    let thresholds = srgb8_thresholds();
    let (w, h) = (params.out_width, params.out_height);
    let [vx, vy, vw, vh] = params.view_rect;
    let bgra = params.bgra != 0;
    let mut out = Vec::with_capacity(params.out_pixels());
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = (x.wrapping_sub(vx), y.wrapping_sub(vy));
            let rgb = if dx < vw && dy < vh {
                let fx = dx * params.film_width / vw;
                let fy = dy * params.film_height / vh;
                let p = (fy * params.film_width + fx) as usize;
                match params.mode {
                    1 => depth_view(aovs.depth[p], params.depth_near, params.depth_scale),
                    2 => normal_view(aovs.normal[p]),
                    3 => triangle_colour(aovs.triangle_id[p]),
                    _ => colour(film[p], params.exposure, thresholds),
                }
            } else {
                BACKGROUND
            };
            out.push(pack(rgb, bgra));
        }
    }
    out
}

/// The film's AOVs on the GPU, as the kernel reads them.
pub struct AovBuffers {
    depth: Buffer,
    triangle_id: Buffer,
    normal: Buffer,
}

impl AovBuffers {
    pub fn upload(gpu: &Gpu, aovs: &Aovs) -> vk::Result<Self> {
        let normal: Vec<[f32; 4]> = aovs
            .normal
            .iter()
            .map(|n| [n[0], n[1], n[2], 0.0])
            .collect();
        Ok(Self {
            depth: gpu.upload("display-depth", &aovs.depth)?,
            triangle_id: gpu.upload("display-triangle-id", &aovs.triangle_id)?,
            normal: gpu.upload("display-normal", &normal)?,
        })
    }
}

/// The `display/tonemap` kernel and its sRGB table.
pub struct Tonemapper {
    pipeline: ComputePipeline,
    thresholds: Buffer,
}

impl Tonemapper {
    pub fn new(gpu: &Gpu) -> vk::Result<Self> {
        Ok(Self {
            pipeline: compute_pipeline(
                gpu,
                shaders::DISPLAY_TONEMAP,
                6,
                size_of::<ToneParams>() as u32,
                &[WORKGROUP],
            )?,
            thresholds: gpu.upload("display-srgb8-thresholds", srgb8_thresholds())?,
        })
    }

    /// Records the kernel: `params.out_pixels()` packed pixels into `out` from `film`
    /// (`[sum r, g, b, weight]` per pixel) and `aovs`.
    pub fn record(
        &self,
        rec: &mut Recorder,
        params: &ToneParams,
        film: &Buffer,
        aovs: &AovBuffers,
        out: &Buffer,
    ) -> vk::Result<()> {
        let needed = params.out_pixels() as u64 * 4;
        if out.size() < needed {
            return Err(vk::VkError::Usage(format!(
                "'{}' holds {} bytes, a {}x{} view needs {needed}",
                out.name(),
                out.size(),
                params.out_width,
                params.out_height
            )));
        }
        rec.dispatch_items(
            &self.pipeline,
            &[
                film.into(),
                (&aovs.depth).into(),
                (&aovs.triangle_id).into(),
                (&aovs.normal).into(),
                (&self.thresholds).into(),
                out.into(),
            ],
            params,
            params.out_pixels() as u64,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn next_up(x: f32) -> f32 {
        f32::from_bits(x.to_bits() + 1)
    }

    fn next_down(x: f32) -> f32 {
        if x == 0.0 {
            x
        } else {
            f32::from_bits(x.to_bits() - 1)
        }
    }

    #[test]
    fn thresholds_split_the_png_encoding_exactly() {
        let t = srgb8_thresholds();
        for k in 1..256 {
            assert!(t[k] > t[k - 1] || k == 1, "thresholds rise: {k}");
            assert!(
                png_encode(t[k]) as usize >= k,
                "t[{k}] encodes to k or more"
            );
            assert!((png_encode(next_down(t[k])) as usize) < k, "below t[{k}]");
        }
        // The encoding through the table is the PNG writer's at and around every step,
        // and on a dense sweep of [0, 1].
        for &x in t.iter() {
            for y in [next_down(x), x, next_up(x)] {
                assert_eq!(encode_srgb8(y, t), png_encode(y), "x = {y:e}");
            }
        }
        let mut state = 0x2545_f491u32;
        for i in 0..200_000u32 {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let x = if i % 2 == 0 {
                (state >> 8) as f32 / (1u32 << 24) as f32
            } else {
                f32::from_bits(state % 1.0f32.to_bits())
            };
            assert_eq!(encode_srgb8(x, t), png_encode(x), "x = {x:e}");
        }
        assert_eq!(encode_srgb8(0.0, t), 0);
        assert_eq!(encode_srgb8(1.0, t), 255);
    }

    #[test]
    fn colour_view_is_the_png_writers_image() {
        use crate::film::FilmSums;
        let (w, h) = (7u32, 3u32);
        let mut sums = FilmSums::new(w, h, 1, false);
        for pass in 0..3 {
            let estimate: Vec<[f64; 3]> = (0..w * h)
                .map(|i| {
                    let v = (i as f64 * 0.173 + pass as f64 * 0.31).fract() * 1.6 - 0.1;
                    [v, v * 0.5, (v * 7.0).fract()]
                })
                .collect();
            sums.add_pass(&estimate);
        }
        let (gpu_sums, _) = sums.to_gpu(1.0);
        let aovs = Aovs {
            depth: vec![1.0; (w * h) as usize],
            triangle_id: vec![0; (w * h) as usize],
            normal: vec![[0.0; 3]; (w * h) as usize],
        };
        let range = depth_range(&aovs.depth);
        let params = ToneParams::new([w, h], [w, h], View::Colour, 1.0, false, range);
        let pixels = tonemap_cpu(&params, &gpu_sums, &aovs);
        let film = sums.to_film().unwrap();
        let png = crate::film::png_out::preview_rgb8(&film, &PreviewSettings::default());
        let shown: Vec<u8> = pixels
            .iter()
            .flat_map(|p| [*p as u8, (p >> 8) as u8, (p >> 16) as u8])
            .collect();
        assert_eq!(shown, png);
    }

    #[test]
    fn fit_keeps_the_aspect_and_magnifies_by_whole_factors() {
        assert_eq!(fit([64, 64], [256, 256]), [0, 0, 256, 256]);
        assert_eq!(fit([64, 48], [300, 200]), [22, 4, 256, 192]);
        assert_eq!(fit([100, 50], [100, 100]), [0, 25, 100, 50]);
        assert_eq!(fit([1000, 500], [100, 100]), [0, 25, 100, 50]);
        assert_eq!(fit([1, 1], [3, 5]), [0, 1, 3, 3]);
        assert_eq!(fit([0, 5], [3, 5]), [0; 4]);
        assert_eq!(fit([5, 5], [0, 5]), [0; 4]);
        assert_eq!(fit([16384, 1], [1, 1]), [0, 0, 1, 1]);
    }

    #[test]
    fn views_cycle_and_depth_ranges_ignore_misses() {
        assert_eq!(View::Colour.next(), View::Depth);
        assert_eq!(View::TriangleId.next(), View::Colour);
        assert_eq!(
            depth_range(&[f32::INFINITY, 2.0, 4.0, f32::NAN]),
            (2.0, 0.5)
        );
        assert_eq!(depth_range(&[3.0, 3.0]), (3.0, 0.0));
        assert_eq!(depth_range(&[f32::INFINITY]), (0.0, 0.0));
        assert_eq!(depth_range(&[]), (0.0, 0.0));
        assert_eq!(triangle_colour(u32::MAX), [0; 3]);
        assert!(triangle_colour(7).iter().all(|&c| c >= 64));
    }
}
