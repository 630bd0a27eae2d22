//! Scenes far from the origin are moved to it when they load (`scene::recentre`): a room
//! placed at 10⁵, where a float step is 1/128 and the ray offset would be 0.4 in a room
//! of two units, renders the image it renders at the origin, and what moves in it moves
//! as it does there. The room's coordinates are multiples of 1/128, so that the far copy
//! holds the very same geometry and the two scenes differ by a translation alone.
//!
//! In survey coordinates (5·10⁶, where f32 steps are 1/2) a room 0.6 wide keeps its shape
//! only because nothing is rounded to f32 before the move: OBJ positions, translations,
//! the camera and the point lights are read in f64, and the room renders and moves (keys,
//! an OBJ sequence) as at the origin, to a few float steps of its size.

use std::path::{Path, PathBuf};

use glam::Vec3;
use splitray::integrator::bpt::{BidirMode, BptIntegrator, BptOptions};
use splitray::integrator::Integrator;
use splitray::scene::{self, AnimatedScene, Scene};

use crate::common;

/// A room [-1, 1] × [0, 2] × [-1, 1] open towards −z, a block on its floor and a light
/// facing down from under its ceiling.
fn room_obj() -> String {
    let mut obj = String::from("mtllib room.mtl\n");
    let mut quads = 0;
    let mut quad = |obj: &mut String, material: &str, corners: [[f32; 3]; 4]| {
        obj.push_str(&format!("usemtl {material}\n"));
        for [x, y, z] in corners {
            obj.push_str(&format!("v {x} {y} {z}\n"));
        }
        let k = 4 * quads + 1;
        obj.push_str(&format!(
            "f {} {} {}\nf {} {} {}\n",
            k,
            k + 1,
            k + 2,
            k,
            k + 2,
            k + 3
        ));
        quads += 1;
    };
    let square =
        |f: &dyn Fn(f32, f32) -> [f32; 3]| [f(-1.0, -1.0), f(1.0, -1.0), f(1.0, 1.0), f(-1.0, 1.0)];
    quad(&mut obj, "white", square(&|a, b| [a, 0.0, -b]));
    quad(&mut obj, "white", square(&|a, b| [a, 2.0, b]));
    quad(&mut obj, "white", square(&|a, b| [a, 1.0 + b, 1.0]));
    quad(&mut obj, "red", square(&|a, b| [-1.0, 1.0 + b, a]));
    quad(&mut obj, "white", square(&|a, b| [1.0, 1.0 - b, a]));
    // A block of 0.5 × 0.75 × 0.5 on the floor (its top and two sides).
    quad(
        &mut obj,
        "white",
        square(&|a, b| [0.25 * a - 0.375, 0.75, 0.25 * b]),
    );
    quad(
        &mut obj,
        "white",
        square(&|a, b| [0.25 * a - 0.375, 0.375 + 0.375 * b, -0.25]),
    );
    quad(
        &mut obj,
        "white",
        square(&|a, b| [-0.125, 0.375 + 0.375 * b, 0.25 * a]),
    );
    quad(
        &mut obj,
        "lamp",
        square(&|a, b| [0.25 * a, 1.875, 0.25 * b]),
    );
    obj
}

const ROOM_MTL: &str = "newmtl white\nKd 0.7 0.7 0.7\nnewmtl red\nKd 0.6 0.1 0.1\n\
                        newmtl lamp\nKd 0 0 0\nKe 10 10 10\n";

/// The room's scene file with everything translated by `at`, and `extra` TOML after it.
/// Its numbers are written as f64s (as splitray reads them), so that each is the exact
/// sum.
fn room_toml(dir: &Path, name: &str, at: [f64; 3], extra: &str) -> PathBuf {
    std::fs::write(dir.join("room.obj"), room_obj()).unwrap();
    std::fs::write(dir.join("room.mtl"), ROOM_MTL).unwrap();
    let [x, y, z] = at;
    let text = format!(
        "[camera]\nposition = [{x}, {}, {}]\nlook_at = [{x}, {}, {z}]\nfov_y = 40\n\
         [film]\nwidth = 16\nheight = 16\n\
         [[mesh]]\npath = \"room.obj\"\ntransform = {{ translate = [{x}, {y}, {z}] }}\n{extra}",
        y + 1.0,
        z - 3.375,
        y + 1.0,
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

const FAR: [f64; 3] = [1e5, -1e5, 2e5];

fn load(path: &Path) -> AnimatedScene {
    scene::load_animated(path.to_str().unwrap()).unwrap()
}

/// Every vertex of `far` is the vertex of `near` moved by one offset, exactly; returns it.
fn moved_by_one_offset(near: &Scene, far: &Scene) -> Vec3 {
    let d = far.triangles[0].p[0] - near.triangles[0].p[0];
    for (a, b) in near.triangles.iter().zip(&far.triangles) {
        assert_eq!(b.p, a.p.map(|p| p + d));
    }
    assert_eq!(far.camera.position, near.camera.position + d);
    assert_eq!(far.camera.look_at, near.camera.look_at + d);
    d
}

fn bpt_image(scene: &Scene) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let frame = scene.camera_frame();
    let options = BptOptions {
        seed: 5,
        ..Default::default()
    };
    let mut bpt = BptIntegrator::new(BidirMode::Bpt, scene, &frame, &options);
    bpt.render_passes(0, 64).unwrap();
    let sums = bpt.sums().unwrap();
    (sums.mean(), sums.stderr().unwrap())
}

#[test]
fn a_room_far_from_the_origin_renders_as_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    let near = load(&room_toml(dir.path(), "near.toml", [0.0; 3], "")).scene;
    let far = load(&room_toml(dir.path(), "far.toml", FAR, "")).scene;
    // Moved next to the origin: the offset left is the room's own, not 10⁵.
    let d = moved_by_one_offset(&near, &far);
    assert!(d.abs().max_element() <= 1.0, "{d}");
    assert!(far.bounds().max.abs().max_element() <= 2.0);
    // Near the origin nothing moves.
    assert_eq!(near.triangles[0].p[0], Vec3::new(-1.0, 0.0, 1.0));

    let (a, a_se) = bpt_image(&near);
    let (b, b_se) = bpt_image(&far);
    let mean = |img: &[[f32; 3]]| img.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let ratio = mean(&b) / mean(&a);
    // Left at 10⁵, bpt reads this room 9% dark.
    assert!((ratio - 1.0).abs() < 2e-3, "image mean ratio {ratio}");
    common::reference::compare_images("the room at the origin", 16, (&b, &b_se), (&a, &a_se))
        .assert_agrees("the room at 10⁵");
}

#[test]
fn what_moves_far_from_the_origin_moves_as_at_the_origin() {
    let keys = "[[mesh.keyframe]]\ntime = 0.0\n[[mesh.keyframe]]\ntime = 1.0\n\
                translate = [0.25, 0.5, 0.125]\n\
                [[camera.keyframe]]\ntime = 0.5\n[[camera.keyframe]]\ntime = 2.0\nfov_y = 30\n";
    let dir = tempfile::tempdir().unwrap();
    let near = load(&room_toml(dir.path(), "near.toml", [0.0; 3], keys));
    let far = load(&room_toml(dir.path(), "far.toml", FAR, keys));
    let d = moved_by_one_offset(&near.scene, &far.scene);
    assert!(d.abs().max_element() <= 1.0, "{d}");
    // The scene is its own pose at time 0, bit for bit.
    assert_eq!(far.pose(0.0), far.scene);
    for t in [0.25, 0.5, 0.75, 1.0, 1.5, 3.0] {
        let (a, b) = (near.pose(t), far.pose(t));
        for (ta, tb) in a.triangles.iter().zip(&b.triangles) {
            for (pa, pb) in ta.p.iter().zip(&tb.p) {
                assert!((*pb - (*pa + d)).abs().max_element() < 1e-6, "t = {t}");
            }
        }
        assert!((b.camera.position - (a.camera.position + d)).length() < 1e-6);
        assert_eq!(b.camera.fov_y, a.camera.fov_y);
    }
}

/// Survey coordinates: an easting and a northing, where f32 steps are 1/16 and 1/2.
const SURVEY: [f64; 3] = [500_000.3, 5_000_000.7, -0.1];

/// The room's OBJ text scaled by 0.3 (coordinates like 0.075 that no float holds
/// exactly) and moved by `at`, each coordinate written as the f64 decimal nearest its
/// exact value.
fn scaled_room_obj(at: [f64; 3]) -> String {
    let mut out = String::new();
    for line in room_obj().lines() {
        match line.strip_prefix("v ") {
            Some(xyz) => {
                let mut v = xyz.split(' ').map(|c| c.parse::<f64>().unwrap());
                let [x, y, z] = [(); 3].map(|_| v.next().unwrap());
                let [ax, ay, az] = at;
                let (x, y, z) = (0.3 * x + ax, 0.3 * y + ay, 0.3 * z + az);
                out.push_str(&format!("v {x} {y} {z}\n"));
            }
            None => out.push_str(&format!("{line}\n")),
        }
    }
    out
}

/// Writes the scaled room at `at` as `name`.obj beside its MTL; returns its path.
fn write_scaled_room(dir: &Path, name: &str, at: [f64; 3]) -> PathBuf {
    std::fs::write(dir.join("room.mtl"), ROOM_MTL).unwrap();
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, scaled_room_obj(at)).unwrap();
    path
}

/// Every vertex of `far` is the vertex of `near` moved by one offset, to a few float
/// steps of the room's own size; returns the offset.
fn moved_by_about_one_offset(near: &Scene, far: &Scene) -> Vec3 {
    let d = far.triangles[0].p[0] - near.triangles[0].p[0];
    for (a, b) in near.triangles.iter().zip(&far.triangles) {
        for (pa, pb) in a.p.iter().zip(&b.p) {
            let error = (*pb - (*pa + d)).abs().max_element();
            assert!(error < 1e-6, "{pb} is not {pa} + {d}: {error}");
        }
    }
    d
}

#[test]
fn an_obj_in_survey_coordinates_keeps_its_shape() {
    let dir = tempfile::tempdir().unwrap();
    let near_path = write_scaled_room(dir.path(), "near", [0.0; 3]);
    let far_path = write_scaled_room(dir.path(), "far", SURVEY);
    let near = scene::load(near_path.to_str().unwrap()).unwrap();
    let far = scene::load(far_path.to_str().unwrap()).unwrap();
    // Read in f32, the file's 0.3-unit steps would land on a grid of 1/2 along y.
    let d = moved_by_about_one_offset(&near, &far);
    assert!(d.abs().max_element() <= 0.3, "{d}");
    let camera_d = far.camera.position - near.camera.position;
    assert!(
        (camera_d - d).abs().max_element() < 1e-5,
        "{camera_d} vs {d}"
    );
}

/// The scaled room at the origin in a TOML scene, moved by a transform, with a camera and
/// a point light at `at` + their near places, each written in the file as an f64.
fn scaled_room_toml(dir: &Path, name: &str, at: [f64; 3]) -> PathBuf {
    write_scaled_room(dir, "room", [0.0; 3]);
    let [x, y, z] = at;
    let text = format!(
        "[camera]\nposition = [{x}, {}, {}]\nlook_at = [{x}, {}, {z}]\nfov_y = 40\n\
         [film]\nwidth = 16\nheight = 16\n\
         [[point_light]]\nposition = [{}, {}, {z}]\nintensity = [0.2, 0.2, 0.2]\n\
         [[mesh]]\npath = \"room.obj\"\ntransform = {{ translate = [{x}, {y}, {z}] }}\n",
        y + 0.3,
        z - 1.0125,
        y + 0.3,
        x + 0.15,
        y + 0.45,
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_room_placed_at_survey_coordinates_renders_as_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    let near = load(&scaled_room_toml(dir.path(), "near.toml", [0.0; 3])).scene;
    let far = load(&scaled_room_toml(dir.path(), "far.toml", SURVEY)).scene;
    let d = moved_by_about_one_offset(&near, &far);
    assert!(d.abs().max_element() <= 0.3, "{d}");
    let moved = |a: Vec3, b: Vec3| (b - (a + d)).abs().max_element() < 1e-6;
    assert!(moved(near.camera.position, far.camera.position));
    assert!(moved(near.camera.look_at, far.camera.look_at));
    let light = |s: &Scene| s.point_lights[0].position;
    assert!(
        moved(light(&near), light(&far)),
        "{} {}",
        light(&near),
        light(&far)
    );

    let (a, a_se) = bpt_image(&near);
    let (b, b_se) = bpt_image(&far);
    common::reference::compare_images("the room at the origin", 16, (&b, &b_se), (&a, &a_se))
        .assert_agrees("the room at survey coordinates");
}

/// `near` and `far` posed at each of `times` differ by one offset, to a few float steps
/// of the room's size, and each is its own pose at time 0.
fn moves_alike(near: &AnimatedScene, far: &AnimatedScene, times: &[f32]) {
    assert_eq!(near.pose(0.0), near.scene);
    assert_eq!(far.pose(0.0), far.scene);
    let d = moved_by_about_one_offset(&near.scene, &far.scene);
    assert!(d.abs().max_element() <= 0.3, "{d}");
    for &t in times {
        let (a, b) = (near.pose(t), far.pose(t));
        assert_ne!(a.triangles, near.scene.triangles, "nothing moved at {t}");
        let dt = moved_by_about_one_offset(&a, &b);
        assert!((dt - d).abs().max_element() < 1e-6, "t = {t}: {dt} vs {d}");
        let camera_d = b.camera.position - a.camera.position;
        assert!((camera_d - d).abs().max_element() < 1e-6, "t = {t}");
    }
}

#[test]
fn a_keyed_mesh_in_survey_coordinates_moves_as_at_the_origin() {
    let keys = "[[mesh.keyframe]]\ntime = 0.0\n[[mesh.keyframe]]\ntime = 1.0\n\
                translate = [0.075, 0.15, 0.0375]\n\
                [[camera.keyframe]]\ntime = 0.5\n[[camera.keyframe]]\ntime = 2.0\nfov_y = 30\n";
    let dir = tempfile::tempdir().unwrap();
    let scene = |name: &str, at: [f64; 3]| {
        let path = scaled_room_toml(dir.path(), name, at);
        let text = std::fs::read_to_string(&path).unwrap() + keys;
        std::fs::write(&path, text).unwrap();
        load(&path)
    };
    let (near, far) = (scene("near.toml", [0.0; 3]), scene("far.toml", SURVEY));
    moves_alike(&near, &far, &[0.25, 0.5, 1.0, 1.5, 3.0]);
}

#[test]
fn an_obj_sequence_in_survey_coordinates_moves_as_at_the_origin() {
    // Two files of the room, the second 0.15 higher: each written in absolute
    // coordinates, far from the origin in the far sequence.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("room.mtl"), ROOM_MTL).unwrap();
    let scene = |name: &str, [x, y, z]: [f64; 3]| {
        for (k, lift) in [0.0, 0.15].into_iter().enumerate() {
            let file = dir.path().join(format!("{name}_{k}.obj"));
            std::fs::write(file, scaled_room_obj([x, y + lift, z])).unwrap();
        }
        let path = dir.path().join(format!("{name}.toml"));
        let text = format!(
            "[camera]\nposition = [{x}, {}, {}]\nlook_at = [{x}, {}, {z}]\nfov_y = 40\n\
             [[mesh]]\npath = \"{name}_{{}}.obj\"\nsequence = {{ first = 0, last = 1, fps = 1.0 }}\n",
            y + 0.3,
            z - 1.0125,
            y + 0.3,
        );
        std::fs::write(&path, text).unwrap();
        load(&path)
    };
    let (near, far) = (scene("near", [0.0; 3]), scene("far", SURVEY));
    moves_alike(&near, &far, &[0.25, 0.5, 1.0]);
}
