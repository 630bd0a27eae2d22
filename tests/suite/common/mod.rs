//! Shared test harness: every GPU test runs with the validation layer on, and any
//! validation error or warning fails it.
#![allow(dead_code)]

pub mod analytic;
pub mod cli;
pub mod lvc_dump;
pub mod mis;
pub mod process;
pub mod reference;
pub mod scenes;
mod turn;

pub use turn::TestGpu;

use splitray::vk::{BufferAccess, Gpu, GpuDesc, InstanceDesc, StreamPlacement};

/// Opens the default device with validation (and synchronization validation if `sync`).
pub fn gpu_with(placement: StreamPlacement, sync: bool) -> TestGpu {
    let _ = env_logger::builder().is_test(true).try_init();
    TestGpu::open(|| {
        open(&GpuDesc {
            instance: InstanceDesc {
                validation: true,
                sync_validation: sync,
            },
            device: None,
            placement,
            ..Default::default()
        })
    })
}

fn open(desc: &GpuDesc) -> Gpu {
    Gpu::new(desc).expect("a Vulkan device with the validation layer (run `make deps`)")
}

/// Whether the device can hold a buffer of `bytes` that is past one storage binding
/// (maxStorageBufferRange), the premise of the tests of kernels taking buffers by
/// address at full size. Not where one allocation is no larger than one binding: on
/// NVIDIA (maxMemoryAllocationSize 4 GiB − 2 MiB, maxStorageBufferRange 4 GiB − 1) every
/// buffer fits one binding; the tests that force `BufferAccess::Addresses` still run
/// the by-address kernels there. Says on stderr why a test stops short.
pub fn holds_past_one_binding(gpu: &Gpu, bytes: u64, what: &str) -> bool {
    let binding = gpu.info().limits.max_storage_buffer_range;
    let (limit, which) = gpu.max_buffer_bytes();
    let holds = bytes > binding && bytes <= limit;
    if !holds {
        eprintln!(
            "{what}: not run on {}: {bytes} bytes are not both past one binding ({binding} \
             bytes) and within one buffer ({which}, {limit} bytes)",
            gpu.info().name
        );
    }
    holds
}

pub fn gpu() -> TestGpu {
    gpu_with(StreamPlacement::Spread, false)
}

/// The default device with validation, its kernels taking buffers as `access` says
/// (lavapipe's default reads descriptors where they fit: this proves the other way).
pub fn gpu_with_access(access: BufferAccess) -> TestGpu {
    let _ = env_logger::builder().is_test(true).try_init();
    TestGpu::open(|| {
        open(&GpuDesc {
            instance: InstanceDesc {
                validation: true,
                sync_validation: false,
            },
            device: None,
            placement: StreamPlacement::Spread,
            buffer_access: Some(access),
        })
    })
}

/// Waits for the device, then fails the test on any validation message.
pub fn assert_clean(gpu: &Gpu) {
    gpu.wait_idle().expect("wait idle");
    let messages = gpu.validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation message(s):\n{}",
        messages.len(),
        messages
            .iter()
            .map(|m| format!("  {} [{}] {}", m.severity, m.id_name, m.text))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The sizes issue 3 asks every primitive to be tested at: empty, one, two, around a
/// power of two, non-powers of two, and large.
pub const ISSUE_SIZES: [usize; 10] = [0, 1, 2, 255, 256, 257, 1000, 65_537, 1_000_003, 1 << 22];

/// The device's tuning with the general (non-segment) path and with segments of 4, 12,
/// 16 and 24 items, so that runs and kept items cross many segments — the last two with
/// 64-bit accesses where the device has them: for primitives whose segment variants
/// must agree with their general path on every device.
pub fn segment_tunings(gpu: &Gpu) -> Vec<(u32, splitray::primitives::Tuning)> {
    let base = splitray::primitives::Tuning::for_device(gpu.info());
    [
        (0u32, false),
        (4, false),
        (12, false),
        (16, true),
        (24, true),
    ]
    .into_iter()
    .map(|(segment, wide)| {
        let tuning = splitray::primitives::Tuning {
            scan_segment: segment,
            wide_accesses: wide,
            ..base
        };
        (segment, tuning.fit(gpu.info()))
    })
    .collect()
}

/// SplitMix64: the tests' deterministic pseudo-random numbers, the same on every
/// machine.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// The low 32 bits of [`SplitMix64::next_u64`].
    pub fn next_u32(&mut self) -> u32 {
        self.next_u64() as u32
    }

    /// Uniform in [0, 1) with 24 bits.
    pub fn uniform(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// Deterministic pseudo-random u32s ([`SplitMix64`]) for test data.
pub fn random_u32s(n: usize, seed: u64) -> Vec<u32> {
    let mut rng = SplitMix64(seed);
    (0..n).map(|_| rng.next_u32()).collect()
}

/// Uniform floats in [0, 1) from [`random_u32s`].
pub fn uniforms(n: usize, seed: u64) -> Vec<f32> {
    random_u32s(n, seed)
        .into_iter()
        .map(|x| (x >> 8) as f32 / (1u32 << 24) as f32)
        .collect()
}

/// (triangles, rays, seed) of the random soups the tracers are checked on: one triangle,
/// sizes that are not powers of two, no rays, one ray.
pub const RANDOM_SOUPS: [(usize, usize, u64); 5] = [
    (1, 100, 1),
    (513, 4099, 2),
    (1000, 20_000, 3),
    (3, 0, 4),
    (2000, 1, 5),
];

/// A soup of `n` triangles in the unit cube, of mixed sizes, a few of them degenerate
/// (every 97th a point, the next a collinear sliver).
pub fn triangle_soup(n: usize, seed: u64) -> Vec<splitray::trace::GpuTriangle> {
    use glam::Vec3;
    let r = uniforms(n * 10, seed);
    (0..n)
        .map(|i| {
            let c = &r[i * 10..];
            let centre = Vec3::new(c[0], c[1], c[2]);
            let size = 0.02 + 0.3 * c[9];
            let a = centre + size * (Vec3::new(c[3], c[4], c[5]) - 0.5);
            let b = centre + size * (Vec3::new(c[6], c[7], c[8]) - 0.5);
            let tri = match i % 97 {
                0 => [centre, centre, centre],                 // a point
                1 => [centre, a, centre + 2.0 * (a - centre)], // collinear
                _ => [centre, a, b],
            };
            splitray::trace::GpuTriangle::new(tri)
        })
        .collect()
}

/// `n` unit rays from around the unit cube towards points inside it; every fifth has a
/// short tmax (0.3).
pub fn random_rays(n: usize, seed: u64) -> Vec<splitray::trace::Ray> {
    use glam::Vec3;
    let r = uniforms(n * 6, seed);
    (0..n)
        .map(|i| {
            let c = &r[i * 6..];
            let origin = Vec3::new(c[0], c[1], c[2]) * 1.4 - 0.2;
            let target = Vec3::new(c[3], c[4], c[5]);
            let dir = (target - origin).try_normalize().unwrap_or(Vec3::X);
            splitray::trace::Ray::new(
                origin,
                dir,
                0.0,
                if i % 5 == 0 { 0.3 } else { f32::INFINITY },
            )
        })
        .collect()
}

/// A soup of 500 triangles followed by a thousand copies of one triangle in the plane
/// z = 0.5, and the index of the first copy: a degenerate hierarchy, where every hit on
/// a copy ties at equal t and must go to the first.
pub fn soup_with_coincident_copies() -> (Vec<splitray::trace::GpuTriangle>, u32) {
    use glam::Vec3;
    let tri = splitray::trace::GpuTriangle::new([
        Vec3::new(0.1, 0.1, 0.5),
        Vec3::new(0.9, 0.1, 0.5),
        Vec3::new(0.5, 0.9, 0.5),
    ]);
    let mut tris = triangle_soup(500, 11);
    let first = tris.len() as u32;
    tris.extend(std::iter::repeat_n(tri, 1000));
    (tris, first)
}

/// `n` rays through the copies of [`soup_with_coincident_copies`], alternately from
/// either side of their plane.
pub fn rays_through_the_copies(n: usize) -> Vec<splitray::trace::Ray> {
    use glam::Vec3;
    (0..n)
        .map(|i| {
            let (x, y) = (0.3 + 0.001 * i as f32, 0.3 + 0.0005 * (i % 7) as f32);
            let dir = if i % 2 == 0 { Vec3::Z } else { -Vec3::Z };
            splitray::trace::Ray::new(Vec3::new(x, y, 0.5 - dir.z * 1.5), dir, 0.0, f32::INFINITY)
        })
        .collect()
}

/// Whether `hit`, of a ray of [`rays_through_the_copies`], is the first copy, or the
/// soup triangle `soup_hit` the ray meets in front of the copies (1.5 away).
pub fn is_the_first_copy_or_in_front(
    hit: &splitray::trace::Hit,
    soup_hit: &splitray::trace::Hit,
    first: u32,
) -> bool {
    hit.triangle == first
        || (soup_hit.is_hit() && soup_hit.t <= 1.5 && hit.triangle == soup_hit.triangle)
}

/// Checks a tracer's answers for `rays`: each ray marked in `misses` gave exactly
/// [`splitray::trace::Hit::NONE`] (no NaN barycentrics, no t), and every occlusion
/// answer `occ` is the CPU twin's `occluded`.
pub fn assert_misses_and_occlusion(
    rays: &[splitray::trace::Ray],
    hits: &[splitray::trace::Hit],
    occ: &[splitray::trace::Hit],
    misses: &[bool],
    occluded: &[bool],
    what: &str,
) {
    for (i, r) in rays.iter().enumerate() {
        if misses[i] {
            assert_eq!(
                bytemuck::bytes_of(&hits[i]),
                bytemuck::bytes_of(&splitray::trace::Hit::NONE),
                "{what}: ray {i} {r:?} gave {:?}",
                hits[i]
            );
        }
        assert_eq!(
            occ[i].is_hit(),
            occluded[i],
            "{what}: occlusion of ray {i} {r:?}"
        );
    }
}

/// The (scale, offset) pairs of [`scale_scene`] that tracers are checked at: shrunk to
/// 1e-6, grown to 1e6, and moved far from the origin.
pub const SCALES_AND_OFFSETS: [(f32, glam::Vec3); 3] = [
    (1e-6, glam::Vec3::ZERO),
    (1e6, glam::Vec3::ZERO),
    (1.0, glam::Vec3::new(300.0, -200.0, 100.0)),
];

/// `tris` scaled by `s` about the origin, then moved by `offset`.
pub fn scale_scene(
    tris: &[splitray::trace::GpuTriangle],
    s: f32,
    offset: glam::Vec3,
) -> Vec<splitray::trace::GpuTriangle> {
    tris.iter()
        .map(|t| {
            let v0 = t.v0();
            splitray::trace::GpuTriangle::new([
                v0 * s + offset,
                (v0 + t.e1()) * s + offset,
                (v0 + t.e2()) * s + offset,
            ])
        })
        .collect()
}

/// `rays` following [`scale_scene`]: origins and (tmin, tmax) scaled by `s`, directions
/// kept, so each ray meets the scaled scene where it met the original (at t × `s`).
pub fn scale_rays(
    rays: &[splitray::trace::Ray],
    s: f32,
    offset: glam::Vec3,
) -> Vec<splitray::trace::Ray> {
    rays.iter()
        .map(|r| {
            splitray::trace::Ray::new(
                glam::Vec3::from(r.origin) * s + offset,
                glam::Vec3::from(r.dir),
                r.tmin * s,
                r.tmax * s,
            )
        })
        .collect()
}

/// Hits of a scene scaled by `s` ([`scale_scene`]) brought back to the original's t, so
/// that [`assert_same_hits`] compares them at the scale its tolerances are made for
/// (its absolute floor near the origin would otherwise swallow every t of a tiny scene).
pub fn unscale_hits(hits: &[splitray::trace::Hit], s: f32) -> Vec<splitray::trace::Hit> {
    hits.iter()
        .map(|h| splitray::trace::Hit { t: h.t / s, ..*h })
        .collect()
}

/// Rays that must meet nothing, made from `good`: NaN, +inf or −inf in one component of
/// its origin or of its direction; a NaN, +inf or −inf bound that leaves no segment
/// (tmin NaN or +inf, tmax NaN or −inf); a zero direction (+0 and −0), over every t
/// and over (−inf, 1); and every field NaN. No tracer may hit with them, whatever it
/// makes of their NaN slab distances and box tests.
pub fn rays_that_miss(good: splitray::trace::Ray) -> Vec<splitray::trace::Ray> {
    use splitray::trace::Ray;
    let mut rays = Vec::new();
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        for k in 0..3 {
            let mut r = good;
            r.origin[k] = bad;
            rays.push(r);
            let mut r = good;
            r.dir[k] = bad;
            rays.push(r);
        }
    }
    for (tmin, tmax) in [
        (f32::NAN, good.tmax),
        (good.tmin, f32::NAN),
        (f32::INFINITY, good.tmax),
        (good.tmin, f32::NEG_INFINITY),
        (f32::NEG_INFINITY, f32::NEG_INFINITY),
    ] {
        rays.push(Ray { tmin, tmax, ..good });
    }
    let o = glam::Vec3::from(good.origin);
    for zero in [glam::Vec3::ZERO, glam::Vec3::splat(-0.0)] {
        rays.push(Ray::new(o, zero, 0.0, f32::INFINITY));
        rays.push(Ray::new(o, zero, f32::NEG_INFINITY, 1.0));
    }
    rays.push(Ray::new(
        glam::Vec3::NAN,
        glam::Vec3::NAN,
        f32::NAN,
        f32::NAN,
    ));
    rays
}

/// `good` rays with the [`rays_that_miss`] variants of every `every`th one inserted
/// after it, so that the bad rays share workgroups, nodes and segments with good ones.
/// Returns the rays and, for each, whether it is one of the bad variants.
pub fn with_rays_that_miss(
    good: &[splitray::trace::Ray],
    every: usize,
) -> (Vec<splitray::trace::Ray>, Vec<bool>) {
    let mut rays = Vec::new();
    let mut bad = Vec::new();
    for (i, r) in good.iter().enumerate() {
        rays.push(*r);
        bad.push(false);
        if i % every == 0 {
            let variants = rays_that_miss(*r);
            bad.extend(std::iter::repeat_n(true, variants.len()));
            rays.extend(variants);
        }
    }
    (rays, bad)
}

/// Good rays with directions far from unit length (×1e12 and ×1e-12) and with the
/// unbounded segment (−inf, +inf): t is then no distance, and boxes are entered at t far
/// from the scene's own scale.
pub fn rays_of_odd_lengths_and_bounds(rays: &[splitray::trace::Ray]) -> Vec<splitray::trace::Ray> {
    rays.iter()
        .enumerate()
        .map(|(i, r)| {
            let d = glam::Vec3::from(r.dir);
            let o = glam::Vec3::from(r.origin);
            match i % 3 {
                0 => splitray::trace::Ray::new(o, d * 1e12, 0.0, f32::INFINITY),
                1 => splitray::trace::Ray::new(o, d * 1e-12, 0.0, f32::INFINITY),
                _ => splitray::trace::Ray::new(o, d, f32::NEG_INFINITY, f32::INFINITY),
            }
        })
        .collect()
}

/// Primary rays through the pixel centres of a `width` × `height` image of `camera`.
pub fn camera_rays(
    camera: &splitray::scene::Camera,
    width: u32,
    height: u32,
) -> Vec<splitray::trace::Ray> {
    let frame = camera.frame(width, height);
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            splitray::trace::Ray::new(
                frame.origin,
                frame.pixel_center_direction(x, y),
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

/// The Cornell box's primary rays at 48 × 48, then 3000 rays from inside its bounds in
/// every direction (every third one ending at t = 100): hits from outside and inside.
pub fn cornell_box_rays_from_outside_and_inside(
    scene: &splitray::scene::Scene,
) -> Vec<splitray::trace::Ray> {
    let mut rays = camera_rays(&scene.camera, 48, 48);
    let b = scene.bounds();
    let u = uniforms(6 * 3000, 7);
    for i in 0..3000 {
        let c = &u[6 * i..];
        let o = b.min
            + (b.max - b.min)
                * glam::Vec3::new(0.1 + 0.8 * c[0], 0.1 + 0.8 * c[1], 0.1 + 0.8 * c[2]);
        let d = (glam::Vec3::new(c[3], c[4], c[5]) - 0.5)
            .try_normalize()
            .unwrap_or(glam::Vec3::X);
        let tmax = if i % 3 == 0 { 100.0 } else { f32::INFINITY };
        rays.push(splitray::trace::Ray::new(o, d, 1e-4, tmax));
    }
    rays
}

/// A 24 × 16 render of `spp` passes of `kind`, seed 7: small enough for every
/// integrator, the options the pass-grouping and checkpoint tests share.
pub fn small_render_options(
    scene: &splitray::scene::Scene,
    kind: splitray::integrator::IntegratorKind,
    spp: u32,
) -> splitray::render::RenderOptions {
    splitray::render::RenderOptions::resolve(
        scene,
        Some(24),
        Some(16),
        Some(spp),
        Some(7),
        Some(kind),
        None,
    )
    .unwrap()
}

/// Uploads `rays`, traces them with `tracer` and reads the hits back.
pub fn trace_hits(
    gpu: &splitray::vk::Gpu,
    tracer: &mut dyn splitray::trace::Tracer,
    rays: &[splitray::trace::Ray],
    query: splitray::trace::Query,
) -> Vec<splitray::trace::Hit> {
    let ray_buf = gpu.upload("rays", rays).unwrap();
    let hit_buf = gpu
        .zeroed::<splitray::trace::Hit>("hits", rays.len())
        .unwrap();
    let done = tracer
        .trace(&ray_buf, &hit_buf, rays.len() as u32, query, &[])
        .unwrap();
    gpu.wait(&done).unwrap();
    hit_buf.read().unwrap()
}

/// Traces `rays` (closest hits) the way a renderer hands them over: they reach their
/// buffer through a copy on another stream, which the tracer must wait for (its `after`
/// point) before reading them. Returns the ray and hit buffers, the hits written.
pub fn trace_after_a_copy(
    gpu: &splitray::vk::Gpu,
    tracer: &mut dyn splitray::trace::Tracer,
    rays: &[splitray::trace::Ray],
) -> (splitray::vk::Buffer, splitray::vk::Buffer) {
    use splitray::vk::{MemoryKind, StreamKind};
    let staging = gpu.upload("rays-staging", rays).unwrap();
    let ray_buf = gpu
        .create_buffer("rays", staging.size(), MemoryKind::Device)
        .unwrap();
    let hit_buf = gpu
        .zeroed::<splitray::trace::Hit>("hits", rays.len())
        .unwrap();
    let mut rec = gpu.recorder(StreamKind::Aux0).unwrap();
    rec.copy(&staging, 0, &ray_buf, 0, staging.size());
    let copied = rec.submit(&[]).unwrap();
    let done = tracer
        .trace(
            &ray_buf,
            &hit_buf,
            rays.len() as u32,
            splitray::trace::Query::ClosestHit,
            &[&copied],
        )
        .unwrap();
    gpu.wait(&done).unwrap();
    (ray_buf, hit_buf)
}

/// Asserts every hit equals the reference (same triangle, t within 1e-5 relative, or
/// 1e-7 absolute nearer than `SAME_HIT_NEAR`: `splitray::trace::cpu::same_hit`).
pub fn assert_same_hits(got: &[splitray::trace::Hit], want: &[splitray::trace::Hit], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}");
    let bad: Vec<_> = got
        .iter()
        .zip(want)
        .enumerate()
        .filter(|(_, (g, w))| !splitray::trace::cpu::same_hit(g, w, 1e-5, false))
        .collect();
    assert!(
        bad.is_empty(),
        "{what}: {} of {} hits differ, first: {:?}",
        bad.len(),
        got.len(),
        &bad[..bad.len().min(4)]
    );
}
