//! One pass of the CPU bidirectional integrators: per pixel one light subpath and (for
//! `bpt`) one camera subpath, all their techniques, and the light-tracing splats.
//!
//! **Determinism.** The pixels are cut into fixed chunks that rayon renders in any
//! order on any number of threads; each chunk's results — its pixels' camera-side
//! estimates, its splats in the order they were made, its counters — are combined in
//! chunk order. Random numbers depend on (pixel, pass, dimension, seed) only. So the film
//! is the same bit for bit whatever the thread count.

use glam::Vec3;
use rayon::prelude::*;

use crate::bidir::random::{fold_seed, PathSampler};
use crate::bidir::techniques::for_each_technique;
use crate::bidir::walk::{camera_subpath, light_subpath};
use crate::bidir::{Connector, Counters, PinholeCamera, Sample, Vertex};

/// One technique's contribution to one pixel in a pass (for technique images).
#[derive(Clone, Copy, Debug)]
pub struct TechniqueEntry {
    pub pixel: u32,
    pub s: u16,
    pub t: u16,
    /// Weighted; a splat still to be divided by the pass's light subpaths.
    pub rgb: [f32; 3],
    pub splat: bool,
}

/// What one chunk of pixels produced.
#[derive(Default)]
pub struct ChunkOutput {
    /// First pixel of the chunk.
    pub start: usize,
    /// Camera-side estimate of each pixel of the chunk (s = 0, s = 1, connections).
    pub camera: Vec<[f64; 3]>,
    /// Light-tracing contributions (pixel, weighted value), in the order they were made.
    pub splats: Vec<(u32, [f32; 3])>,
    /// Every contribution by technique, when technique images are kept.
    pub entries: Vec<TechniqueEntry>,
    pub counters: Counters,
}

/// What a pass needs to know.
pub struct PassInputs<'a> {
    pub connector: Connector<'a>,
    pub camera: &'a PinholeCamera,
    pub seed: u64,
    /// Trace camera subpaths (`bpt`) or only light subpaths (`light`).
    pub camera_paths: bool,
    pub keep_techniques: bool,
    pub chunk_pixels: usize,
}

/// Renders pass `pass` chunk by chunk in parallel; the results in chunk order.
pub fn render_chunks(inputs: &PassInputs, pass: u32) -> Vec<ChunkOutput> {
    let pixels = inputs.camera.pixel_count();
    let chunk = inputs.chunk_pixels.max(1);
    (0..pixels.div_ceil(chunk))
        .into_par_iter()
        .map(|c| render_chunk(inputs, pass, c * chunk, (c * chunk + chunk).min(pixels)))
        .collect()
}

fn render_chunk(inputs: &PassInputs, pass: u32, start: usize, end: usize) -> ChunkOutput {
    let _span = tracing::info_span!("bidir chunk", pixels = (end - start) as u64).entered();
    let mut out = ChunkOutput {
        start,
        camera: vec![[0.0; 3]; end - start],
        ..Default::default()
    };
    let mut light: Vec<Vertex> = Vec::new();
    let mut camera: Vec<Vertex> = Vec::new();
    let seed = fold_seed(inputs.seed);
    let scene = inputs.connector.scene;
    let settings = inputs.connector.settings;
    // The walks' and connections' counts; `record` counts what it drops in `out`.
    let mut counters = Counters::default();
    for pixel in start..end {
        let sampler = PathSampler::new(pixel as u32, pass, seed);
        light_subpath(scene, settings, &sampler, &mut light, &mut counters);
        if inputs.camera_paths {
            let (cam, id) = (inputs.camera, pixel as u32);
            camera_subpath(
                scene,
                cam,
                settings,
                &sampler,
                id,
                &mut camera,
                &mut counters,
            );
        }
        let mut sink = |s: Sample| record(&mut out, inputs.keep_techniques, pixel, &s);
        for_each_technique(
            &inputs.connector,
            &light,
            &camera,
            &sampler,
            &mut counters,
            &mut sink,
        );
    }
    counters.non_finite += out.counters.non_finite;
    out.counters = counters;
    out
}

/// Adds one technique's weighted contribution to the chunk (a NaN or infinity is
/// dropped and counted: it would poison the pixel for good).
fn record(out: &mut ChunkOutput, keep: bool, pixel: usize, s: &Sample) {
    let w: Vec3 = s.weighted();
    if !w.is_finite() {
        out.counters.non_finite += 1;
        return;
    }
    let rgb = w.to_array();
    let target = match s.pixel {
        Some(p) => {
            out.splats.push((p, rgb));
            p
        }
        None => {
            let e = &mut out.camera[pixel - out.start];
            for c in 0..3 {
                e[c] += rgb[c] as f64;
            }
            pixel as u32
        }
    };
    if keep {
        out.entries.push(TechniqueEntry {
            pixel: target,
            s: s.s.min(u16::MAX as u32) as u16,
            t: s.t.min(u16::MAX as u32) as u16,
            rgb,
            splat: s.pixel.is_some(),
        });
    }
}

/// The pass estimate of every pixel from the chunks (in chunk order): its camera-side
/// estimate plus the splats that landed on it divided by the pass's light subpaths.
pub fn pass_estimate(chunks: &[ChunkOutput], pixels: usize, light_paths: f64) -> Vec<[f64; 3]> {
    let mut estimate = vec![[0.0f64; 3]; pixels];
    let mut splat = vec![[0.0f64; 3]; pixels];
    for chunk in chunks {
        estimate[chunk.start..chunk.start + chunk.camera.len()].copy_from_slice(&chunk.camera);
        for &(p, rgb) in &chunk.splats {
            let s = &mut splat[p as usize];
            for c in 0..3 {
                s[c] += rgb[c] as f64;
            }
        }
    }
    for (e, s) in estimate.iter_mut().zip(&splat) {
        for c in 0..3 {
            e[c] += s[c] / light_paths;
        }
    }
    estimate
}
