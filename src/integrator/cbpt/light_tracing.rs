//! `sample({y_lt})` and `compute_lt()` of Algorithm 2: N_T light paths per step traced
//! on every core, each vertex linked to the pinhole and splatted to the pixel it
//! projects to (§3.2, "Light-tracing"). Light tracing contributes neither emitters seen
//! directly nor direct lighting (§3.1; [`CombinatorialCounts::traces_light_vertex`]).
//! The splats go to the light-tracing image, which the pass divides by its light-traced
//! paths: splitray's importance W_e already carries the pixel's 1/A_pix, which is the
//! paper's multiplication by the pixel count N_p of an importance normalised over the
//! whole image.
//!
//! [`CombinatorialCounts::traces_light_vertex`]: crate::bidir::combinatorial::CombinatorialCounts::traces_light_vertex

use glam::Vec3;
use rayon::prelude::*;

use super::combine::Linking;
use super::population::SamplingInputs;
use crate::bidir::random::PathSampler;
use crate::bidir::walk::light_subpath;
use crate::bidir::Counters;

/// Light paths per unit of parallel work.
const CHUNK: u32 = 64;

/// A light-tracing contribution: a pixel and its weighted value.
pub type Splat = (u32, Vec3);

/// The splats of light-traced paths `step·count .. step·count + count` of pass `pass`,
/// in path order (a NaN or infinite one is dropped and counted).
pub fn light_trace(
    inputs: &SamplingInputs,
    linking: &Linking,
    pass: u32,
    step: u32,
    count: u32,
    counters: &mut Counters,
) -> Vec<Splat> {
    let _span = tracing::info_span!(
        "cbpt light tracing",
        step = step as u64,
        paths = count as u64
    )
    .entered();
    let chunks: Vec<(Vec<Splat>, Counters)> = (0..count.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut splats = Vec::new();
            let mut counters = Counters::default();
            let mut path = Vec::new();
            for k in c * CHUNK..(c * CHUNK + CHUNK).min(count) {
                let sampler = PathSampler::new(step * count + k, pass, inputs.streams.traced);
                light_subpath(
                    inputs.scene,
                    inputs.settings,
                    &sampler,
                    &mut path,
                    &mut counters,
                );
                for i in 0..path.len() {
                    if !linking.counts.traces_light_vertex(i) {
                        continue;
                    }
                    let Some(s) = linking.connector.light_trace(&path, i, &mut counters) else {
                        continue;
                    };
                    let v = s.weighted();
                    if !v.is_finite() {
                        counters.non_finite += 1;
                    } else if let Some(pixel) = s.pixel {
                        splats.push((pixel, v));
                    }
                }
            }
            (splats, counters)
        })
        .collect();
    let mut out = Vec::new();
    for (splats, c) in chunks {
        out.extend(splats);
        *counters += c;
    }
    out
}
