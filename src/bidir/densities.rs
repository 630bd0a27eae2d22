//! The explicit densities of a path made by one technique, read off its two subpaths:
//! the input of the brute-force [`oracle`](super::oracle). Densities inside a subpath
//! come from its vertices (`pdf_fwd`, `pdf_rev`, set by the walks); those that depend on
//! the connection are evaluated here afresh, independently of [`super::connect`].

use glam::Vec3;

use super::camera::PinholeCamera;
use super::lights::Lights;
use super::oracle::PathDensities;
use super::scene::CpuScene;
use super::vertex::{Vertex, VertexKind};
use crate::bsdf::TransportMode;

/// Solid-angle density at surface vertex `v` of sampling towards `to`, arriving from
/// `from` (both unit directions away from `v`).
fn bsdf_pdf(scene: &CpuScene, v: &Vertex, from: Vec3, to: Vec3) -> f64 {
    let bsdf = scene.bsdf(v.material);
    let (wo, wi) = (v.frame.to_local(from), v.frame.to_local(to));
    bsdf.pdf(wo, wi, TransportMode::Radiance) as f64
}

fn unit(from: &Vertex, to: &Vertex) -> Vec3 {
    (to.p - from.p).normalize()
}

/// Area density at `to` of a solid-angle density `pdf` from `from`.
fn area(from: &Vertex, to: &Vertex, pdf: f64) -> f64 {
    from.area_density_at(to, 1.0) as f64 * pdf
}

/// Emission density of light vertex `light` towards `to` (solid angle).
fn emission_pdf(light: &Vertex, to: &Vertex) -> f64 {
    if light.delta {
        return crate::bsdf::sampling::uniform_sphere_pdf() as f64;
    }
    (light.ng.dot(unit(light, to)).max(0.0) * std::f32::consts::FRAC_1_PI) as f64
}

/// The densities of the path `light[..]` + `camera[..].reverse()` (s = `light.len()`,
/// t = `camera.len()` ≥ 1): x₀ = `light[0]`, or for s = 0 the emitter that the camera
/// subpath's last vertex lies on. `light[0]`'s `pdf_fwd` is both its emission and its
/// next-event density (the two distributions agree in splitray).
pub fn path_densities(
    scene: &CpuScene,
    camera_model: &PinholeCamera,
    light: &[Vertex],
    camera: &[Vertex],
) -> PathDensities {
    let (s, t) = (light.len(), camera.len());
    let k = s + t - 1;
    // x_i in light-to-camera order.
    let x: Vec<&Vertex> = light.iter().chain(camera.iter().rev()).collect();
    let mut fwd = vec![0.0f64; k + 1];
    let mut rev = vec![0.0f64; k + 1];
    let mut delta = vec![false; k + 1];
    for i in 0..s {
        fwd[i] = light[i].pdf_fwd as f64;
        rev[i] = light[i].pdf_rev as f64;
        delta[i] = light[i].delta;
    }
    for m in 0..t {
        rev[k - m] = camera[m].pdf_fwd as f64;
        fwd[k - m] = camera[m].pdf_rev as f64;
        delta[k - m] = camera[m].delta;
    }
    // Connection endpoints scatter by the connection, never by a delta lobe.
    if s >= 1 {
        delta[s - 1] = light[s - 1].kind == VertexKind::Light && light[s - 1].delta;
    }
    delta[s.min(k)] = false;
    if s == 0 {
        // The camera subpath ends on an emitter: x₀'s light densities.
        let e = x[0];
        let lights = Lights::new(&scene.tables.lights);
        fwd[0] = lights.pdf_area_of_triangle(e.triangle, scene.triangle_area(e.triangle)) as f64;
        let cos = e.ng.dot(unit(e, x[1])).max(0.0);
        fwd[1] = area(e, x[1], (cos * std::f32::consts::FRAC_1_PI) as f64);
        let direct = fwd[0];
        return PathDensities {
            fwd,
            rev,
            direct,
            delta,
        };
    }
    let (y, z) = (x[s - 1], x[s]);
    // The camera side's densities of y and of the vertex before it.
    rev[s - 1] = if t == 1 {
        let dir = unit(z, y);
        area(z, y, camera_model.pdf_direction(dir) as f64)
    } else {
        area(z, y, bsdf_pdf(scene, z, z.wo, unit(z, y)))
    };
    if s >= 2 {
        rev[s - 2] = area(y, x[s - 2], bsdf_pdf(scene, y, unit(y, z), y.wo));
    }
    // The light side's densities of z and of the vertex after it.
    if t >= 2 {
        fwd[s] = if s == 1 {
            area(y, z, emission_pdf(y, z))
        } else {
            area(y, z, bsdf_pdf(scene, y, y.wo, unit(y, z)))
        };
    }
    if t >= 3 {
        fwd[s + 1] = area(z, x[s + 1], bsdf_pdf(scene, z, unit(z, y), z.wo));
    }
    PathDensities {
        direct: fwd[0],
        fwd,
        rev,
        delta,
    }
}
