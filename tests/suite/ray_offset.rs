//! Rays leave surfaces by an offset that follows float rounding, not the scene's extent
//! (`Aabb::ray_epsilon`): a unit cube standing on a ground plane 2·10⁴ wide casts its
//! shadow. An offset of a fixed fraction of the scene's radius (1e-4 of it is 1.4 here)
//! would start the floor's shadow rays above the cube, and the cube would cast none.

use crate::common;
use crate::render::options;

use glam::{DVec3, Vec3};
use splitray::bench::workloads::primary_rays;
use splitray::integrator::IntegratorKind;
use splitray::render::render;
use splitray::scene::{Camera, FilmSize, Material, PointLight, RenderSettings, Scene, Triangle};
use splitray::trace::cpu;

const SIDE: u32 = 32;
/// Half the ground plane's width.
const GROUND: f32 = 1e4;
const LIGHT: Vec3 = Vec3::new(2.0, 1.5, 0.5);

/// Two triangles of the quad a b c d (counter-clockwise seen from its front).
fn quad([a, b, c, d]: [Vec3; 4]) -> [Triangle; 2] {
    [Triangle::new(a, b, c, 0), Triangle::new(a, c, d, 0)]
}

/// The unit cube [-½, ½] × [0, 1] × [-½, ½] on the plane y = 0, lit by a point light low
/// beside it, seen from above the other side.
fn cube_on_a_wide_plane() -> Scene {
    let g = GROUND;
    let c = |x: f32, y: f32, z: f32| Vec3::new(x - 0.5, y, z - 0.5);
    let faces = [
        [
            Vec3::new(-g, 0.0, -g),
            Vec3::new(-g, 0.0, g),
            Vec3::new(g, 0.0, g),
            Vec3::new(g, 0.0, -g),
        ],
        [c(0., 1., 0.), c(0., 1., 1.), c(1., 1., 1.), c(1., 1., 0.)],
        [c(0., 0., 0.), c(0., 1., 0.), c(1., 1., 0.), c(1., 0., 0.)],
        [c(0., 0., 1.), c(1., 0., 1.), c(1., 1., 1.), c(0., 1., 1.)],
        [c(0., 0., 0.), c(0., 0., 1.), c(0., 1., 1.), c(0., 1., 0.)],
        [c(1., 0., 0.), c(1., 1., 0.), c(1., 1., 1.), c(1., 0., 1.)],
    ];
    Scene {
        name: "cube-on-a-wide-plane".into(),
        camera: Camera {
            position: Vec3::new(-2.5, 2.5, -3.0),
            look_at: Vec3::new(-0.3, 0.2, 0.3),
            up: Vec3::Y,
            fov_y: 60.0,
        },
        film: FilmSize {
            width: SIDE,
            height: SIDE,
        },
        triangles: faces.into_iter().flat_map(quad).collect(),
        materials: vec![Material {
            diffuse: Vec3::splat(0.7),
            ..Material::named("white")
        }],
        point_lights: vec![PointLight {
            position: LIGHT,
            intensity: Vec3::splat(10.0),
        }],
        settings: RenderSettings::default(),
    }
}

/// Whether the segment from `p` to the light passes through the cube grown by `grow` on
/// every side (slabs, in f64, with no offset).
fn segment_meets_cube(p: DVec3, grow: f64) -> bool {
    let (lo, hi) = (
        DVec3::new(-0.5, 0.0, -0.5) - grow,
        DVec3::new(0.5, 1.0, 0.5) + grow,
    );
    let d = LIGHT.as_dvec3() - p;
    let (mut enter, mut leave) = (0.0f64, 1.0f64);
    for axis in 0..3 {
        let (a, b) = (
            (lo[axis] - p[axis]) / d[axis],
            (hi[axis] - p[axis]) / d[axis],
        );
        enter = enter.max(a.min(b));
        leave = leave.min(a.max(b));
    }
    enter < leave
}

/// The floor pixels (the plane's two triangles hit through the pixel centre, as the
/// CPU traces it) that are clearly in the cube's shadow (`true`) or clearly lit:
/// pixels whose segment to the light passes within 0.02 of the cube's surface are left
/// out.
fn floor_pixels(scene: &Scene) -> Vec<(usize, bool)> {
    let rays = primary_rays(scene, SIDE, SIDE);
    let hits = cpu::closest_hits(&rays, &scene.gpu_triangles());
    let mut pixels = Vec::new();
    for (pixel, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
        if !hit.is_hit() || hit.triangle >= 2 {
            continue;
        }
        let p = Vec3::from(ray.origin).as_dvec3() + hit.t as f64 * Vec3::from(ray.dir).as_dvec3();
        let p = DVec3::new(p.x, 0.0, p.z);
        let (inner, outer) = (segment_meets_cube(p, -0.02), segment_meets_cube(p, 0.02));
        if inner == outer {
            pixels.push((pixel, inner));
        }
    }
    pixels
}

/// A pixel's brightness: the mean of its channels.
fn brightness(film: &splitray::film::Film, pixel: usize) -> f32 {
    film.mean_rgb(pixel).iter().sum::<f32>() / 3.0
}

#[test]
fn a_cube_on_a_wide_plane_casts_its_shadow() {
    let scene = cube_on_a_wide_plane();
    let pixels = floor_pixels(&scene);
    let shadowed = pixels.iter().filter(|(_, s)| *s).count();
    let lit = pixels.len() - shadowed;
    assert!(
        shadowed >= 20 && lit >= 100,
        "{shadowed} shadowed, {lit} lit floor pixels"
    );
    let gpu = common::gpu();

    // `shadow`: direct light from the point light alone, so a shadowed floor is black.
    let out = render(
        &gpu,
        &scene,
        &options(&scene, SIDE, SIDE, 1, IntegratorKind::Shadow),
        &mut |_| {},
    )
    .unwrap();
    for &(pixel, in_shadow) in &pixels {
        let b = brightness(&out.film, pixel);
        assert_eq!(
            b == 0.0,
            in_shadow,
            "shadow: floor pixel {pixel} of brightness {b}"
        );
    }

    // The light transport integrators: the shadow holds only light that the floor and the
    // cube pass on, a small fraction of the direct light beside it.
    for integrator in [
        IntegratorKind::Pt,
        IntegratorKind::Bpt,
        IntegratorKind::LvcBdpt,
        IntegratorKind::Cbpt,
    ] {
        let out = render(
            &gpu,
            &scene,
            &options(&scene, SIDE, SIDE, 8, integrator),
            &mut |_| {},
        )
        .unwrap();
        let mean = |want: bool| {
            let chosen: Vec<f32> = pixels
                .iter()
                .filter(|(_, s)| *s == want)
                .map(|&(p, _)| brightness(&out.film, p))
                .collect();
            chosen.iter().sum::<f32>() / chosen.len() as f32
        };
        let (dark, bright) = (mean(true), mean(false));
        assert!(
            dark < 0.25 * bright,
            "{integrator}: shadowed floor {dark}, lit floor {bright}"
        );
    }
    common::assert_clean(&gpu);
}
