//! The CPU twins of the combination kernels (`glsl/integrator/cbpt/`), on the same
//! tables and with the same arithmetic as `bpt`'s connections ([`endpoint`],
//! [`CpuScene::shadow_ray`]), and [`evaluate`]: every segment of a step on every core —
//! CBPT's combination without a GPU, and the all-CPU baseline of the paper's Table 1.

use glam::Vec3;
use rayon::prelude::*;

use super::layout::{CombinationData, Kinds, Shading, Tables};
use crate::bidir::connect::{endpoint, segment, Endpoint};
use crate::bidir::CpuScene;
use crate::bsdf::TransportMode;
use crate::trace::{Hit, Ray, MISS};

/// Segments per unit of parallel work (a multiple of 32).
const CHUNK: usize = 4096;

/// The ray that tests a segment whose ends coincide: it tests nothing and
/// [`pack_visibility`] counts it occluded, as [`CpuScene::unoccluded`] does.
pub fn degenerate_ray(origin: Vec3) -> Ray {
    Ray::new(origin, Vec3::Z, 0.0, 0.0)
}

/// `visibility_rays.comp`: the shadow ray of `segment` (camera-vertex major).
pub fn visibility_ray(scene: &CpuScene, tables: &Tables, segment: usize) -> Ray {
    let v_l = tables.light.len();
    let (z, y) = (&tables.camera[segment / v_l], &tables.light[segment % v_l]);
    let (zp, yp) = (Vec3::from(z.p), Vec3::from(y.p));
    scene
        .shadow_ray(zp, Vec3::from(z.ng), yp, Vec3::from(y.ng))
        .unwrap_or_else(|| degenerate_ray(zp))
}

/// `visibility_pack.comp`: bit b of word w is set when ray 32w + b has a positive reach
/// and hit nothing.
pub fn pack_visibility(rays: &[Ray], hits: &[Hit]) -> Vec<u32> {
    rays.chunks(32)
        .zip(hits.chunks(32))
        .map(|(r, h)| {
            r.iter().zip(h).enumerate().fold(0u32, |word, (b, (r, h))| {
                word | (((h.triangle == MISS && r.tmax > 0.0) as u32) << b)
            })
        })
        .collect()
}

/// `camera_shading.comp`: the camera vertex's BSDF towards the light vertex of segment
/// `s` (camera-vertex major); zero where the two coincide.
pub fn camera_shading(scene: &CpuScene, tables: &Tables, s: usize) -> Endpoint {
    let v_l = tables.light.len();
    let z = tables.camera[s / v_l].surface();
    let y = Vec3::from(tables.light[s % v_l].p);
    match segment(z.p, y) {
        Some((dir, _)) => endpoint(scene, &z, dir, TransportMode::Radiance),
        None => Endpoint::default(),
    }
}

/// `light_shading.comp`: the surface light vertex's adjoint BSDF towards the camera
/// vertex of segment `s` (light-vertex major); zero where the two coincide.
pub fn light_shading(scene: &CpuScene, tables: &Tables, s: usize) -> Endpoint {
    let v_c = tables.camera.len();
    let y = tables.light[s / v_c].surface();
    let z = Vec3::from(tables.camera[s % v_c].p);
    // The direction from the camera end, as `Connector::connect` takes it.
    match segment(z, y.p) {
        Some((dir, _)) => endpoint(scene, &y, -dir, TransportMode::Importance),
        None => Endpoint::default(),
    }
}

/// Every segment's combination data of `kinds` (the others stay zero), on every core.
pub fn evaluate(scene: &CpuScene, tables: &Tables, kinds: Kinds) -> CombinationData {
    let _span =
        tracing::info_span!("cbpt combination (cpu)", segments = tables.segments()).entered();
    let mut data = CombinationData::zeroed(tables);
    if kinds.visibility {
        let n = tables.segments() as usize;
        data.visibility
            .par_chunks_mut(CHUNK / 32)
            .enumerate()
            .for_each(|(chunk, words)| {
                let first = chunk * CHUNK;
                for (w, word) in words.iter_mut().enumerate() {
                    let start = first + 32 * w;
                    *word = (start..(start + 32).min(n)).fold(0, |acc, s| {
                        let ray = visibility_ray(scene, tables, s);
                        let free = ray.tmax > 0.0 && !scene.bvh.occluded(&ray);
                        acc | ((free as u32) << (s - start))
                    });
                }
            });
    }
    if kinds.camera {
        fill(&mut data.camera, &|s| camera_shading(scene, tables, s));
    }
    if kinds.light {
        fill(&mut data.light, &|s| light_shading(scene, tables, s));
    }
    data
}

/// Fills every segment of `shading` with `eval` in parallel chunks.
fn fill(shading: &mut Shading, eval: &(dyn Fn(usize) -> Endpoint + Sync)) {
    let n = shading.segments;
    let chunks: Vec<Vec<Endpoint>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| (c * CHUNK..(c * CHUNK + CHUNK).min(n)).map(eval).collect())
        .collect();
    for (c, values) in chunks.iter().enumerate() {
        for (k, e) in values.iter().enumerate() {
            shading.set(c * CHUNK + k, e);
        }
    }
}
