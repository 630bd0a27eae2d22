//! The GPU's MIS weights against the brute-force oracle (src/bidir/oracle.rs) on the
//! paths the GPU really made: every emitter hit, direct-lighting sample, connection to a
//! cache vertex and light-tracing splat of a render is dumped with its weight; its path
//! is traced again on the CPU (the camera subpath of its pixel and pass, the light
//! subpath of its cache vertex — of another pixel's light path, as a cache makes
//! them), its densities read off ([`path_densities`]) and n_s p_s / Σ_j n_j p_j computed
//! with the render's technique counts, the count factor of the cache included. The
//! weights of a path's techniques then sum to 1 by construction of the oracle; the GPU's
//! must be the oracle's.
//!
//! Scenes: `lamps` with a point light (shading normals, a mixed diffuse-and-mirror
//! sphere, conductors, lights inside fixtures), unbounded; the Cornell box at
//! max_depth 4 with resampled connections.
mod common;

use glam::Vec3;
use splitray::bidir::densities::path_densities;
use splitray::bidir::lights::Lights;
use splitray::bidir::random::{dims as bidir_dims, fold_seed, PathSampler};
use splitray::bidir::vertex::{Vertex, NO_TRIANGLE};
use splitray::bidir::walk::{camera_subpath, light_subpath};
use splitray::bidir::{Counters, CpuScene, PinholeCamera, WalkSettings};
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

/// Whether the CPU's vertex is the GPU's record (the walks agree up to rounding).
fn same(cpu: &Vertex, gpu: &LvcVertex, scale: f32) -> bool {
    cpu.triangle == gpu.triangle && (cpu.p - gpu.position()).length() <= 1e-4 * scale
}

#[derive(Debug, Default)]
struct Checked {
    /// Light tracing, emitter hits, direct lighting, connections.
    families: [usize; 4],
    /// Dumped samples whose CPU walk had parted from the GPU's (skipped).
    parted: usize,
    through_delta: usize,
    worst: f64,
}

impl Checked {
    fn weight(
        &mut self,
        family: usize,
        gpu: &Contribution,
        d: &splitray::bidir::oracle::PathDensities,
        counts: &splitray::bidir::TechniqueCounts,
    ) {
        let (s, t) = gpu.technique();
        assert_eq!(d.segments() + 1, (s + t) as usize);
        assert!(
            d.can_sample(counts, s as usize),
            "({s}, {t}) cannot make its path"
        );
        let w = d.balance_weights(counts)[s as usize];
        let error = (gpu.weight as f64 - w).abs() / w.max(1e-6);
        assert!(
            error < 2e-3,
            "({s}, {t}): GPU weight {} vs oracle {w}; {d:?}",
            gpu.weight
        );
        self.worst = self.worst.max(error);
        self.families[family] += 1;
        let k = d.segments();
        self.through_delta += d.delta[1..k].contains(&true) as usize;
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
    let mut checked = Checked::default();
    for d in &dumps.chunks {
        let first = d.chunk.first_pass;
        // The light subpath of cache vertex y, cut after y, if the CPU's walk agrees.
        let light_of = |y: &LvcVertex| -> Option<Vec<Vertex>> {
            let l = walks.light(y.path % light_paths, first + y.path / light_paths);
            let i = y.depth as usize;
            (l.len() > i && same(&l[i], y, scale)).then(|| l[..=i].to_vec())
        };
        for (y, c) in d.cache.iter().zip(&d.splats) {
            if !c.is_some() {
                continue;
            }
            match light_of(y) {
                Some(l) => {
                    let pinhole = &walks.camera(0, 0)[..1];
                    let densities = path_densities(&cpu, &camera, &l, pinhole);
                    checked.weight(0, c, &densities, &counts);
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
                let cam = walks.camera(pixel, pass);
                let j = z.depth as usize;
                if cam.len() <= j || !same(&cam[j], z, scale) {
                    checked.parted += 1;
                    continue;
                }
                let cam = &cam[..=j];
                if b.emitted[i].is_some() {
                    checked.weight(
                        1,
                        &b.emitted[i],
                        &path_densities(&cpu, &camera, &[], cam),
                        &counts,
                    );
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
                    let densities = path_densities(&cpu, &camera, &light, cam);
                    checked.weight(2, &b.contributions[i], &densities, &counts);
                }
                let n = options.connections as usize;
                for k in 0..n {
                    let g = &b.contributions[b.base as usize + i * n + k];
                    if !g.is_some() {
                        continue;
                    }
                    match light_of(&d.cache[g.target as usize]) {
                        Some(l) => {
                            let densities = path_densities(&cpu, &camera, &l, cam);
                            checked.weight(3, g, &densities, &counts);
                        }
                        None => checked.parted += 1,
                    }
                }
            }
        }
    }
    eprintln!("{name}: {checked:?}");
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
