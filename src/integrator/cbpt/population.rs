//! A step's population couple (§3.1): N_C camera paths through the step's image
//! positions and N_L light paths, sampled on every core with `bpt`'s random walks.
//! Paths are sampled in fixed chunks and concatenated in order, so a population does not
//! depend on the thread count.

use std::ops::Range;

use rayon::prelude::*;

use super::steps::{ImagePositions, StepId, Streams};
use crate::bidir::random::{dims, PathSampler};
use crate::bidir::walk::{camera_subpath_at, light_subpath};
use crate::bidir::{Counters, CpuScene, PinholeCamera, Vertex, WalkSettings};

/// Paths per unit of parallel sampling work.
const CHUNK: usize = 64;

/// Subpaths stored end to end.
#[derive(Clone, Debug, Default)]
pub struct PathSet {
    pub vertices: Vec<Vertex>,
    /// Path k is `vertices[starts[k]..starts[k + 1]]`.
    starts: Vec<u32>,
}

impl PathSet {
    pub fn len(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Where path `k`'s vertices lie in [`PathSet::vertices`].
    pub fn range(&self, k: usize) -> Range<usize> {
        self.starts[k] as usize..self.starts[k + 1] as usize
    }

    pub fn path(&self, k: usize) -> &[Vertex] {
        &self.vertices[self.range(k)]
    }

    /// Samples `count` paths in parallel chunks; `walk(k, path, counters)` traces path k.
    pub fn sample(
        count: usize,
        counters: &mut Counters,
        walk: &(dyn Fn(usize, &mut Vec<Vertex>, &mut Counters) + Sync),
    ) -> Self {
        let chunks: Vec<(Vec<Vertex>, Vec<u32>, Counters)> = (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut vertices = Vec::new();
                let mut lengths = Vec::new();
                let mut path = Vec::new();
                let mut counters = Counters::default();
                for k in c * CHUNK..(c * CHUNK + CHUNK).min(count) {
                    walk(k, &mut path, &mut counters);
                    lengths.push(path.len() as u32);
                    vertices.extend_from_slice(&path);
                }
                (vertices, lengths, counters)
            })
            .collect();
        let mut set = PathSet {
            vertices: Vec::with_capacity(chunks.iter().map(|c| c.0.len()).sum()),
            starts: Vec::with_capacity(count + 1),
        };
        set.starts.push(0);
        for (vertices, lengths, c) in chunks {
            for len in lengths {
                let last = *set.starts.last().expect("starts at 0");
                set.starts.push(last + len);
            }
            set.vertices.extend(vertices);
            *counters += c;
        }
        set
    }
}

/// A step's population couple.
#[derive(Clone, Debug)]
pub struct Population {
    pub id: StepId,
    pub camera: PathSet,
    /// The pixel of each camera path.
    pub pixels: Vec<u32>,
    pub light: PathSet,
}

/// What sampling a population needs.
pub struct SamplingInputs<'a> {
    pub scene: &'a CpuScene,
    pub camera: &'a PinholeCamera,
    pub settings: &'a WalkSettings,
    pub streams: Streams,
    /// N_L.
    pub light_paths: u32,
}

impl Population {
    /// Samples step `id`'s camera paths through `positions` and its light paths.
    pub fn sample(
        inputs: &SamplingInputs,
        id: StepId,
        positions: &ImagePositions,
        counters: &mut Counters,
    ) -> Self {
        let _span = tracing::info_span!("cbpt sample", step = id.step as u64).entered();
        let first = id.cameras.start;
        let cameras = id.cameras.len();
        let points: Vec<_> = (0..cameras as u32)
            .map(|k| {
                let sampler = PathSampler::new(first + k, id.pass, inputs.streams.camera);
                let u = [
                    sampler.get(dims::CAMERA_JITTER),
                    sampler.get(dims::CAMERA_JITTER + 1),
                ];
                (sampler, positions.film_point(first + k, u))
            })
            .collect();
        let camera = PathSet::sample(cameras, counters, &|k, path, c| {
            let (sampler, film) = &points[k];
            camera_subpath_at(
                inputs.scene,
                inputs.camera,
                inputs.settings,
                sampler,
                *film,
                path,
                c,
            );
        });
        let light = sample_light_paths(
            inputs,
            id.pass,
            id.step,
            inputs.light_paths,
            inputs.streams.light,
            counters,
        );
        Self {
            pixels: points.iter().map(|(_, f)| f.pixel).collect(),
            id,
            camera,
            light,
        }
    }
}

/// Light paths `step·count .. step·count + count` of pass `pass` under `seed`: a
/// population's N_L, or the N_T of the light tracer.
pub fn sample_light_paths(
    inputs: &SamplingInputs,
    pass: u32,
    step: u32,
    count: u32,
    seed: u32,
    counters: &mut Counters,
) -> PathSet {
    PathSet::sample(count as usize, counters, &|k, path, c| {
        let sampler = PathSampler::new(step * count + k as u32, pass, seed);
        light_subpath(inputs.scene, inputs.settings, &sampler, path, c);
    })
}
