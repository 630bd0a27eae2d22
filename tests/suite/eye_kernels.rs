//! The eye integrators' secondary rays (src/integrator/eye.rs) against CPU twins that
//! repeat their kernels step by step on the Cornell box, whose walls and blocks occlude
//! AO and shadow rays and whose open front lets paths escape:
//!
//! - `ao`: `ao_rays.comp` (offset point, basis, cosine directions, random dimensions) and
//!   `shade_ao.comp`, each AO ray tested by `cpu::occluded`;
//! - `shadow`: `shadow_rays.comp` and `shade_shadow.comp` with a point light that the
//!   blocks hide from part of the floor;
//! - the normal AOV of `write_aovs.comp`, on a box with half its triangles wound the
//!   other way so that turning the normal to the viewer matters;
//! - `path`: every bounce of `path_bounce.comp`, misses and escapes included.
//!
//! The GPU traces its camera rays with its own tracer: a ray through a shared edge may
//! take the neighbouring triangle, and a secondary ray that grazes an edge may part from
//! its twin after a rounding difference in sin or cos. Such pixels must stay rare (1 in
//! 100 at most); every other pixel must equal its twin.

use crate::common;
use crate::render::options;

use glam::Vec3;
use splitray::bench::workloads::primary_rays;
use splitray::bidir::random::{fold_seed, random01};
use splitray::integrator::IntegratorKind;
use splitray::render::{render, shadow_light, RenderOutput};
use splitray::scene::{self, PointLight, Scene};
use splitray::trace::{cpu, GpuTriangle, Hit, Ray};

const SIDE: u32 = 32;

/// A render of `scene` at SIDE × SIDE, one sample per pixel (through the pixel centres,
/// as the twins' rays go).
fn render_one_sample(scene: &Scene, integrator: IntegratorKind) -> RenderOutput {
    let gpu = common::gpu();
    let out = render(
        &gpu,
        scene,
        &options(scene, SIDE, SIDE, 1, integrator),
        &mut |_| {},
    )
    .unwrap();
    common::assert_clean(&gpu);
    out
}

/// What the kernels know of a scene, and the camera rays and hits of the twin.
struct Twin {
    scene: Scene,
    triangles: Vec<GpuTriangle>,
    rays: Vec<Ray>,
    hits: Vec<Hit>,
    ray_epsilon: f32,
    /// The folded seed of `options`' renders.
    seed: u32,
}

impl Twin {
    fn new(scene: Scene) -> Self {
        let triangles = scene.gpu_triangles();
        let rays = primary_rays(&scene, SIDE, SIDE);
        let hits = cpu::closest_hits(&rays, &triangles);
        let seed = fold_seed(options(&scene, SIDE, SIDE, 1, IntegratorKind::Ao).seed);
        Self {
            ray_epsilon: scene.bounds().ray_epsilon([scene.camera.position]),
            scene,
            triangles,
            rays,
            hits,
            seed,
        }
    }

    /// The kernels' surface point of a hit: the unit geometric normal
    /// normalize(e1 × e2) turned against the ray, and the hit point moved ray_epsilon
    /// along it.
    fn surface(&self, ray: &Ray, hit: &Hit) -> (Vec3, Vec3) {
        let d = Vec3::from(ray.dir);
        let mut n = self.triangles[hit.triangle as usize].normal().normalize();
        if n.dot(d) > 0.0 {
            n = -n;
        }
        (Vec3::from(ray.origin) + hit.t * d + self.ray_epsilon * n, n)
    }

    fn material(&self, triangle: u32) -> &scene::Material {
        &self.scene.materials[self.scene.triangles[triangle as usize].material as usize]
    }
}

/// The orthonormal basis of ao_rays.comp and path_bounce.comp (Duff et al. 2017). Not
/// glam's `any_orthonormal_pair`: that takes the sign of −0 as −1, the kernels as +1,
/// and the Cornell box's walls have normals with z = ±0.
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let c = n.x * n.y * a;
    (
        Vec3::new(1.0 + s * n.x * n.x * a, s * c, -s * n.x),
        Vec3::new(c, s + n.y * n.y * a, -n.y),
    )
}

/// The kernels' cosine-weighted direction about `n` (Malley's method) from u1, u2.
fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, b) = basis(n);
    let r = u1.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    (r * phi.cos() * t + r * phi.sin() * b + (1.0 - u1).max(0.0).sqrt() * n).normalize()
}

/// Asserts that at least 99 in 100 pixels agree.
fn assert_most_agree(what: &str, agree: usize) {
    let pixels = (SIDE * SIDE) as usize;
    assert!(
        agree * 100 >= pixels * 99,
        "{what}: {agree} of {pixels} pixels equal the twin's"
    );
}

#[test]
fn ambient_occlusion_in_the_cornell_box_matches_its_twin() {
    let scene = scene::load("cornell-box").unwrap();
    let opts = options(&scene, SIDE, SIDE, 1, IntegratorKind::Ao);
    let out = render_one_sample(&scene, IntegratorKind::Ao);
    let twin = Twin::new(scene);
    // EyeOptions' default reach: a quarter of the scene's radius.
    let reach = 0.25 * twin.scene.bounds().radius();
    let (mut agree, mut partial) = (0, 0);
    for (pixel, (ray, hit)) in twin.rays.iter().zip(&twin.hits).enumerate() {
        let expected = if hit.is_hit() {
            let (p, n) = twin.surface(ray, hit);
            let open = (0..opts.ao_rays)
                .filter(|k| {
                    let dim = 2 + 2 * k;
                    let u1 = random01(pixel as u32, 0, dim, twin.seed);
                    let u2 = random01(pixel as u32, 0, dim + 1, twin.seed);
                    let ao = Ray::new(p, cosine_direction(n, u1, u2), 0.0, reach);
                    !cpu::occluded(&ao, &twin.triangles)
                })
                .count();
            open as f32 / opts.ao_rays as f32
        } else {
            0.0
        };
        let got = out.film.mean_rgb(pixel);
        assert_eq!(got, [got[0]; 3], "pixel {pixel}: AO is grey");
        agree += (got[0] == expected) as usize;
        partial += (expected > 0.0 && expected < 1.0) as usize;
    }
    assert_most_agree("ao", agree);
    // Corners and the blocks' feet are partly occluded: a hemisphere turned into the
    // surface, or an occlusion test that never fires, could not match these.
    assert!(partial > 100, "only {partial} partly occluded pixels");
}

#[test]
fn shadow_integrator_matches_its_twin_where_the_blocks_shadow_the_floor() {
    let mut scene = scene::load("cornell-box").unwrap();
    // Low by the red wall, little above the short block's top (165): both blocks throw
    // long shadows across the floor towards the green wall.
    scene.point_lights = vec![PointLight {
        position: Vec3::new(540.0, 200.0, 150.0),
        intensity: Vec3::splat(5.0e4),
    }];
    let out = render_one_sample(&scene, IntegratorKind::Shadow);
    let light = shadow_light(&scene);
    let twin = Twin::new(scene);
    let floor = 0..2u32;
    let (mut agree, mut floor_shadowed, mut floor_seen) = (0, 0, 0);
    for (pixel, (ray, hit)) in twin.rays.iter().zip(&twin.hits).enumerate() {
        let got = Vec3::from(out.film.mean_rgb(pixel));
        if !hit.is_hit() {
            agree += (got == Vec3::ZERO) as usize;
            continue;
        }
        // shadow_rays.comp: the lit value waits while the shadow ray is traced.
        let (p, n) = twin.surface(ray, hit);
        let to_light = light.truncate() - p;
        let d2 = to_light.length_squared().max(1e-12);
        let l = to_light * (1.0 / d2.sqrt());
        let cos_l = n.dot(l);
        let m = twin.material(hit.triangle);
        let lit = if cos_l > 0.0 {
            m.diffuse * std::f32::consts::FRAC_1_PI * light.w * cos_l / d2
        } else {
            Vec3::ZERO
        };
        let reach = if cos_l > 0.0 {
            d2.sqrt() * (1.0 - 1e-4)
        } else {
            0.0
        };
        let shadowed = reach > 0.0 && cpu::occluded(&Ray::new(p, l, 0.0, reach), &twin.triangles);
        let expected = m.emission + if shadowed { Vec3::ZERO } else { lit };
        if (got - expected).abs().max_element() <= 1e-5 * expected.max_element() {
            agree += 1;
        }
        floor_shadowed += (shadowed && floor.contains(&hit.triangle)) as usize;
        floor_seen += floor.contains(&hit.triangle) as usize;
    }
    assert_most_agree("shadow", agree);
    // The floor fills only the bottom rows of the image (some 90 pixels at 32 × 32).
    assert!(
        floor_shadowed * 10 >= floor_seen && floor_shadowed < floor_seen,
        "{floor_shadowed} of {floor_seen} floor pixels in shadow"
    );
}

#[test]
fn normal_aov_is_the_hit_triangles_normal_facing_the_viewer() {
    let mut scene = scene::load("cornell-box").unwrap();
    // Every other triangle wound the other way: its normal e1 × e2 faces away from the
    // camera, and the AOV must turn it round.
    for t in scene.triangles.iter_mut().skip(1).step_by(2) {
        t.p.swap(1, 2);
    }
    let out = render_one_sample(&scene, IntegratorKind::Primary);
    let twin = Twin::new(scene);
    let ids = out.film.triangle_id.as_ref().unwrap();
    let normals = out.film.normal.as_ref().unwrap();
    let (mut same_triangle, mut turned) = (0, 0);
    for (pixel, (ray, hit)) in twin.rays.iter().zip(&twin.hits).enumerate() {
        if ids[pixel] != hit.triangle {
            continue;
        }
        same_triangle += 1;
        let got = Vec3::from(normals[pixel]);
        if !hit.is_hit() {
            assert_eq!(got, Vec3::ZERO, "pixel {pixel} missed");
            continue;
        }
        let (_, expected) = twin.surface(ray, hit);
        assert!(
            (got - expected).abs().max_element() <= 1e-5,
            "pixel {pixel}: normal {got} vs {expected}"
        );
        turned += (twin.triangles[hit.triangle as usize].normal().dot(expected) < 0.0) as usize;
    }
    // As in render.rs: only a ray through a shared edge may take the other triangle.
    assert!(
        same_triangle * 1000 >= ids.len() * 999,
        "{same_triangle} of {} triangle ids match",
        ids.len()
    );
    assert!(turned > 100, "only {turned} normals were turned round");
}

#[test]
fn path_integrator_matches_its_twin_as_paths_escape_the_open_box() {
    let scene = scene::load("cornell-box").unwrap();
    let out = render_one_sample(&scene, IntegratorKind::Path);
    let twin = Twin::new(scene);
    // path_bounce.comp's MAX_BOUNCES: bounces after the camera hit.
    const BOUNCES: u32 = 7;
    let (mut agree, mut escaped, mut lit) = (0, 0, 0);
    for (pixel, (camera_ray, camera_hit)) in twin.rays.iter().zip(&twin.hits).enumerate() {
        let mut radiance = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        let (mut ray, mut hit) = (*camera_ray, *camera_hit);
        for bounce in 0..=BOUNCES {
            if !hit.is_hit() {
                // A path ends at its first miss: it adds nothing more.
                escaped += (bounce > 0) as usize;
                break;
            }
            let m = twin.material(hit.triangle);
            radiance += throughput * m.emission;
            throughput *= m.diffuse;
            if bounce == BOUNCES || throughput.max_element() == 0.0 {
                break;
            }
            let (p, n) = twin.surface(&ray, &hit);
            let dim = 2 + 2 * bounce;
            let u1 = random01(pixel as u32, 0, dim, twin.seed);
            let u2 = random01(pixel as u32, 0, dim + 1, twin.seed);
            ray = Ray::new(p, cosine_direction(n, u1, u2), 0.0, f32::INFINITY);
            hit = cpu::closest_hit(&ray, &twin.triangles);
        }
        // Every pixel counts its one sample once, at the camera hit or miss.
        assert_eq!(out.film.weight(pixel), 1.0, "pixel {pixel}: sample weight");
        let got = Vec3::from(out.film.mean_rgb(pixel));
        if (got - radiance).abs().max_element() <= 1e-5 * radiance.max_element() {
            agree += 1;
        }
        lit += (radiance.max_element() > 0.0) as usize;
    }
    assert_most_agree("path", agree);
    assert!(escaped > 200, "only {escaped} paths left the box");
    // Emission-only paths at one sample per pixel: few find the light, and those carry
    // every bounce's albedo to compare.
    assert!(lit > 20, "only {lit} paths reached the light");
}
