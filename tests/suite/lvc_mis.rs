//! The GPU's MIS weights against the brute-force oracle (src/bidir/oracle.rs) on the
//! paths the GPU really made: every emitter hit, direct-lighting sample, connection to a
//! cache vertex and light-tracing splat of a render is dumped with its weight; its path
//! is traced again on the CPU (the camera subpath of its pixel and pass, the light
//! subpath of its cache vertex — of another pixel's light path, as a cache makes
//! them), its densities read off ([`path_densities`]) and n_s p_s / Σ_j n_j p_j computed
//! with the render's technique counts, the count factor of the cache included. The
//! weights of a path's techniques then sum to 1 by construction of the oracle; the GPU's
//! must be the oracle's. A path the CPU's walk does not reproduce (another triangle or
//! point, or MIS quantities drifted apart beyond [`MIS_STATE_DRIFT`]) is skipped as
//! parted; at most 1 % may be.
//!
//! Scenes: `lamps` with a point light (shading normals, a mixed diffuse-and-mirror
//! sphere, conductors, lights inside fixtures), unbounded; the Cornell box at
//! max_depth 4 with resampled connections.
use crate::common;

use glam::Vec3;
use splitray::bidir::densities::path_densities;
use splitray::bidir::lights::Lights;
use splitray::bidir::oracle::PathDensities;
use splitray::bidir::random::{dims as bidir_dims, fold_seed, PathSampler};
use splitray::bidir::vertex::{Vertex, NO_TRIANGLE};
use splitray::bidir::walk::{camera_subpath, light_subpath};
use splitray::bidir::{Counters, CpuScene, PinholeCamera, TechniqueCounts, WalkSettings};
use splitray::bsdf::Frame;
use splitray::integrator::lvc::gpu::{Contribution, LvcVertex, VERTEX_VALID};
use splitray::integrator::lvc::{LvcOptions, Variant};
use splitray::scene::{builtin, PointLight, Scene};

/// The subpaths of the CPU's walks, by (index, pass).
struct Walks<'a> {
    scene: &'a CpuScene,
    camera: &'a PinholeCamera,
    settings: &'a WalkSettings,
    seed: u32,
}

impl Walks<'_> {
    fn camera(&self, pixel: u32, pass: u32) -> Vec<Vertex> {
        let mut v = Vec::new();
        let sampler = PathSampler::new(pixel, pass, self.seed);
        let mut c = Counters::default();
        camera_subpath(
            self.scene,
            self.camera,
            self.settings,
            &sampler,
            pixel,
            &mut v,
            &mut c,
        );
        v
    }

    fn light(&self, index: u32, pass: u32) -> Vec<Vertex> {
        let mut v = Vec::new();
        let sampler = PathSampler::new(index, pass, self.seed);
        light_subpath(
            self.scene,
            self.settings,
            &sampler,
            &mut v,
            &mut Counters::default(),
        );
        v
    }
}

/// How far apart the two walks' MIS states may drift, relatively, before the CPU's walk
/// no longer stands for the GPU's path. A weight is 1 / (1 + Σ), each Σ term the vertex's
/// `d_vcm` or `d_vc` times densities at the connection, so its relative error is at most
/// the states' relative difference plus the connection's own rounding: a state drift
/// beyond this bound could move the weight by half the tolerance of [`Checked::weight`]
/// by itself. Two f32 walks drift apart over many bounces (NVIDIA fuses multiply-adds
/// where the CPU rounds twice), so long paths may exceed it; such paths are skipped as
/// parted, and the test bounds how many are.
const MIS_STATE_DRIFT: f32 = 1e-3;

/// Relative difference of two non-negative MIS quantities (0 when both are 0).
fn drift(a: f32, b: f32) -> f32 {
    let m = a.abs().max(b.abs());
    if m == 0.0 {
        0.0
    } else {
        (a - b).abs() / m
    }
}

/// The CPU's vertex moved onto the GPU's record of it: the point, shading normal and
/// incoming direction the GPU connected or splatted from, the rest (its densities and
/// MIS state among them) the CPU walk's. The two walks' endpoints differ by the rounding
/// of every bounce before them, and a connection's densities at an endpoint with a narrow
/// glossy lobe follow its direction closely: on NVIDIA, nine bounces of f32 rounding moved
/// one reverse density by 0.4 % and the oracle's weight by 2.8e-3, where the GPU's weight
/// was the oracle's on the recorded endpoint to 1e-6. Neither reading of the path is
/// exact (the recorded one mixes the GPU's endpoint with the CPU's vertices before it),
/// so a weight is checked against both ([`Checked::weight`]).
fn as_recorded(cpu: &Vertex, gpu: &LvcVertex) -> Vertex {
    let ns = Vec3::from(gpu.ns);
    Vertex {
        p: gpu.position(),
        ns,
        frame: Frame::from_normal(ns),
        wo: Vec3::from(gpu.wo),
        ..*cpu
    }
}

/// The MIS state drift between the CPU's vertex and the GPU's record if they are the same
/// vertex: the same triangle and point, reached with the same MIS state, up to rounding.
fn agreement(cpu: &Vertex, gpu: &LvcVertex, scale: f32) -> Option<f32> {
    let state = drift(cpu.mis.d_vcm, gpu.d_vcm).max(drift(cpu.mis.d_vc, gpu.d_vc));
    (cpu.triangle == gpu.triangle
        && (cpu.p - gpu.position()).length() <= 1e-4 * scale
        && state <= MIS_STATE_DRIFT)
        .then_some(state)
}

/// A subpath as the CPU walked it, the same with its last vertex moved onto the GPU's
/// record of it ([`as_recorded`]), and that vertex's MIS state drift.
struct Subpath {
    walked: Vec<Vertex>,
    recorded: Vec<Vertex>,
    drift: f32,
}

impl Subpath {
    /// `walk[..=i]` if its vertex i is the GPU's record `gpu`.
    fn cut(walk: &[Vertex], i: usize, gpu: &LvcVertex, scale: f32) -> Option<Self> {
        let drift = agreement(walk.get(i)?, gpu, scale)?;
        let walked = walk[..=i].to_vec();
        let mut recorded = walked.clone();
        recorded[i] = as_recorded(&walked[i], gpu);
        Some(Self {
            walked,
            recorded,
            drift,
        })
    }
}

#[derive(Debug, Default)]
struct Checked {
    /// Light tracing, emitter hits, direct lighting, connections.
    families: [usize; 4],
    /// Dumped samples whose CPU walk had parted from the GPU's (skipped).
    parted: usize,
    through_delta: usize,
    worst: f64,
    /// The largest MIS state drift among the checked paths' endpoints.
    worst_drift: f32,
    /// The largest change of an oracle weight between the walked and recorded endpoints.
    worst_sensitivity: f64,
    /// Weights that matched the oracle only on the recorded endpoints.
    only_recorded: usize,
    /// The weights beyond the tolerance, described.
    wrong: Vec<String>,
}

impl Checked {
    /// Checks the GPU's weight of a sample against the oracle's on its path, `d` being the
    /// path's densities with the CPU walk's endpoints and with the GPU's recorded ones
    /// ([`as_recorded`]): the weight must be within 2e-3 (relative) of the oracle's on one
    /// of the two. A wrong weight formula misses both on any path; rounding moves the
    /// readings apart only on ill-conditioned paths, and there the GPU's weight is the
    /// oracle's on one of them.
    fn weight(
        &mut self,
        family: usize,
        gpu: &Contribution,
        d: [PathDensities; 2],
        counts: &TechniqueCounts,
        drift: f32,
    ) {
        let (s, t) = gpu.technique();
        assert_eq!(d[0].segments() + 1, (s + t) as usize);
        assert!(
            d[0].can_sample(counts, s as usize),
            "({s}, {t}) cannot make its path"
        );
        let w = d.each_ref().map(|d| d.balance_weights(counts)[s as usize]);
        let [walked, recorded] = w.map(|w| (gpu.weight as f64 - w).abs() / w.max(1e-6));
        let error = walked.min(recorded);
        if error >= 2e-3 {
            self.wrong.push(format!(
                "({s}, {t}): GPU weight {} vs oracle {} (on the GPU's endpoints: {}), \
                 endpoints' MIS state drift {drift}; {:?}; on the GPU's endpoints {:?}",
                gpu.weight, w[0], w[1], d[0], d[1],
            ));
        }
        self.only_recorded += (walked >= 2e-3 && recorded < 2e-3) as usize;
        self.worst = self.worst.max(error);
        self.worst_sensitivity = self
            .worst_sensitivity
            .max((w[1] - w[0]).abs() / w[0].max(1e-6));
        self.worst_drift = self.worst_drift.max(drift);
        self.families[family] += 1;
        let k = d[0].segments();
        self.through_delta += d[0].delta[1..k].contains(&true) as usize;
    }
}

fn check(name: &str, scene: &Scene, size: u32, options: LvcOptions, passes: u32) -> Checked {
    let gpu = common::gpu();
    let (dumps, lvc) = common::lvc_dump::render(&gpu, scene, size, size, &options, passes);
    let counts = lvc.counts();
    let light_paths = lvc.constants().light_paths;
    drop(lvc);
    common::assert_clean(&gpu);
    let cpu = CpuScene::new(scene);
    let camera = PinholeCamera::new(&scene.camera.frame(size, size));
    let settings = WalkSettings {
        max_depth: options.max_depth,
        rr_depth: options.rr_depth,
        counts,
    };
    let walks = Walks {
        scene: &cpu,
        camera: &camera,
        settings: &settings,
        seed: fold_seed(options.seed),
    };
    let scale = scene.bounds().radius();
    let densities = |light: [&[Vertex]; 2], cam: [&[Vertex]; 2]| {
        [0, 1].map(|e| path_densities(&cpu, &camera, light[e], cam[e]))
    };
    let mut checked = Checked::default();
    for d in &dumps.chunks {
        let first = d.chunk.first_pass;
        // The light subpath of cache vertex y, cut after y, if the CPU's walk agrees.
        let light_of = |y: &LvcVertex| -> Option<Subpath> {
            let l = walks.light(y.path % light_paths, first + y.path / light_paths);
            Subpath::cut(&l, y.depth as usize, y, scale)
        };
        let pinhole = &walks.camera(0, 0)[..1];
        for (y, c) in d.cache.iter().zip(&d.splats) {
            if !c.is_some() {
                continue;
            }
            match light_of(y) {
                Some(l) => {
                    let d = densities([&l.walked, &l.recorded], [pinhole; 2]);
                    checked.weight(0, c, d, &counts, l.drift);
                }
                None => checked.parted += 1,
            }
        }
        for b in &d.bounces {
            for i in 0..b.view_paths as usize {
                let z = &b.vertices[i];
                if !z.is(VERTEX_VALID) {
                    continue;
                }
                let c = b.active[i];
                let (pixel, pass) = (
                    b.pixel_offset + c % b.pixel_count,
                    first + c / b.pixel_count,
                );
                let walk = walks.camera(pixel, pass);
                let j = z.depth as usize;
                let Some(cam) = Subpath::cut(&walk, j, z, scale) else {
                    checked.parted += 1;
                    continue;
                };
                let cams = [&cam.walked[..], &cam.recorded[..]];
                if b.emitted[i].is_some() {
                    let d = densities([&[]; 2], cams);
                    checked.weight(1, &b.emitted[i], d, &counts, cam.drift);
                }
                if b.contributions[i].is_some() {
                    let sampler = PathSampler::new(pixel, pass, walks.seed);
                    let u = [
                        bidir_dims::LIGHT_PICK,
                        bidir_dims::LIGHT_POINT,
                        bidir_dims::LIGHT_POINT + 1,
                    ]
                    .map(|o| sampler.get(bidir_dims::camera_vertex(j as u32, o)));
                    let point = Lights::new(&cpu.tables.lights).sample(u).unwrap();
                    let light = [Vertex::light(&point, NO_TRIANGLE)];
                    let d = densities([&light; 2], cams);
                    checked.weight(2, &b.contributions[i], d, &counts, cam.drift);
                }
                let n = options.connections as usize;
                for k in 0..n {
                    let g = &b.contributions[b.base as usize + i * n + k];
                    if !g.is_some() {
                        continue;
                    }
                    match light_of(&d.cache[g.target as usize]) {
                        Some(l) => {
                            let d = densities([&l.walked, &l.recorded], cams);
                            checked.weight(3, g, d, &counts, cam.drift.max(l.drift));
                        }
                        None => checked.parted += 1,
                    }
                }
            }
        }
    }
    let wrong = std::mem::take(&mut checked.wrong);
    eprintln!("{name}: {checked:?}");
    assert!(
        wrong.is_empty(),
        "{name}: {} weights differ from the oracle's:\n{}",
        wrong.len(),
        wrong[..wrong.len().min(8)].join("\n")
    );
    let total: usize = checked.families.iter().sum();
    assert!(checked.parted * 100 <= total, "{name}: {checked:?}");
    checked
}

#[test]
fn gpu_weights_equal_the_oracle_on_dumped_paths() {
    let mut lamps = builtin("lamps").unwrap();
    lamps.point_lights.push(PointLight {
        position: Vec3::new(1.2, 1.6, -0.5),
        intensity: Vec3::new(3.0, 2.5, 2.0),
    });
    let mut options = LvcOptions::new(Variant::LvcBdpt, true);
    options.seed = 11;
    options.connections = 3;
    let lamps = check("lamps", &lamps, 12, options, 4);
    assert!(
        lamps.through_delta > 20,
        "paths through the sphere's mirror layer"
    );

    // The Cornell box with a glowing red wall: camera paths hit an emitter often.
    let mut cornell = builtin("cornell-box").unwrap();
    cornell.materials[1].emission = Vec3::new(0.5, 0.1, 0.1);
    let mut options = LvcOptions::new(Variant::CisLbdpt, true);
    options.seed = 5;
    options.connections = 2;
    options.candidates = 6;
    options.max_depth = 4;
    let cornell = check("cornell-box", &cornell, 10, options, 4);
    // The lamps' emitters hide in their shades: the Cornell box supplies the hits.
    for f in 0..4 {
        let n = lamps.families[f] + cornell.families[f];
        assert!(n > 20, "family {f}: {n} weights checked");
    }
}
