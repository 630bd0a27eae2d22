//! The recursive balance heuristic (src/bidir/mis.rs) against the brute-force oracle
//! (src/bidir/oracle.rs): on random synthetic paths of every length up to 8 with delta
//! vertices, point lights and random technique counts, and on paths the walks really
//! trace through a scene with mirrors, a mixed delta/diffuse material, shading normals
//! and a point light. Each weight lies in [0, 1], the weights of all techniques that can
//! make a path sum to 1, and each equals n_s p_s / Σ n_j p_j from explicit products.
use crate::common;

use splitray::bidir::connect::Sample;
use splitray::bidir::densities::path_densities;
use splitray::bidir::lights::Lights;
use splitray::bidir::mis::{self, EmissionDensities, SubpathMis, TechniqueCounts};
use splitray::bidir::oracle::PathDensities;
use splitray::bidir::random::PathSampler;
use splitray::bidir::vertex::{Vertex, NO_TRIANGLE};
use splitray::bidir::walk::{camera_subpath, light_subpath};
use splitray::bidir::{Connector, Counters, CpuScene, PinholeCamera, WalkSettings};

/// A synthetic path x0..xk: per segment its squared length and the |cos| at both ends,
/// per interior vertex its solid-angle densities in both walk directions.
struct Synthetic {
    k: usize,
    d2: Vec<f32>,
    /// cos at x_i towards x_{i+1}.
    cos_a: Vec<f32>,
    /// cos at x_{i+1} towards x_i.
    cos_b: Vec<f32>,
    /// Density at x_i of sampling towards x_{i+1} (light walk), i in 1..k.
    omega_l: Vec<f32>,
    /// Density at x_i of sampling towards x_{i-1} (camera walk), i in 1..k.
    omega_c: Vec<f32>,
    delta: Vec<bool>,
    emit: f32,
    direct: f32,
    emit_dir: f32,
    camera_dir: f32,
}

fn synthetic(k: usize, u: &mut impl Iterator<Item = f32>) -> Synthetic {
    let mut next = |lo: f32, hi: f32| lo + (hi - lo) * u.next().unwrap();
    let point_light = next(0.0, 1.0) < 0.25;
    let mut delta = vec![point_light];
    for _ in 1..k {
        delta.push(next(0.0, 1.0) < 0.3);
    }
    delta.push(false);
    let d2: Vec<f32> = (0..k).map(|_| next(0.05, 20.0)).collect();
    let mut cos_a: Vec<f32> = (0..k).map(|_| next(0.05, 1.0)).collect();
    let cos_b: Vec<f32> = (0..k).map(|_| next(0.05, 1.0)).collect();
    if point_light {
        cos_a[0] = 1.0;
    }
    let (mut omega_l, mut omega_c) = (vec![0.0; k + 1], vec![0.0; k + 1]);
    for i in 1..k {
        if delta[i] {
            let p = next(0.1, 1.0);
            omega_l[i] = p;
            omega_c[i] = p;
        } else {
            omega_l[i] = next(0.02, 4.0);
            omega_c[i] = next(0.02, 4.0);
        }
    }
    let emit = next(0.01, 3.0);
    Synthetic {
        k,
        d2,
        cos_a,
        cos_b,
        omega_l,
        omega_c,
        delta,
        emit,
        direct: if next(0.0, 1.0) < 0.5 {
            emit
        } else {
            next(0.01, 3.0)
        },
        emit_dir: if point_light {
            0.25 / std::f32::consts::PI
        } else {
            next(0.02, 1.0)
        },
        camera_dir: next(1.0, 1e4),
    }
}

impl Synthetic {
    /// Explicit area densities for the oracle.
    fn densities(&self) -> PathDensities {
        let k = self.k;
        let mut fwd = vec![0.0f64; k + 1];
        let mut rev = vec![0.0f64; k + 1];
        fwd[0] = self.emit as f64;
        fwd[1] = (self.emit_dir * self.cos_b[0] / self.d2[0]) as f64;
        for i in 1..k {
            fwd[i + 1] = (self.omega_l[i] * self.cos_b[i] / self.d2[i]) as f64;
            rev[i - 1] = (self.omega_c[i] * self.cos_a[i - 1] / self.d2[i - 1]) as f64;
        }
        rev[k - 1] = (self.camera_dir * self.cos_a[k - 1] / self.d2[k - 1]) as f64;
        rev[k] = 1.0;
        PathDensities {
            fwd,
            rev,
            direct: self.direct as f64,
            delta: self.delta.clone(),
        }
    }

    /// The light subpath's MIS quantities at x_{s-1} (s ≥ 1).
    fn light_mis(&self, counts: &TechniqueCounts, s: usize) -> SubpathMis {
        let mut m = SubpathMis::light(
            counts,
            &EmissionDensities {
                direct: self.direct,
                emit: self.emit,
                direction: self.emit_dir,
                cos: self.cos_a[0],
                delta_position: self.delta[0],
            },
        );
        for i in 1..s {
            m.arrive(self.d2[i - 1], self.cos_b[i - 1]);
            if i < s - 1 {
                let c = counts.light_vertex(i);
                m.scatter(
                    c,
                    self.cos_a[i],
                    self.omega_l[i],
                    self.omega_c[i],
                    self.delta[i],
                );
            }
        }
        m
    }

    /// The camera subpath's MIS quantities at x_s (t ≥ 2: camera vertex j = t - 1).
    fn camera_mis(&self, counts: &TechniqueCounts, t: usize) -> SubpathMis {
        let k = self.k;
        let mut m = SubpathMis::camera(self.camera_dir);
        for j in 1..t {
            let x = k - j;
            m.arrive(self.d2[x], self.cos_a[x]);
            if j < t - 1 {
                let c = counts.camera_vertex(j, false);
                m.scatter(
                    c,
                    self.cos_b[x - 1],
                    self.omega_c[x],
                    self.omega_l[x],
                    self.delta[x],
                );
            }
        }
        m
    }

    /// The recursive weight of technique s.
    fn recursive_weight(&self, counts: &TechniqueCounts, s: usize) -> f32 {
        let k = self.k;
        let t = k + 1 - s;
        let area = |pdf: f32, seg: usize, cos: f32| pdf * cos / self.d2[seg];
        match (s, t) {
            (0, _) => {
                let m = self.camera_mis(counts, t);
                mis::emitter_hit_weight(counts, k, &m, self.direct, self.emit, self.emit_dir)
            }
            (1, 1) => {
                let cam = area(self.camera_dir, 0, self.cos_a[0]);
                mis::light_trace_emitter_weight(counts, cam, self.emit, self.delta[0])
            }
            (_, 1) => {
                let m = self.light_mis(counts, s);
                let cam = area(self.camera_dir, k - 1, self.cos_a[k - 1]);
                let partial = m.partial(counts.light_vertex(k - 1), self.omega_c[k - 1]);
                mis::light_trace_weight(counts, cam, partial)
            }
            (1, _) => {
                let m = self.camera_mis(counts, t);
                let light_rev = if self.delta[0] {
                    0.0
                } else {
                    area(self.omega_c[1], 0, self.cos_a[0])
                };
                let camera_fwd = area(self.emit_dir, 0, self.cos_b[0]);
                let partial = m.partial(counts.camera_vertex(t - 1, false), self.omega_l[1]);
                mis::light_sample_weight(
                    counts,
                    light_rev,
                    self.direct,
                    self.emit,
                    camera_fwd,
                    partial,
                )
            }
            _ => {
                let (l, c) = (self.light_mis(counts, s), self.camera_mis(counts, t));
                let seg = s - 1;
                mis::connection_weight(
                    counts,
                    area(self.omega_c[s], seg, self.cos_a[seg]),
                    l.partial(counts.light_vertex(s - 1), self.omega_c[s - 1]),
                    area(self.omega_l[s - 1], seg, self.cos_b[seg]),
                    c.partial(counts.camera_vertex(t - 1, false), self.omega_l[s]),
                )
            }
        }
    }
}

fn random_counts(u: &mut impl Iterator<Item = f32>, k: usize) -> TechniqueCounts {
    let mut c = |zero: f32| {
        let v = u.next().unwrap();
        if v < zero {
            0.0
        } else {
            0.1 + 20.0 * v
        }
    };
    match k % 4 {
        0 => TechniqueCounts::bpt(4096.0),
        1 => TechniqueCounts::light_tracer(300.0),
        _ => TechniqueCounts {
            emitter_hit: c(0.1),
            light_sample: c(0.1),
            connection: c(0.1),
            light_trace: c(0.1),
            light_trace_emitter: c(0.5),
        },
    }
}

#[test]
fn recursive_weights_equal_the_brute_force_balance_heuristic_on_random_paths() {
    let mut u = common::uniforms(4_000_000, 21).into_iter();
    let mut checked = 0usize;
    let mut with_delta = 0usize;
    for case in 0..16_000 {
        let k = 1 + case % 8;
        let path = synthetic(k, &mut u);
        let counts = random_counts(&mut u, case / 8);
        let oracle = path.densities();
        let w = oracle.balance_weights(&counts);
        let possible: Vec<usize> = (0..=k).filter(|&s| oracle.can_sample(&counts, s)).collect();
        if possible.is_empty() {
            continue;
        }
        let sum: f64 = w.iter().sum();
        assert!(
            (sum - 1.0).abs() < 1e-9,
            "case {case}: oracle weights sum to {sum}"
        );
        let mut recursive_sum = 0.0f64;
        for &s in &possible {
            let r = path.recursive_weight(&counts, s) as f64;
            assert!(
                (0.0..=1.0).contains(&r),
                "case {case} k {k} s {s}: weight {r}"
            );
            assert!(
                common::mis::close(r, w[s]),
                "case {case} k {k} s {s}: recursive {r} vs oracle {} (delta {:?}, counts {counts:?})",
                w[s],
                path.delta
            );
            recursive_sum += r;
            checked += 1;
        }
        assert!(
            (recursive_sum - 1.0).abs() < 1e-3,
            "case {case}: {recursive_sum}"
        );
        with_delta += path.delta.iter().any(|&d| d) as usize;
    }
    eprintln!("{checked} technique weights checked, {with_delta} paths with a delta vertex");
    assert!(checked > 30_000 && with_delta > 5_000);
}

#[test]
fn weights_of_traced_paths_equal_the_oracle() {
    let scene = common::scenes::tricky_cornell_box();
    let cpu = CpuScene::new(&scene);
    let camera = PinholeCamera::new(&scene.camera.frame(12, 12));
    for counts in [
        TechniqueCounts::bpt(144.0),
        TechniqueCounts {
            connection: 0.37,
            light_trace_emitter: 5.0,
            ..TechniqueCounts::bpt(50.0)
        },
    ] {
        let settings = WalkSettings {
            max_depth: 8,
            rr_depth: 3,
            counts,
        };
        let connector = Connector {
            scene: &cpu,
            camera: &camera,
            settings: &settings,
        };
        let (mut light, mut cam) = (Vec::new(), Vec::new());
        let mut counters = Counters::default();
        let mut checked = [0usize; 4];
        // Checked paths through a mirror (an interior delta vertex) and from the point light.
        let (through_mirror, from_point) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
        for pass in 0..12u32 {
            for pixel in 0..144u32 {
                let sampler = PathSampler::new(pixel, pass, 3);
                light_subpath(&cpu, &settings, &sampler, &mut light, &mut counters);
                camera_subpath(
                    &cpu,
                    &camera,
                    &settings,
                    &sampler,
                    pixel,
                    &mut cam,
                    &mut counters,
                );
                let check = |sample: Sample, l: &[Vertex], c: &[Vertex], family: &mut usize| {
                    let d = path_densities(&cpu, &camera, l, c);
                    common::mis::assert_weight_is_the_oracles(&d, &counts, &sample);
                    *family += 1;
                    let k = d.segments();
                    through_mirror.set(through_mirror.get() + d.delta[1..k].contains(&true) as u32);
                    from_point.set(from_point.get() + d.delta[0] as u32);
                };
                for i in 0..light.len() {
                    if let Some(smp) = connector.light_trace(&light, i, &mut counters) {
                        check(smp, &light[..=i], &cam[..1], &mut checked[0]);
                    }
                }
                for j in 1..cam.len() {
                    if let Some(smp) = connector.emitter_hit(&cam, j, &mut counters) {
                        check(smp, &[], &cam[..=j], &mut checked[1]);
                    }
                    if settings.allows(j + 1) {
                        let lights = Lights::new(&cpu.tables.lights);
                        let u = [0.37, (pixel as f32 * 0.618) % 1.0, (j as f32 * 0.31) % 1.0];
                        for k in 0..lights.len() {
                            let Some(p) = lights.point(k, u[1], u[2]) else {
                                continue;
                            };
                            let lv = Vertex::light(&p, NO_TRIANGLE);
                            if let Some(smp) =
                                connector.connect_light_point(&lv, &cam, j, &mut counters)
                            {
                                check(smp, &[lv], &cam[..=j], &mut checked[2]);
                            }
                        }
                    }
                    for i in 1..light.len() {
                        if !settings.allows(i + j + 1) {
                            break;
                        }
                        if let Some(smp) = connector.connect(&light, i, &cam, j, &mut counters) {
                            check(smp, &light[..=i], &cam[..=j], &mut checked[3]);
                        }
                    }
                }
            }
        }
        let (mirror, point) = (through_mirror.get(), from_point.get());
        eprintln!(
            "{counts:?}: checked light tracing / hits / NEE / connections {checked:?}, \
             {mirror} through a mirror, {point} from the point light"
        );
        assert!(checked.iter().all(|&n| n > 20), "{checked:?}"); // hits are the rarest: ~40
        assert!(mirror > 100 && point > 100);
    }
}
