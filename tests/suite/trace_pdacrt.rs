//! PDACRT against the brute-force CPU twin: random soups, the built-in scenes, the
//! Stanford bunny, adversarial geometry and ray sets, and parameter independence.

use crate::common;

use glam::Vec3;
use splitray::scene;
use splitray::trace::{
    cpu, BruteForceTracer, FlushReduce, GpuTriangle, Hit, LevelSplit, PdacrtParams, PdacrtTracer,
    Query, Ray,
};
use splitray::vk::{BufferAccess, Gpu};

/// Small thresholds force deep hierarchies even on small inputs.
fn deep() -> PdacrtParams {
    PdacrtParams {
        alpha: 4,
        beta: 4,
        eta: 1 << 12,
        lambda: 3 << 10,
        batch: 16,
        intersect_workgroup: 8,
        max_rays_per_chunk: 1 << 12,
        ..PdacrtParams::default()
    }
}

/// The GPU brute-force hits: the oracle (itself checked against the CPU twin in
/// tests/suite/trace_brute_force.rs). The GPU is the reference rather than the CPU because a
/// ray that runs exactly along an edge shared by two triangles may hit one of them or
/// slip between them depending on how the compiler fuses multiply-adds; both GPU tracers
/// share the GLSL test, so they agree bit for bit.
fn brute_force(gpu: &Gpu, triangles: &[GpuTriangle], rays: &[Ray]) -> Vec<Hit> {
    let mut oracle = BruteForceTracer::new(gpu, triangles).unwrap();
    common::trace_hits(gpu, &mut oracle, rays, Query::ClosestHit)
}

/// PDACRT equals brute force for closest hits, and occlusion agrees with it.
fn check(gpu: &Gpu, triangles: &[GpuTriangle], rays: &[Ray], params: PdacrtParams, what: &str) {
    let mut tracer = PdacrtTracer::with_params(gpu, triangles, params).unwrap();
    let hits = common::trace_hits(gpu, &mut tracer, rays, Query::ClosestHit);
    let expected = brute_force(gpu, triangles, rays);
    common::assert_same_hits(&hits, &expected, what);
    let occluded = common::trace_hits(gpu, &mut tracer, rays, Query::Occlusion);
    for (i, (o, e)) in occluded.iter().zip(&expected).enumerate() {
        assert_eq!(o.is_hit(), e.is_hit(), "{what}: occlusion of ray {i}");
    }
}

/// [`check`] for each of `variants`, and against the CPU twin as well: the rays
/// flagged in `misses` miss exactly (`Hit::NONE`, bit for bit, and not occluded), as
/// `cpu::closest_hits` and `cpu::occluded` say they do; the others hit what
/// `cpu::closest_hits` hits. Returns each variant's closest hits.
fn check_with_cpu(
    gpu: &Gpu,
    triangles: &[GpuTriangle],
    rays: &[Ray],
    misses: &[bool],
    variants: &[(PdacrtParams, &str)],
) -> Vec<Vec<Hit>> {
    let want = cpu::closest_hits(rays, triangles);
    let occluded: Vec<bool> = rays.iter().map(|r| cpu::occluded(r, triangles)).collect();
    for (i, r) in rays.iter().enumerate().filter(|(i, _)| misses[*i]) {
        assert_eq!(want[i], Hit::NONE, "the CPU twin hits with ray {i} {r:?}");
        assert!(!occluded[i], "CPU occlusion of ray {i} {r:?}");
    }
    let oracle = brute_force(gpu, triangles, rays);
    let mut all_hits = vec![];
    for &(params, what) in variants {
        let mut tracer = PdacrtTracer::with_params(gpu, triangles, params).unwrap();
        let hits = common::trace_hits(gpu, &mut tracer, rays, Query::ClosestHit);
        common::assert_same_hits(&hits, &oracle, what);
        common::assert_same_hits(&hits, &want, &format!("{what}: against the CPU twin"));
        let occ = common::trace_hits(gpu, &mut tracer, rays, Query::Occlusion);
        common::assert_misses_and_occlusion(rays, &hits, &occ, misses, &occluded, what);
        all_hits.push(hits);
    }
    all_hits
}

/// The two ways through PDACRT's kernels: the paper's (sort by key, sort by ray, halves
/// of the parent's box, staged triangles) in a deep hierarchy, and the device's defaults
/// (prefix sums, atomic flush where the device has it, tight boxes).
fn both_ways(gpu: &Gpu) -> [(PdacrtParams, &'static str); 2] {
    [
        (
            PdacrtParams {
                stage_triangles: true,
                ..deep()
            },
            "deep",
        ),
        (PdacrtParams::for_device(gpu), "defaults"),
    ]
}

/// Rays with a NaN or infinite origin or direction, empty or NaN bounds and zero
/// directions (`common::rays_that_miss`), mixed in among good rays, unit and of odd
/// lengths, bounded and not: a bad ray may pass or fail any box test (its slab distances
/// are NaN), but must reach no hit and disturb no other ray's.
#[test]
fn nan_infinite_and_zero_rays_miss_like_brute_force() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(600, 71);
    let mut good = common::random_rays(1000, 72);
    good.extend(common::rays_of_odd_lengths_and_bounds(
        &common::random_rays(300, 73),
    ));
    let (rays, misses) = common::with_rays_that_miss(&good, 13);
    assert!(misses.iter().filter(|&&m| m).count() > 2000);
    let hits = check_with_cpu(&gpu, &soup, &rays, &misses, &both_ways(&gpu));
    let count = hits[0].iter().filter(|h| h.is_hit()).count();
    assert!(count > good.len() / 4, "only {count} hits");
    common::assert_clean(&gpu);
}

/// A thousand copies of one triangle after a soup: wherever the hierarchy sends one copy
/// it sends all of them, so no split ever separates them and every terminal node holding
/// one tests a thousand hits at equal t. A ray through them must report the first copy,
/// in either flush reduction, also when the copies' hits reach the closest hit over
/// several flushes (a small η flushes at every level).
#[test]
fn coincident_triangles_resolve_to_the_smallest_index() {
    let gpu = common::gpu();
    let (tris, first) = common::soup_with_coincident_copies();
    let mut rays = common::rays_through_the_copies(400);
    rays.extend(common::random_rays(500, 12));
    let through = 400;
    let soup_hits = cpu::closest_hits(&rays[..through], &tris[..first as usize]);
    let mut variants = both_ways(&gpu).to_vec();
    variants.push((
        PdacrtParams {
            eta: 64,
            lambda: 64,
            ..deep()
        },
        "deep, a flush every level",
    ));
    let all_hits = check_with_cpu(&gpu, &tris, &rays, &vec![false; rays.len()], &variants);
    for ((_, name), hits) in variants.iter().zip(&all_hits) {
        let firsts = hits.iter().filter(|h| h.triangle == first).count();
        assert!(
            firsts > through / 2,
            "{name}: {firsts} hits of the first copy"
        );
        for (i, (h, s)) in hits[..through].iter().zip(&soup_hits).enumerate() {
            assert!(
                common::is_the_first_copy_or_in_front(h, s, first),
                "{name}: ray {i} {:?} hit {h:?}",
                rays[i]
            );
        }
    }
    common::assert_clean(&gpu);
}

/// A soup shrunk to 1e-6, grown to 1e6 and moved far from the origin: the box padding
/// follows the scene's size and position (`scene_box`), so no hit is lost to rounding
/// in the box tests; t is compared at the original scale.
#[test]
fn tiny_huge_and_far_offset_scenes_match_the_cpu_twin() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(600, 41);
    let rays = common::random_rays(2000, 42);
    let want = cpu::closest_hits(&rays, &soup);
    for (scale, offset) in common::SCALES_AND_OFFSETS {
        let tris = common::scale_scene(&soup, scale, offset);
        let scaled_rays = common::scale_rays(&rays, scale, offset);
        let what = format!("scale {scale}, offset {offset}");
        let expected = cpu::closest_hits(&scaled_rays, &tris);
        let hits = expected.iter().filter(|h| h.is_hit()).count();
        assert!(hits > rays.len() / 20, "{what}: only {hits} hits");
        if offset == Vec3::ZERO {
            // Scaling by a power of ten rounds the vertices, so a ray near an edge may
            // change triangles; most keep theirs.
            let kept = common::unscale_hits(&expected, scale)
                .iter()
                .zip(&want)
                .filter(|(a, b)| cpu::same_hit(a, b, 1e-4, false))
                .count();
            assert!(kept > rays.len() * 99 / 100, "{what}: {kept} hits kept");
        }
        for (params, name) in both_ways(&gpu) {
            let mut tracer = PdacrtTracer::with_params(&gpu, &tris, params).unwrap();
            let got = common::trace_hits(&gpu, &mut tracer, &scaled_rays, Query::ClosestHit);
            common::assert_same_hits(
                &common::unscale_hits(&got, scale),
                &common::unscale_hits(&expected, scale),
                &format!("{what}, {name}"),
            );
            let occluded = common::trace_hits(&gpu, &mut tracer, &scaled_rays, Query::Occlusion);
            for (i, (o, e)) in occluded.iter().zip(&expected).enumerate() {
                assert_eq!(
                    o.is_hit(),
                    e.is_hit(),
                    "{what}, {name}: occlusion of ray {i}"
                );
            }
        }
        let oracle = brute_force(&gpu, &tris, &scaled_rays);
        common::assert_same_hits(
            &common::unscale_hits(&oracle, scale),
            &common::unscale_hits(&expected, scale),
            &format!("{what}: brute force"),
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn random_soups_match_brute_force() {
    let gpu = common::gpu();
    for (tris, rays, seed) in [
        (1usize, 7usize, 1u64),
        (300, 5000, 2),
        (2000, 20_000, 3),
        (5000, 3001, 4),
    ] {
        let soup = common::triangle_soup(tris, seed);
        let rays = common::random_rays(rays, seed + 50);
        check(
            &gpu,
            &soup,
            &rays,
            deep(),
            &format!("{tris} triangles, deep"),
        );
        check(
            &gpu,
            &soup,
            &rays,
            PdacrtParams::for_device(&gpu),
            &format!("{tris} triangles, defaults"),
        );
    }
    common::assert_clean(&gpu);
}

/// Every PDACRT kernel in the form that takes its buffers by address (lavapipe runs the
/// descriptor twins wherever buffers fit one binding), against brute force in the
/// default form: both split methods and both flush reductions, deep hierarchies.
#[test]
fn kernels_taking_buffers_by_address_match_brute_force() {
    let by_address = common::gpu_with_access(BufferAccess::Addresses);
    let gpu = common::gpu();
    let soup = common::triangle_soup(2000, 11);
    let rays = common::random_rays(6000, 12);
    let expected = brute_force(&gpu, &soup, &rays);
    for split in [LevelSplit::SortByKey, LevelSplit::PrefixSums] {
        for flush in [FlushReduce::SortByRay, FlushReduce::AtomicMin] {
            if flush == FlushReduce::AtomicMin && !gpu.info().capabilities.buffer_int64_atomics {
                continue;
            }
            for stage_triangles in [false, true] {
                let params = PdacrtParams {
                    split,
                    flush_reduce: flush,
                    stage_triangles,
                    ..deep()
                };
                let mut tracer = PdacrtTracer::with_params(&by_address, &soup, params).unwrap();
                let hits = common::trace_hits(&by_address, &mut tracer, &rays, Query::ClosestHit);
                let what = format!("by address: {split:?}, {flush:?}, staged {stage_triangles}");
                common::assert_same_hits(&hits, &expected, &what);
            }
        }
    }
    common::assert_clean(&by_address);
    common::assert_clean(&gpu);
}

#[test]
fn empty_batches_and_empty_scenes() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(100, 9);
    check(&gpu, &soup, &[], deep(), "no rays");
    check(
        &gpu,
        &[],
        &common::random_rays(50, 3),
        deep(),
        "no triangles",
    );
    common::assert_clean(&gpu);
}

/// Empty segments (tmax <= tmin, as the integrators' "no ray", or a NaN tmax) miss, and
/// leave at the root: a batch with them added builds the same levels below the root as
/// the batch without them, even where their origins lie on the geometry (a zero-length
/// segment there passes every box test around its origin).
#[test]
fn empty_segments_leave_at_the_root() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(2000, 61);
    let rays = common::random_rays(2500, 62);
    let empties: Vec<Ray> = soup
        .iter()
        .take(1500)
        .enumerate()
        .map(|(i, t)| {
            let (tmin, tmax) = match i % 3 {
                0 => (0.0, 0.0),
                1 => (0.5, 0.25),
                _ => (0.0, f32::NAN),
            };
            Ray::new(t.v0(), Vec3::new(0.3, -0.5, 0.8).normalize(), tmin, tmax)
        })
        .collect();
    let mixed: Vec<Ray> = rays.iter().chain(&empties).copied().collect();
    let below_root = |batch: &[Ray], query: Query| {
        let mut tracer = PdacrtTracer::with_params(&gpu, &soup, deep()).unwrap();
        let hits = common::trace_hits(&gpu, &mut tracer, batch, query);
        let levels: Vec<_> = tracer
            .stats()
            .levels
            .iter()
            .filter(|l| l.level > 0)
            .map(|l| (l.level, l.nodes, l.triangles, l.rays, l.terminal_nodes))
            .collect();
        (hits, levels)
    };
    for query in [Query::ClosestHit, Query::Occlusion] {
        let (hits, levels) = below_root(&mixed, query);
        let (alone_hits, alone_levels) = below_root(&rays, query);
        assert!(levels.len() > 3, "{query:?}: a hierarchy of a few levels");
        assert_eq!(levels, alone_levels, "{query:?}: levels below the root");
        assert_eq!(
            hits[..rays.len()],
            alone_hits[..],
            "{query:?}: the real rays"
        );
        for (i, hit) in hits[rays.len()..].iter().enumerate() {
            assert!(!hit.is_hit(), "{query:?}: empty segment {i} hit {hit:?}");
        }
    }
    common::assert_clean(&gpu);
}

fn scene_triangles(scene: &scene::Scene) -> Vec<GpuTriangle> {
    scene.gpu_triangles()
}

#[test]
fn builtin_scenes_match_including_cameras_inside_the_box() {
    let gpu = common::gpu();
    for name in ["cornell-box", "fixture"] {
        let mut s = scene::load(name).unwrap();
        let tris = scene_triangles(&s);
        check(
            &gpu,
            &tris,
            &common::camera_rays(&s.camera, 64, 48),
            deep(),
            name,
        );
        check(
            &gpu,
            &tris,
            &common::camera_rays(&s.camera, 64, 48),
            PdacrtParams {
                tight_boxes: true,
                ..deep()
            },
            &format!("{name}, tight boxes"),
        );
        // From the centre of the scene box, looking at a corner.
        let b = s.bounds();
        s.camera.position = b.center();
        s.camera.look_at = b.max;
        check(
            &gpu,
            &tris,
            &common::camera_rays(&s.camera, 48, 48),
            deep(),
            &format!("{name} from inside"),
        );
    }
    common::assert_clean(&gpu);
}

#[test]
fn the_stanford_bunny_matches() {
    let path = "../shared/meshes/bunny/bunny.obj";
    if !std::path::Path::new(path).exists() {
        eprintln!("skipped: {path} not found");
        return;
    }
    let gpu = common::gpu();
    let s = scene::load(path).unwrap();
    let tris = scene_triangles(&s);
    let mut rays = common::camera_rays(&s.camera, 40, 40);
    // Secondary-like rays: from points on the surface in random directions.
    let u = common::uniforms(3000, 77);
    for k in 0..1000 {
        let t = &s.triangles[(k * 69) % s.triangles.len()];
        let p = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
        let d = Vec3::new(u[3 * k] - 0.5, u[3 * k + 1] - 0.5, u[3 * k + 2] - 0.5).normalize();
        rays.push(Ray::new(p, d, 1e-5, f32::INFINITY));
    }
    check(&gpu, &tris, &rays, PdacrtParams::for_device(&gpu), "bunny");
    check(
        &gpu,
        &tris,
        &rays,
        PdacrtParams {
            alpha: 64,
            beta: 64,
            ..PdacrtParams::for_device(&gpu)
        },
        "bunny α=β=64",
    );
    common::assert_clean(&gpu);
}

/// A 4×4×4 lattice of unit cells with flat axis-aligned triangles lying exactly in the
/// planes the midpoint splits pick (x, y, z = 0, 1, 2, 3, 4 in a box of side 4), and
/// rays parallel to those planes, starting on them, and running inside them.
#[test]
fn split_planes_flat_triangles_and_axis_parallel_rays() {
    let gpu = common::gpu();
    let mut tris = Vec::new();
    for a in 0..=4 {
        for b in 0..4 {
            for c in 0..4 {
                let (a, b, c) = (a as f32, b as f32, c as f32);
                // A triangle in the plane x = a, and its rotations into y = a and z = a.
                let q = [
                    Vec3::new(a, b, c),
                    Vec3::new(a, b + 1.0, c),
                    Vec3::new(a, b, c + 1.0),
                ];
                tris.push(GpuTriangle::new(q));
                tris.push(GpuTriangle::new(q.map(|p| Vec3::new(p.y, p.x, p.z))));
                tris.push(GpuTriangle::new(q.map(|p| Vec3::new(p.z, p.y, p.x))));
            }
        }
    }
    // Zero-area triangles on the planes too.
    tris.push(GpuTriangle::new([Vec3::splat(2.0); 3]));
    tris.push(GpuTriangle::new([
        Vec3::ZERO,
        Vec3::splat(2.0),
        Vec3::splat(4.0),
    ]));
    let mut rays = Vec::new();
    let u = common::uniforms(6000, 5);
    for k in 0..1000 {
        let o = Vec3::new(u[6 * k], u[6 * k + 1], u[6 * k + 2]) * 4.0;
        let axis = k % 3;
        let mut d = Vec3::ZERO;
        d[axis] = if k % 2 == 0 { 1.0 } else { -1.0 };
        let mut origin = o;
        match k % 4 {
            0 => origin[(axis + 1) % 3] = 2.0, // inside the plane of a split
            1 => origin[axis] = 2.0,           // starting on a split plane
            2 => origin = Vec3::new(2.0, 2.0, 2.0) + 0.0 * o, // from the centre corner
            _ => origin[(axis + 2) % 3] = (o[(axis + 2) % 3]).floor(), // along a lattice plane
        }
        rays.push(Ray::new(origin, d, 0.0, f32::INFINITY));
        // And an oblique ray from outside the box.
        let target = Vec3::new(u[6 * k + 3], u[6 * k + 4], u[6 * k + 5]) * 4.0;
        let from = Vec3::new(-1.0, 5.0, -2.0);
        rays.push(Ray::new(
            from,
            (target - from).normalize(),
            0.0,
            f32::INFINITY,
        ));
    }
    check(&gpu, &tris, &rays, deep(), "lattice, deep");
    // Tight boxes around flat triangles have zero extent on an axis; rays run inside
    // them and along their faces.
    for split in [LevelSplit::SortByKey, LevelSplit::PrefixSums] {
        check(
            &gpu,
            &tris,
            &rays,
            PdacrtParams {
                tight_boxes: true,
                terminal_cost: 64,
                split,
                ..deep()
            },
            &format!("lattice, deep, tight boxes, {split:?}"),
        );
    }
    check(
        &gpu,
        &tris,
        &rays,
        PdacrtParams {
            alpha: 16,
            beta: 16,
            ..deep()
        },
        "lattice, α=β=16",
    );
    common::assert_clean(&gpu);
}

#[test]
fn results_do_not_depend_on_the_parameters() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(3000, 21);
    let rays = common::random_rays(9000, 22);
    let expected = brute_force(&gpu, &soup, &rays);
    let variants = [
        PdacrtParams::for_device(&gpu),
        deep(),
        PdacrtParams {
            alpha: 1,
            beta: 1,
            max_depth: 12,
            ..deep()
        },
        PdacrtParams {
            eta: 64,
            lambda: 64,
            ..deep()
        }, // flush every level, grow the buffer
        PdacrtParams {
            batch: 1,
            intersect_workgroup: 1,
            ..deep()
        },
        PdacrtParams {
            batch: 300,
            intersect_workgroup: 256,
            ..PdacrtParams::for_device(&gpu)
        },
        PdacrtParams {
            max_rays_per_chunk: 1000,
            ..deep()
        }, // chunks of non-power-of-two size
        PdacrtParams {
            alpha: 100_000,
            ..deep()
        }, // the root is terminal
        // Both level splits, with staged and direct triangle reads in the intersection.
        PdacrtParams {
            split: LevelSplit::SortByKey,
            stage_triangles: true,
            ..deep()
        },
        PdacrtParams {
            split: LevelSplit::PrefixSums,
            stage_triangles: true,
            ..deep()
        },
        PdacrtParams {
            split: LevelSplit::SortByKey,
            stage_triangles: false,
            ..deep()
        },
        PdacrtParams {
            split: LevelSplit::PrefixSums,
            stage_triangles: false,
            intersect_workgroup: 3, // segments of 24 rays: 8 per invocation, some partial
            ..deep()
        },
        // Tiles per workgroup of one invocation, of a non-power of two, and of more
        // invocations than most tiles have elements.
        PdacrtParams {
            split: LevelSplit::PrefixSums,
            tile_workgroup: 1,
            ..deep()
        },
        PdacrtParams {
            split: LevelSplit::PrefixSums,
            tile_workgroup: 3,
            ..deep()
        },
        PdacrtParams {
            tile_workgroup: 256,
            ..PdacrtParams::for_device(&gpu)
        },
        PdacrtParams {
            split: LevelSplit::SortByKey,
            ..PdacrtParams::for_device(&gpu)
        },
        PdacrtParams {
            flush_reduce: FlushReduce::SortByRay,
            ..PdacrtParams::for_device(&gpu)
        },
        // Children boxed by their triangles and by the halves of their parents, with
        // both splits; nodes of few rays terminal by count and by cost.
        PdacrtParams {
            tight_boxes: true,
            split: LevelSplit::SortByKey,
            ..deep()
        },
        PdacrtParams {
            tight_boxes: true,
            terminal_cost: 64,
            split: LevelSplit::PrefixSums,
            tile_workgroup: 3,
            ..deep()
        },
        PdacrtParams {
            terminal_cost: 8,
            alpha: 2,
            beta: 64,
            ..deep()
        },
        PdacrtParams {
            one_dispatch_plan: false,
            ..PdacrtParams::for_device(&gpu)
        },
        PdacrtParams {
            tight_boxes: false,
            terminal_cost: 0,
            ..PdacrtParams::for_device(&gpu)
        },
    ];
    // The atomic flush on both intersection variants, where the device has it.
    let atomic = gpu.info().capabilities.buffer_int64_atomics;
    let atomic_variants = [true, false].map(|stage_triangles| PdacrtParams {
        flush_reduce: FlushReduce::AtomicMin,
        stage_triangles,
        eta: 64,
        lambda: 64, // many flushes: the packed hits must carry over between them
        ..deep()
    });
    let variants = variants
        .into_iter()
        .chain(atomic_variants.into_iter().filter(|_| atomic));
    for (i, params) in variants.into_iter().enumerate() {
        let mut tracer = PdacrtTracer::with_params(&gpu, &soup, params).unwrap();
        let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
        common::assert_same_hits(&hits, &expected, &format!("variant {i}: {params:?}"));
    }
    common::assert_clean(&gpu);
}

/// The one-dispatch level plan (level_plan.comp) builds the hierarchy the four-dispatch
/// plan builds, level for level, and the same hits: with the device's tiles, with tiles
/// of three invocations and with one (on CPU devices the plan's workgroup is the
/// tiles', so its workgroup scans see runs of odd lengths too).
#[test]
fn the_one_dispatch_plan_builds_the_same_levels() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(4000, 41);
    let rays = common::random_rays(12_000, 42);
    let expected = brute_force(&gpu, &soup, &rays);
    let shapes = [
        PdacrtParams::for_device(&gpu),
        PdacrtParams {
            split: LevelSplit::PrefixSums,
            tight_boxes: true,
            tile_workgroup: 3,
            ..deep()
        },
        PdacrtParams {
            split: LevelSplit::PrefixSums,
            tile_workgroup: 1,
            ..deep()
        },
    ];
    for base in shapes {
        let levels = [true, false].map(|one_dispatch_plan| {
            let params = PdacrtParams {
                one_dispatch_plan,
                ..base
            };
            let mut tracer = PdacrtTracer::with_params(&gpu, &soup, params).unwrap();
            let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
            common::assert_same_hits(&hits, &expected, &format!("{params:?}"));
            let stats = tracer.stats();
            stats
                .levels
                .iter()
                .map(|l| {
                    (
                        l.chunk,
                        l.level,
                        l.nodes,
                        l.triangles,
                        l.rays,
                        l.terminal_nodes,
                    )
                })
                .collect::<Vec<_>>()
        });
        assert!(levels[0].len() > 3, "{base:?}: a hierarchy of a few levels");
        assert_eq!(
            levels[0], levels[1],
            "{base:?}: levels with and without the plan"
        );
    }
    common::assert_clean(&gpu);
}

/// Rays whose segments start behind their origins (negative tmin) find hits at negative
/// t: the closest is the most negative one past tmin. Both flush reductions order them
/// like brute force (the atomic one through its order-preserving float bits).
#[test]
fn negative_t_hits_reduce_like_brute_force() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(2000, 31);
    let rays: Vec<Ray> = common::random_rays(6000, 32)
        .into_iter()
        .enumerate()
        .map(|(i, mut r)| {
            if i % 2 == 0 {
                r.tmin = -0.5;
            }
            r
        })
        .collect();
    let expected = brute_force(&gpu, &soup, &rays);
    assert!(
        expected
            .iter()
            .any(|h| h.triangle != splitray::trace::MISS && h.t < 0.0),
        "the ray set must produce negative-t hits"
    );
    let mut reductions = vec![FlushReduce::SortByRay];
    if gpu.info().capabilities.buffer_int64_atomics {
        reductions.push(FlushReduce::AtomicMin);
    }
    for flush_reduce in reductions {
        let params = PdacrtParams {
            flush_reduce,
            ..deep()
        };
        check(&gpu, &soup, &rays, params, &format!("{flush_reduce:?}"));
    }
    common::assert_clean(&gpu);
}
