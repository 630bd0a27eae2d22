//! Built-in scenes, generated in code.
//!
//! Winding: every quad is split into two triangles (a, b, c), (a, c, d), oriented so that
//! the counter-clockwise geometric normal `(p1 − p0) × (p2 − p0)` of room walls points
//! *into* the room, the normal of block / box faces points *out of* the block, and the
//! normal of an area light points to the side it lights (lights emit one-sided, on the
//! normal side).
//!
//! ## `cornell-box`
//! The published Cornell box data (millimetres; <https://www.graphics.cornell.edu/online/box/data.html>):
//! floor y = 0, ceiling y = 548.8, back wall z ≈ 559.2, red wall at x ≈ 550, green wall at
//! x = 0, a short block (height 165) and a tall block (height 330). The light is the
//! quad x ∈ [213, 343], z ∈ [227, 332] at y = 548.7 (0.1 below the ceiling, so it does not
//! coincide with it), facing down, emission (17, 12, 4). Camera at (278, 273, −800)
//! looking at (278, 273, 0), up +y, fov_y 39.3077°; right = forward × up = −x, so the red
//! (high-x) wall is on the LEFT of the image. 32 triangles, film 512×512.
//! The same scene is in `scenes/cornell-box.{toml,obj,mtl}`.
//!
//! ## `fixture`
//! A closed room that is lit only indirectly (metres, 640×480 film):
//! - room: x ∈ [−3, 3], y ∈ [0, 3], z ∈ [−3, 3], six inward-facing walls, white 0.7;
//! - an open-sided box on the floor: x ∈ [1, 2], y ∈ [0, 1], z ∈ [0.5, 1.5] with faces at
//!   x = 1 (back), y = 1 (top), z = 0.5 and z = 1.5 (sides), grey 0.5, **open on +x**,
//!   its opening facing the +x wall 1 m away (the room floor closes its bottom);
//! - the only light: a quad at x = 1.01 inside the box (y ∈ [0.2, 0.8], z ∈ [0.7, 1.3]),
//!   facing +x through the opening, emission (40, 36, 30);
//! - camera at (0, 1.5, −2.8) looking at (0, 1.2, 3), up +y, fov_y 60°. The camera is
//!   behind the light's plane and outside the box's opening, so it never sees the light:
//!   everything it sees is lit by light that bounced off the +x wall (image left) first,
//!   or by light leaving the box's opening at grazing angles.
//!   There are no point lights.
//!
//! ## `lamps`
//! A room lit by three hanging lamps whose area lights sit deep inside their shades, with
//! layered materials and procedural objects of some thousands of triangles: see
//! `lamps` (its own module).

mod lamps;

use glam::Vec3;

use super::{Camera, FilmSize, Material, RenderSettings, Scene, Triangle};

/// The built-in scene names and a one-line description of each.
pub fn builtin_names() -> &'static [(&'static str, &'static str)] {
    &[
        (
            "cornell-box",
            "the classic Cornell box (published geometry, mm), ceiling area light, red wall left",
        ),
        (
            "fixture",
            "closed room lit only indirectly: its one area light hides in an open box facing a wall",
        ),
        (
            "lamps",
            "room with three hanging lamps, lights deep inside their shades, layered materials, ~7k triangles",
        ),
        super::animation::builtin::NAMES[0],
        super::animation::builtin::NAMES[1],
    ]
}

/// The built-in scene called `name`, or `None`.
pub fn builtin(name: &str) -> Option<Scene> {
    match name {
        "cornell-box" => Some(cornell_box()),
        "fixture" => Some(fixture()),
        "lamps" => Some(lamps::lamps()),
        // Animated scenes posed at time 0 (`scene::load_animated` keeps them moving).
        _ => super::animation::builtin::animated(name).map(|a| a.scene),
    }
}

fn material(name: &str, diffuse: Vec3, emission: Vec3) -> Material {
    Material {
        diffuse,
        emission,
        ..Material::named(name)
    }
}

/// Which way a quad's geometric normal must point.
#[derive(Clone, Copy)]
enum Facing {
    Toward(Vec3),
    AwayFrom(Vec3),
}

/// Appends quad a-b-c-d (a planar, convex loop) as two triangles wound so that the
/// normal obeys `facing`.
fn quad(out: &mut Vec<Triangle>, v: [Vec3; 4], material: u32, facing: Facing) {
    let [a, b, c, d] = v;
    let n = (b - a).cross(c - a) + (c - a).cross(d - a);
    let centre = (a + b + c + d) * 0.25;
    let flip = match facing {
        Facing::Toward(p) => n.dot(p - centre) < 0.0,
        Facing::AwayFrom(p) => n.dot(centre - p) < 0.0,
    };
    if flip {
        out.push(Triangle::new(a, c, b, material));
        out.push(Triangle::new(a, d, c, material));
    } else {
        out.push(Triangle::new(a, b, c, material));
        out.push(Triangle::new(a, c, d, material));
    }
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// A block given by its top quad (at height `h`) over the floor: top face and four sides.
fn block(out: &mut Vec<Triangle>, top: [[f32; 2]; 4], h: f32, material: u32) {
    let centre = top
        .iter()
        .fold(Vec3::ZERO, |acc, [x, z]| acc + v(*x, h * 0.5, *z))
        / 4.0;
    let t = |i: usize| v(top[i][0], h, top[i][1]);
    let b = |i: usize| v(top[i][0], 0.0, top[i][1]);
    quad(
        out,
        [t(0), t(1), t(2), t(3)],
        material,
        Facing::AwayFrom(centre),
    );
    for i in 0..4 {
        let j = (i + 1) % 4;
        quad(
            out,
            [b(i), t(i), t(j), b(j)],
            material,
            Facing::AwayFrom(centre),
        );
    }
}

fn cornell_box() -> Scene {
    let materials = vec![
        material("white", Vec3::splat(0.73), Vec3::ZERO),
        material("red", v(0.63, 0.065, 0.05), Vec3::ZERO),
        material("green", v(0.14, 0.45, 0.09), Vec3::ZERO),
        material("light", Vec3::splat(0.78), v(17.0, 12.0, 4.0)),
    ];
    let (white, red, green, light) = (0, 1, 2, 3);
    let inside = Facing::Toward(v(278.0, 274.4, 279.6));
    let mut t = Vec::new();
    // Floor.
    quad(
        &mut t,
        [
            v(552.8, 0.0, 0.0),
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 559.2),
            v(549.6, 0.0, 559.2),
        ],
        white,
        inside,
    );
    // Ceiling.
    quad(
        &mut t,
        [
            v(556.0, 548.8, 0.0),
            v(556.0, 548.8, 559.2),
            v(0.0, 548.8, 559.2),
            v(0.0, 548.8, 0.0),
        ],
        white,
        inside,
    );
    // Back wall.
    quad(
        &mut t,
        [
            v(549.6, 0.0, 559.2),
            v(0.0, 0.0, 559.2),
            v(0.0, 548.8, 559.2),
            v(556.0, 548.8, 559.2),
        ],
        white,
        inside,
    );
    // Green wall (x = 0, image right).
    quad(
        &mut t,
        [
            v(0.0, 0.0, 559.2),
            v(0.0, 0.0, 0.0),
            v(0.0, 548.8, 0.0),
            v(0.0, 548.8, 559.2),
        ],
        green,
        inside,
    );
    // Red wall (x ≈ 550, image left).
    quad(
        &mut t,
        [
            v(552.8, 0.0, 0.0),
            v(549.6, 0.0, 559.2),
            v(556.0, 548.8, 559.2),
            v(556.0, 548.8, 0.0),
        ],
        red,
        inside,
    );
    // Short block.
    block(
        &mut t,
        [[130.0, 65.0], [82.0, 225.0], [240.0, 272.0], [290.0, 114.0]],
        165.0,
        white,
    );
    // Tall block.
    block(
        &mut t,
        [
            [423.0, 247.0],
            [265.0, 296.0],
            [314.0, 456.0],
            [472.0, 406.0],
        ],
        330.0,
        white,
    );
    // Light, just below the ceiling, facing down.
    quad(
        &mut t,
        [
            v(343.0, 548.7, 227.0),
            v(343.0, 548.7, 332.0),
            v(213.0, 548.7, 332.0),
            v(213.0, 548.7, 227.0),
        ],
        light,
        Facing::Toward(v(278.0, 0.0, 279.5)),
    );
    Scene {
        name: "cornell-box".to_string(),
        camera: Camera {
            position: v(278.0, 273.0, -800.0),
            look_at: v(278.0, 273.0, 0.0),
            up: Vec3::Y,
            fov_y: 39.3077,
        },
        film: FilmSize {
            width: 512,
            height: 512,
        },
        triangles: t,
        materials,
        point_lights: Vec::new(),
        settings: RenderSettings::default(),
    }
}

/// The four corners, in loop order, of the face of box [min, max] perpendicular to
/// `axis` on its `high` (max) or low (min) side.
fn box_face(min: Vec3, max: Vec3, axis: usize, high: bool) -> [Vec3; 4] {
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    let corner = |a: bool, b: bool| {
        let mut p = min;
        p[axis] = if high { max[axis] } else { min[axis] };
        p[u] = if a { max[u] } else { min[u] };
        p[w] = if b { max[w] } else { min[w] };
        p
    };
    [
        corner(false, false),
        corner(true, false),
        corner(true, true),
        corner(false, true),
    ]
}

fn fixture() -> Scene {
    let materials = vec![
        material("white", Vec3::splat(0.7), Vec3::ZERO),
        material("box", Vec3::splat(0.5), Vec3::ZERO),
        material("light", Vec3::ZERO, v(40.0, 36.0, 30.0)),
    ];
    let (white, grey, light) = (0, 1, 2);
    let mut t = Vec::new();

    let (room_min, room_max) = (v(-3.0, 0.0, -3.0), v(3.0, 3.0, 3.0));
    let room_centre = (room_min + room_max) * 0.5;
    for axis in 0..3 {
        for high in [false, true] {
            quad(
                &mut t,
                box_face(room_min, room_max, axis, high),
                white,
                Facing::Toward(room_centre),
            );
        }
    }

    let (box_min, box_max) = (v(1.0, 0.0, 0.5), v(2.0, 1.0, 1.5));
    let box_centre = (box_min + box_max) * 0.5;
    // Back (x = 1), top (y = 1), sides (z = 0.5, z = 1.5); open at x = 2, no bottom.
    for (axis, high) in [(0, false), (1, true), (2, false), (2, true)] {
        quad(
            &mut t,
            box_face(box_min, box_max, axis, high),
            grey,
            Facing::AwayFrom(box_centre),
        );
    }

    quad(
        &mut t,
        [
            v(1.01, 0.2, 0.7),
            v(1.01, 0.8, 0.7),
            v(1.01, 0.8, 1.3),
            v(1.01, 0.2, 1.3),
        ],
        light,
        Facing::Toward(v(3.0, 0.5, 1.0)),
    );

    Scene {
        name: "fixture".to_string(),
        camera: Camera {
            position: v(0.0, 1.5, -2.8),
            look_at: v(0.0, 1.2, 3.0),
            up: Vec3::Y,
            fov_y: 60.0,
        },
        film: FilmSize {
            width: 640,
            height: 480,
        },
        triangles: t,
        materials,
        point_lights: Vec::new(),
        settings: RenderSettings::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{validate, Location};

    #[test]
    fn all_builtins_validate() {
        for (name, _) in builtin_names() {
            let s = builtin(name).unwrap();
            let stats =
                validate::validate_scene(&s, &Location::file(format!("builtin:{name}"))).unwrap();
            assert_eq!(stats.degenerate_triangles, 0, "{name}");
            assert_eq!(stats.emissive_materials, 1, "{name}");
        }
        assert!(builtin("nope").is_none());
    }

    #[test]
    fn cornell_walls_face_inside() {
        let s = builtin("cornell-box").unwrap();
        assert_eq!(s.triangles.len(), 32);
        let centre = v(278.0, 274.4, 279.6);
        for (i, tri) in s.triangles.iter().enumerate() {
            let n = tri.geometric_normal();
            let m = &s.materials[tri.material as usize].name;
            let is_block = (10..30).contains(&i);
            if !is_block {
                assert!(n.dot(centre - tri.centroid()) > 0.0, "{i} {m}");
            }
        }
        // The light faces down.
        let l = s.emissive_triangles();
        assert_eq!(l.len(), 2);
        for i in l {
            assert!(s.geometric_normal(i as usize).y < -0.99);
        }
    }

    #[test]
    fn fixture_light_is_hidden_from_camera() {
        let s = builtin("fixture").unwrap();
        let b = s.bounds();
        assert!(b.contains(s.camera.position));
        let l = s.emissive_triangles();
        assert_eq!(l.len(), 2);
        for i in l {
            let t = &s.triangles[i as usize];
            let n = t.geometric_normal();
            assert!(n.x > 0.99, "light faces +x");
            // The camera is behind the emitting side.
            assert!((s.camera.position - t.p[0]).dot(n) < 0.0);
        }
        // Every room wall faces the room centre.
        for t in &s.triangles[..12] {
            assert!(t.geometric_normal().dot(v(0.0, 1.5, 0.0) - t.centroid()) > 0.0);
        }
    }
}
