//! `lamps`: a room lit by three hanging lamps whose lights sit deep inside their shades,
//! in the spirit of the thesis's test scenes (ch. 4, Fig. 4.5–4.6: Monkeybox, Whiteroom,
//! Bedroom, whose "lights [sit] inside deep fixtures" and whose materials are layered).
//!
//! Metres, 640×480 film. The room is x ∈ [−3, 3], y ∈ [0, 2.8], z ∈ [−3, 3], every wall
//! facing in. Three lamps hang from the ceiling on thin rods at (x, z) = (−1.6, 1.0),
//! (0, 1.8) and (1.6, 1.0): each shade is a frustum open at the bottom (radius 0.12 at
//! its closed top, y = 2.2, to 0.3 at its rim, y = 1.85), a brass-coloured conductor
//! outside and a white diffuse shell 5 mm inside it. The only lights are discs of radius
//! 0.1 at y = 2.15 inside each shade, facing down, 0.3 m above the rim: no light leaves a
//! lamp except downwards through its opening, and the ceiling and the upper walls are lit
//! only by light that bounced off the floor, the furniture or the inside of a shade.
//!
//! Procedural objects with interpolated shading normals:
//! - a vase on a table (a lathe surface, 48 × 24 quads), glazed ceramic (plastic coat
//!   over blue diffuse);
//! - a torus on the floor (48 × 24 quads), rough gold conductor;
//! - a sphere on the floor (an icosahedron subdivided three times, 1280 facets), three
//!   layers: red plastic (diffuse + GGX coat) with a mirror layer;
//! - the table: a top and four legs (boxes), varnished wood (plastic).
//!
//! Materials (one emissive, as in every built-in scene): plaster walls (Lambert), an
//! Oren–Nayar terracotta wall, a varnished floor (plastic), the brass shade (conductor),
//! the shade's inside (Lambert), the lamp discs (emitter), the table, the vase, the torus
//! and the sphere. The camera stands near the front wall at eye height and looks across
//! the room at the lamps; it never sees a light directly.

use std::f32::consts::{PI, TAU};

use glam::Vec3;

use super::{box_face, quad, v, Facing};
use crate::scene::{
    shapes, BsdfKind, Camera, FilmSize, Material, MaterialBsdf, MaterialLayer, MicrofacetModel,
    RenderSettings, Scene, Triangle,
};

/// The lamps' (x, z) positions under the ceiling.
pub const LAMP_POSITIONS: [[f32; 2]; 3] = [[-1.6, 1.0], [0.0, 1.8], [1.6, 1.0]];
/// Height of the light discs, of the shades' closed tops and of their rims.
pub const LIGHT_Y: f32 = 2.15;
const SHADE_TOP_Y: f32 = 2.2;
pub const SHADE_RIM_Y: f32 = 1.85;
const SHADE_TOP_RADIUS: f32 = 0.12;
pub const SHADE_RIM_RADIUS: f32 = 0.3;
const LIGHT_RADIUS: f32 = 0.1;
const CEILING_Y: f32 = 2.8;

/// Indices into the material list of [`lamps`].
mod m {
    pub const PLASTER: u32 = 0;
    pub const TERRACOTTA: u32 = 1;
    pub const FLOOR: u32 = 2;
    pub const BRASS: u32 = 3;
    pub const SHADE_INSIDE: u32 = 4;
    pub const LIGHT: u32 = 5;
    pub const TABLE: u32 = 6;
    pub const VASE: u32 = 7;
    pub const GOLD: u32 = 8;
    pub const SPHERE: u32 = 9;
}

fn layer(kind: BsdfKind, reflectance: Vec3, roughness: f32, weight: f32) -> MaterialLayer {
    MaterialLayer {
        kind,
        reflectance,
        roughness,
        distribution: MicrofacetModel::Ggx,
        ior: 1.5,
        weight,
    }
}

fn explicit(name: &str, layers: Vec<MaterialLayer>) -> Material {
    Material {
        bsdf: Some(MaterialBsdf { layers }),
        ..Material::named(name)
    }
}

fn materials() -> Vec<Material> {
    use BsdfKind::*;
    vec![
        explicit(
            "plaster",
            vec![layer(Lambert, v(0.75, 0.73, 0.7), 0.0, 1.0)],
        ),
        explicit(
            "terracotta",
            vec![layer(OrenNayar, v(0.62, 0.33, 0.22), 0.5, 1.0)],
        ),
        explicit(
            "floor",
            vec![layer(Plastic, v(0.42, 0.27, 0.15), 0.12, 1.0)],
        ),
        explicit(
            "brass",
            vec![layer(Conductor, v(0.91, 0.78, 0.42), 0.3, 1.0)],
        ),
        explicit(
            "shade-inside",
            vec![layer(Lambert, v(0.85, 0.85, 0.8), 0.0, 1.0)],
        ),
        Material {
            diffuse: Vec3::ZERO,
            emission: v(120.0, 100.0, 75.0),
            ..Material::named("lamp")
        },
        explicit("table", vec![layer(Plastic, v(0.3, 0.17, 0.09), 0.25, 1.0)]),
        explicit("vase", vec![layer(Plastic, v(0.1, 0.22, 0.55), 0.05, 1.0)]),
        explicit("gold", vec![layer(Conductor, v(1.0, 0.78, 0.34), 0.2, 1.0)]),
        explicit(
            "sphere",
            vec![
                layer(Plastic, v(0.7, 0.12, 0.1), 0.3, 0.75),
                layer(Mirror, v(0.9, 0.9, 0.9), 0.0, 0.25),
            ],
        ),
    ]
}

/// The room's six walls, facing in; the wall at x = −3 is terracotta.
fn room(out: &mut Vec<Triangle>) {
    let (lo, hi) = (v(-3.0, 0.0, -3.0), v(3.0, CEILING_Y, 3.0));
    let centre = (lo + hi) * 0.5;
    for axis in 0..3 {
        for high in [false, true] {
            let material = match (axis, high) {
                (0, false) => m::TERRACOTTA,
                (1, false) => m::FLOOR,
                _ => m::PLASTER,
            };
            quad(
                out,
                box_face(lo, hi, axis, high),
                material,
                Facing::Toward(centre),
            );
        }
    }
}

/// A closed box [lo, hi], faces pointing out.
fn cuboid(out: &mut Vec<Triangle>, lo: Vec3, hi: Vec3, material: u32) {
    let centre = (lo + hi) * 0.5;
    for axis in 0..3 {
        for high in [false, true] {
            quad(
                out,
                box_face(lo, hi, axis, high),
                material,
                Facing::AwayFrom(centre),
            );
        }
    }
}

/// A triangle with shading normals.
fn smooth(p: [Vec3; 3], n: [Vec3; 3], material: u32) -> Triangle {
    Triangle {
        n: Some(n),
        ..Triangle::new(p[0], p[1], p[2], material)
    }
}

/// A quad grid over (u, w) ∈ [0, 1]² of `nu` × `nw` cells, each split in two triangles
/// wound so that the geometric normal agrees with `surface`'s normal at the cell
/// centre; `surface` returns a point and its unit normal.
fn grid(
    out: &mut Vec<Triangle>,
    nu: usize,
    nw: usize,
    material: u32,
    surface: impl Fn(f32, f32) -> (Vec3, Vec3),
) {
    let at = |i: usize, j: usize| surface(i as f32 / nu as f32, j as f32 / nw as f32);
    for i in 0..nu {
        for j in 0..nw {
            let corners = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            let (_, n_mid) = surface((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nw as f32);
            for [a, b, c] in [[0, 1, 2], [0, 2, 3]] {
                let (pa, pb, pc) = (corners[a], corners[b], corners[c]);
                let mut t = smooth([pa.0, pb.0, pc.0], [pa.1, pb.1, pc.1], material);
                if t.is_degenerate() {
                    continue;
                }
                if t.geometric_normal().dot(n_mid) < 0.0 {
                    t = smooth([pa.0, pc.0, pb.0], [pa.1, pc.1, pb.1], material);
                }
                out.push(t);
            }
        }
    }
}

/// A surface of revolution about the vertical axis through `base`: `profile(s)` gives
/// (radius, height) for s ∈ [0, 1], normals face away from the axis.
fn lathe(
    out: &mut Vec<Triangle>,
    base: Vec3,
    segments: usize,
    rings: usize,
    material: u32,
    profile: impl Fn(f32) -> (f32, f32),
) {
    grid(out, segments, rings, material, |u, s| {
        let phi = TAU * u;
        let (r, y) = profile(s);
        let ds = 1e-3;
        let (r0, y0) = profile((s - ds).max(0.0));
        let (r1, y1) = profile((s + ds).min(1.0));
        // The profile's outward normal in the (r, y) plane: its tangent turned by −90°.
        let (tr, ty) = (r1 - r0, y1 - y0);
        let radial = Vec3::new(phi.cos(), 0.0, phi.sin());
        let n = (radial * ty - Vec3::Y * tr).normalize_or_zero();
        (base + radial * r + Vec3::Y * y, n)
    });
}

fn torus(out: &mut Vec<Triangle>, centre: Vec3, major: f32, minor: f32, material: u32) {
    grid(out, 48, 24, material, |u, w| {
        let (phi, theta) = (TAU * u, TAU * w);
        let radial = Vec3::new(phi.cos(), 0.0, phi.sin());
        let n = radial * theta.cos() + Vec3::Y * theta.sin();
        (centre + radial * major + n * minor, n)
    });
}

/// An icosphere ([`shapes::icosphere`]) of `radius` about `centre`, smooth-shaded with
/// the sphere's normals.
fn icosphere(out: &mut Vec<Triangle>, centre: Vec3, radius: f32, levels: u32, material: u32) {
    for [a, b, c] in shapes::icosphere(levels) {
        let p = [a, b, c].map(|n| centre + n * radius);
        out.push(smooth(p, [a, b, c], material));
    }
}

/// A flat horizontal disc of 24 triangles at `centre`, facing up (+y) or down.
fn disc(out: &mut Vec<Triangle>, centre: Vec3, radius: f32, facing_up: bool, material: u32) {
    let segments = 24;
    for k in 0..segments {
        let (a0, a1) = (
            TAU * k as f32 / segments as f32,
            TAU * (k + 1) as f32 / segments as f32,
        );
        let p0 = centre + Vec3::new(a0.cos(), 0.0, a0.sin()) * radius;
        let p1 = centre + Vec3::new(a1.cos(), 0.0, a1.sin()) * radius;
        let t = Triangle::new(centre, p0, p1, material);
        let up = t.geometric_normal().y > 0.0;
        out.push(if up == facing_up {
            t
        } else {
            Triangle::new(centre, p1, p0, material)
        });
    }
}

/// One lamp: rod, shade (brass outside, white inside, closed top) and the light disc.
fn lamp(out: &mut Vec<Triangle>, x: f32, z: f32) {
    let rod = 0.01;
    cuboid(
        out,
        v(x - rod, SHADE_TOP_Y, z - rod),
        v(x + rod, CEILING_Y, z + rod),
        m::BRASS,
    );
    let height = SHADE_TOP_Y - SHADE_RIM_Y;
    let frustum = |inset: f32| {
        move |s: f32| {
            let r = SHADE_RIM_RADIUS + (SHADE_TOP_RADIUS - SHADE_RIM_RADIUS) * s - inset;
            (r, height * s)
        }
    };
    let base = v(x, SHADE_RIM_Y, z);
    lathe(out, base, 32, 4, m::BRASS, frustum(0.0));
    // The inside: the same frustum 5 mm in, its normals turned towards the axis.
    let start = out.len();
    lathe(out, base, 32, 4, m::SHADE_INSIDE, frustum(0.005));
    for t in &mut out[start..] {
        t.p.swap(1, 2);
        if let Some(n) = &mut t.n {
            n.swap(1, 2);
            for k in n.iter_mut() {
                *k = -*k;
            }
        }
    }
    disc(out, v(x, SHADE_TOP_Y, z), SHADE_TOP_RADIUS, true, m::BRASS);
    disc(
        out,
        v(x, SHADE_TOP_Y - 0.005, z),
        SHADE_TOP_RADIUS - 0.005,
        false,
        m::SHADE_INSIDE,
    );
    disc(out, v(x, LIGHT_Y, z), LIGHT_RADIUS, false, m::LIGHT);
}

fn table(out: &mut Vec<Triangle>, centre: [f32; 2], height: f32) {
    let [cx, cz] = centre;
    let (half_w, half_d, top) = (0.6, 0.4, 0.04);
    cuboid(
        out,
        v(cx - half_w, height - top, cz - half_d),
        v(cx + half_w, height, cz + half_d),
        m::TABLE,
    );
    let leg = 0.03;
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let (lx, lz) = (cx + sx * (half_w - 0.06), cz + sz * (half_d - 0.06));
        cuboid(
            out,
            v(lx - leg, 0.0, lz - leg),
            v(lx + leg, height - top, lz + leg),
            m::TABLE,
        );
    }
}

/// The `lamps` scene (see the module docs).
pub fn lamps() -> Scene {
    let mut t = Vec::new();
    room(&mut t);
    for [x, z] in LAMP_POSITIONS {
        lamp(&mut t, x, z);
    }
    let table_centre = [0.2, 1.0];
    let table_height = 0.75;
    table(&mut t, table_centre, table_height);
    // A vase with a round belly and a flared neck.
    lathe(
        &mut t,
        v(table_centre[0] - 0.25, table_height, table_centre[1]),
        48,
        24,
        m::VASE,
        |s| {
            let belly = 0.11 * (PI * s.min(0.8) / 0.8).sin();
            let neck = 0.035 + 0.03 * ((s - 0.8).max(0.0) / 0.2).powi(2);
            (0.04 + belly.max(neck - 0.04), 0.4 * s)
        },
    );
    torus(&mut t, v(1.5, 0.08, -0.2), 0.26, 0.08, m::GOLD);
    icosphere(&mut t, v(-1.5, 0.35, 0.2), 0.35, 3, m::SPHERE);
    Scene {
        name: "lamps".to_string(),
        camera: Camera {
            position: v(0.3, 1.45, -2.75),
            look_at: v(0.0, 1.05, 1.5),
            up: Vec3::Y,
            fov_y: 62.0,
        },
        film: FilmSize {
            width: 640,
            height: 480,
        },
        triangles: t,
        materials: materials(),
        point_lights: Vec::new(),
        settings: RenderSettings::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lights_hide_inside_their_shades() {
        let s = lamps();
        let lights = s.emissive_triangles();
        assert_eq!(lights.len(), 3 * 24);
        for &i in &lights {
            let tri = &s.triangles[i as usize];
            assert!(tri.geometric_normal().y < -0.999, "lights face down");
            assert!(tri.p.iter().all(|p| (p.y - LIGHT_Y).abs() < 1e-6));
        }
        // The camera is outside every shade's cone below its rim, so it cannot see a
        // light: the segment from the camera to any point of a disc crosses the shade.
        for [x, z] in LAMP_POSITIONS {
            let light = v(x, LIGHT_Y, z);
            let to = light - s.camera.position;
            let t = (SHADE_RIM_Y - s.camera.position.y) / to.y;
            let at_rim = s.camera.position + to * t;
            let off_axis = ((at_rim.x - x).powi(2) + (at_rim.z - z).powi(2)).sqrt();
            assert!(
                off_axis > SHADE_RIM_RADIUS + LIGHT_RADIUS,
                "lamp at ({x}, {z}) seen directly"
            );
        }
    }

    #[test]
    fn objects_have_thousands_of_triangles_and_layered_materials() {
        let s = lamps();
        assert!(s.triangles.len() > 5000, "{}", s.triangles.len());
        assert!(s.materials.len() >= 6);
        let layered = s
            .materials
            .iter()
            .filter(|m| {
                let p = crate::integrator::pt::materials::bsdf_of(m);
                p.active().len() >= 2
            })
            .count();
        assert!(layered >= 3, "{layered} layered materials");
        // Smooth objects carry unit shading normals on the geometric side.
        for t in s.triangles.iter().filter(|t| t.n.is_some()) {
            for n in t.n.unwrap() {
                assert!((n.length() - 1.0).abs() < 1e-3);
                assert!(n.dot(t.geometric_normal()) > 0.0);
            }
        }
    }
}
