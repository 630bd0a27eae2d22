//! `combine()` of Algorithm 2: each camera path's bidirectional contribution f^b(x, {y})
//! from the combination data of its linking segments (§3.1):
//!
//!   f^b = Σ_j f_{j,−1}(x) + (1 / N_L) Σ_{y} Σ_{i ≥ 0, j ≥ 1} f_{i,j}(x, y)
//!
//! — the emitter hits of the camera path (s = 0, no light path involved) and, for each of
//! the N_L light paths, the camera vertices linked to its first vertex (s = 1) and to its
//! vertices on surfaces (s ≥ 2), weighted by the balance heuristic of
//! [`crate::bidir::combinatorial`]. Each technique's value and weight come from `bpt`'s
//! own arithmetic ([`Connector::weigh_light_point`], [`Connector::weigh_connection`])
//! fed with the downloaded shading tuples, and count only where the visibility bit is
//! set. Camera paths are combined in parallel; the N_C values are then splatted in
//! camera-path order, so the image does not depend on the thread count.

use glam::Vec3;
use rayon::prelude::*;

use super::layout::{CombinationData, Tables, NOT_LINKED};
use super::population::Population;
use crate::bidir::combinatorial::{self, CombinatorialCounts};
use crate::bidir::connect::{segment, Connector, Sample};
use crate::bidir::Counters;

/// How the techniques of a step are weighted.
#[derive(Clone, Copy)]
pub struct Linking<'a> {
    /// Weighs with [`CombinatorialCounts::walk`].
    pub connector: Connector<'a>,
    /// Weighs paths of two segments ([`CombinatorialCounts::of_path`]`(2)`).
    pub direct: Connector<'a>,
    pub counts: CombinatorialCounts,
}

/// One technique's contribution to a camera path's f^b.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contribution {
    pub sample: Sample,
    /// The factor its weighted value enters f^b with: 1 for an emitter hit, 1 / N_L for
    /// a technique of one of the N_L light paths.
    pub scale: f32,
    /// The light path it links to (`None`: an emitter hit).
    pub light_path: Option<usize>,
}

impl Contribution {
    pub fn value(&self) -> Vec3 {
        self.sample.weighted() * self.scale
    }
}

/// The step's data as `combine` reads them.
#[derive(Clone, Copy)]
pub struct StepData<'a> {
    pub population: &'a Population,
    pub tables: &'a Tables,
    pub data: &'a CombinationData,
}

/// Hands every visible, non-zero technique of camera path `k` with the step's light
/// paths to `sink`, in a fixed order: per camera vertex, its emitter hit, then per light
/// path the link to its first vertex and to its surface vertices in order.
pub fn for_each_technique(
    linking: &Linking,
    step: StepData,
    k: usize,
    counters: &mut Counters,
    sink: &mut dyn FnMut(&Contribution),
) {
    let (population, tables, data) = (step.population, step.tables, step.data);
    let settings = linking.connector.settings;
    let camera_range = population.camera.range(k);
    let camera = &population.camera.vertices[camera_range.clone()];
    let light_scale = 1.0 / linking.counts.light_paths;
    for j in 1..camera.len() {
        if let Some(sample) = combinatorial::emitter_hit(&linking.connector, camera, j, counters) {
            sink(&Contribution {
                sample,
                scale: 1.0,
                light_path: None,
            });
        }
        let c = tables.camera_index[camera_range.start + j];
        if c == NOT_LINKED {
            continue;
        }
        let z = &camera[j];
        for l in 0..population.light.len() {
            let light_range = population.light.range(l);
            let light = &population.light.vertices[light_range.clone()];
            let mut emit = |sample: Sample| {
                sink(&Contribution {
                    sample,
                    scale: light_scale,
                    light_path: Some(l),
                })
            };
            if let Some(y0) = light.first().filter(|_| settings.allows(j + 1)) {
                let s = tables.segment(c, tables.light_index[light_range.start]);
                if segment(z.p, y0.p).is_some() {
                    counters.basic_contributions += 1;
                    let connector = if j == 1 {
                        &linking.direct
                    } else {
                        &linking.connector
                    };
                    let e = data.camera.get(s);
                    if let Some(sample) = connector.weigh_light_point(y0, camera, j, &e) {
                        if data.visible(s) {
                            emit(sample);
                        }
                    }
                }
            }
            for i in 1..light.len() {
                if !settings.allows(i + j + 1) {
                    break;
                }
                let li = tables.light_index[light_range.start + i];
                if li == NOT_LINKED || segment(z.p, light[i].p).is_none() {
                    continue;
                }
                counters.basic_contributions += 1;
                let s = tables.segment(c, li);
                let ez = data.camera.get(s);
                let ey = data.light.get(tables.light_segment(li, c));
                let sample = linking
                    .connector
                    .weigh_connection(light, i, camera, j, &ez, &ey);
                if let Some(sample) = sample.filter(|_| data.visible(s)) {
                    emit(sample);
                }
            }
        }
    }
}

/// f^b of every camera path of the step, in camera-path order, computed in parallel
/// (a NaN or infinite technique is dropped and counted, as in `bpt`).
pub fn combine(linking: &Linking, step: StepData, counters: &mut Counters) -> Vec<Vec3> {
    let _span = tracing::info_span!(
        "cbpt combine",
        step = step.population.id.step as u64,
        camera_paths = step.population.camera.len() as u64
    )
    .entered();
    let results: Vec<(Vec3, Counters)> = (0..step.population.camera.len())
        .into_par_iter()
        .map(|k| {
            let mut c = Counters::default();
            let mut value = Vec3::ZERO;
            let mut dropped = 0;
            for_each_technique(linking, step, k, &mut c, &mut |t| {
                let v = t.value();
                if v.is_finite() {
                    value += v;
                } else {
                    dropped += 1;
                }
            });
            c.non_finite += dropped;
            (value, c)
        })
        .collect();
    results
        .into_iter()
        .map(|(value, c)| {
            *counters += c;
            value
        })
        .collect()
}
