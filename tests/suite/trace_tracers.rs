//! The cpu-dacrt and ray-query tracers against brute force.
//!
//! cpu-dacrt must equal `cpu::closest_hits` bit for bit (same triangle, t, u, v; ties to
//! the smaller index) whatever its thresholds. ray-query may break ties differently, so a
//! different triangle is accepted only at the same t (1e-5 relative). Ray-query tests
//! skip, with a note, on devices without VK_KHR_ray_query.

use crate::common;

use std::time::Instant;

use glam::Vec3;
use splitray::trace::cpu_dacrt::{self, DacrtParams};
use splitray::trace::{
    cpu, CpuDacrtTracer, GpuTriangle, Hit, Query, Ray, RayQueryTracer, Tracer, TracerKind,
};

const BUNNY: &str = "../shared/meshes/bunny/bunny.obj";

fn params_grid() -> Vec<DacrtParams> {
    let d = DacrtParams::default();
    vec![
        d,
        // Tiny leaves: recursion stops mostly at the depth limit.
        DacrtParams {
            leaf_triangles: 2,
            leaf_rays: 2,
            max_depth: 16,
        },
        DacrtParams {
            leaf_triangles: 2,
            leaf_rays: 64,
            ..d
        },
        DacrtParams {
            leaf_triangles: 64,
            leaf_rays: 2,
            ..d
        },
        DacrtParams {
            leaf_triangles: 256,
            leaf_rays: 256,
            ..d
        },
        DacrtParams { max_depth: 3, ..d },
        DacrtParams { max_depth: 0, ..d },
    ]
}

/// Bit-for-bit equality with the brute-force CPU twin, closest hit and occlusion.
fn assert_dacrt_exact(rays: &[Ray], tris: &[GpuTriangle], params: &DacrtParams, what: &str) {
    let expected = cpu::closest_hits(rays, tris);
    let (hits, _) = cpu_dacrt::trace(rays, tris, Query::ClosestHit, params);
    let bad: Vec<_> = hits
        .iter()
        .zip(&expected)
        .enumerate()
        .filter(|(_, (h, e))| h.t.to_bits() != e.t.to_bits() || h.triangle != e.triangle || h != e)
        .take(5)
        .collect();
    assert!(
        bad.is_empty(),
        "{what} {params:?}: DACRT ≠ brute force: {bad:?}"
    );
    let (occ, _) = cpu_dacrt::trace(rays, tris, Query::Occlusion, params);
    for (i, (h, e)) in occ.iter().zip(&expected).enumerate() {
        assert_eq!(
            h.is_hit(),
            e.is_hit(),
            "{what} {params:?}: occlusion of ray {i}"
        );
        if h.is_hit() {
            // Any blocker: a real hit of that triangle within the ray's range.
            let r = &rays[i];
            let (t, _, _) = cpu::intersect_triangle(
                Vec3::from(r.origin),
                Vec3::from(r.dir),
                r.tmin,
                r.tmax,
                &tris[h.triangle as usize],
            );
            assert_eq!(t, h.t, "{what}: occlusion hit of ray {i} is not a hit");
        }
    }
}

/// Ray-query hits against brute force: both miss, or both hit with t equal within 1e-5
/// relative (`cpu::same_hit`, which also accepts a different triangle at the same t) —
/// or within an absolute 4e-6 × `scale` (the scene's size): the driver computes t its own
/// way, so for hits very near the origin (t ≪ the coordinates) t differs by a few ulps
/// of the coordinates, which is far more than 1e-5 of t. Returns how many rays hit.
fn assert_close(hits: &[Hit], expected: &[Hit], scale: f32, what: &str) -> usize {
    assert_eq!(hits.len(), expected.len());
    let close = |h: &Hit, e: &Hit| {
        cpu::same_hit(h, e, 1e-5, true)
            || (h.is_hit() && e.is_hit() && (h.t - e.t).abs() <= 4e-6 * scale)
    };
    let bad: Vec<_> = hits
        .iter()
        .zip(expected)
        .enumerate()
        .filter(|(_, (h, e))| !close(h, e))
        .take(5)
        .collect();
    assert!(
        bad.is_empty(),
        "{what}: hits differ from brute force: {bad:?}"
    );
    hits.iter().filter(|h| h.is_hit()).count()
}

fn bunny() -> Option<splitray::scene::Scene> {
    if !std::path::Path::new(BUNNY).exists() {
        eprintln!("note: {BUNNY} is missing; skipping the bunny test");
        return None;
    }
    Some(splitray::scene::load(BUNNY).expect("bunny loads"))
}

/// A scene whose box is exactly [0, 1]³, so the first splits are the planes x, y, z = ½,
/// then ¼ and ¾: axis-aligned flat triangles lying in those planes, zero-area triangles,
/// and exact duplicates (equal t: the smaller index must win).
fn split_plane_scene() -> Vec<GpuTriangle> {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let mut tris = vec![
        // Corners pinning the box to [0, 1]³.
        GpuTriangle::new([v(0.0, 0.0, 0.0), v(0.05, 0.0, 0.0), v(0.0, 0.05, 0.0)]),
        GpuTriangle::new([v(1.0, 1.0, 1.0), v(0.95, 1.0, 1.0), v(1.0, 0.95, 1.0)]),
    ];
    for c in [0.25f32, 0.5, 0.75] {
        // Flat in x = c, y = c and z = c.
        tris.push(GpuTriangle::new([
            v(c, 0.1, 0.1),
            v(c, 0.9, 0.1),
            v(c, 0.1, 0.9),
        ]));
        tris.push(GpuTriangle::new([
            v(0.1, c, 0.1),
            v(0.9, c, 0.9),
            v(0.9, c, 0.1),
        ]));
        tris.push(GpuTriangle::new([
            v(0.2, 0.2, c),
            v(0.8, 0.3, c),
            v(0.3, 0.8, c),
        ]));
        // Straddling the plane.
        tris.push(GpuTriangle::new([
            v(c - 0.1, 0.4, 0.4),
            v(c + 0.1, 0.6, 0.4),
            v(c, 0.5, 0.7),
        ]));
    }
    // Zero-area: a point, a segment, a segment lying in a split plane.
    tris.push(GpuTriangle::new([v(0.5, 0.5, 0.5); 3]));
    tris.push(GpuTriangle::new([
        v(0.2, 0.2, 0.2),
        v(0.6, 0.6, 0.6),
        v(0.4, 0.4, 0.4),
    ]));
    tris.push(GpuTriangle::new([
        v(0.5, 0.1, 0.1),
        v(0.5, 0.9, 0.9),
        v(0.5, 0.5, 0.5),
    ]));
    // Duplicates of earlier triangles at later indices, and one whose earlier copy comes
    // after the original in a child's list order.
    let dups: Vec<GpuTriangle> = tris[2..8].to_vec();
    tris.extend(dups);
    tris.insert(3, tris[10]);
    tris
}

/// Rays exercising the split planes: parallel to them, lying in them, starting on them,
/// along the axes, and from inside the box.
fn split_plane_rays() -> Vec<Ray> {
    let mut rays = Vec::new();
    let coords = [0.0f32, 0.125, 0.25, 0.3, 0.5, 0.6, 0.75, 1.0];
    let axes = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z];
    for &a in &coords {
        for &b in &coords {
            for (k, dir) in axes.iter().enumerate() {
                // Origins on the planes a, b in the two axes other than the direction's,
                // starting outside the box and inside it (on a split plane).
                let o = match k % 3 {
                    0 => Vec3::new(if k < 3 { -0.5 } else { 1.5 }, a, b),
                    1 => Vec3::new(a, if k < 3 { -0.5 } else { 1.5 }, b),
                    _ => Vec3::new(a, b, if k < 3 { -0.5 } else { 1.5 }),
                };
                rays.push(Ray::new(o, *dir, 0.0, f32::INFINITY));
                let inside = o + *dir * 1.0; // on the plane ½ along the ray's own axis
                rays.push(Ray::new(inside, *dir, 0.0, f32::INFINITY));
                rays.push(Ray::new(inside, *dir, 0.0, 0.25));
            }
        }
    }
    // Diagonal rays from points on split planes, and from the centre outwards.
    let u = common::uniforms(3000, 42);
    for i in 0..1000 {
        let d = (Vec3::new(u[3 * i], u[3 * i + 1], u[3 * i + 2]) - 0.5)
            .try_normalize()
            .unwrap_or(Vec3::Y);
        let on_plane = match i % 4 {
            0 => Vec3::new(0.5, u[3 * i + 1], u[3 * i]),
            1 => Vec3::new(u[3 * i + 2], 0.25, u[3 * i]),
            2 => Vec3::new(u[3 * i + 1], u[3 * i + 2], 0.75),
            _ => Vec3::splat(0.5),
        };
        rays.push(Ray::new(on_plane, d, 0.0, f32::INFINITY));
        // Directions within a split plane (parallel to it).
        let mut flat = d;
        flat[i % 3] = 0.0;
        if let Some(flat) = flat.try_normalize() {
            rays.push(Ray::new(on_plane, flat, 0.0, f32::INFINITY));
        }
    }
    rays
}

// ---------------------------------------------------------------- cpu-dacrt, CPU only

#[test]
fn cpu_dacrt_equals_brute_force_on_random_soups_for_any_thresholds() {
    for (triangles, rays, seed) in common::RANDOM_SOUPS.into_iter().chain([(0, 10, 6)]) {
        let soup = common::triangle_soup(triangles, seed);
        let rays = common::random_rays(rays, seed + 100);
        for params in params_grid() {
            assert_dacrt_exact(&rays, &soup, &params, &format!("{triangles} triangles"));
        }
    }
}

#[test]
fn cpu_dacrt_equals_brute_force_on_split_planes_flat_and_degenerate_triangles() {
    let tris = split_plane_scene();
    let rays = split_plane_rays();
    let expected = cpu::closest_hits(&rays, &tris);
    assert!(
        expected.iter().filter(|h| h.is_hit()).count() > rays.len() / 4,
        "too few hits to be a test"
    );
    for params in params_grid() {
        assert_dacrt_exact(&rays, &tris, &params, "split planes");
    }
}

#[test]
fn cpu_dacrt_keeps_the_smaller_index_among_equal_hits() {
    // Eight copies of the same triangle and one ray through it: index 0 must win even
    // when the copies are spread over many leaves.
    let base = common::triangle_soup(300, 11);
    let tri = GpuTriangle::new([
        Vec3::new(0.1, 0.1, 0.5),
        Vec3::new(0.9, 0.1, 0.5),
        Vec3::new(0.5, 0.9, 0.5),
    ]);
    let mut tris = base.clone();
    for k in 0..8 {
        tris.insert(k * 37, tri);
    }
    let rays: Vec<Ray> = (0..200)
        .map(|i| {
            let x = 0.3 + 0.002 * i as f32;
            Ray::new(Vec3::new(x, 0.3, -1.0), Vec3::Z, 0.0, f32::INFINITY)
        })
        .collect();
    for params in params_grid() {
        assert_dacrt_exact(&rays, &tris, &params, "duplicates");
    }
}

#[test]
fn cpu_dacrt_equals_brute_force_in_the_cornell_box_from_outside_and_inside() {
    let scene = splitray::scene::load("cornell-box").unwrap();
    let tris = scene.gpu_triangles();
    let rays = common::cornell_box_rays_from_outside_and_inside(&scene);
    for params in params_grid() {
        assert_dacrt_exact(&rays, &tris, &params, "cornell box");
    }
}

#[test]
fn cpu_dacrt_handles_empty_batches_and_single_triangles() {
    let tri = common::triangle_soup(3, 1)[2];
    let p = DacrtParams::default();
    assert!(cpu_dacrt::trace(&[], &[tri], Query::ClosestHit, &p)
        .0
        .is_empty());
    let rays = common::random_rays(500, 3);
    let (hits, _) = cpu_dacrt::trace(&rays, &[], Query::ClosestHit, &p);
    assert!(hits.iter().all(|h| *h == Hit::NONE));
    for params in params_grid() {
        assert_dacrt_exact(&rays, &[tri], &params, "one triangle");
    }
}

#[test]
fn cpu_dacrt_equals_brute_force_on_the_bunny() {
    let Some(scene) = bunny() else { return };
    let tris = scene.gpu_triangles();
    assert_eq!(tris.len(), 69_451);
    // A 64×64 camera subset keeps the brute-force reference affordable.
    let rays = common::camera_rays(&scene.camera, 64, 64);
    let expected = cpu::closest_hits(&rays, &tris);
    let hit_count = expected.iter().filter(|h| h.is_hit()).count();
    assert!(
        hit_count > rays.len() / 10,
        "the framing camera should see the bunny"
    );
    for params in [
        DacrtParams::default(),
        DacrtParams {
            leaf_triangles: 32,
            leaf_rays: 4,
            ..DacrtParams::default()
        },
    ] {
        let (hits, stats) = cpu_dacrt::trace(&rays, &tris, Query::ClosestHit, &params);
        assert_eq!(hits, expected, "{params:?}");
        eprintln!("bunny 64x64 {params:?}: {stats:?}");
    }
}

// ---------------------------------------------------------------- through the Tracer API

#[test]
fn cpu_dacrt_tracer_reads_rays_after_its_wait_points_and_writes_hits() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(700, 21);
    let rays = common::random_rays(3000, 22);
    let mut tracer = TracerKind::CpuDacrt.create(&gpu, &soup).unwrap();
    assert_eq!(tracer.name(), "cpu-dacrt");
    let (ray_buf, hit_buf) = common::trace_after_a_copy(&gpu, tracer.as_mut(), &rays);
    assert_eq!(
        hit_buf.read::<Hit>().unwrap(),
        cpu::closest_hits(&rays, &soup)
    );
    let occ = common::trace_hits(&gpu, tracer.as_mut(), &rays, Query::Occlusion);
    for (i, (h, r)) in occ.iter().zip(&rays).enumerate() {
        assert_eq!(h.is_hit(), cpu::occluded(r, &soup), "occlusion of ray {i}");
    }
    // An empty batch still returns a point.
    let done = tracer
        .trace(&ray_buf, &hit_buf, 0, Query::ClosestHit, &[])
        .unwrap();
    gpu.wait(&done).unwrap();
    common::assert_clean(&gpu);
}

#[test]
fn host_tracers_refuse_more_rays_than_their_buffers_hold() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(40, 23);
    let rays = common::random_rays(17, 24);
    let ray_buf = gpu.upload("rays", &rays).unwrap();
    let hit_buf = gpu.zeroed::<Hit>("hits", rays.len()).unwrap();
    let short_hits = gpu.zeroed::<Hit>("short-hits", rays.len() - 1).unwrap();
    for kind in [TracerKind::CpuDacrt, TracerKind::CpuBvh] {
        let mut tracer = kind.create(&gpu, &soup).unwrap();
        for (count, hits) in [(18, &hit_buf), (17, &short_hits)] {
            let error = tracer
                .trace(&ray_buf, hits, count, Query::ClosestHit, &[])
                .err()
                .unwrap_or_else(|| panic!("{}: {count} rays into '{}'", kind.name(), hits.name()))
                .to_string();
            let want = format!(
                "{}: {count} rays do not fit buffers 'rays' and '{}'",
                kind.name(),
                hits.name()
            );
            assert!(error.contains(&want), "{error:?} should say {want:?}");
        }
        // The whole batch still traces after the refusals.
        let done = tracer
            .trace(&ray_buf, &hit_buf, 17, Query::ClosestHit, &[])
            .unwrap();
        gpu.wait(&done).unwrap();
        assert_eq!(
            hit_buf.read::<Hit>().unwrap(),
            cpu::closest_hits(&rays, &soup)
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn tracer_kinds_are_registered() {
    for name in ["cpu-dacrt", "ray-query", "brute-force"] {
        let kind: TracerKind = name.parse().unwrap();
        assert_eq!(kind.name(), name);
    }
}

// ---------------------------------------------------------------- ray-query

/// The device, or `None` (with a note) when it lacks ray queries; then creating the
/// tracer must fail naming the extension.
fn ray_query_gpu() -> Option<common::TestGpu> {
    let gpu = common::gpu();
    if gpu.ray_query() {
        return Some(gpu);
    }
    let err = match TracerKind::RayQuery.create(&gpu, &common::triangle_soup(4, 1)) {
        Ok(_) => panic!("ray-query created on a device without ray queries"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("VK_KHR_ray_query"), "unclear error: {err}");
    eprintln!(
        "note: device '{}' lacks VK_KHR_ray_query; skipping the ray-query test",
        gpu.info().name
    );
    common::assert_clean(&gpu);
    None
}

/// `rays` with every seventh one (from the fourth, so that a batch of one ray keeps a
/// real one) made an empty segment starting on a triangle (tmin =
/// tmax, tmin > tmax, NaN tmax), which must miss: ray queries take (tmin, tmax) as a
/// closed interval with tmin ≤ tmax, so the tracer must turn such rays away itself.
fn with_empty_segments(soup: &[GpuTriangle], rays: Vec<Ray>) -> Vec<Ray> {
    if soup.is_empty() {
        return rays;
    }
    rays.into_iter()
        .enumerate()
        .map(|(i, r)| {
            let on = soup[i % soup.len()].v0();
            let dir = Vec3::from(r.dir);
            match (i % 7, (i / 7) % 3) {
                (3, 0) => Ray::new(on, dir, 0.0, 0.0),
                (3, 1) => Ray::new(on, dir, 0.5, 0.25),
                (3, _) => Ray::new(on, dir, 0.0, f32::NAN),
                _ => r,
            }
        })
        .collect()
}

#[test]
fn ray_query_matches_brute_force_on_random_soups() {
    let Some(gpu) = ray_query_gpu() else { return };
    for (triangles, rays, seed) in common::RANDOM_SOUPS.into_iter().chain([(0, 10, 6)]) {
        let soup = common::triangle_soup(triangles, seed);
        let rays = with_empty_segments(&soup, common::random_rays(rays, seed + 100));
        let mut tracer = RayQueryTracer::new(&gpu, &soup).unwrap();
        let expected = cpu::closest_hits(&rays, &soup);
        let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
        let n = assert_close(&hits, &expected, 1.0, &format!("{triangles} triangles"));
        if !rays.is_empty() && triangles > 100 {
            assert!(n > rays.len() / 10, "too few hits to be a test");
        }
        let occ = common::trace_hits(&gpu, &mut tracer, &rays, Query::Occlusion);
        for (i, (h, r)) in occ.iter().zip(&rays).enumerate() {
            assert_eq!(h.is_hit(), cpu::occluded(r, &soup), "occlusion of ray {i}");
        }
    }
    common::assert_clean(&gpu);
}

/// Rays with a NaN or infinite origin or direction, empty or NaN bounds and zero
/// directions (`common::rays_that_miss`) among good ones miss, as in the CPU twin: the
/// tracer keeps them from the driver, for which most of them are undefined.
#[test]
fn ray_query_misses_nan_infinite_and_zero_rays() {
    let Some(gpu) = ray_query_gpu() else { return };
    let soup = common::triangle_soup(500, 71);
    let (rays, misses) = common::with_rays_that_miss(&common::random_rays(1000, 72), 13);
    let expected = cpu::closest_hits(&rays, &soup);
    let mut tracer = RayQueryTracer::new(&gpu, &soup).unwrap();
    let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
    let n = assert_close(&hits, &expected, 1.0, "bad rays among good");
    assert!(n > rays.len() / 10, "too few hits to be a test");
    let occ = common::trace_hits(&gpu, &mut tracer, &rays, Query::Occlusion);
    for (i, r) in rays.iter().enumerate() {
        if misses[i] {
            assert_eq!(
                expected[i],
                Hit::NONE,
                "the CPU twin hits with ray {i} {r:?}"
            );
            assert_eq!(
                bytemuck::bytes_of(&hits[i]),
                bytemuck::bytes_of(&Hit::NONE),
                "ray {i} {r:?} gave {:?}",
                hits[i]
            );
        }
        assert_eq!(
            occ[i].is_hit(),
            cpu::occluded(r, &soup),
            "occlusion of ray {i} {r:?}"
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn ray_query_rebuilds_for_a_moving_scene() {
    let Some(gpu) = ray_query_gpu() else { return };
    let rays = common::random_rays(5000, 8);
    let mut soup = common::triangle_soup(800, 9);
    let mut tracer = RayQueryTracer::new(&gpu, &soup).unwrap();
    for frame in 0..3 {
        for t in &mut soup {
            t.v0[1] += 0.05;
        }
        let build = tracer.rebuild(&soup).unwrap();
        eprintln!("frame {frame}: rebuild of 800 triangles took {build:?}");
        let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
        assert_close(
            &hits,
            &cpu::closest_hits(&rays, &soup),
            1.0,
            &format!("frame {frame}"),
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn ray_query_matches_brute_force_in_the_cornell_box() {
    let Some(gpu) = ray_query_gpu() else { return };
    let scene = splitray::scene::load("cornell-box").unwrap();
    let tris = scene.gpu_triangles();
    let rays = common::camera_rays(&scene.camera, 96, 96);
    let mut tracer = RayQueryTracer::new(&gpu, &tris).unwrap();
    let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
    let scale = scene.bounds().extent().max_element();
    let n = assert_close(
        &hits,
        &cpu::closest_hits(&rays, &tris),
        scale,
        "cornell box",
    );
    assert!(n > rays.len() / 2);
    common::assert_clean(&gpu);
}

/// The bunny at 512×512 from its framing camera: cpu-dacrt against brute force on a
/// subset, its occlusion against its closest hits on all rays, and ray-query against
/// cpu-dacrt on all rays for both queries. (Throughput is `splitray bench trace`'s.)
#[test]
fn bunny_512_ray_query_and_cpu_dacrt_agree() {
    let Some(scene) = bunny() else { return };
    let tris = scene.gpu_triangles();
    let rays = common::camera_rays(&scene.camera, 512, 512);

    let gpu = common::gpu();
    let mut dacrt = CpuDacrtTracer::new(&gpu, &tris);
    let dacrt_hits = common::trace_hits(&gpu, &mut dacrt, &rays, Query::ClosestHit);
    // Brute force on every 61st ray.
    let sample: Vec<usize> = (0..rays.len()).step_by(61).collect();
    let sample_rays: Vec<Ray> = sample.iter().map(|&i| rays[i]).collect();
    let expected = cpu::closest_hits(&sample_rays, &tris);
    for (k, &i) in sample.iter().enumerate() {
        assert_eq!(dacrt_hits[i], expected[k], "ray {i}");
    }
    let (occluded, _) = cpu_dacrt::trace(&rays, &tris, Query::Occlusion, &dacrt.params());
    for (i, (o, d)) in occluded.iter().zip(&dacrt_hits).enumerate() {
        assert_eq!(o.is_hit(), d.is_hit(), "cpu-dacrt occlusion of ray {i}");
    }

    if !gpu.ray_query() {
        eprintln!(
            "note: no VK_KHR_ray_query on '{}'; skipping ray-query",
            gpu.info().name
        );
        common::assert_clean(&gpu);
        return;
    }
    let mut rq = RayQueryTracer::new(&gpu, &tris).unwrap();
    let ray_buf = gpu.upload("rays", &rays).unwrap();
    let hit_buf = gpu.zeroed::<Hit>("hits", rays.len()).unwrap();
    for query in [Query::ClosestHit, Query::Occlusion] {
        gpu.wait(
            &rq.trace(&ray_buf, &hit_buf, rays.len() as u32, query, &[])
                .unwrap(),
        )
        .unwrap();
        let hits = hit_buf.read::<Hit>().unwrap();
        match query {
            Query::ClosestHit => {
                let scale = scene.bounds().extent().max_element();
                assert_close(&hits, &dacrt_hits, scale, "bunny ray-query vs cpu-dacrt");
            }
            Query::Occlusion => {
                for (i, (h, d)) in hits.iter().zip(&dacrt_hits).enumerate() {
                    assert_eq!(h.is_hit(), d.is_hit(), "occlusion of ray {i}");
                }
            }
        }
    }
    drop(rq);
    common::assert_clean(&gpu);
}

/// Times cpu-dacrt on the bunny at 512×512 for a grid of thresholds (run with
/// `--ignored --nocapture`); the defaults come from this sweep.
#[test]
#[ignore]
fn bunny_dacrt_threshold_sweep() {
    let Some(scene) = bunny() else { return };
    let tris = scene.gpu_triangles();
    let rays = common::camera_rays(&scene.camera, 512, 512);
    for alpha in [2u32, 4, 8, 16, 32, 64, 256] {
        for beta in [2u32, 4, 8, 16, 32, 256] {
            let params = DacrtParams {
                leaf_triangles: alpha,
                leaf_rays: beta,
                ..DacrtParams::default()
            };
            let start = Instant::now();
            let (_, stats) = cpu_dacrt::trace(&rays, &tris, Query::ClosestHit, &params);
            let t = start.elapsed().as_secs_f64();
            eprintln!(
                "alpha {alpha:3} beta {beta:3}: {t:.3} s {:.3} Mrays/s, {} tests, {} nodes",
                rays.len() as f64 / t / 1e6,
                stats.ray_triangle_tests,
                stats.nodes
            );
        }
    }
}
