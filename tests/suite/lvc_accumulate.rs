//! `camera_accumulate` (both builds of its visibility tally: per subgroup and per
//! invocation) against its CPU twin `twin::accumulate` on synthetic bounces: no live
//! path, one, sizes around the workgroup's and a large one; live ids in any order;
//! contributions absent, occluded, unoccluded, NaN and infinite. The radiance sums, the
//! non-finite count and the tally must be the twin's exactly (the kernel only adds, in
//! the twin's order).
//!
//! `splat` against `fixed::FixedFilm` on synthetic light-tracing contributions crowded
//! into a few slots of a film that already holds sums, so that low words carry into high
//! words at almost every addition: values just under 1, with a half, past the clamp,
//! negative, negative zero, denormal, NaN and infinite, absent and occluded, at splat
//! scales 1 and 2^-20. The film's words and the non-finite and clamp counters must be
//! the twin's exactly (integer sums do not depend on the atomics' order).
//!
//! `finish` against `twin::finish` on synthetic passes of radiance and splats about 1,
//! 2^70 and 2^-80 (whose squares leave f32's range), at the brightness scale that
//! brings them near 1, added to sums (and remainders) that already hold passes: a chunk
//! of the film's pixels, and a whole large film. Σ estimate and Σ (s · estimate)² must
//! be the twin's bit for bit (one invocation per pixel adds the passes in the twin's
//! order), and Σ estimate must hold every estimate's bits.
//!
//! Both on films past one storage binding (maxStorageBufferRange), which they take by
//! address: `finish` on the last pixels of such a film, `splat` into its last slots.

use crate::common;

use bytemuck::Zeroable;
use splitray::film::compensated;
use splitray::integrator::lvc::fixed::{FixedFilm, FIXED_MAX, FIXED_WORDS};
use splitray::integrator::lvc::gpu::{
    Contribution, LvcConstants, LvcPush, VisibilityTally, CONTRIBUTION_NONE, COUNTERS,
    COUNTER_CLAMPED, COUNTER_NON_FINITE,
};
use splitray::integrator::lvc::kernels::{AccumulateTally, Kernels};
use splitray::integrator::lvc::twin::{accumulate, finish, BounceRecords, FinishChunk};
use splitray::integrator::lvc::{LvcOptions, Variant};
use splitray::trace::{Hit, MISS};
use splitray::vk::{Gpu, StreamKind};

/// A synthetic bounce: `paths` live paths out of about twice as many, `connections`
/// slots each.
struct Bounce {
    connections: usize,
    base: usize,
    live_ids: Vec<u32>,
    emitted: Vec<Contribution>,
    contributions: Vec<Contribution>,
    shadow_hits: Vec<Hit>,
    radiance: Vec<[f32; 4]>,
}

/// What a slot holds, drawn from one random word: mostly ordinary contributions, some
/// absent, a few NaN or infinite.
fn contribution(word: u32, value: f32) -> Contribution {
    let mut c = Contribution {
        value: [value, 0.5 * value, 2.0 * value],
        code: 2 | 3 << 16,
        weight: 0.5,
        target: 0,
        pad: [0; 2],
    };
    match word % 16 {
        0..=4 => c.code = CONTRIBUTION_NONE,
        5 => c.value[1] = f32::NAN,
        6 => c.value[2] = f32::INFINITY,
        7 => c.value[0] = f32::NEG_INFINITY,
        _ => {}
    }
    c
}

/// A shadow ray's answer drawn from one random word: a third occluded.
fn hit(word: u32) -> Hit {
    Hit {
        t: 1.0,
        triangle: if word % 3 == 0 { 7 } else { MISS },
        u: 0.0,
        v: 0.0,
    }
}

impl Bounce {
    fn new(paths: usize, connections: usize, seed: u64) -> Self {
        // Live paths are a scattered subset of the pass's paths, in shuffled order.
        let total = paths * 2 + 3;
        let mut ids: Vec<u32> = (0..total as u32).collect();
        let shuffle = common::random_u32s(total, seed);
        for i in (1..total).rev() {
            ids.swap(i, shuffle[i] as usize % (i + 1));
        }
        ids.truncate(paths);
        // The connections' region starts past the direct slots, as in the integrator.
        let base = paths.div_ceil(8) * 8 + 8;
        let slots = base + paths * connections;
        let words = common::random_u32s(2 * slots + paths, seed + 1);
        let values = common::uniforms(slots + paths, seed + 2);
        let radiance = common::uniforms(total, seed + 3)
            .into_iter()
            .map(|r| [r, 2.0 * r, 0.25 * r, 1.0])
            .collect();
        Self {
            connections,
            base,
            emitted: (0..paths)
                .map(|i| contribution(words[2 * slots + i], values[slots + i]))
                .collect(),
            contributions: (0..slots)
                .map(|s| contribution(words[s], values[s]))
                .collect(),
            shadow_hits: (0..slots).map(|s| hit(words[slots + s])).collect(),
            live_ids: ids,
            radiance,
        }
    }

    fn twin(&self) -> (Vec<[f32; 4]>, u32, VisibilityTally) {
        let mut radiance = self.radiance.clone();
        let records = BounceRecords {
            live_ids: &self.live_ids,
            emitted: &self.emitted,
            contributions: &self.contributions,
            shadow_hits: &self.shadow_hits,
            base: self.base,
            connections: self.connections,
        };
        let (non_finite, tally) = accumulate(&records, &mut radiance);
        (radiance, non_finite, tally)
    }

    fn on_gpu(&self, gpu: &Gpu, kernels: &Kernels) -> (Vec<[f32; 4]>, u32, VisibilityTally) {
        let constants = LvcConstants {
            connections: self.connections as u32,
            ..Zeroable::zeroed()
        };
        // A buffer of at least one element (no live path: nothing is read).
        fn upload<T: bytemuck::Pod>(gpu: &Gpu, name: &str, data: &[T]) -> splitray::vk::Buffer {
            if data.is_empty() {
                gpu.upload(name, &[T::zeroed()]).unwrap()
            } else {
                gpu.upload(name, data).unwrap()
            }
        }
        let buffers = [
            gpu.upload("constants", &[constants]).unwrap(),
            upload(gpu, "live-ids", &self.live_ids),
            upload(gpu, "emitted", &self.emitted),
            upload(gpu, "shadow-hits", &self.shadow_hits),
            upload(gpu, "contributions", &self.contributions),
            gpu.upload("radiance", &self.radiance).unwrap(),
            gpu.zeroed::<u32>("counters", COUNTERS).unwrap(),
            gpu.zeroed::<VisibilityTally>("tally", 1).unwrap(),
        ];
        let push = LvcPush {
            active_count: self.live_ids.len() as u32,
            base: self.base as u32,
            ..Default::default()
        };
        let bindings: Vec<_> = buffers.iter().map(|b| b.into()).collect();
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.dispatch_items(
            &kernels.camera_accumulate,
            &bindings,
            &push,
            self.live_ids.len() as u64,
        )
        .unwrap();
        gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
        let counters = buffers[6].read::<u32>().unwrap();
        (
            buffers[5].read().unwrap(),
            counters[COUNTER_NON_FINITE],
            buffers[7].read::<VisibilityTally>().unwrap()[0],
        )
    }
}

fn check(
    gpu: &Gpu,
    (tally, kernels): (AccumulateTally, &Kernels),
    paths: usize,
    connections: usize,
    seed: u64,
) {
    let bounce = Bounce::new(paths, connections, seed);
    let (want_radiance, want_non_finite, want_tally) = bounce.twin();
    let (radiance, non_finite, got_tally) = bounce.on_gpu(gpu, kernels);
    let what = format!("{tally:?}, {paths} paths, N = {connections}");
    for (id, (g, w)) in radiance.iter().zip(&want_radiance).enumerate() {
        assert!(
            g.iter().zip(w).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{what}: path {id}: {g:?} vs {w:?}"
        );
    }
    assert_eq!(non_finite, want_non_finite, "{what}: non-finite count");
    assert_eq!(got_tally, want_tally, "{what}: tally");
    if paths > 100 {
        // The synthetic mix leaves something in every entry to compare.
        assert!(want_tally.connections_unoccluded > 0 && want_tally.direct_unoccluded > 0);
        assert!(want_tally.connection_rays > want_tally.connections_unoccluded);
        assert!(want_non_finite > 0);
    }
}

#[test]
fn accumulation_and_tally_match_the_twin() {
    let gpu = common::gpu();
    let mut builds = vec![AccumulateTally::Atomic];
    if gpu.info().capabilities.subgroup_arithmetic {
        builds.push(AccumulateTally::Subgroup);
    }
    for &tally in &builds {
        let kernels = Kernels::with_tally(
            &gpu,
            &LvcOptions::new(Variant::LvcBdpt, false),
            u32::MAX,
            tally,
        )
        .unwrap();
        for (k, &paths) in [0usize, 1, 7, 63, 64, 65, 1000, 100_003].iter().enumerate() {
            for connections in [1, 5, 16] {
                check(
                    &gpu,
                    (tally, &kernels),
                    paths,
                    connections,
                    17 * k as u64 + connections as u64,
                );
            }
        }
    }
    common::assert_clean(&gpu);
}

/// Splat slots the contributions crowd into: few, so that every slot takes thousands of
/// additions and its low words carry often.
const SPLAT_SLOTS: usize = 3;

/// One channel of a synthetic splat, drawn from one random word. 0.9999999 has low
/// word 2^32 − 2^9, so nearly every addition after the first carries; 1.5 carries every
/// other time; 2 × FIXED_MAX is clamped at scale 1; −1, −0 and 1e-40 (denormal, flushed or
/// not) add nothing; NaN and ±∞ drop the whole contribution.
fn splat_channel(word: u32) -> f32 {
    match word % 16 {
        0..=5 => 0.999_999_9,
        6..=9 => 1.5,
        10 => 2.0 * FIXED_MAX,
        11 => -1.0,
        12 => -0.0,
        13 => 1e-40,
        14 => f32::NAN,
        _ if word & 0x100 == 0 => f32::INFINITY,
        _ => f32::NEG_INFINITY,
    }
}

/// Light-tracing contributions, their shadow hits (a third occluded) and a splat film
/// that already holds sums.
struct Splats {
    contributions: Vec<Contribution>,
    shadow_hits: Vec<Hit>,
    film: Vec<u32>,
}

impl Splats {
    fn new(count: usize, seed: u64) -> Self {
        Self::into_slots_from(count, seed, 0)
    }

    /// [`Splats::new`] crowding into the last [`SPLAT_SLOTS`] of a film of
    /// `first_slot + SPLAT_SLOTS` slots (the others hold sums too).
    fn into_slots_from(count: usize, seed: u64, first_slot: usize) -> Self {
        let words = common::random_u32s(5 * count, seed);
        let contributions = (0..count)
            .map(|k| {
                let w = &words[5 * k..5 * k + 5];
                Contribution {
                    value: [w[0], w[1], w[2]].map(splat_channel),
                    // One in eight absent, whatever its value.
                    code: if w[3] % 8 == 0 {
                        CONTRIBUTION_NONE
                    } else {
                        1 | 1 << 16
                    },
                    weight: 1.0,
                    target: (first_slot + w[4] as usize % SPLAT_SLOTS) as u32,
                    pad: [0; 2],
                }
            })
            .collect();
        let shadow_hits = words
            .iter()
            .skip(3)
            .step_by(5)
            .map(|&w| hit(w >> 8))
            .collect();
        Self {
            contributions,
            shadow_hits,
            film: common::random_u32s((first_slot + SPLAT_SLOTS) * FIXED_WORDS, seed + 1),
        }
    }

    /// `splat.comp` on the CPU: absent and occluded contributions skipped, those with
    /// a non-finite channel counted and dropped whole (before scaling, as the kernel
    /// tests them), the rest added by the fixed-point twin. Returns the film and the
    /// non-finite count.
    fn twin(&self, scale: f32) -> (FixedFilm, u32) {
        let mut film = FixedFilm::from_words(&self.film, scale);
        let mut non_finite = 0;
        for (c, h) in self.contributions.iter().zip(&self.shadow_hits) {
            if !c.is_some() || h.triangle != MISS {
                continue;
            }
            if c.value.iter().any(|v| !v.is_finite()) {
                non_finite += 1;
                continue;
            }
            film.add(c.target as usize, c.value);
        }
        (film, non_finite)
    }

    /// The film's words and the counters after `splat` at `scale`.
    fn on_gpu(&self, gpu: &Gpu, kernels: &Kernels, scale: f32) -> (Vec<u32>, Vec<u32>) {
        let constants = LvcConstants {
            brightness_scale: scale,
            ..Zeroable::zeroed()
        };
        // A buffer of at least one element (no contribution: nothing is read).
        let contributions = if self.contributions.is_empty() {
            gpu.upload("contributions", &[Contribution::zeroed()])
        } else {
            gpu.upload("contributions", &self.contributions)
        }
        .unwrap();
        let shadow_hits = if self.shadow_hits.is_empty() {
            gpu.upload("shadow-hits", &[Hit::zeroed()])
        } else {
            gpu.upload("shadow-hits", &self.shadow_hits)
        }
        .unwrap();
        let film = gpu.upload("splat-film", &self.film).unwrap();
        let counters = gpu.zeroed::<u32>("counters", COUNTERS).unwrap();
        let constants = gpu.upload("constants", &[constants]).unwrap();
        let push = LvcPush {
            active_count: self.contributions.len() as u32,
            ..Default::default()
        };
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.dispatch_items(
            &kernels.splat,
            &[
                (&contributions).into(),
                (&shadow_hits).into(),
                (&film).into(),
                (&counters).into(),
                (&constants).into(),
            ],
            &push,
            self.contributions.len() as u64,
        )
        .unwrap();
        gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
        (film.read().unwrap(), counters.read().unwrap())
    }
}

/// `splat` on `splats` at `scale` against the twin: the film's words and the counters.
fn check_splats(gpu: &Gpu, kernels: &Kernels, splats: &Splats, scale: f32, what: &str) {
    let (want, want_non_finite) = splats.twin(scale);
    let (words, counters) = splats.on_gpu(gpu, kernels, scale);
    assert!(
        FixedFilm::from_words(&words, scale).sums == want.sums,
        "{what}: film"
    );
    assert_eq!(
        counters[COUNTER_NON_FINITE], want_non_finite,
        "{what}: non-finite count"
    );
    assert_eq!(
        counters[COUNTER_CLAMPED] as u64, want.clamped,
        "{what}: clamp count"
    );
    if splats.contributions.len() > 1000 {
        // The mix leaves something in every count to compare.
        assert!(want_non_finite > 0, "{what}: no non-finite splat");
        assert_eq!(want.clamped > 0, scale == 1.0, "{what}: clamps");
        assert!(want.sums != FixedFilm::from_words(&splats.film, scale).sums);
    }
}

#[test]
fn splat_matches_the_fixed_point_twin() {
    let gpu = common::gpu();
    let kernels = Kernels::new(&gpu, &LvcOptions::new(Variant::LvcBdpt, false), u32::MAX).unwrap();
    for (k, &count) in [0usize, 1, 64, 65, 100_003].iter().enumerate() {
        let splats = Splats::new(count, 101 + k as u64);
        for scale in [1.0, 2f32.powi(-20)] {
            let what = format!("{count} contributions at scale {scale}");
            check_splats(&gpu, &kernels, &splats, scale, &what);
        }
    }
    common::assert_clean(&gpu);
}

/// Synthetic passes for `finish`: a film of `width × height` pixels whose chunk of
/// `pixel_count` pixels from `pixel_offset` adds `passes` estimates of about
/// 2^`exponent`, at the brightness scale 2^-`exponent`.
struct Finish {
    width: u32,
    height: u32,
    pixel_offset: usize,
    pixel_count: usize,
    scale: f32,
    radiance: Vec<[f32; 4]>,
    /// The splat film's words: whole parts below 4, so that splats are about the
    /// radiance's size.
    splat_words: Vec<u32>,
    /// The films it starts from: their sums, then the remainders.
    accum: Vec<[f32; 4]>,
    accum2: Vec<[f32; 4]>,
}

impl Finish {
    fn new(width: u32, height: u32, chunk: (usize, usize), passes: usize, exponent: i32) -> Self {
        let (pixel_offset, pixel_count) = chunk;
        let pixels = (width * height) as usize;
        let unit = 2f32.powi(exponent);
        let seed = pixels as u64 + exponent.unsigned_abs() as u64;
        let radiance = common::uniforms(passes * pixel_count, seed)
            .into_iter()
            .map(|r| [r * unit, 2.0 * r * unit, 0.0, 1.0])
            .collect();
        let splat_words = common::random_u32s(passes * pixels * FIXED_WORDS, seed + 1)
            .chunks_exact(FIXED_WORDS)
            .flat_map(|w| {
                // A third of the slots empty; high words small.
                let empty = w[3] % 3 == 0;
                let hi = |x: u32| if empty { 0 } else { x % 4 };
                let lo = |x: u32| if empty { 0 } else { x };
                [lo(w[0]), lo(w[1]), lo(w[2]), hi(w[3]), hi(w[4]), hi(w[5])]
            })
            .collect();
        let start = common::uniforms(pixels, seed + 2);
        // Sums of about 2^exponent with remainders well inside their last bit.
        let rest = |v: f32, k: i32| v * 2f32.powi(k);
        let accum = start
            .iter()
            .map(|&v| [v * unit, v * unit, v, 2.0])
            .chain(
                start
                    .iter()
                    .map(|&v| [rest(v * unit, -30), -rest(v * unit, -31), rest(v, -26), 0.0]),
            )
            .collect();
        let accum2 = start
            .iter()
            .map(|&v| [v, v, v, 0.0])
            .chain(
                start
                    .iter()
                    .map(|&v| [rest(v, -27), 0.0, -rest(v, -40), 0.0]),
            )
            .collect();
        Self {
            width,
            height,
            pixel_offset,
            pixel_count,
            scale: 1.0 / unit,
            radiance,
            splat_words,
            accum,
            accum2,
        }
    }

    fn splats(&self) -> FixedFilm {
        FixedFilm::from_words(&self.splat_words, self.scale)
    }

    fn twin(&self) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
        let (mut accum, mut accum2) = (self.accum.clone(), self.accum2.clone());
        let splats = self.splats();
        let chunk = FinishChunk {
            radiance: &self.radiance,
            splats: &splats,
            pixels: (self.width * self.height) as usize,
            pixel_offset: self.pixel_offset,
            pixel_count: self.pixel_count,
        };
        finish(&chunk, &mut accum, &mut accum2);
        (accum, accum2)
    }

    fn on_gpu(&self, gpu: &Gpu, kernels: &Kernels) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
        let constants = LvcConstants {
            width: self.width,
            height: self.height,
            brightness_scale: self.scale,
            ..Zeroable::zeroed()
        };
        let buffers = [
            gpu.upload("constants", &[constants]).unwrap(),
            gpu.upload("radiance", &self.radiance).unwrap(),
            gpu.upload("splat-film", &self.splat_words).unwrap(),
            gpu.upload("accum", &self.accum).unwrap(),
            gpu.upload("accum2", &self.accum2).unwrap(),
        ];
        let push = LvcPush {
            path_count: self.radiance.len() as u32,
            pixel_offset: self.pixel_offset as u32,
            pixel_count: self.pixel_count as u32,
            ..Default::default()
        };
        let bindings: Vec<_> = buffers.iter().map(|b| b.into()).collect();
        let mut rec = gpu.recorder(StreamKind::Main).unwrap();
        rec.dispatch_items(&kernels.finish, &bindings, &push, self.pixel_count as u64)
            .unwrap();
        gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
        (buffers[3].read().unwrap(), buffers[4].read().unwrap())
    }

    /// Σ estimate and Σ (s · estimate)² of every pixel in f64, from the sums it started
    /// with, each estimate rounded to f32 as the kernel adds it.
    fn exact_sums(&self) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let splats = self.splats();
        let pixels = (self.width * self.height) as usize;
        let mut sum = compensated::film_rgb(&self.accum, 1.0);
        let mut q = compensated::film_rgb(&self.accum2, 1.0);
        for (j, r) in self.radiance.iter().enumerate() {
            let (pass, i) = (j / self.pixel_count, j % self.pixel_count);
            let pixel = self.pixel_offset + i;
            let s = splats.value(pass * pixels + pixel);
            for k in 0..3 {
                sum[pixel][k] += (r[k] + s[k]) as f64;
                q[pixel][k] += ((r[k] as f64 + s[k] as f64) * self.scale as f64).powi(2);
            }
        }
        (sum, q)
    }
}

fn bits(v: &[[f32; 4]]) -> Vec<u32> {
    v.iter().flatten().map(|x| x.to_bits()).collect()
}

/// `finish` on `case` against the twin, bit for bit, and against the exact sums.
fn check_finish(gpu: &Gpu, kernels: &Kernels, case: &Finish, what: &str) {
    let (width, height) = (case.width, case.height);
    let chunk = (case.pixel_offset, case.pixel_count);
    let passes = case.radiance.len() / case.pixel_count;
    let (want, want2) = case.twin();
    let (got, got2) = case.on_gpu(gpu, kernels);
    assert!(bits(&got) == bits(&want), "{what}: Σ estimate");
    assert!(bits(&got2) == bits(&want2), "{what}: Σ (s · estimate)²");
    // The sums keep the estimates' every bit: each addition rounds a pair by half its
    // quantum (2^-48 of the sum at most, or 2^-127 below 2^-79, where the quantum stops
    // at 2^-126) and its remainder's own sum by about 2^-47 of the sum. Scaled, the
    // second moments are the f64 sums' to f32 rounding of each square, where squares of
    // estimates of 2^70 would overflow f32 and those of 2^-80 vanish.
    let (exact, exact2) = case.exact_sums();
    let (sums, sums2) = (
        compensated::film_rgb(&want, 1.0),
        compensated::film_rgb(&want2, 1.0),
    );
    for p in 0..sums.len() {
        for k in 0..3 {
            let (s, e) = (sums[p][k], exact[p][k]);
            let bound = passes as f64 * (e.abs() * 2f64.powi(-46) + 2f64.powi(-126));
            assert!((s - e).abs() <= bound, "{what}: pixel {p}: {s} vs {e}");
            let (q, e) = (sums2[p][k], exact2[p][k]);
            assert!((q - e).abs() <= 1e-6 * e, "{what}: pixel {p}: {q} vs {e}");
        }
    }
    // Pixels outside the chunk, and their remainders, are left alone.
    let pixels = (width * height) as usize;
    let (lo, hi) = (chunk.0, chunk.0 + chunk.1);
    for range in [0..lo, hi..pixels + lo, pixels + hi..2 * pixels] {
        assert!(want[range.clone()] == case.accum[range], "{what}");
    }
    assert!(
        want[lo..hi].iter().all(|s| s[3] == 2.0 + passes as f32),
        "{what}"
    );
}

#[test]
fn finish_matches_its_twin_bit_for_bit() {
    let gpu = common::gpu();
    let kernels = Kernels::new(&gpu, &LvcOptions::new(Variant::LvcBdpt, false), u32::MAX).unwrap();
    for (width, height, chunk, passes) in [(13, 7, (5, 70), 3), (317, 316, (0, 100_172), 2)] {
        for exponent in [0, 70, -80] {
            let case = Finish::new(width, height, chunk, passes, exponent);
            let what =
                format!("{width}×{height}, pixels {chunk:?}, {passes} passes of 2^{exponent}");
            check_finish(&gpu, &kernels, &case, &what);
        }
    }
    common::assert_clean(&gpu);
}

/// Both kernels on films past one storage binding, which they take by address: `finish`
/// on the last pixels of a film whose sums and remainders, and whose two passes of
/// splats, are each past it, and `splat` into the last slots of a film past it.
#[test]
fn finish_and_splat_take_films_past_one_binding() {
    let gpu = common::gpu();
    let kernels = Kernels::new(&gpu, &LvcOptions::new(Variant::LvcBdpt, false), u32::MAX).unwrap();
    let binding = gpu.info().limits.max_storage_buffer_range;
    // Sums and remainders: 32 bytes a pixel.
    let side = ((binding / 32) as f64).sqrt() as u32 + 1;
    let pixels = side as usize * side as usize;
    let film_bytes = pixels as u64 * 32;
    if common::holds_past_one_binding(&gpu, film_bytes, "a film's sums and remainders") {
        let chunk = (pixels - 40_000, 40_000);
        let case = Finish::new(side, side, chunk, 2, 0);
        assert!(case.splat_words.len() as u64 * 4 > binding);
        let what = format!("{side}×{side}, pixels {chunk:?}, 2 passes");
        check_finish(&gpu, &kernels, &case, &what);
    }
    let slot_bytes = (FIXED_WORDS * 4) as u64;
    let first_slot = (binding / slot_bytes) as usize + 1;
    let splat_bytes = (first_slot + SPLAT_SLOTS) as u64 * slot_bytes;
    if common::holds_past_one_binding(&gpu, splat_bytes, "a splat film") {
        let splats = Splats::into_slots_from(100_003, 7, first_slot);
        check_splats(&gpu, &kernels, &splats, 1.0, "splats past one binding");
    }
    common::assert_clean(&gpu);
}
