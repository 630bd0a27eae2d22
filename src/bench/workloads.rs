//! The ray workloads of the PDACRT paper's Tables 1–2, generated deterministically on the
//! host from a scene: primary rays, shadow rays to one point light, one perfect-mirror
//! bounce, 8 ambient-occlusion rays per hit, and 7-bounce diffuse paths.

use std::fmt;
use std::str::FromStr;

use glam::Vec3;
use serde::Serialize;

use crate::scene::Scene;
use crate::trace::{GpuTriangle, Hit, Query, Ray};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Workload {
    Primary,
    Shadow,
    Reflection,
    Ao,
    Path,
}

impl Workload {
    pub const ALL: [Workload; 5] = [
        Self::Primary,
        Self::Shadow,
        Self::Reflection,
        Self::Ao,
        Self::Path,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary",
            Self::Shadow => "shadow",
            Self::Reflection => "reflection",
            Self::Ao => "ao",
            Self::Path => "path",
        }
    }
}

impl fmt::Display for Workload {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Workload {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|w| w.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown workload '{s}' (choose one of: primary, shadow, reflection, ao, path)"
                )
            })
    }
}

/// One batch of rays and the query it needs.
pub struct RayBatch {
    pub label: String,
    pub rays: Vec<Ray>,
    pub query: Query,
}

/// Ambient-occlusion rays per primary hit (the paper's Table 2).
pub const AO_RAYS: usize = 8;
/// Diffuse bounces of the path workload (the paper's §3.1).
pub const PATH_BOUNCES: usize = 7;

/// Primary rays through the pixel centres, row 0 first.
pub fn primary_rays(scene: &Scene, width: u32, height: u32) -> Vec<Ray> {
    let frame = scene.camera.frame(width, height);
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            Ray::new(
                frame.origin,
                frame.pixel_center_direction(x, y),
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

/// Counter-based uniform numbers in [0, 1), as in glsl/common/random.glsl.
fn random01(a: u32, b: u32, c: u32) -> f32 {
    fn pcg(v: u32) -> u32 {
        let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
        (word >> 22) ^ word
    }
    (pcg(a ^ pcg(b ^ pcg(c))) >> 8) as f32 / 16_777_216.0
}

/// A surface point a secondary ray starts from: the hit point nudged off the surface to
/// the side the ray came from, and the normal on that side.
struct SurfacePoint {
    p: Vec3,
    n: Vec3,
    incoming: Vec3,
}

fn surface_points(
    rays: &[Ray],
    hits: &[Hit],
    triangles: &[GpuTriangle],
    eps: f32,
) -> Vec<(usize, SurfacePoint)> {
    rays.iter()
        .zip(hits)
        .enumerate()
        .filter(|(_, (_, h))| h.is_hit())
        .map(|(i, (r, h))| {
            let d = Vec3::from(r.dir);
            let mut n = triangles[h.triangle as usize].normal().normalize_or_zero();
            if n.dot(d) > 0.0 {
                n = -n;
            }
            let p = Vec3::from(r.origin) + h.t * d + eps * n;
            (i, SurfacePoint { p, n, incoming: d })
        })
        .collect()
}

fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    (r * phi.cos() * t + r * phi.sin() * b + (1.0 - u1).max(0.0).sqrt() * n).normalize()
}

/// The point light of the shadow workload: the scene's first, else one inside the top of
/// the scene box (so a closed room such as the Cornell box is lit from within).
pub fn shadow_light(scene: &Scene) -> Vec3 {
    scene
        .point_lights
        .first()
        .map(|l| l.position)
        .unwrap_or_else(|| {
            let b = scene.bounds();
            b.center() + Vec3::new(0.1, 0.45, 0.1) * b.extent()
        })
}

/// Secondary batches derived from the primary hits. `trace` casts a batch of
/// closest-hit rays (used for the bounces of the path workload).
pub fn secondary_batches(
    workload: Workload,
    scene: &Scene,
    triangles: &[GpuTriangle],
    primary: &[Ray],
    primary_hits: &[Hit],
    trace: &mut dyn FnMut(&[Ray]) -> Vec<Hit>,
) -> Vec<RayBatch> {
    let radius = scene.bounds().radius().max(1e-6);
    // The integrators' offset, so that `bench` casts the rays they would.
    let eps = scene.bounds().ray_epsilon([scene.camera.position]);
    let points = surface_points(primary, primary_hits, triangles, eps);
    match workload {
        Workload::Primary => vec![],
        Workload::Shadow => one_batch(
            "shadow",
            shadow_rays(shadow_light(scene), &points),
            Query::Occlusion,
        ),
        Workload::Reflection => {
            one_batch("reflection", reflection_rays(&points), Query::ClosestHit)
        }
        Workload::Ao => one_batch("ao", ao_rays(0.25 * radius, &points), Query::Occlusion),
        Workload::Path => path_batches(points, triangles, eps, trace),
    }
}

/// A workload of one batch.
fn one_batch(label: &str, rays: Vec<Ray>, query: Query) -> Vec<RayBatch> {
    vec![RayBatch {
        label: label.into(),
        rays,
        query,
    }]
}

/// From each point to the light, stopping just short of it.
fn shadow_rays(light: Vec3, points: &[(usize, SurfacePoint)]) -> Vec<Ray> {
    points
        .iter()
        .map(|(_, s)| {
            let to = light - s.p;
            let dist = to.length();
            Ray::new(s.p, to / dist, 0.0, dist * (1.0 - 1e-4))
        })
        .collect()
}

/// The perfect mirror's direction at each point.
fn reflection_rays(points: &[(usize, SurfacePoint)]) -> Vec<Ray> {
    points
        .iter()
        .map(|(_, s)| {
            Ray::new(
                s.p,
                s.incoming - 2.0 * s.incoming.dot(s.n) * s.n,
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

/// [`AO_RAYS`] cosine-distributed rays of length `reach` from each point.
fn ao_rays(reach: f32, points: &[(usize, SurfacePoint)]) -> Vec<Ray> {
    points
        .iter()
        .flat_map(|(i, s)| {
            (0..AO_RAYS).map(move |k| {
                let d = cosine_direction(
                    s.n,
                    random01(*i as u32, 2 * k as u32, 1),
                    random01(*i as u32, 2 * k as u32 + 1, 1),
                );
                Ray::new(s.p, d, 0.0, reach)
            })
        })
        .collect()
}

/// The diffuse bounces of the path workload, one batch each, from the primary hits'
/// `points` until [`PATH_BOUNCES`] or until every path has left the scene.
fn path_batches(
    points: Vec<(usize, SurfacePoint)>,
    triangles: &[GpuTriangle],
    eps: f32,
    trace: &mut dyn FnMut(&[Ray]) -> Vec<Hit>,
) -> Vec<RayBatch> {
    let mut batches = Vec::new();
    let mut current = points;
    for bounce in 1..PATH_BOUNCES {
        let rays = diffuse_rays(bounce, &current);
        if rays.is_empty() {
            break;
        }
        let hits = trace(&rays);
        let next = surface_points(&rays, &hits, triangles, eps);
        batches.push(RayBatch {
            label: format!("bounce {bounce}"),
            rays,
            query: Query::ClosestHit,
        });
        current = next;
    }
    batches
}

/// Bounce `bounce`'s cosine-distributed rays from each point.
fn diffuse_rays(bounce: usize, points: &[(usize, SurfacePoint)]) -> Vec<Ray> {
    points
        .iter()
        .map(|(i, s)| {
            let d = cosine_direction(
                s.n,
                random01(*i as u32, bounce as u32, 2),
                random01(*i as u32, bounce as u32, 3),
            );
            Ray::new(s.p, d, 0.0, f32::INFINITY)
        })
        .collect()
}
