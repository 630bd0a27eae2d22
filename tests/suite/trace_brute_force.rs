//! The GPU brute-force tracer against its CPU twin, and the shared struct layouts.

use crate::common;

use glam::Vec3;
use splitray::shaders;
use splitray::trace::{cpu, BruteForceTracer, GpuTriangle, Hit, Query, Ray};
use splitray::vk::{ComputePipeline, Gpu, PipelineDesc, StreamKind};

#[test]
fn brute_force_matches_cpu_on_random_triangle_soups() {
    let gpu = common::gpu();
    // And a scene without triangles: every ray misses.
    for (triangles, rays, seed) in common::RANDOM_SOUPS.into_iter().chain([(0, 10, 6)]) {
        let soup = common::triangle_soup(triangles, seed);
        let rays = common::random_rays(rays, seed + 100);
        let mut tracer = BruteForceTracer::new(&gpu, &soup).unwrap();
        let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
        let expected = cpu::closest_hits(&rays, &soup);
        common::assert_same_hits(&hits, &expected, &format!("{triangles} triangles"));
        if !rays.is_empty() && triangles > 100 {
            assert!(
                hits.iter().filter(|h| h.is_hit()).count() > rays.len() / 10,
                "too few hits to be a test"
            );
        }
        let occ = common::trace_hits(&gpu, &mut tracer, &rays, Query::Occlusion);
        for (i, (h, r)) in occ.iter().zip(&rays).enumerate() {
            assert_eq!(h.is_hit(), cpu::occluded(r, &soup), "occlusion of ray {i}");
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn results_do_not_depend_on_batching() {
    use splitray::trace::brute_force::BruteForceTuning;
    let gpu = common::gpu();
    let soup = common::triangle_soup(777, 9);
    // Every seventh ray an empty segment starting on a triangle (tmin = tmax, tmin >
    // tmax, NaN tmax): it misses, and skips its tests in a workgroup whose other rays
    // keep testing (the barriers stay uniform).
    let rays: Vec<Ray> = common::random_rays(3001, 10)
        .into_iter()
        .enumerate()
        .map(|(i, r)| match (i % 7, (i / 7) % 3) {
            (0, 0) => Ray::new(soup[i % soup.len()].v0(), Vec3::from(r.dir), 0.0, 0.0),
            (0, 1) => Ray::new(soup[i % soup.len()].v0(), Vec3::from(r.dir), 0.5, 0.25),
            (0, _) => Ray::new(soup[i % soup.len()].v0(), Vec3::from(r.dir), 0.0, f32::NAN),
            _ => r,
        })
        .collect();
    let expected = cpu::closest_hits(&rays, &soup);
    assert!(rays
        .iter()
        .zip(&expected)
        .all(|(r, h)| !r.is_empty() || !h.is_hit()));
    for (workgroup_size, batch) in [(1, 1), (8, 7), (64, 512), (256, 64)] {
        let mut tracer = BruteForceTracer::with_tuning(
            &gpu,
            &soup,
            BruteForceTuning {
                workgroup_size,
                batch,
            },
        )
        .unwrap();
        let hits = common::trace_hits(&gpu, &mut tracer, &rays, Query::ClosestHit);
        common::assert_same_hits(
            &hits,
            &expected,
            &format!("wg {workgroup_size}, batch {batch}"),
        );
    }
    common::assert_clean(&gpu);
}

/// The brute-force tracer on `rays`, with the default tuning and with workgroups and
/// batches of awkward sizes: closest hits against the CPU twin (the rays flagged in
/// `misses` exactly `Hit::NONE`, bit for bit) and occlusion as `cpu::occluded` says.
fn assert_like_the_cpu_twin(
    gpu: &Gpu,
    triangles: &[GpuTriangle],
    rays: &[Ray],
    misses: &[bool],
    what: &str,
) {
    use splitray::trace::brute_force::BruteForceTuning;
    let want = cpu::closest_hits(rays, triangles);
    for (i, r) in rays.iter().enumerate().filter(|(i, _)| misses[*i]) {
        assert_eq!(
            want[i],
            Hit::NONE,
            "{what}: the CPU twin hits with ray {i} {r:?}"
        );
        assert!(
            !cpu::occluded(r, triangles),
            "{what}: CPU occlusion of ray {i}"
        );
    }
    let tunings = [
        None,
        Some(BruteForceTuning {
            workgroup_size: 8,
            batch: 7,
        }),
    ];
    let occluded: Vec<bool> = rays.iter().map(|r| cpu::occluded(r, triangles)).collect();
    for tuning in tunings {
        let mut tracer = match tuning {
            None => BruteForceTracer::new(gpu, triangles),
            Some(t) => BruteForceTracer::with_tuning(gpu, triangles, t),
        }
        .unwrap();
        let what = format!("{what}, {tuning:?}");
        let hits = common::trace_hits(gpu, &mut tracer, rays, Query::ClosestHit);
        common::assert_same_hits(&hits, &want, &what);
        let occ = common::trace_hits(gpu, &mut tracer, rays, Query::Occlusion);
        common::assert_misses_and_occlusion(rays, &hits, &occ, misses, &occluded, &what);
    }
}

/// Rays with a NaN or infinite origin or direction, empty or NaN bounds and zero
/// directions (`common::rays_that_miss`) among good rays, unit and of odd lengths,
/// bounded and not: the bad ones miss, the good ones hit as on the CPU.
#[test]
fn nan_infinite_and_zero_rays_miss_like_the_cpu_twin() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(700, 71);
    let mut good = common::random_rays(1500, 72);
    good.extend(common::rays_of_odd_lengths_and_bounds(
        &common::random_rays(600, 73),
    ));
    let (rays, misses) = common::with_rays_that_miss(&good, 23);
    assert_like_the_cpu_twin(&gpu, &soup, &rays, &misses, "bad rays among good");
    common::assert_clean(&gpu);
}

/// A thousand copies of one triangle after a soup, staged across many batches (of 7 and
/// of the default size): equal t goes to the first copy whichever batch finds it.
#[test]
fn coincident_triangles_resolve_to_the_smallest_index() {
    let gpu = common::gpu();
    let (tris, first) = common::soup_with_coincident_copies();
    let mut rays = common::rays_through_the_copies(400);
    let want = cpu::closest_hits(&rays, &tris);
    let soup_hits = cpu::closest_hits(&rays, &tris[..first as usize]);
    for (i, (h, s)) in want.iter().zip(&soup_hits).enumerate() {
        assert!(
            common::is_the_first_copy_or_in_front(h, s, first),
            "ray {i}: the CPU twin hit {h:?}"
        );
    }
    rays.extend(common::random_rays(1000, 12));
    assert_like_the_cpu_twin(&gpu, &tris, &rays, &vec![false; rays.len()], "copies");
    common::assert_clean(&gpu);
}

/// A soup shrunk to 1e-6, grown to 1e6 and moved far from the origin, t compared at the
/// original scale.
#[test]
fn tiny_huge_and_far_offset_scenes_match_the_cpu_twin() {
    let gpu = common::gpu();
    let soup = common::triangle_soup(1000, 41);
    let rays = common::random_rays(3000, 42);
    for (scale, offset) in common::SCALES_AND_OFFSETS {
        let tris = common::scale_scene(&soup, scale, offset);
        let scaled_rays = common::scale_rays(&rays, scale, offset);
        let what = format!("scale {scale}, offset {offset}");
        let want = cpu::closest_hits(&scaled_rays, &tris);
        let hits = want.iter().filter(|h| h.is_hit()).count();
        assert!(hits > rays.len() / 20, "{what}: only {hits} hits");
        let mut tracer = BruteForceTracer::new(&gpu, &tris).unwrap();
        let got = common::trace_hits(&gpu, &mut tracer, &scaled_rays, Query::ClosestHit);
        common::assert_same_hits(
            &common::unscale_hits(&got, scale),
            &common::unscale_hits(&want, scale),
            &what,
        );
        let occ = common::trace_hits(&gpu, &mut tracer, &scaled_rays, Query::Occlusion);
        for (i, (o, r)) in occ.iter().zip(&scaled_rays).enumerate() {
            assert_eq!(
                o.is_hit(),
                cpu::occluded(r, &tris),
                "{what}: occlusion of ray {i}"
            );
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn rust_and_glsl_struct_layouts_agree() {
    let gpu = common::gpu();
    let n = 5usize;
    let f = common::uniforms(n * 24, 77);
    let rays: Vec<Ray> = (0..n)
        .map(|i| {
            Ray::new(
                Vec3::new(f[i], f[i + 1], f[i + 2]),
                Vec3::new(f[i + 3], f[i + 4], f[i + 5]),
                f[i + 6],
                f[i + 7],
            )
        })
        .collect();
    let hits: Vec<Hit> = (0..n)
        .map(|i| Hit {
            t: f[i + 8],
            triangle: i as u32 * 3 + 1,
            u: f[i + 9],
            v: f[i + 10],
        })
        .collect();
    let tris: Vec<GpuTriangle> = (0..n)
        .map(|i| GpuTriangle {
            v0: [f[i], f[i + 1], f[i + 2], f[i + 3]],
            v1: [f[i + 4], f[i + 5], f[i + 6], f[i + 7]],
            v2: [f[i + 8], f[i + 9], f[i + 10], f[i + 11]],
        })
        .collect();
    let pipeline = ComputePipeline::new(
        &gpu,
        &PipelineDesc {
            kernel: shaders::TEST_LAYOUT_ECHO,
            bindings: 4,
            push_constant_bytes: 4,
            spec: &[64],
        },
    )
    .unwrap();
    let (rb, hb, tb) = (
        gpu.upload("r", &rays).unwrap(),
        gpu.upload("h", &hits).unwrap(),
        gpu.upload("t", &tris).unwrap(),
    );
    let out = gpu.zeroed::<f32>("out", n * 24).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch_items(
        &pipeline,
        &[(&rb).into(), (&hb).into(), (&tb).into(), (&out).into()],
        &(n as u32),
        n as u64,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let fields = out.read::<f32>().unwrap();
    for i in 0..n {
        let (r, h, t) = (&rays[i], &hits[i], &tris[i]);
        let mut expected = vec![];
        expected.extend(r.origin);
        expected.push(r.tmin);
        expected.extend(r.dir);
        expected.push(r.tmax);
        expected.extend([h.t, h.triangle as f32, h.u, h.v]);
        expected.extend(t.v0);
        expected.extend(t.v1);
        expected.extend(t.v2);
        assert_eq!(&fields[i * 24..(i + 1) * 24], &expected[..], "record {i}");
    }
    common::assert_clean(&gpu);
}
