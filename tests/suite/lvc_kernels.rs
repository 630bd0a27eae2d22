//! Every kernel of the light-vertex-cache integrators against its CPU twin
//! (src/integrator/lvc/twin.rs, which runs the CPU BPT's walks and techniques on the
//! kernels' records), on what the kernels really wrote (an [`Observer`] reads the
//! buffers after each stage):
//!
//! - light pass (`light_generate`, `light_shade`, `light_store`): each light path's
//!   cached vertices against `bidir::walk::light_subpath` of the same random numbers;
//! - the per-path index (`light_index`, count → prefix sum → write): exact;
//! - light tracing (`light_connect`) against `Connector::light_trace`, and the splat film
//!   (`splat`) against the fixed-point sums of the same contributions: exact;
//! - camera pass: vertex records (`camera_generate`, `camera_vertex`, `camera_bounce`)
//!   against `bidir::walk::camera_subpath`; emitter hits, direct lighting and
//!   connections (`camera_vertex`, `camera_direct`, `camera_connect`, uniform and
//!   resampled, independent and systematic draws) against `Connector` on the GPU's own
//!   records, with the cache vertices the selection must have drawn (and, resampled,
//!   each draw's candidate and copies from `twin::resample`); `camera_accumulate` and
//!   `finish` (`twin::finish`: the film's sums and second moments) against sums of the
//!   dumped contributions, and the visibility tally of every bounce, summed into the
//!   integrator's counters, against `twin::accumulate`'s; with sorting on, every bounce's `order` (`sort_keys` and the
//!   radix sort of the keys' ranks) against a stable CPU sort of the 32-bit material
//!   keys of the same hits.
//!
//! Sizes: one pixel, a non-power-of-two film, several passes per chunk, a scene whose
//! light paths leave nothing to cache, bounded and unbounded depth. A walk may leave
//! its CPU twin where rounding flips a decision (a roulette draw within an ulp of its
//! threshold, a ray through an edge); such paths are counted and must stay rare (at
//! most 1 in 100), and every vertex before the divergence must agree.
use crate::common;

use common::lvc_dump::{render, BounceDump, ChunkDump};
use glam::Vec3;
use splitray::bidir::random::{fold_seed, random01, PathSampler};
use splitray::bidir::{Connector, CpuScene, PinholeCamera, WalkSettings};
use splitray::film::compensated;
use splitray::integrator::lvc::fixed::FixedFilm;
use splitray::integrator::lvc::gpu::{dims, Contribution, LvcVertex, VERTEX_CONNECTIBLE};
use splitray::integrator::lvc::options::{MAX_CANDIDATES, MAX_CONNECTIONS};
use splitray::integrator::lvc::{twin, LvcOptions, Resampling, Variant, Visibility};
use splitray::integrator::pt::PtScene;
use splitray::integrator::Integrator;
use splitray::scene::{builtin, Material, PointLight, Scene, Triangle};
use splitray::trace::MISS;

/// Relative closeness of two vectors, scaled by the larger norm (and `floor`).
fn close(a: Vec3, b: Vec3, rel: f32, floor: f32) -> bool {
    (a - b).length() <= rel * a.length().max(b.length()).max(floor)
}

fn close1(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-30)
}

/// Whether two records describe the same vertex (up to rounding). `scale`: the scene's
/// size, for positions.
fn same_vertex(gpu: &LvcVertex, cpu: &LvcVertex, scale: f32) -> bool {
    gpu.triangle == cpu.triangle
        && gpu.material == cpu.material
        && gpu.depth == cpu.depth
        && gpu.flags == cpu.flags
        && close(gpu.position(), cpu.position(), 1e-4, scale)
        && close(Vec3::from(gpu.wo), Vec3::from(cpu.wo), 1e-3, 1.0)
        && close(Vec3::from(gpu.ns), Vec3::from(cpu.ns), 1e-3, 1.0)
        && close(Vec3::from(gpu.beta), Vec3::from(cpu.beta), 2e-3, 1e-12)
        && close1(gpu.d_vcm, cpu.d_vcm, 2e-3)
        && close1(gpu.d_vc, cpu.d_vc, 2e-3)
}

/// Compares two walks of one path: the number of leading vertices that agree, and
/// whether the walks agree wholly.
fn compare_walks(gpu: &[LvcVertex], cpu: &[LvcVertex], scale: f32) -> (usize, bool) {
    let agree = gpu
        .iter()
        .zip(cpu)
        .take_while(|(g, c)| same_vertex(g, c, scale))
        .count();
    (agree, agree == gpu.len() && agree == cpu.len())
}

/// Counts paths and the ones that left their twin.
#[derive(Default, Debug)]
struct Agreement {
    paths: usize,
    diverged: usize,
    vertices: usize,
}

impl Agreement {
    fn add(&mut self, (agree, whole): (usize, bool), what: &str) {
        self.paths += 1;
        self.vertices += agree;
        if !whole {
            self.diverged += 1;
            eprintln!("{what}: walks agree on {agree} vertices, then part");
        }
    }

    fn check(&self, what: &str) {
        eprintln!("{what}: {self:?}");
        assert!(self.paths > 0, "{what}: no paths");
        assert!(
            self.diverged * 100 <= self.paths,
            "{what}: {} of {} paths left their CPU twin",
            self.diverged,
            self.paths
        );
    }
}

/// A case: a scene and the integrator's settings.
struct Case {
    name: &'static str,
    scene: Scene,
    width: u32,
    height: u32,
    options: LvcOptions,
    passes: u32,
}

fn lamps_with_point_light() -> Scene {
    let mut s = builtin("lamps").unwrap();
    s.point_lights.push(PointLight {
        position: Vec3::new(1.2, 1.6, -0.5),
        intensity: Vec3::new(3.0, 2.5, 2.0),
    });
    s
}

/// A floor and a light above it that faces away: no light path reaches a surface.
fn dark_floor() -> Scene {
    let mut s = builtin("cornell-box").unwrap();
    let floor = |p: [f32; 3]| Vec3::from(p);
    s.triangles = vec![
        Triangle::new(
            floor([0., 0., 0.]),
            floor([0., 0., 1.]),
            floor([1., 0., 1.]),
            0,
        ),
        Triangle::new(
            floor([0., 0., 0.]),
            floor([1., 0., 1.]),
            floor([1., 0., 0.]),
            0,
        ),
        Triangle::new(
            floor([0., 1., 0.]),
            floor([0., 1., 1.]),
            floor([1., 1., 1.]),
            1,
        ),
    ];
    s.materials = vec![
        Material::named("floor"),
        Material {
            emission: Vec3::ONE,
            ..Material::named("light")
        },
    ];
    s.camera.position = Vec3::new(0.5, 0.5, -1.0);
    s.camera.look_at = Vec3::new(0.5, 0.0, 0.5);
    s
}

fn options(variant: Variant, connections: u32, max_depth: i32) -> LvcOptions {
    let mut o = LvcOptions::new(variant, true);
    o.seed = 3;
    o.connections = connections;
    o.max_depth = max_depth;
    o
}

/// Checks every kernel of `case`; returns the most distinct material keys one sorted
/// bounce ordered (0 without sorting).
fn check_case(case: Case) -> usize {
    let gpu = common::gpu();
    let (dumps, mut lvc) = render(
        &gpu,
        &case.scene,
        case.width,
        case.height,
        &case.options,
        case.passes,
    );
    let c = *lvc.constants();
    let counts = lvc.counts();
    let cpu_scene = CpuScene::new(&case.scene);
    let open = twin::unoccluded(PtScene::new(&case.scene));
    let frame = case.scene.camera.frame(case.width, case.height);
    let camera = PinholeCamera::new(&frame);
    let settings = WalkSettings {
        max_depth: case.options.max_depth,
        rr_depth: case.options.rr_depth,
        counts,
    };
    let connector = Connector {
        scene: &open,
        camera: &camera,
        settings: &settings,
    };
    let seed = fold_seed(case.options.seed);
    let scale = case.scene.bounds().radius();
    let pixels = case.width * case.height;
    let (mut light, mut cam) = (Agreement::default(), Agreement::default());
    // Sums, then their remainders (film::compensated).
    let mut film = vec![[0.0f32; 4]; 2 * pixels as usize];
    let mut film2 = film.clone();
    let mut sorted_keys = 0;
    // The material keys the sorted bounces are checked against.
    let sorted_scene = case.options.sort.then(|| PtScene::new(&case.scene));
    for d in &dumps.chunks {
        let ch = d.chunk;
        check_index(d);
        let twins = twin::light_pass(
            &cpu_scene,
            &settings,
            seed,
            ch.first_pass,
            ch.passes,
            c.light_paths,
        );
        for (l, cpu) in twins.iter().enumerate() {
            let gpu: Vec<LvcVertex> = (d.path_offset[l]..d.path_offset[l + 1])
                .map(|k| d.cache[d.index[k as usize] as usize])
                .collect();
            light.add(
                compare_walks(&gpu, cpu, scale),
                &format!("{} light path {l}", case.name),
            );
        }
        check_light_tracing(d, &connector, &open, c.light_paths, pixels);
        check_splat_film(d, pixels, c.brightness_scale);
        if let Some(pt) = &sorted_scene {
            for b in &d.bounces {
                sorted_keys = sorted_keys.max(check_material_order(b, pt, case.name));
            }
        }
        let radiance = check_camera(
            d, &case, &connector, &cpu_scene, &open, seed, scale, &mut cam,
        );
        // finish: the film gains each pass's radiance plus its splats.
        let splats = FixedFilm::from_words(&d.splat_film, c.brightness_scale);
        let radiance: Vec<[f32; 4]> = radiance.iter().map(|r| [r[0], r[1], r[2], 0.0]).collect();
        let chunk = twin::FinishChunk {
            radiance: &radiance[..(ch.passes * pixels) as usize],
            splats: &splats,
            pixels: pixels as usize,
            pixel_offset: 0,
            pixel_count: pixels as usize,
        };
        twin::finish(&chunk, &mut film, &mut film2);
    }
    light.check(&format!("{} light walks", case.name));
    cam.check(&format!("{} camera walks", case.name));
    let sums = lvc.sums().unwrap();
    // The second moments are compared as the GPU sums them, at the brightness scale.
    let s2 = (c.brightness_scale as f64).powi(2);
    let (film, film2) = (
        compensated::film_rgb(&film, 1.0),
        compensated::film_rgb(&film2, 1.0),
    );
    for (p, (e, e2)) in film.iter().zip(&film2).enumerate() {
        for k in 0..3 {
            let (got, want) = (sums.sum[p][k] as f32, e[k] as f32);
            assert!(
                close1(got, want, 1e-5) || (want - got).abs() < 1e-6,
                "{}: film pixel {p}: {got} vs {want}",
                case.name
            );
            let (got, want) = (
                (sums.sum_sq.as_ref().unwrap()[p][k] * s2) as f32,
                e2[k] as f32,
            );
            assert!(
                close1(got, want, 1e-4) || (want - got).abs() < 1e-6,
                "{}: film pixel {p}: second moment {got} vs {want}",
                case.name
            );
        }
    }
    assert_eq!(lvc.kernel_counters().unwrap(), [0, 0], "{}", case.name);
    assert_eq!(
        lvc.lvc_counters().visibility,
        visibility_twin(&dumps.chunks, case.options.connections as usize),
        "{}: visibility tally",
        case.name
    );
    drop(lvc);
    common::assert_clean(&gpu);
    sorted_keys
}

/// The live paths' positions in the order of their hits' material keys (type << 24 | id,
/// misses last), equal keys in position order: what a stable sort of the 32-bit keys
/// gives, which the GPU must reach sorting only the keys' ranks.
/// Returns how many distinct keys the bounce sorted.
fn check_material_order(b: &BounceDump, pt: &PtScene, name: &str) -> usize {
    let key = |i: u32| {
        let tri = b.closest[i as usize].triangle;
        if tri == MISS {
            u32::MAX
        } else {
            pt.materials[pt.triangle_material[tri as usize] as usize].key
        }
    };
    let mut expected: Vec<u32> = (0..b.view_paths).collect();
    expected.sort_by_key(|&i| key(i));
    assert_eq!(
        b.order, expected,
        "{name}: bounce {} material order",
        b.bounce
    );
    let distinct: std::collections::BTreeSet<u32> = expected.iter().map(|&i| key(i)).collect();
    distinct.len()
}

/// The index lists every cache vertex once, each light path's contiguously and in order.
fn check_index(d: &ChunkDump) {
    let n = d.chunk.vertices as usize;
    assert_eq!(d.path_offset[0], 0);
    assert_eq!(*d.path_offset.last().unwrap() as usize, n);
    let mut seen = vec![false; n];
    for l in 0..d.chunk.light_paths as usize {
        for (o, k) in (d.path_offset[l]..d.path_offset[l + 1]).enumerate() {
            let slot = d.index[k as usize] as usize;
            assert!(!seen[slot], "cache vertex {slot} listed twice");
            seen[slot] = true;
            let v = &d.cache[slot];
            assert_eq!((v.path as usize, v.ordinal as usize), (l, o));
            assert!(v.is(VERTEX_CONNECTIBLE));
        }
    }
    assert!(seen.iter().all(|&s| s));
}

fn check_light_tracing(
    d: &ChunkDump,
    connector: &Connector,
    open: &CpuScene,
    light_paths: u32,
    pixels: u32,
) {
    assert_eq!(d.splats.len(), d.cache.len());
    let mut compared = 0;
    for (k, (y, g)) in d.cache.iter().zip(&d.splats).enumerate() {
        let cpu = twin::light_trace(connector, y).filter(|s| s.value != Vec3::ZERO);
        match (cpu, g.is_some()) {
            (None, false) => {}
            (Some(s), true) => {
                let pass = y.path / light_paths;
                assert_eq!(
                    g.target,
                    pass * pixels + s.pixel.unwrap(),
                    "splat {k}: pixel"
                );
                assert_eq!(g.technique(), (s.s, s.t));
                assert!(
                    close1(g.weight, s.weight, 1e-3),
                    "splat {k}: weight {} vs {}",
                    g.weight,
                    s.weight
                );
                let expected = s.weighted() / light_paths as f32;
                assert!(
                    close(g.value(), expected, 2e-3, 1e-20),
                    "splat {k}: {:?} vs {expected}",
                    g.value
                );
                let ray = twin::shadow_ray(
                    open,
                    y.position(),
                    twin::geometric_normal(open, y),
                    connector.camera.position(),
                    Vec3::ZERO,
                )
                .unwrap();
                let r = &d.splat_rays[k];
                assert!(close(
                    Vec3::from(r.origin),
                    Vec3::from(ray.origin),
                    1e-5,
                    1.0
                ));
                assert!(close(Vec3::from(r.dir), Vec3::from(ray.dir), 1e-4, 1.0));
                assert!(close1(r.tmax, ray.tmax, 1e-4));
                compared += 1;
            }
            (cpu, gpu) => panic!("splat {k}: CPU {cpu:?}, GPU {gpu} ({g:?})"),
        }
    }
    eprintln!(
        "light tracing: {compared} of {} cache vertices splat",
        d.cache.len()
    );
}

/// The splat film is the fixed-point sum of the unoccluded contributions, to the bit.
fn check_splat_film(d: &ChunkDump, pixels: u32, scale: f32) {
    let mut expected = FixedFilm::new((d.chunk.passes * pixels) as usize, scale);
    for (c, h) in d.splats.iter().zip(&d.splat_hits) {
        if c.is_some() && h.triangle == MISS {
            expected.add(c.target as usize, c.value);
        }
    }
    let gpu = FixedFilm::from_words(&d.splat_film[..expected.sums.len() * 6], scale);
    assert_eq!(gpu.sums, expected.sums);
}

/// The camera pass: per bounce, each live path's vertex against its CPU walk, its
/// techniques against the CPU's on the GPU's record; returns each path's radiance after
/// its last bounce, recomputed from the dumped contributions.
#[allow(clippy::too_many_arguments)]
fn check_camera(
    d: &ChunkDump,
    case: &Case,
    connector: &Connector,
    cpu_scene: &CpuScene,
    open: &CpuScene,
    seed: u32,
    scale: f32,
    agreement: &mut Agreement,
) -> Vec<[f32; 3]> {
    let o = &case.options;
    let n_conn = o.connections as usize;
    let light_paths = d.chunk.light_paths / d.chunk.passes;
    let mut radiance: Vec<[f32; 3]> = Vec::new();
    let mut walks: std::collections::BTreeMap<u32, (Vec<LvcVertex>, Vec<LvcVertex>)> =
        Default::default();
    for b in &d.bounces {
        let paths = (d.chunk.passes * b.pixel_count) as usize;
        if b.bounce == 1 {
            radiance = vec![[0.0; 3]; paths];
        }
        for i in 0..b.view_paths as usize {
            let c = b.active[i];
            let pixel = b.pixel_offset + c % b.pixel_count;
            let pass_in_chunk = c / b.pixel_count;
            let pass = d.chunk.first_pass + pass_in_chunk;
            let z = &b.vertices[i];
            let entry = walks.entry(c).or_insert_with(|| {
                let cpu = twin::camera_records(
                    cpu_scene,
                    connector.camera,
                    connector.settings,
                    seed,
                    pixel,
                    pass,
                    c,
                );
                (cpu, Vec::new())
            });
            if z.is(splitray::integrator::lvc::gpu::VERTEX_VALID) {
                entry.1.push(*z);
            }
            // Techniques on the GPU's own record.
            let mut sum = radiance[c as usize];
            if z.is(splitray::integrator::lvc::gpu::VERTEX_VALID) {
                let cpu = twin::emitter_hit(connector, z).filter(|s| s.value != Vec3::ZERO);
                compare_sample(
                    "emitter hit",
                    cpu.map(|s| (s.weighted(), s.weight, (s.s, s.t))),
                    &b.emitted[i],
                );
                let sampler = PathSampler::new(pixel, pass, seed);
                let cpu = twin::direct(connector, z, &sampler);
                compare_sample(
                    "direct",
                    cpu.map(|s| (s.weighted(), s.weight, (s.s, s.t))),
                    &b.contributions[i],
                );
                check_connections(
                    d,
                    b,
                    i,
                    z,
                    pixel,
                    pass,
                    pass_in_chunk,
                    light_paths,
                    connector,
                    open,
                    seed,
                    n_conn,
                    &case.options,
                );
            }
            add(&mut sum, &b.emitted[i], true);
            add(&mut sum, &b.contributions[i], b.hits[i].triangle == MISS);
            for k in 0..n_conn {
                let slot = b.base as usize + i * n_conn + k;
                add(
                    &mut sum,
                    &b.contributions[slot],
                    b.hits[slot].triangle == MISS,
                );
            }
            radiance[c as usize] = sum;
            let g = b.radiance[c as usize];
            for k in 0..3 {
                assert!(
                    close1(g[k], sum[k], 1e-6) || (g[k] - sum[k]).abs() < 1e-12,
                    "accumulate: path {c}: {g:?} vs {sum:?}"
                );
            }
        }
    }
    for (c, (cpu, gpu)) in &walks {
        agreement.add(
            compare_walks(gpu, cpu, scale),
            &format!("{} camera path {c}", case.name),
        );
    }
    radiance
}

/// The visibility tally of every dumped bounce as `twin::accumulate` counts it.
fn visibility_twin(chunks: &[ChunkDump], connections: usize) -> Visibility {
    let mut sum = Visibility::default();
    for b in chunks.iter().flat_map(|d| &d.bounces) {
        let paths = b.view_paths as usize;
        let records = twin::BounceRecords {
            live_ids: &b.active[..paths],
            emitted: &b.emitted,
            contributions: &b.contributions,
            shadow_hits: &b.hits,
            base: b.base as usize,
            connections,
        };
        let mut scratch = vec![[0.0f32; 4]; b.radiance.len()];
        sum.merge(&twin::accumulate(&records, &mut scratch).1.into());
    }
    assert!(sum.connection_rays > 0 || chunks.iter().all(|d| d.cache.is_empty()));
    sum
}

/// `camera_accumulate`'s addition of one contribution.
fn add(sum: &mut [f32; 3], v: &Contribution, visible: bool) {
    if v.is_some() && visible {
        for (s, v) in sum.iter_mut().zip(v.value) {
            *s += v;
        }
    }
}

/// A CPU sample: weighted value, weight, technique (s, t).
type Expected = (Vec3, f32, (u32, u32));

fn compare_sample(what: &str, cpu: Option<Expected>, gpu: &Contribution) {
    match (cpu, gpu.is_some()) {
        (None, false) => {}
        (Some((value, weight, technique)), true) => {
            assert_eq!(gpu.technique(), technique, "{what}");
            assert!(
                close1(gpu.weight, weight, 1e-3),
                "{what}: weight {} vs {weight}",
                gpu.weight
            );
            assert!(
                close(gpu.value(), value, 2e-3, 1e-20),
                "{what}: {:?} vs {value}",
                gpu.value
            );
        }
        (cpu, g) => panic!("{what}: CPU {cpu:?}, GPU {g} ({gpu:?})"),
    }
}

/// The connections of live path i: the cache vertices the selection draws and their
/// contributions (uniform), or the candidates and the resampled ones (CIS).
#[allow(clippy::too_many_arguments)]
fn check_connections(
    d: &ChunkDump,
    b: &BounceDump,
    i: usize,
    z: &LvcVertex,
    pixel: u32,
    pass: u32,
    pass_in_chunk: u32,
    light_paths: u32,
    connector: &Connector,
    open: &CpuScene,
    seed: u32,
    n: usize,
    o: &LvcOptions,
) {
    let start = d.path_offset[(pass_in_chunk * light_paths) as usize];
    let size = d.path_offset[((pass_in_chunk + 1) * light_paths) as usize] - start;
    let slots = (0..n).map(|k| &b.contributions[b.base as usize + i * n + k]);
    if size == 0 || !z.is(VERTEX_CONNECTIBLE) {
        assert!(slots.clone().all(|c| !c.is_some()));
        return;
    }
    let j = z.depth;
    let pick = |k: u32| {
        d.index[(start + twin::uniform_index(pixel, pass, dims::select(j, k), seed, size)) as usize]
    };
    let contribution = |slot: u32| {
        twin::connect(connector, &d.cache[slot as usize], z)
            .map(|s| (s.weighted(), s.weight, (s.s, s.t)))
    };
    match o.variant {
        Variant::LvcBdpt => {
            let scale = size as f32 / (n as f32 * light_paths as f32);
            for (k, g) in slots.enumerate() {
                let slot = pick(k as u32);
                let cpu = contribution(slot).map(|(v, w, t)| (v * scale, w, t));
                compare_sample("connection", cpu, g);
                if g.is_some() {
                    assert_eq!(g.target, slot, "connection {k}: the selected cache vertex");
                    let y = &d.cache[slot as usize];
                    let r = twin::shadow_ray(
                        open,
                        z.position(),
                        twin::geometric_normal(open, z),
                        y.position(),
                        twin::geometric_normal(open, y),
                    )
                    .unwrap();
                    let gr = &b.rays[b.base as usize + i * n + k];
                    assert!(close(
                        Vec3::from(gr.origin),
                        Vec3::from(r.origin),
                        1e-5,
                        1.0
                    ));
                }
            }
        }
        Variant::CisLbdpt => {
            let m = o.candidates;
            let candidates: Vec<(u32, Option<Expected>)> =
                (0..m).map(|k| (pick(k), contribution(pick(k)))).collect();
            let lum = |v: Vec3| v.dot(Vec3::new(0.212_671, 0.715_16, 0.072_169)).max(0.0);
            let targets: Vec<f32> = candidates
                .iter()
                .map(|(_, c)| c.map_or(0.0, |c| lum(c.0)))
                .collect();
            let total: f32 = targets.iter().sum();
            let scale = size as f32 / (m as f32 * n as f32 * light_paths as f32);
            // A candidate drawn c times is one slot with c times its contribution: the
            // copies of the traced slots account for all n draws.
            let mut draws = 0;
            let mut copies_of = Vec::new();
            for g in slots.clone() {
                if !g.is_some() {
                    copies_of.push(0);
                    continue;
                }
                let (_, chosen) = candidates
                    .iter()
                    .find(|(slot, _)| *slot == g.target)
                    .unwrap_or_else(|| panic!("resampled vertex {} is no candidate", g.target));
                let (v, w, t) = chosen.expect("a chosen candidate contributes");
                let once = v * (total / lum(v)) * scale;
                let copies = (lum(g.value()) / lum(once)).round().max(1.0);
                draws += copies as usize;
                copies_of.push(copies as usize);
                compare_sample("resampled connection", Some((once * copies, w, t)), g);
            }
            assert!(
                draws == n || total == 0.0,
                "{draws} of {n} resampled draws traced (total target {total})"
            );
            let random = |k: u32| random01(pixel, pass, dims::select(j, dims::RESAMPLE + k), seed);
            let Some(expected) = twin::resample(&targets, n as u32, o.resampling, random) else {
                return;
            };
            // Where a draw's point lies within rounding of the end of a candidate's
            // interval, the GPU's targets (rounded otherwise) may draw the neighbour.
            if expected.iter().any(|d| d.margin < 1e-4) {
                return;
            }
            // Which draws the GPU traced, and how often each candidate was drawn: the
            // twin's, draw for draw.
            for (k, g) in slots.enumerate() {
                let c = expected[k].candidate;
                let first = expected[..k].iter().all(|d| d.candidate != c);
                let copies = expected.iter().filter(|d| d.candidate == c).count();
                if first {
                    assert_eq!(
                        (g.target, copies_of[k]),
                        (candidates[c].0, copies),
                        "resampled draw {k} ({:?}): the cache vertex and its copies",
                        o.resampling
                    );
                } else {
                    assert!(
                        !g.is_some(),
                        "draw {k} repeats an earlier draw and is traced"
                    );
                }
            }
        }
    }
}

#[test]
fn lamps_with_a_point_light_unbounded() {
    let sorted_keys = check_case(Case {
        name: "lamps",
        scene: lamps_with_point_light(),
        width: 13,
        height: 7,
        // Sorted: the scene of the most materials checks the material order.
        options: LvcOptions {
            sort: true,
            ..options(Variant::LvcBdpt, 3, -1)
        },
        passes: 3,
    });
    assert!(
        sorted_keys >= 4,
        "a bounce of lamps sorted only {sorted_keys} distinct keys"
    );
}

/// Independent draws: two connections from five candidates, bounded depth.
#[test]
fn cornell_box_resampled_bounded_depth() {
    let mut o = options(Variant::CisLbdpt, 2, 4);
    o.candidates = 5;
    o.resampling = Resampling::Independent;
    check_case(Case {
        name: "cornell-box",
        scene: builtin("cornell-box").unwrap(),
        width: 9,
        height: 9,
        options: o,
        passes: 2,
    });
}

/// Systematic draws: three connections from seven candidates (N does not divide M, so
/// candidates are drawn floor or ceil of N w times), unbounded paths.
#[test]
fn cornell_box_resampled_systematically() {
    let mut o = options(Variant::CisLbdpt, 3, -1);
    o.candidates = 7;
    o.resampling = Resampling::Systematic;
    check_case(Case {
        name: "cornell-box systematic",
        scene: builtin("cornell-box").unwrap(),
        width: 7,
        height: 5,
        options: o,
        passes: 2,
    });
}

/// The largest M and N the options accept: every camera vertex fills all its candidate
/// and connection slots, so an index past a vertex's stride would land in its
/// neighbour's records. Both ways of drawing, one pass each to keep the run short.
#[test]
fn cornell_box_resampled_at_the_largest_candidates_and_connections() {
    for (name, resampling) in [
        (
            "cornell-box M = N = max, independent",
            Resampling::Independent,
        ),
        (
            "cornell-box M = N = max, systematic",
            Resampling::Systematic,
        ),
    ] {
        let mut o = options(Variant::CisLbdpt, MAX_CONNECTIONS, -1);
        o.candidates = MAX_CANDIDATES;
        o.resampling = resampling;
        check_case(Case {
            name,
            scene: builtin("cornell-box").unwrap(),
            width: 5,
            height: 5,
            options: o,
            passes: 1,
        });
    }
}

#[test]
fn one_pixel_and_an_empty_cache() {
    check_case(Case {
        name: "cornell-box 1x1",
        scene: builtin("cornell-box").unwrap(),
        width: 1,
        height: 1,
        options: options(Variant::LvcBdpt, 1, -1),
        passes: 5,
    });
    check_case(Case {
        name: "dark floor",
        scene: dark_floor(),
        width: 5,
        height: 3,
        options: options(Variant::CisLbdpt, 4, -1),
        passes: 2,
    });
}
