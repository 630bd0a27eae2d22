//! CPU twins of the kernels, for the tests that compare them (`tests/suite/lvc_kernels.rs`):
//! the walks and techniques are the CPU `bpt`'s ([`crate::bidir`]) run on the kernels'
//! records, so each kernel is checked against the code it mirrors.
//!
//! Techniques are evaluated on a scene without occluders ([`unoccluded`]), so that
//! [`Connector`] returns the unoccluded contribution a kernel writes before its shadow
//! ray is traced; the shadow ray itself is [`shadow_ray`].

use glam::Vec3;

use super::fixed::FixedFilm;
use super::gpu::{
    Contribution, LvcVertex, VisibilityTally, VERTEX_CONNECTIBLE, VERTEX_EXTENDS, VERTEX_VALID,
};
use super::options::Resampling;
use crate::bidir::random::{pcg_hash, PathSampler};
use crate::bidir::scene::SurfaceHit;
use crate::bidir::walk::{camera_subpath, light_subpath};
use crate::bidir::{Connector, Counters, CpuScene, PinholeCamera, Sample, Vertex, WalkSettings};
use crate::film::compensated;
use crate::integrator::pt::PtScene;
use crate::trace::{CpuBvh, Hit, Ray, MISS};

/// `random_u32` of lvc_random.glsl: the full hash whose top 24 bits `random01` takes.
pub fn random_u32(index: u32, sample: u32, dimension: u32, seed: u32) -> u32 {
    pcg_hash(index ^ pcg_hash(sample ^ pcg_hash(dimension ^ pcg_hash(seed))))
}

/// `uniform_index` of lvc_random.glsl: an exactly uniform index in [0, size).
pub fn uniform_index(index: u32, sample: u32, dimension: u32, seed: u32, size: u32) -> u32 {
    const TRIES: u32 = 8;
    const STRIDE: u32 = 0x0100_0000;
    let threshold = 0u32.wrapping_sub(size) % size;
    let mut hi = 0;
    for k in 0..TRIES {
        let h = random_u32(index, sample, dimension.wrapping_add(k * STRIDE), seed);
        let product = h as u64 * size as u64;
        hi = (product >> 32) as u32;
        if (product as u32) >= threshold {
            return hi;
        }
    }
    hi
}

/// The scene's tables without occluders: every connection is visible.
pub fn unoccluded(tables: PtScene) -> CpuScene {
    CpuScene {
        bvh: CpuBvh::new(&[]),
        ray_epsilon: tables.ray_epsilon,
        tables,
    }
}

/// The shadow ray between two points (`shadow_ray` in lvc.glsl, `CpuScene::unoccluded`);
/// `None` when they coincide.
pub fn shadow_ray(scene: &CpuScene, a: Vec3, a_ng: Vec3, b: Vec3, b_ng: Vec3) -> Option<Ray> {
    let d0 = b - a;
    let from = scene.offset(a, a_ng, d0);
    let to = scene.offset(b, b_ng, -d0);
    let d = to - from;
    let reach = d.length();
    (reach > 0.0).then(|| Ray::new(from, d / reach, 0.0, reach * (1.0 - 1e-4)))
}

/// The geometric normal of a record's triangle.
pub fn geometric_normal(scene: &CpuScene, v: &LvcVertex) -> Vec3 {
    scene.tables.triangles[v.triangle as usize]
        .normal()
        .normalize()
}

/// A record as the CPU BPT's vertex.
pub fn to_vertex(scene: &CpuScene, v: &LvcVertex) -> Vertex {
    let hit = SurfaceHit {
        p: v.position(),
        ng: geometric_normal(scene, v),
        ns: Vec3::from(v.ns),
        triangle: v.triangle,
        material: v.material,
        t: 0.0,
    };
    let mut out = Vertex::surface(&hit, Vec3::from(v.wo), v.is(VERTEX_CONNECTIBLE));
    out.beta = Vec3::from(v.beta);
    out.mis.d_vcm = v.d_vcm;
    out.mis.d_vc = v.d_vc;
    out
}

/// The record of surface vertex `depth` of a CPU subpath.
pub fn to_record(v: &Vertex, path: u32, depth: u32, flags: u32) -> LvcVertex {
    LvcVertex {
        p: v.p.into(),
        material: v.material,
        ns: v.ns.into(),
        triangle: v.triangle,
        wo: v.wo.into(),
        d_vcm: v.mis.d_vcm,
        beta: v.beta.into(),
        d_vc: v.mis.d_vc,
        path,
        depth,
        flags: VERTEX_VALID | flags | if v.connectible { VERTEX_CONNECTIBLE } else { 0 },
        ordinal: 0,
    }
}

/// The light pass's twin: per light path of the chunk (`light_paths` per pass, passes
/// from `first_pass`), the records it caches, in order, with their ordinals.
pub fn light_pass(
    scene: &CpuScene,
    settings: &WalkSettings,
    seed: u32,
    first_pass: u32,
    passes: u32,
    light_paths: u32,
) -> Vec<Vec<LvcVertex>> {
    let mut counters = Counters::default();
    let mut path = Vec::new();
    (0..passes * light_paths)
        .map(|l| {
            let sampler = PathSampler::new(l % light_paths, first_pass + l / light_paths, seed);
            light_subpath(scene, settings, &sampler, &mut path, &mut counters);
            let mut cached = Vec::new();
            for (i, v) in path.iter().enumerate().skip(1) {
                if v.connectible {
                    let mut r = to_record(v, l, i as u32, 0);
                    r.ordinal = cached.len() as u32;
                    cached.push(r);
                }
            }
            cached
        })
        .collect()
}

/// The camera subpath of `pixel` in `pass` as records (the pinhole left out; vertex j
/// is entry j − 1), with the flags `camera_vertex` sets.
pub fn camera_records(
    scene: &CpuScene,
    camera: &PinholeCamera,
    settings: &WalkSettings,
    seed: u32,
    pixel: u32,
    pass: u32,
    path: u32,
) -> Vec<LvcVertex> {
    let mut counters = Counters::default();
    let mut vertices = Vec::new();
    let sampler = PathSampler::new(pixel, pass, seed);
    camera_subpath(
        scene,
        camera,
        settings,
        &sampler,
        pixel,
        &mut vertices,
        &mut counters,
    );
    vertices
        .iter()
        .enumerate()
        .skip(1)
        .map(|(j, v)| {
            let extends = settings.max_depth < 0 || (j as i32) < settings.max_depth;
            to_record(v, path, j as u32, if extends { VERTEX_EXTENDS } else { 0 })
        })
        .collect()
}

/// `count` copies of a vertex: the CPU techniques read only entry `i` of a subpath and
/// take its index from `i`.
fn subpath_to(v: Vertex, i: usize) -> Vec<Vertex> {
    vec![v; i + 1]
}

/// Light tracing (t = 1) of a cache record (`light_connect`): the unoccluded sample.
pub fn light_trace(connector: &Connector, y: &LvcVertex) -> Option<Sample> {
    let i = y.depth as usize;
    let light = subpath_to(to_vertex(connector.scene, y), i);
    connector.light_trace(&light, i, &mut Counters::default())
}

/// The emitter hit (s = 0) at a camera record (`camera_vertex`).
pub fn emitter_hit(connector: &Connector, z: &LvcVertex) -> Option<Sample> {
    let j = z.depth as usize;
    let camera = subpath_to(to_vertex(connector.scene, z), j);
    connector.emitter_hit(&camera, j, &mut Counters::default())
}

/// Direct lighting (s = 1) at a camera record (`camera_direct`), with the random numbers
/// of its pixel and pass: the unoccluded sample.
pub fn direct(connector: &Connector, z: &LvcVertex, sampler: &PathSampler) -> Option<Sample> {
    let j = z.depth as usize;
    if !connector.settings.allows(j + 1) {
        return None;
    }
    let camera = subpath_to(to_vertex(connector.scene, z), j);
    connector.light_sample(&camera, j, sampler, &mut Counters::default())
}

/// The connection of a camera record to a cache record (`connection` in
/// camera_connect.comp): the unoccluded sample, before the selection's scale.
pub fn connect(connector: &Connector, y: &LvcVertex, z: &LvcVertex) -> Option<Sample> {
    let (i, j) = (y.depth as usize, z.depth as usize);
    if !connector.settings.allows(i + j + 1) {
        return None;
    }
    let light = subpath_to(to_vertex(connector.scene, y), i);
    let camera = subpath_to(to_vertex(connector.scene, z), j);
    connector.connect(&light, i, &camera, j, &mut Counters::default())
}

/// One resampled draw of `camera_connect.comp`: the candidate drawn, and how far the
/// draw's point lay from the nearest end of that candidate's interval, as a fraction of
/// the total target (a GPU whose targets differ by rounding may draw a neighbour when
/// that is tiny).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Draw {
    pub candidate: usize,
    pub margin: f32,
}

/// The N draws of CIS-LBDPT's resampling (`camera_connect.comp`): per draw k, a point
/// u_k · total on the candidates' running sum of targets, and the first candidate whose
/// running sum passes it (the last one with a target, when rounding leaves the point at
/// the very end). u_k is `random(k)` for independent draws; systematic draws take
/// (random(0) + k) / N. `None` when no candidate has a target.
pub fn resample(
    targets: &[f32],
    n: u32,
    resampling: Resampling,
    random: impl Fn(u32) -> f32,
) -> Option<Vec<Draw>> {
    let total: f32 = targets.iter().sum();
    // As the kernel's `!(total > 0.0)`: nothing to draw from, NaN included.
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let first = random(0);
    let draw = |k: u32| {
        let u01 = match resampling {
            Resampling::Independent => random(k),
            Resampling::Systematic => (first + k as f32) / n as f32,
        };
        let u = u01 * total;
        let (mut chosen, mut below, mut running) = (0, 0.0f32, 0.0f32);
        for (m, &target) in targets.iter().enumerate() {
            if target > 0.0 {
                chosen = m;
                below = running;
                running += target;
                if u < running {
                    break;
                }
            }
        }
        let margin = (u - below).abs().min((running - u).abs()) / total;
        Draw {
            candidate: chosen,
            margin,
        }
    };
    Some((0..n).map(draw).collect())
}

/// What `camera_accumulate` reads of one camera bounce.
pub struct BounceRecords<'a> {
    /// The live paths' ids, in wavefront order.
    pub live_ids: &'a [u32],
    /// Per live path: its emitter hit.
    pub emitted: &'a [Contribution],
    /// The bounce's shadow-ray slots: direct lighting at i, connection k of path i at
    /// base + i N + k; and the occlusion query's answer for each slot.
    pub contributions: &'a [Contribution],
    pub shadow_hits: &'a [Hit],
    pub base: usize,
    pub connections: usize,
}

/// `camera_accumulate` (camera_accumulate.comp): each live path's radiance gains its
/// emitter hit and its unoccluded direct lighting and connections, in that order;
/// non-finite contributions are dropped and counted. Returns that count and the
/// bounce's visibility tally.
pub fn accumulate(records: &BounceRecords, radiance: &mut [[f32; 4]]) -> (u32, VisibilityTally) {
    let mut non_finite = 0;
    let mut tally = VisibilityTally::default();
    // A slot's shadow ray counts where it carried a contribution, and as unoccluded where
    // the tracer found nothing in its way.
    let count = |rays: &mut u32, unoccluded: &mut u32, c: &Contribution, open: bool| {
        *rays += u32::from(c.is_some());
        *unoccluded += u32::from(c.is_some() && open);
    };
    let mut add = |sum: &mut Vec3, c: &Contribution| {
        if !c.is_some() {
            return;
        }
        let v = c.value();
        if v.is_finite() {
            *sum += v;
        } else {
            non_finite += 1;
        }
    };
    for (i, &id) in records.live_ids.iter().enumerate() {
        let r = &mut radiance[id as usize];
        let mut sum = Vec3::new(r[0], r[1], r[2]);
        add(&mut sum, &records.emitted[i]);
        let direct = &records.contributions[i];
        let open = records.shadow_hits[i].triangle == MISS;
        count(
            &mut tally.direct_rays,
            &mut tally.direct_unoccluded,
            direct,
            open,
        );
        if open {
            add(&mut sum, direct);
        }
        for k in 0..records.connections {
            let slot = records.base + i * records.connections + k;
            let c = &records.contributions[slot];
            let reached = records.shadow_hits[slot].triangle == MISS;
            count(
                &mut tally.connection_rays,
                &mut tally.connections_unoccluded,
                c,
                reached,
            );
            if reached {
                add(&mut sum, c);
            }
        }
        r[..3].copy_from_slice(&sum.to_array());
    }
    (non_finite, tally)
}

/// A chunk's pixels as `finish` reads them: `pixel_count` pixels from `pixel_offset` of
/// a film of `pixels`, each pass's camera radiance at `radiance[q * pixel_count + i]`.
pub struct FinishChunk<'a> {
    pub radiance: &'a [[f32; 4]],
    /// The passes' light-tracing splats, slot `q * pixels + pixel`.
    pub splats: &'a FixedFilm,
    pub pixels: usize,
    pub pixel_offset: usize,
    pub pixel_count: usize,
}

/// `finish` (finish.comp): each pass's estimate of each pixel of the chunk, its camera
/// radiance plus its splats (unscaled), added in pass order to Σ estimate (`accum`, w
/// counts them) and Σ (s · estimate)² (`accum2`), s = the splat film's scale (the
/// brightness scale). `accum` and `accum2` cover the whole film: its sums, then their
/// remainders ([`compensated`]).
pub fn finish(chunk: &FinishChunk, accum: &mut [[f32; 4]], accum2: &mut [[f32; 4]]) {
    let scale = chunk.splats.scale;
    let passes = chunk.radiance.len() / chunk.pixel_count.max(1);
    for i in 0..chunk.pixel_count {
        let pixel = chunk.pixel_offset + i;
        for q in 0..passes {
            let splats = chunk.splats.value(q * chunk.pixels + pixel);
            let r = chunk.radiance[q * chunk.pixel_count + i];
            let l: [f32; 3] = std::array::from_fn(|k| r[k] + splats[k]);
            let squared = l.map(|v| (v * scale) * (v * scale));
            compensated::add_to_film(accum, pixel, [l[0], l[1], l[2], 1.0]);
            compensated::add_to_film(accum2, pixel, [squared[0], squared[1], squared[2], 0.0]);
        }
    }
}
