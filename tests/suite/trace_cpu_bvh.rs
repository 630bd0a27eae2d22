//! The CPU BVH (`CpuBvh`, tracer `cpu-bvh`) against brute force.
//!
//! Every closest hit must equal `cpu::closest_hit` bit for bit (triangle, t, u, v; equal
//! t resolved to the smaller index), every occlusion answer `cpu::occluded`, on scenes
//! and rays chosen to break a BVH: axis-parallel rays, rays lying in triangle planes and
//! box faces, rays starting on surfaces, tmin/tmax windows, coincident and degenerate
//! triangles, tiny and huge coordinates, NaN and infinite rays.

use crate::common;

use glam::Vec3;
use splitray::trace::cpu_bvh::is_hittable;
use splitray::trace::{cpu, CpuBvh, GpuTriangle, Hit, Query, Ray, TracerKind};

const BUNNY: &str = "../shared/meshes/bunny/bunny.obj";

/// The scene as brute force should see it: triangles the BVH never hits (degenerate)
/// replaced by all-zero ones, which the triangle test cannot hit either (its edge
/// functions are exactly zero), so that indices stay put.
fn hittable_only(tris: &[GpuTriangle]) -> Vec<GpuTriangle> {
    tris.iter()
        .map(|t| {
            if is_hittable(t) {
                *t
            } else {
                GpuTriangle::default()
            }
        })
        .collect()
}

/// Bit-for-bit equality with brute force of closest hits (one by one and in parallel),
/// occlusion, and any-hit records (a real hit of the reported triangle). Returns the
/// number of rays that hit.
fn assert_exact(bvh: &CpuBvh, rays: &[Ray], tris: &[GpuTriangle], what: &str) -> usize {
    let tris = &hittable_only(tris);
    let want: Vec<Hit> = cpu::closest_hits(rays, tris);
    let got = bvh.closest_hits(rays);
    assert_eq!(got.len(), rays.len(), "{what}");
    let bad: Vec<_> = got
        .iter()
        .zip(&want)
        .enumerate()
        .filter(|(_, (g, w))| g != w || g.t.to_bits() != w.t.to_bits())
        .take(5)
        .map(|(i, (g, w))| (i, rays[i], *g, *w))
        .collect();
    assert!(bad.is_empty(), "{what}: BVH ≠ brute force: {bad:#?}");
    for (i, r) in rays.iter().enumerate().step_by(7) {
        assert_eq!(bvh.closest_hit(r), got[i], "{what}: ray {i} alone");
    }
    let occluded = bvh.occluded_all(rays);
    let any = bvh.any_hits(rays);
    for (i, r) in rays.iter().enumerate() {
        // Brute force finds a closest hit exactly when some triangle passes the same
        // test within (tmin, tmax): `cpu::occluded`, without a second pass.
        let want_occluded = want[i].is_hit();
        assert_eq!(
            occluded[i], want_occluded,
            "{what}: occlusion of ray {i} {r:?}"
        );
        assert_eq!(any[i].is_hit(), want_occluded, "{what}: any hit of ray {i}");
        if any[i].is_hit() {
            let (t, u, v) = cpu::intersect_triangle(
                Vec3::from(r.origin),
                Vec3::from(r.dir),
                r.tmin,
                r.tmax,
                &tris[any[i].triangle as usize],
            );
            assert_eq!((t, u, v), (any[i].t, any[i].u, any[i].v), "{what}: ray {i}");
        }
    }
    want.iter().filter(|h| h.is_hit()).count()
}

/// Incoherent rays from points on random triangles (nudged off the surface or exactly
/// on it) in random directions: what a path tracer's bounces look like.
fn surface_rays(tris: &[GpuTriangle], n: usize, seed: u64, nudge: f32) -> Vec<Ray> {
    let u = common::uniforms(6 * n, seed);
    (0..n)
        .map(|i| {
            let c = &u[6 * i..];
            let t = &tris[(c[0] * tris.len() as f32) as usize % tris.len()];
            let (mut a, mut b) = (c[1], c[2]);
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let p = t.v0() + a * t.e1() + b * t.e2();
            let d = (Vec3::new(c[3], c[4], c[5]) - 0.5)
                .try_normalize()
                .unwrap_or(Vec3::Y);
            let n = t.normal().normalize_or_zero();
            let o = p + nudge * if n.dot(d) >= 0.0 { n } else { -n };
            Ray::new(o, d, 0.0, f32::INFINITY)
        })
        .collect()
}

/// Axis-aligned geometry on an exact grid: walls of a unit room, flat triangles in the
/// planes x, y, z ∈ {¼, ½, ¾}, triangles sharing edges and vertices, exact duplicates.
fn grid_scene() -> Vec<GpuTriangle> {
    let v = Vec3::new;
    let mut tris = Vec::new();
    let quad = |tris: &mut Vec<GpuTriangle>, o: Vec3, a: Vec3, b: Vec3| {
        tris.push(GpuTriangle::new([o, o + a, o + a + b]));
        tris.push(GpuTriangle::new([o, o + a + b, o + b]));
    };
    // The room: floor, ceiling and four walls, two triangles each.
    quad(&mut tris, v(0.0, 0.0, 0.0), Vec3::X, Vec3::Z);
    quad(&mut tris, v(0.0, 1.0, 0.0), Vec3::Z, Vec3::X);
    quad(&mut tris, v(0.0, 0.0, 0.0), Vec3::Y, Vec3::X);
    quad(&mut tris, v(0.0, 0.0, 1.0), Vec3::X, Vec3::Y);
    quad(&mut tris, v(0.0, 0.0, 0.0), Vec3::Z, Vec3::Y);
    quad(&mut tris, v(1.0, 0.0, 0.0), Vec3::Y, Vec3::Z);
    for c in [0.25f32, 0.5, 0.75] {
        quad(&mut tris, v(c, 0.25, 0.25), 0.5 * Vec3::Y, 0.5 * Vec3::Z);
        quad(&mut tris, v(0.3, c, 0.3), 0.4 * Vec3::X, 0.4 * Vec3::Z);
        quad(&mut tris, v(0.2, 0.2, c), 0.6 * Vec3::X, 0.6 * Vec3::Y);
    }
    let dups: Vec<GpuTriangle> = tris[12..20].to_vec();
    tris.extend(dups);
    tris
}

/// Rays along the axes through grid coordinates (so along walls, edges and the planes of
/// flat triangles), from outside the room, from inside it and from points on its
/// planes, plus directions lying in those planes.
fn grid_rays() -> Vec<Ray> {
    let coords = [0.0f32, 0.2, 0.25, 0.3, 0.5, 0.7, 0.75, 1.0];
    let axes = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z];
    let mut rays = Vec::new();
    for &a in &coords {
        for &b in &coords {
            for (k, dir) in axes.iter().enumerate() {
                let start = if k < 3 { -0.5 } else { 1.5 };
                let o = match k % 3 {
                    0 => Vec3::new(start, a, b),
                    1 => Vec3::new(a, start, b),
                    _ => Vec3::new(a, b, start),
                };
                rays.push(Ray::new(o, *dir, 0.0, f32::INFINITY));
                // From the plane ½ (inside the room) and from a wall.
                rays.push(Ray::new(o + *dir, *dir, 0.0, f32::INFINITY));
                rays.push(Ray::new(o + 0.5 * *dir, *dir, 0.0, f32::INFINITY));
                rays.push(Ray::new(o + *dir, *dir, 0.0, 0.25));
                // −0.0 components: the same axis ray with signed zeros elsewhere.
                rays.push(Ray::new(o + *dir, *dir - Vec3::splat(0.0), 0.0, 2.0));
            }
        }
    }
    let u = common::uniforms(4000, 42);
    for i in 0..1000 {
        let c = &u[4 * i..];
        let d = (Vec3::new(c[0], c[1], c[2]) - 0.5)
            .try_normalize()
            .unwrap_or(Vec3::Y);
        let on_plane = match i % 4 {
            0 => Vec3::new(0.5, c[1], c[3]),
            1 => Vec3::new(c[2], 0.25, c[3]),
            2 => Vec3::new(c[1], c[3], 0.75),
            _ => Vec3::new(0.0, c[3], c[2]),
        };
        rays.push(Ray::new(on_plane, d, 0.0, f32::INFINITY));
        // The same direction flattened into the plane the origin lies on.
        let mut flat = d;
        flat[[0, 1, 2, 0][i % 4]] = 0.0;
        if let Some(flat) = flat.try_normalize() {
            rays.push(Ray::new(on_plane, flat, 0.0, f32::INFINITY));
        }
    }
    rays
}

#[test]
fn equals_brute_force_on_random_soups() {
    // (The soup's first two triangles are degenerate.)
    for (triangles, rays, seed) in [(5usize, 3000usize, 1u64), (513, 4099, 2), (2000, 10_000, 3)] {
        let soup = common::triangle_soup(triangles, seed);
        let rays = common::random_rays(rays, seed + 100);
        let bvh = CpuBvh::new(&soup);
        assert_eq!(bvh.triangle_count(), triangles);
        let hits = assert_exact(&bvh, &rays, &soup, &format!("{triangles} triangles"));
        assert!(hits > 0, "{triangles} triangles: no hits");
        let incoherent = surface_rays(&soup, 2000, seed + 200, 1e-4);
        assert_exact(&bvh, &incoherent, &soup, "rays leaving surfaces");
    }
}

#[test]
fn equals_brute_force_on_axis_aligned_geometry_with_axis_parallel_and_in_plane_rays() {
    let tris = grid_scene();
    let rays = grid_rays();
    let bvh = CpuBvh::new(&tris);
    let hits = assert_exact(&bvh, &rays, &tris, "grid");
    assert!(
        hits > rays.len() / 2,
        "only {hits} of {} rays hit",
        rays.len()
    );
}

#[test]
fn equals_brute_force_in_the_cornell_box_from_outside_and_inside() {
    let scene = splitray::scene::load("cornell-box").unwrap();
    let tris = scene.gpu_triangles();
    let mut rays = common::cornell_box_rays_from_outside_and_inside(&scene);
    rays.extend(surface_rays(&tris, 2000, 8, 0.0));
    let bvh = CpuBvh::new(&tris);
    assert_exact(&bvh, &rays, &tris, "cornell box");
}

#[test]
fn equals_brute_force_on_the_bunny() {
    if !std::path::Path::new(BUNNY).exists() {
        eprintln!("note: {BUNNY} is missing; skipping the bunny test");
        return;
    }
    let scene = splitray::scene::load(BUNNY).expect("bunny loads");
    let tris = scene.gpu_triangles();
    let bvh = CpuBvh::new(&tris);
    assert_eq!(bvh.triangle_count(), tris.len());
    // A 32×32 camera and 512 rays leaving the surface keep brute force affordable.
    let rays = common::camera_rays(&scene.camera, 32, 32);
    let hits = assert_exact(&bvh, &rays, &tris, "bunny camera");
    assert!(hits > rays.len() / 10, "the framing camera sees the bunny");
    let radius = scene.bounds().radius();
    let bounces = surface_rays(&tris, 512, 9, 1e-4 * radius);
    assert_exact(&bvh, &bounces, &tris, "bunny bounces");
}

#[test]
fn rays_are_limited_to_the_open_interval_tmin_tmax() {
    // Planes z = 1, 2, …, 8 (index k at z = k + 1), crossed by rays along +z from z = 0.
    let tris: Vec<GpuTriangle> = (0..8)
        .map(|k| {
            let z = (k + 1) as f32;
            GpuTriangle::new([
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(2.0, -1.0, z),
                Vec3::new(-1.0, 2.0, z),
            ])
        })
        .collect();
    let bvh = CpuBvh::new(&tris);
    let ray = |tmin: f32, tmax: f32| Ray::new(Vec3::new(0.1, 0.2, 0.0), Vec3::Z, tmin, tmax);
    // (tmin, tmax) → the expected triangle, or None.
    let cases = [
        (0.0, f32::INFINITY, Some(0)),
        (1.0, f32::INFINITY, Some(1)), // t = tmin is excluded
        (1.5, 4.0, Some(1)),
        (2.5, 3.0, None), // t = tmax is excluded
        (2.5, 3.0001, Some(2)),
        (f32::NEG_INFINITY, 0.5, None),
        (8.0, f32::INFINITY, None),
        (5.0, 5.0, None),
        (6.0, 2.0, None), // an empty interval
        (-3.0, 1.5, Some(0)),
        (7.9, 8.1, Some(7)),
    ];
    let rays: Vec<Ray> = cases.iter().map(|&(a, b, _)| ray(a, b)).collect();
    for ((tmin, tmax, want), r) in cases.iter().zip(&rays) {
        let hit = bvh.closest_hit(r);
        assert_eq!(
            hit.is_hit().then_some(hit.triangle),
            *want,
            "({tmin}, {tmax})"
        );
        assert_eq!(
            bvh.occluded(r),
            want.is_some(),
            "occlusion ({tmin}, {tmax})"
        );
    }
    assert_exact(&bvh, &rays, &tris, "tmin/tmax windows");
    // Going backwards from inside the stack.
    let back: Vec<Ray> = [0.0f32, 1.0, 3.5]
        .iter()
        .map(|&tmin| Ray::new(Vec3::new(0.1, 0.2, 4.5), -Vec3::Z, tmin, 10.0))
        .collect();
    assert_eq!(bvh.closest_hit(&back[0]).triangle, 3);
    assert_exact(&bvh, &back, &tris, "backwards");
}

#[test]
fn rays_starting_exactly_on_surfaces() {
    let soup = common::triangle_soup(800, 31);
    let bvh = CpuBvh::new(&soup);
    let on_surface = surface_rays(&soup, 5000, 32, 0.0);
    assert_exact(&bvh, &on_surface, &soup, "soup surfaces");
    // From the grid's vertices and edges, in every direction.
    let grid = grid_scene();
    let bvh = CpuBvh::new(&grid);
    let dirs = common::uniforms(3 * 64, 33);
    let mut rays = Vec::new();
    for t in &grid {
        for p in [t.v0(), t.v0() + t.e1(), t.v0() + 0.5 * t.e2()] {
            for k in 0..8 {
                let d = (Vec3::from_slice(&dirs[3 * k..]) - 0.5).normalize();
                rays.push(Ray::new(p, d, 0.0, f32::INFINITY));
            }
        }
    }
    assert_exact(&bvh, &rays, &grid, "grid vertices and edges");
}

#[test]
fn degenerate_triangles_are_never_hit() {
    let v = Vec3::new;
    let mut tris = vec![
        GpuTriangle::new([v(0.5, 0.5, 0.5); 3]), // a point
        GpuTriangle::new([v(0.0, 0.5, 0.5), v(1.0, 0.5, 0.5), v(0.0, 0.5, 0.5)]), // repeated vertex
        GpuTriangle::new([v(0.0, 0.5, 0.5), v(1.0, 0.5, 0.5), v(0.5, 0.5, 0.5)]), // collinear on an axis
        GpuTriangle::new([v(0.2, 0.2, 0.2), v(0.8, 0.8, 0.8), v(0.4, 0.4, 0.4)]), // collinear diagonal
    ];
    let rays: Vec<Ray> = (0..=20)
        .flat_map(|i| {
            let x = i as f32 / 20.0;
            [
                Ray::new(v(x, 0.5, -1.0), Vec3::Z, 0.0, f32::INFINITY),
                Ray::new(v(x, -1.0, 0.5), Vec3::Y, 0.0, f32::INFINITY),
                Ray::new(v(x, x, -1.0), Vec3::Z, 0.0, f32::INFINITY),
                Ray::new(v(0.5, 0.5, 0.5), v(1.0, x, 0.3).normalize(), 0.0, 5.0),
            ]
        })
        .collect();
    let only_degenerate = CpuBvh::new(&tris);
    assert_eq!(only_degenerate.triangle_count(), 4);
    assert_eq!(only_degenerate.node_count(), 0, "nothing to put in a tree");
    for r in &rays {
        assert!(!only_degenerate.closest_hit(r).is_hit());
        assert!(!only_degenerate.occluded(r));
    }
    assert_exact(&only_degenerate, &rays, &tris, "degenerate only");
    // Mixed with a real triangle right where the degenerate ones are.
    tris.push(GpuTriangle::new([
        v(-1.0, -1.0, 0.5),
        v(3.0, -1.0, 0.5),
        v(-1.0, 3.0, 0.5),
    ]));
    let mixed = CpuBvh::new(&tris);
    assert_exact(&mixed, &rays, &tris, "mixed");
    assert!(mixed
        .closest_hits(&rays)
        .iter()
        .all(|h| !h.is_hit() || h.triangle == 4));
    // The soups' degenerate triangles (every 97th a point, the next a collinear sliver),
    // which brute force hits now and then by rounding.
    let soup = common::triangle_soup(2000, 5);
    assert!((0..soup.len())
        .filter(|i| i % 97 <= 1)
        .all(|i| !is_hittable(&soup[i])));
    let bvh = CpuBvh::new(&soup);
    let mut rays = common::random_rays(20_000, 6);
    rays.extend(surface_rays(&soup, 20_000, 7, 1e-4));
    let hits = bvh.closest_hits(&rays);
    assert!(hits.iter().all(|h| !h.is_hit() || h.triangle % 97 > 1));
    assert!(bvh
        .any_hits(&rays)
        .iter()
        .all(|h| !h.is_hit() || h.triangle % 97 > 1));
}

#[test]
fn single_triangles_empty_scenes_and_empty_batches() {
    let tri = GpuTriangle::new([Vec3::ZERO, Vec3::X, Vec3::Y]);
    let bvh = CpuBvh::new(&[tri]);
    assert_eq!(bvh.triangle_count(), 1);
    let rays = common::random_rays(500, 3);
    assert_exact(&bvh, &rays, &[tri], "one triangle");
    let through = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z, 0.0, f32::INFINITY);
    let hit = bvh.closest_hit(&through);
    assert_eq!((hit.triangle, hit.t, hit.u, hit.v), (0, 1.0, 0.25, 0.25));

    assert!(bvh.closest_hits(&[]).is_empty());
    assert!(bvh.occluded_all(&[]).is_empty());
    let empty = CpuBvh::new(&[]);
    assert_eq!(empty.triangle_count(), 0);
    assert!(empty.closest_hits(&rays).iter().all(|h| *h == Hit::NONE));
    assert!(empty.occluded_all(&rays).iter().all(|o| !o));
}

#[test]
fn nan_infinite_and_zero_rays_miss_without_panicking() {
    let soup = common::triangle_soup(300, 12);
    let bvh = CpuBvh::new(&soup);
    let good = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, 0.0, f32::INFINITY);
    let rays = common::rays_that_miss(good);
    for r in &rays {
        assert!(!bvh.closest_hit(r).is_hit(), "{r:?}");
        assert!(!bvh.occluded(r), "{r:?}");
    }
    assert_exact(&bvh, &rays, &soup, "NaN and infinite rays");
    // Infinite tmin/tmax are ordinary bounds.
    let mut wide = good;
    wide.tmin = f32::NEG_INFINITY;
    assert_eq!(bvh.closest_hit(&wide), cpu::closest_hit(&wide, &soup));
}

#[test]
fn tiny_huge_and_far_offset_coordinates() {
    // Within the f32 triangle test's range: its scaled t is a product of three
    // coordinates' worth of magnitude (≈ 10¹⁵ here at most), and its determinant of two
    // (≥ 10⁻²⁶).
    let soup = common::triangle_soup(1000, 41);
    let rays = common::random_rays(3000, 42);
    for (scale, offset) in [
        (1e-4f32, Vec3::ZERO),
        (1e-7, Vec3::ZERO),
        (1e12, Vec3::ZERO),
        (1e9, Vec3::splat(-1e9)),
        (1.0, Vec3::new(3e4, -2e4, 1e4)),
        (1e-3, Vec3::splat(1e3)),
    ] {
        let tris = common::scale_scene(&soup, scale, offset);
        let rays = common::scale_rays(&rays, scale, offset);
        let bvh = CpuBvh::new(&tris);
        let what = format!("scale {scale}, offset {offset}");
        let hits = assert_exact(&bvh, &rays, &tris, &what);
        assert!(hits > rays.len() / 20, "{what}: only {hits} hits");
    }
}

#[test]
fn coincident_triangles_resolve_to_the_smallest_index() {
    // A thousand copies of one triangle (a deep, degenerate tree) among a soup: a ray
    // through them must report the first copy.
    let (tris, first) = common::soup_with_coincident_copies();
    let bvh = CpuBvh::new(&tris);
    // Deeper than the traversal stack kept on the thread's stack (32 entries).
    assert!(bvh.depth() > 32, "depth {}", bvh.depth());
    let rays: Vec<Ray> = (0..200)
        .map(|i| {
            let x = 0.3 + 0.002 * i as f32;
            Ray::new(Vec3::new(x, 0.3, -1.0), Vec3::Z, 0.0, f32::INFINITY)
        })
        .collect();
    assert_exact(&bvh, &rays, &tris, "coincident copies");
    let hits = bvh.closest_hits(&rays);
    let soup_hits = cpu::closest_hits(&rays, &hittable_only(&tris[..first as usize]));
    for (h, s) in hits.iter().zip(&soup_hits) {
        // Either a soup triangle in front of the copies, or the first copy.
        assert!(
            h.triangle == first || (s.is_hit() && s.t <= 1.5 && h == s),
            "{h:?}"
        );
    }
}

#[test]
fn rebuild_replaces_the_geometry() {
    let a = common::triangle_soup(400, 51);
    let b = common::scale_scene(&common::triangle_soup(700, 52), 2.0, Vec3::splat(-0.5));
    let rays = common::random_rays(3000, 53);
    let mut bvh = CpuBvh::new(&a);
    assert_exact(&bvh, &rays, &a, "before");
    bvh.rebuild(&b);
    assert_eq!(bvh.triangle_count(), 700);
    assert_exact(&bvh, &rays, &b, "after");
}

#[test]
fn tracer_equals_brute_force_through_gpu_buffers() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(900, 61);
    let rays = common::random_rays(5000, 62);
    let mut tracer = TracerKind::CpuBvh.create(&gpu, &soup).unwrap();
    assert_eq!(tracer.name(), "cpu-bvh");
    assert_eq!("cpu-bvh".parse::<TracerKind>(), Ok(TracerKind::CpuBvh));
    let (ray_buf, hit_buf) = common::trace_after_a_copy(&gpu, tracer.as_mut(), &rays);
    let reference = hittable_only(&soup);
    assert_eq!(
        hit_buf.read::<Hit>().unwrap(),
        cpu::closest_hits(&rays, &reference)
    );
    let occ = common::trace_hits(&gpu, tracer.as_mut(), &rays, Query::Occlusion);
    for (i, (h, r)) in occ.iter().zip(&rays).enumerate() {
        assert_eq!(
            h.is_hit(),
            cpu::occluded(r, &reference),
            "occlusion of ray {i}"
        );
    }
    let timing = tracer
        .host_timing()
        .expect("a CPU tracer reports its host times");
    assert_eq!(timing.rays, 2 * rays.len() as u64);
    // New geometry, then a partial batch (the first 1 000 rays of the buffer) and an
    // empty one, which still returns a point.
    let other = common::triangle_soup(300, 63);
    tracer.set_geometry(&other).unwrap();
    assert_eq!(tracer.host_timing().unwrap().rays, 0);
    let done = tracer
        .trace(&ray_buf, &hit_buf, 1000, Query::ClosestHit, &[])
        .unwrap();
    gpu.wait(&done).unwrap();
    let hits = hit_buf.read::<Hit>().unwrap();
    assert_eq!(
        hits[..1000],
        cpu::closest_hits(&rays[..1000], &hittable_only(&other))[..]
    );
    let done = tracer
        .trace(&ray_buf, &hit_buf, 0, Query::ClosestHit, &[])
        .unwrap();
    gpu.wait(&done).unwrap();
    // More rays than the buffers hold is an error, not a panic.
    assert!(tracer
        .trace(
            &ray_buf,
            &hit_buf,
            rays.len() as u32 + 1,
            Query::ClosestHit,
            &[]
        )
        .is_err());
    common::assert_clean(&gpu);
}
