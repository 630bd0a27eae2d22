//! The display kernel (glsl/display/tonemap.comp) against its CPU twin, on every view, at
//! edge sizes (one pixel, non-powers of two, magnified, shrunk, letterboxed, an empty
//! output, a 2-megapixel film) and on adversarial films (NaN, infinities, negatives,
//! values at and one ULP below every 8-bit step, zero and huge weights, exposures that
//! overflow); and a film read from the GPU while rendering against the film's sums.
//! Pixels must be equal, except that on a device whose division is not correctly rounded
//! an estimate on an 8-bit step may land on either side of it ([`assert_same`]).

use crate::common;

use splitray::display::readback::FilmReader;
use splitray::display::tonemap::{
    depth_range, srgb8_thresholds, tonemap_cpu, AovBuffers, ToneParams, Tonemapper, View,
};
use splitray::film::png_out::{preview_rgb8, PreviewSettings};
use splitray::integrator::aov::Aovs;
use splitray::integrator::IntegratorKind;
use splitray::render::{create_integrator, RenderOptions};
use splitray::vk::{Gpu, MemoryKind, StreamKind};

/// Deterministic xorshift numbers for the test films.
struct Rng(u32);

impl Rng {
    fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }

    fn unit(&mut self) -> f32 {
        (self.next() >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// A film whose pixels cycle through the hard cases, then random sums and weights.
fn adversarial_film(n: usize, rng: &mut Rng) -> Vec<[f32; 4]> {
    let t = srgb8_thresholds();
    let below = |x: f32| f32::from_bits(x.to_bits().saturating_sub(1));
    let mut special: Vec<[f32; 4]> = vec![
        [f32::NAN, 0.5, 0.5, 1.0],
        [0.5, f32::INFINITY, 0.5, 1.0],
        [0.5, 0.5, f32::NEG_INFINITY, 1.0],
        [-1.0, -0.0, 0.0, 1.0],
        [1e38, 3e38, 1.0, 1.0],
        [1e-40, 1e-45, 1e-38, 1.0],
        [5.0, 6.0, 7.0, 0.0],
        [5.0, 6.0, 7.0, -2.0],
        [5.0, 6.0, 7.0, f32::NAN],
        [1.0, 2.0, 3.0, 1e-40],
        [0.25, 0.5, 0.75, 1e30],
        [3.0, 3.0, 3.0, 3.0],
    ];
    for (k, &step) in t.iter().enumerate().skip(1) {
        let weight = if k % 2 == 0 { 1.0 } else { 7.0 };
        special.push([step, below(step), step * 7.0, weight]);
    }
    (0..n)
        .map(|i| match special.get(i) {
            Some(p) => *p,
            None => {
                let w = (rng.next() % 1000 + 1) as f32;
                [
                    rng.unit() * 2.0 * w,
                    rng.unit() * w,
                    rng.unit() * 0.1 * w,
                    w,
                ]
            }
        })
        .collect()
}

fn adversarial_aovs(n: usize, rng: &mut Rng) -> Aovs {
    let mut aovs = Aovs {
        depth: Vec::with_capacity(n),
        triangle_id: Vec::with_capacity(n),
        normal: Vec::with_capacity(n),
    };
    for i in 0..n {
        let miss = i % 7 == 3;
        aovs.depth.push(match i % 11 {
            _ if miss => f32::INFINITY,
            5 => f32::NAN,
            _ => 0.5 + rng.unit() * 20.0,
        });
        aovs.triangle_id
            .push(if miss { u32::MAX } else { rng.next() % 100_000 });
        let n3 = [rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5];
        let len = (n3[0] * n3[0] + n3[1] * n3[1] + n3[2] * n3[2])
            .sqrt()
            .max(1e-6);
        aovs.normal.push(match i % 13 {
            _ if miss => [0.0; 3],
            4 => [1.0, -1.0, 0.0],
            _ => n3.map(|c| c / len),
        });
    }
    aovs
}

fn run_kernel(
    gpu: &Gpu,
    tonemapper: &Tonemapper,
    params: &ToneParams,
    film: &splitray::vk::Buffer,
    aovs: &AovBuffers,
) -> Vec<u32> {
    let n = params.out_pixels();
    let out = gpu
        .create_buffer("test-pixels", (n as u64 * 4).max(4), MemoryKind::Readback)
        .unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    tonemapper
        .record(&mut rec, params, film, aovs, &out)
        .unwrap();
    let done = rec.submit(&[]).unwrap();
    let mut pixels = out.read_after::<u32>(&done).unwrap();
    pixels.truncate(n);
    pixels
}

/// `film` with every finite sum scaled by `factor` (weights kept).
fn scaled_sums(film: &[[f32; 4]], factor: f32) -> Vec<[f32; 4]> {
    let scale = |x: f32| {
        if x.is_finite() {
            (x * factor).clamp(-f32::MAX, f32::MAX)
        } else {
            x
        }
    };
    film.iter()
        .map(|p| [scale(p[0]), scale(p[1]), scale(p[2]), p[3]])
        .collect()
}

/// The pixels' bytes, low byte first.
fn bytes(p: u32) -> [u32; 4] {
    [0, 8, 16, 24].map(|shift| p >> shift & 255)
}

/// Asserts the kernel's pixels are the CPU twin's. `bounds`, for the colour view: the
/// twin's pixels for the film with its sums scaled down and up by 2⁻²¹. The colour view
/// divides each sum by its weight, and Vulkan lets a device's division be 2.5 ULP from
/// the quotient (the CPU's is correctly rounded; NVIDIA's is not), so a mean that lies on
/// an 8-bit step may fall on either side of it there. Scaling the sums by 2⁻²¹ (4 to 8
/// ULP, less half a ULP for each rounding of the scaled sum and its quotient) moves each
/// mean further than the device may, and the encoding is monotonic: a pixel that differs
/// from the twin's must lie, byte by byte, between those of the scaled films.
fn assert_same(
    gpu: &[u32],
    cpu: &[u32],
    bounds: Option<[&[u32]; 2]>,
    what: &str,
    film: &[[f32; 4]],
) {
    assert_eq!(gpu.len(), cpu.len(), "{what}: pixel count");
    let allowed = |i: usize| {
        bounds.is_some_and(|[lo, hi]| {
            let (g, a, b) = (bytes(gpu[i]), bytes(lo[i]), bytes(hi[i]));
            (0..4).all(|c| a[c].min(b[c]) <= g[c] && g[c] <= a[c].max(b[c]))
        })
    };
    let differ: Vec<usize> = (0..gpu.len()).filter(|&i| gpu[i] != cpu[i]).collect();
    if let Some(&i) = differ.iter().find(|&&i| !allowed(i)) {
        panic!(
            "{what}: {} pixels differ, at least one beyond the rounding of a division; first \
             at {i}: GPU {:08x}, CPU {:08x} (film[{i}] if unscaled: {:?})",
            differ.len(),
            gpu[i],
            cpu[i],
            film.get(i)
        );
    }
    if !differ.is_empty() {
        eprintln!(
            "{what}: {} pixels on an 8-bit step, within a division's rounding",
            differ.len()
        );
    }
}

#[test]
fn kernel_matches_its_cpu_twin_on_every_view_and_edge_size() {
    let gpu = common::gpu();
    let tonemapper = Tonemapper::new(&gpu).unwrap();
    let mut rng = Rng(0x1234_5678);
    // (film, output): identity, magnified, letterboxed, shrunk, empty output, large.
    let cases: [([u32; 2], [u32; 2]); 9] = [
        ([1, 1], [1, 1]),
        ([1, 1], [7, 5]),
        ([3, 5], [640, 480]),
        ([64, 64], [64, 64]),
        ([17, 300], [300, 17]),
        ([1000, 1], [250, 3]),
        ([257, 129], [1024, 768]),
        ([5, 5], [0, 0]),
        ([1920, 1080], [1920, 1080]),
    ];
    for (film_size, out) in cases {
        let n = film_size[0] as usize * film_size[1] as usize;
        let film = adversarial_film(n, &mut rng);
        let aovs = adversarial_aovs(n, &mut rng);
        let film_buffer = gpu.upload("test-film", &film).unwrap();
        let aov_buffers = AovBuffers::upload(&gpu, &aovs).unwrap();
        let range = depth_range(&aovs.depth);
        let large = n > 1 << 20;
        for view in View::ALL {
            if large && view != View::Colour {
                continue;
            }
            let exposures: &[f32] = match view {
                View::Colour if !large => &[1.0, 0.088_388_35, 128.0, 1.7e38],
                _ => &[1.0],
            };
            for &exposure in exposures {
                for bgra in [false, true] {
                    let params = ToneParams::new(film_size, out, view, exposure, bgra, range);
                    let what = format!(
                        "{film_size:?} into {out:?}, {} view, exposure {exposure}, bgra {bgra}",
                        view.name()
                    );
                    let gpu_pixels =
                        run_kernel(&gpu, &tonemapper, &params, &film_buffer, &aov_buffers);
                    let cpu_pixels = tonemap_cpu(&params, &film, &aovs);
                    let bounds = (view == View::Colour).then(|| {
                        [1.0 - 2f32.powi(-21), 1.0 + 2f32.powi(-21)]
                            .map(|f| tonemap_cpu(&params, &scaled_sums(&film, f), &aovs))
                    });
                    let bounds = bounds.as_ref().map(|[lo, hi]| [&lo[..], &hi[..]]);
                    assert_same(&gpu_pixels, &cpu_pixels, bounds, &what, &film);
                }
            }
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn a_film_read_while_rendering_is_the_films_mean_and_shows_as_its_png() {
    let gpu = common::gpu();
    let scene = splitray::scene::load("cornell-box").unwrap();
    let options = RenderOptions::resolve(
        &scene,
        Some(23),
        Some(17),
        Some(3),
        Some(7),
        Some(IntegratorKind::Primary),
        None,
    )
    .unwrap();
    let mut integrator = create_integrator(&gpu, &scene, &options).unwrap();
    integrator.render_passes(0, 3).unwrap();
    let film = integrator
        .device_film()
        .expect("primary keeps its film on the GPU");
    assert_eq!((film.width, film.height), (23, 17));
    let reader = FilmReader::new(&film).unwrap();
    let mean = reader.read_mean(&film).unwrap();
    let sums = integrator.sums().unwrap();
    let bits =
        |v: &[[f32; 3]]| -> Vec<[u32; 3]> { v.iter().map(|p| p.map(f32::to_bits)).collect() };
    assert_eq!(bits(&mean), bits(&sums.mean()));

    // The colour view of the film on the GPU, unscaled, is the PNG writer's image.
    let aovs = Aovs {
        depth: vec![1.0; 23 * 17],
        triangle_id: vec![0; 23 * 17],
        normal: vec![[0.0; 3]; 23 * 17],
    };
    let params = ToneParams::new([23, 17], [23, 17], View::Colour, 1.0, false, (0.0, 0.0));
    let tonemapper = Tonemapper::new(&gpu).unwrap();
    let aov_buffers = AovBuffers::upload(&gpu, &aovs).unwrap();
    let pixels = run_kernel(&gpu, &tonemapper, &params, &film.sums, &aov_buffers);
    let shown: Vec<u8> = pixels
        .iter()
        .flat_map(|p| [*p as u8, (p >> 8) as u8, (p >> 16) as u8])
        .collect();
    let png = preview_rgb8(&sums.to_film().unwrap(), &PreviewSettings::default());
    assert_eq!(shown, png);
    drop(integrator);
    common::assert_clean(&gpu);
}
