//! Animated built-in scenes, generated in code: the dynamic scenes of `bench dynamic`.
//!
//! ## `waves`
//! A 8 m × 8 m sea (x, z ∈ [−4, 4], metres) of 224 × 224 quads = 100,352 triangles
//! whose height is a sum of three travelling sine waves, with shading normals from the
//! exact gradient; four floating crates (12 triangles each) bob and turn on keyframes;
//! a 1 m² area light 5 m up and a point light light it. The camera moves on keyframes
//! over 4 s and holds still after; the waves move for ever. Every frame deforms every
//! triangle of the sea: the case for which PDACRT, with nothing to rebuild, is made.
//!
//! ## `swarm`
//! 80 icospheres (1,280 triangles each, 102,400 in all; radius 0.15–0.35 m) fly around
//! the y axis on circles of radius 1–3.5 m at heights 0.3–2.3 m, each turning with its
//! orbit, on keyframes every 0.5 s over 4 s (at most 45° of orbit between keys), above a
//! floor; an area light and a point light above. Many separately moving objects: the
//! case in which a refitted hierarchy degrades fastest.

use std::sync::Arc;

use glam::{Quat, Vec3};

use super::{AnimatedScene, Animation, Keyframes, MeshMotion, Motion, Procedure, Transform};
use crate::scene::{
    shapes, Camera, FilmSize, Material, PointLight, RenderSettings, Scene, Triangle,
};

/// The animated built-in scene names and a one-line description of each.
pub const NAMES: [(&str, &str); 2] = [
    (
        "waves",
        "animated: a sea of 100,352 triangles deforming every frame, floating crates, moving camera",
    ),
    (
        "swarm",
        "animated: 80 icospheres (102,400 triangles) flying around on keyframes above a floor",
    ),
];

/// The animated built-in scene called `name`, or `None`.
pub fn animated(name: &str) -> Option<AnimatedScene> {
    match name {
        "waves" => Some(waves()),
        "swarm" => Some(swarm()),
        _ => None,
    }
}

fn material(name: &str, diffuse: Vec3, emission: Vec3) -> Material {
    Material {
        diffuse,
        emission,
        ..Material::named(name)
    }
}

/// A square area light of side `side` centred at `centre`, facing down (−y).
fn ceiling_light(centre: Vec3, side: f32, material: u32) -> [Triangle; 2] {
    let h = side * 0.5;
    let c = |dx: f32, dz: f32| centre + Vec3::new(dx, 0.0, dz);
    // (a, b, c) with (b − a) × (c − a) pointing −y.
    [
        Triangle::new(c(-h, -h), c(h, -h), c(h, h), material),
        Triangle::new(c(-h, -h), c(h, h), c(-h, h), material),
    ]
}

/// Appends `rest` to the soup as a mesh moved by `keys` (increasing times).
fn keyed_mesh(
    name: String,
    rest: Vec<Triangle>,
    keys: Vec<(f32, Transform)>,
    triangles: &mut Vec<Triangle>,
) -> MeshMotion {
    let start = triangles.len();
    triangles.extend(&rest);
    MeshMotion {
        name,
        range: start..triangles.len(),
        motion: Motion::Keyed {
            rest,
            base: None,
            keys: Some(Keyframes::new(keys).expect("increasing times")),
            sequence: None,
        },
    }
}

/// Finishes a scene: posed at time 0, validated by the caller's tests.
fn posed(scene: Scene, animation: Animation) -> AnimatedScene {
    let mut a = AnimatedScene { scene, animation };
    a.scene = a.pose(0.0);
    a
}

/// Quads per side of the `waves` sea.
const SEA_CELLS: usize = 224;
const SEA_HALF: f32 = 4.0;

/// (amplitude m, wave vector rad/m, angular frequency rad/s, phase) of the sea's waves.
const WAVES: [(f32, [f32; 2], f32, f32); 3] = [
    (0.18, [1.3, 0.4], 1.7, 0.0),
    (0.10, [-0.5, 1.9], 2.3, 1.0),
    (0.05, [2.9, -2.2], 3.1, 2.0),
];

/// The sea's height at (x, z) and time t, and its gradient (∂h/∂x, ∂h/∂z).
fn sea_height(x: f32, z: f32, t: f32) -> (f32, f32, f32) {
    let (mut h, mut dx, mut dz) = (0.0, 0.0, 0.0);
    for (a, [kx, kz], w, phase) in WAVES {
        let arg = kx * x + kz * z - w * t + phase;
        let (s, c) = arg.sin_cos();
        h += a * s;
        dx += a * kx * c;
        dz += a * kz * c;
    }
    (h, dx, dz)
}

/// Writes the sea at time `t`: two triangles per cell, (a, b, c), (a, c, d) wound so
/// that the geometric normal points up.
fn write_sea(t: f32, out: &mut [Triangle]) {
    let n = SEA_CELLS + 1;
    let step = 2.0 * SEA_HALF / SEA_CELLS as f32;
    let mut p = Vec::with_capacity(n * n);
    let mut normal = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let (x, z) = (-SEA_HALF + i as f32 * step, -SEA_HALF + j as f32 * step);
            let (h, dx, dz) = sea_height(x, z, t);
            p.push(Vec3::new(x, h, z));
            normal.push(Vec3::new(-dx, 1.0, -dz).normalize());
        }
    }
    for j in 0..SEA_CELLS {
        for i in 0..SEA_CELLS {
            let [a, b, c, d] = [
                j * n + i,
                (j + 1) * n + i,
                (j + 1) * n + i + 1,
                j * n + i + 1,
            ];
            let k = 2 * (j * SEA_CELLS + i);
            for (slot, v) in [(k, [a, b, c]), (k + 1, [a, c, d])] {
                out[slot].p = v.map(|v| p[v]);
                out[slot].n = Some(v.map(|v| normal[v]));
            }
        }
    }
}

/// A unit cube centred at the origin, faces wound outwards.
fn cube(material: u32) -> Vec<Triangle> {
    let mut out = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|k| if k == axis { sign } else { 0.0 }));
            let (u, v) = n.any_orthonormal_pair();
            let c = n * 0.5;
            let q = [
                c - u * 0.5 - v * 0.5,
                c + u * 0.5 - v * 0.5,
                c + u * 0.5 + v * 0.5,
                c - u * 0.5 + v * 0.5,
            ];
            let mut tris = [
                Triangle::new(q[0], q[1], q[2], material),
                Triangle::new(q[0], q[2], q[3], material),
            ];
            if tris[0].geometric_normal().dot(n) < 0.0 {
                for t in &mut tris {
                    t.p.swap(1, 2);
                }
            }
            out.extend(tris);
        }
    }
    out
}

fn waves() -> AnimatedScene {
    let materials = vec![
        material("sea", Vec3::new(0.15, 0.35, 0.6), Vec3::ZERO),
        material("crate", Vec3::new(0.75, 0.45, 0.2), Vec3::ZERO),
        material("light", Vec3::splat(0.8), Vec3::splat(20.0)),
    ];
    let sea_triangles = 2 * SEA_CELLS * SEA_CELLS;
    let mut triangles = vec![Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Z, 0); sea_triangles];
    let sea: Procedure = Arc::new(write_sea);
    let mut meshes = vec![MeshMotion {
        name: "sea".into(),
        range: 0..sea_triangles,
        motion: Motion::Procedural(sea),
    }];
    for (i, (x, z)) in [(-2.0f32, -1.0f32), (1.5, -2.0), (2.2, 1.4), (-1.2, 2.1)]
        .into_iter()
        .enumerate()
    {
        let keys = (0..=8)
            .map(|k| {
                let t = k as f32 * 0.5;
                let phase = i as f32 * 1.3 + t * 1.6;
                let transform = Transform {
                    translate: Vec3::new(x, 0.25 * phase.sin(), z),
                    rotate: Quat::from_axis_angle(Vec3::Y, 0.3 * t + i as f32)
                        * Quat::from_axis_angle(Vec3::X, 0.2 * phase.cos()),
                    scale: Vec3::splat(0.45),
                };
                (t, transform)
            })
            .collect();
        meshes.push(keyed_mesh(
            format!("crate {i}"),
            cube(1),
            keys,
            &mut triangles,
        ));
    }
    triangles.extend(ceiling_light(Vec3::new(0.0, 5.0, 0.0), 1.0, 2));

    let camera = |position: Vec3| Camera {
        position,
        look_at: Vec3::new(0.0, -0.3, 0.0),
        up: Vec3::Y,
        fov_y: 50.0,
    };
    let camera_keys = Keyframes::new(vec![
        (0.0, camera(Vec3::new(0.0, 3.5, 8.0))),
        (2.0, camera(Vec3::new(3.0, 3.0, 7.0))),
        (4.0, camera(Vec3::new(4.5, 4.0, 5.0))),
    ])
    .expect("increasing times");
    posed(
        Scene {
            name: "waves".into(),
            camera: camera_keys.sample(0.0),
            film: FilmSize {
                width: 512,
                height: 512,
            },
            triangles,
            materials,
            point_lights: vec![PointLight {
                position: Vec3::new(2.0, 6.0, 3.0),
                intensity: Vec3::splat(60.0),
            }],
            settings: RenderSettings::default(),
        },
        Animation {
            meshes,
            camera: Some(camera_keys),
        },
    )
}

/// Deterministic numbers in [0, 1) for the swarm's layout.
fn hash01(i: u32, salt: u32) -> f32 {
    let mut x = i.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
    x ^= x >> 16;
    x = x.wrapping_mul(0x7FEB_352D);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846C_A68B);
    x ^= x >> 16;
    (x >> 8) as f32 / 16_777_216.0
}

const SWARM_SPHERES: u32 = 80;

fn swarm() -> AnimatedScene {
    let materials = vec![
        material("floor", Vec3::splat(0.6), Vec3::ZERO),
        material("sphere-a", Vec3::new(0.7, 0.3, 0.25), Vec3::ZERO),
        material("sphere-b", Vec3::new(0.25, 0.5, 0.7), Vec3::ZERO),
        material("light", Vec3::splat(0.8), Vec3::splat(25.0)),
    ];
    let f = 5.0;
    let mut triangles = vec![
        Triangle::new(
            Vec3::new(-f, 0.0, -f),
            Vec3::new(-f, 0.0, f),
            Vec3::new(f, 0.0, f),
            0,
        ),
        Triangle::new(
            Vec3::new(-f, 0.0, -f),
            Vec3::new(f, 0.0, f),
            Vec3::new(f, 0.0, -f),
            0,
        ),
    ];
    let mut meshes = Vec::new();
    for i in 0..SWARM_SPHERES {
        let rest: Vec<Triangle> = shapes::icosphere(3)
            .into_iter()
            .map(|[a, b, c]| Triangle::new(a, b, c, 1 + i % 2))
            .collect();
        let radius = 1.0 + 2.5 * hash01(i, 1);
        let height = 0.3 + 2.0 * hash01(i, 2);
        let size = 0.15 + 0.2 * hash01(i, 3);
        let phase = std::f32::consts::TAU * hash01(i, 4);
        // Up to 90°/s either way: at most 45° of orbit between keys 0.5 s apart.
        let speed = (hash01(i, 5) * 2.0 - 1.0) * std::f32::consts::FRAC_PI_2;
        let keys = (0..=8)
            .map(|k| {
                let t = k as f32 * 0.5;
                let angle = phase + speed * t;
                let transform = Transform {
                    translate: Vec3::new(
                        radius * angle.cos(),
                        height + 0.3 * (2.0 * angle).sin(),
                        radius * angle.sin(),
                    ),
                    rotate: Quat::from_axis_angle(Vec3::Y, -angle),
                    scale: Vec3::splat(size),
                };
                (t, transform)
            })
            .collect();
        meshes.push(keyed_mesh(
            format!("sphere {i}"),
            rest,
            keys,
            &mut triangles,
        ));
    }
    triangles.extend(ceiling_light(Vec3::new(0.0, 4.5, 0.0), 1.0, 3));
    posed(
        Scene {
            name: "swarm".into(),
            camera: Camera {
                position: Vec3::new(0.0, 4.0, 8.5),
                look_at: Vec3::new(0.0, 1.0, 0.0),
                up: Vec3::Y,
                fov_y: 45.0,
            },
            film: FilmSize {
                width: 512,
                height: 512,
            },
            triangles,
            materials,
            point_lights: vec![PointLight {
                position: Vec3::new(-1.5, 4.0, 2.0),
                intensity: Vec3::splat(40.0),
            }],
            settings: RenderSettings::default(),
        },
        Animation {
            meshes,
            camera: None,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_windings_and_motion() {
        let w = waves();
        assert_eq!(w.scene.triangles.len(), 100_352 + 4 * 12 + 2);
        let s = swarm();
        assert_eq!(s.scene.triangles.len(), 2 + 80 * 1280 + 2);
        // The sea faces up; crates and spheres face outwards.
        let sea = &w.scene.triangles[..100_352];
        assert!(sea.iter().all(|t| t.geometric_normal().y > 0.5));
        for t in &w.scene.triangles[100_352..100_352 + 12] {
            let centre = Vec3::new(-2.0, 0.25 * 0.0f32.sin(), -1.0);
            assert!(t.geometric_normal().dot(t.centroid() - centre) > 0.0);
        }
        for m in &s.animation.meshes {
            let tris = &s.scene.triangles[m.range.clone()];
            let centre = tris.iter().map(|t| t.centroid()).sum::<Vec3>() / tris.len() as f32;
            assert!(tris
                .iter()
                .all(|t| t.geometric_normal().dot(t.centroid() - centre) > 0.0));
        }
        // Everything that should move moves.
        let mut posed = w.scene.clone();
        let changed = w.advance(&mut posed, 0.0, 0.1);
        assert_eq!(changed.len(), 5);
        assert_ne!(posed.camera, w.scene.camera);
        assert_eq!(s.animation.end_time(), Some(4.0));
    }
}
