//! `camera_accumulate` (both builds of its visibility tally: per subgroup and per
//! invocation) against its CPU twin `twin::accumulate` on synthetic bounces: no live
//! path, one, sizes around the workgroup's and a large one; live ids in any order;
//! contributions absent, occluded, unoccluded, NaN and infinite. The radiance sums, the
//! non-finite count and the tally must be the twin's exactly (the kernel only adds, in
//! the twin's order).

use crate::common;

use bytemuck::Zeroable;
use splitray::integrator::lvc::gpu::{
    Contribution, LvcConstants, LvcPush, VisibilityTally, CONTRIBUTION_NONE, COUNTERS,
    COUNTER_NON_FINITE,
};
use splitray::integrator::lvc::kernels::{AccumulateTally, Kernels};
use splitray::integrator::lvc::twin::{accumulate, BounceRecords};
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
