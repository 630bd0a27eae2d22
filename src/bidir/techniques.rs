//! Every technique of one camera subpath and one light subpath: standard BPT's
//! combination step (CBPT §3.1: all couples (i, j); pbrt-v4's double loop over s and t).

use super::connect::{Connector, Sample};
use super::random::PathSampler;
use super::vertex::Vertex;
use super::Counters;

/// Evaluates every technique the two subpaths allow within `max_depth` and whose count
/// ([`super::mis::TechniqueCounts`]) is non-zero, and hands each non-zero, unoccluded
/// one to `sink`, in a fixed order: light tracing (by light vertex), then per camera
/// vertex the emitter hit, next-event estimation and the connections (by light vertex).
/// `camera` may be empty (light tracing alone), `light` too (a scene without lights).
pub fn for_each_technique(
    connector: &Connector,
    light: &[Vertex],
    camera: &[Vertex],
    camera_sampler: &PathSampler,
    counters: &mut Counters,
    sink: &mut dyn FnMut(Sample),
) {
    let settings = connector.settings;
    for i in 0..light.len() {
        if let Some(s) = connector.light_trace(light, i, counters) {
            sink(s);
        }
    }
    for j in 1..camera.len() {
        if let Some(s) = connector.emitter_hit(camera, j, counters) {
            sink(s);
        }
        if settings.allows(j + 1) {
            if let Some(s) = connector.light_sample(camera, j, camera_sampler, counters) {
                sink(s);
            }
        }
        for i in 1..light.len() {
            if !settings.allows(i + j + 1) {
                break;
            }
            if let Some(s) = connector.connect(light, i, camera, j, counters) {
                sink(s);
            }
        }
    }
}
