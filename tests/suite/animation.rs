//! Animated scenes from the scene file to the frames: keyframed transforms, OBJ
//! sequences and a keyframed camera load (and bad animation input is refused with the
//! file and the problem); every tracer follows moving geometry; every integrator's
//! frame k of a sequence is bit for bit the still render of the scene posed at time k,
//! with its scene tables moved in place, and a new frame keeps the film; `render
//! --frames` writes the numbered files (frames_cli.rs).

mod frames_cli;

use crate::common;

use std::path::{Path, PathBuf};

use glam::Vec3;
use splitray::integrator::pt::LightTable;
use splitray::integrator::{IntegratorKind, SceneFrame};
use splitray::render::frames::{render_frames, FrameRange, FramesControl};
use splitray::render::{create_integrator, render, RenderError, RenderOptions, RenderOutput};
use splitray::scene::{self, AnimatedScene, Scene};
use splitray::trace::{cpu, GpuTriangle, Hit, Query, Ray, RayQueryTracer, Tracer, TracerKind};

const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");

/// A 4 × 4-quad sheet (32 triangles, with vertex normals where `normals`) standing in
/// the Cornell box, bent by `bend` (mm at its centre line): one file of an OBJ sequence.
fn sheet_obj(bend: f32, normals: bool) -> String {
    let mut obj = String::from("# test sheet\n");
    let n = 5;
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / 4.0, j as f32 / 4.0);
            let z = 420.0 + bend * (std::f32::consts::PI * u).sin();
            obj += &format!("v {} {} {z}\n", 120.0 + 300.0 * u, 80.0 + 300.0 * v);
            let nz = -1.0;
            let nx = bend * std::f32::consts::PI / 300.0 * (std::f32::consts::PI * u).cos();
            if normals {
                obj += &format!("vn {nx} 0 {nz}\n");
            }
        }
    }
    for j in 0..4 {
        for i in 0..4 {
            let a = j * n + i + 1;
            let (b, c, d) = (a + 1, a + n + 1, a + n);
            obj += &match normals {
                true => format!("f {a}//{a} {c}//{c} {b}//{b}\nf {a}//{a} {d}//{d} {c}//{c}\n"),
                false => format!("f {a} {c} {b}\nf {a} {d} {c}\n"),
            };
        }
    }
    obj
}

/// The Cornell room with the short block on keyframes (translated and turned over
/// 0..1 s, after a static rotation), a bending sheet from a 3-file OBJ sequence at
/// 4 files/s, a keyframed camera and a point light.
const SCENE_TOML: &str = r#"
name = "animated-test"

[camera]
look_at = [278.0, 273.0, 0.0]
fov_y = 39.3077

[[camera.keyframe]]
time = 0.0
position = [278.0, 273.0, -800.0]

[[camera.keyframe]]
time = 1.0
position = [330.0, 300.0, -760.0]
look_at = [270.0, 260.0, 10.0]

[[mesh]]
path = "ROOM"

[[mesh]]
path = "BLOCK"
material = "white"
transform = { rotate = { axis = [0.0, 1.0, 0.0], degrees = 3.0 } }

[[mesh.keyframe]]
time = 0.0

[[mesh.keyframe]]
time = 1.0
translate = [30.0, 40.0, 0.0]
rotate = { quaternion = [0.0, 0.0871557, 0.0, 0.9961947] }
scale = [1.0, 1.2, 1.0]

[[mesh]]
path = "sheet_{:02}.obj"
sequence = { first = 0, last = 2, fps = 4.0 }

[[point_light]]
position = [278.0, 500.0, 279.5]
intensity = [20000.0, 20000.0, 20000.0]
"#;

/// Writes the test scene (and its sequence) into `dir`; returns the TOML's path.
fn write_scene(dir: &Path) -> PathBuf {
    for (k, bend) in [0.0, 60.0, -40.0].into_iter().enumerate() {
        std::fs::write(dir.join(format!("sheet_{k:02}.obj")), sheet_obj(bend, true)).unwrap();
    }
    let toml = SCENE_TOML
        .replace("ROOM", &format!("{SCENES}/cornell-room.obj"))
        .replace("BLOCK", &format!("{SCENES}/cornell-short-block.obj"));
    let path = dir.join("animated.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

fn load(dir: &Path) -> AnimatedScene {
    scene::load_animated(write_scene(dir).to_str().unwrap()).unwrap()
}

#[test]
fn the_scene_file_animates_meshes_sequence_and_camera() {
    let dir = tempfile::tempdir().unwrap();
    let a = load(dir.path());
    let room = 12;
    let block = 10;
    assert_eq!(a.scene.triangles.len(), room + block + 32);
    assert_eq!(a.animation.meshes.len(), 2);
    assert_eq!(a.animation.end_time(), Some(1.0));
    // Time 0 is the scene as `load` gives it.
    let still = scene::load(dir.path().join("animated.toml").to_str().unwrap()).unwrap();
    assert_eq!(still, a.scene);
    assert_eq!(a.pose(0.0), a.scene);

    let t1 = a.pose(1.0);
    // The room stands still.
    assert_eq!(t1.triangles[..room], a.scene.triangles[..room]);
    // The block rose by 40 (translation) and grew by 1.2 in y: its top (y = 165 at
    // rest, the static rotation is about y) is now at 165 · 1.2 + 40.
    let top = t1.triangles[room..room + block]
        .iter()
        .flat_map(|t| t.p)
        .map(|p| p.y)
        .fold(f32::MIN, f32::max);
    assert!((top - (165.0 * 1.2 + 40.0)).abs() < 1e-3, "{top}");
    // The sheet is file 0 at t = 0, file 1 at 0.25 s, half way at 0.125 s, file 2 from
    // 0.5 s on; its normals follow.
    let sheet = |s: &Scene| s.triangles[room + block].p[1].z;
    // Vertex 1 of the sheet's first triangle is at u = 1/4 along the bend.
    let z = |bend: f32| 420.0 + bend * (std::f32::consts::PI * 0.25).sin();
    assert_eq!(sheet(&a.pose(0.25)), z(60.0));
    assert!((sheet(&a.pose(0.125)) - 0.5 * (z(0.0) + z(60.0))).abs() < 1e-3);
    assert_eq!(sheet(&t1), z(-40.0));
    assert!(t1.triangles[room + block].n.is_some());
    // The camera moved and holds after its last key.
    assert_eq!(t1.camera.position, Vec3::new(330.0, 300.0, -760.0));
    assert_eq!(a.pose(5.0).camera, t1.camera);
    assert_eq!(a.camera_at(0.5).fov_y, 39.3077);
}

/// `[camera]` is optional where every key gives the whole camera: the keys' headers alone
/// make the table (an implicit one, which has no span of its own in the file).
#[test]
fn a_camera_given_only_by_its_keys_moves_as_with_a_camera_table() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path());
    let with_table = scene::load_animated(path.to_str().unwrap()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let table = "[camera]\nlook_at = [278.0, 273.0, 0.0]\nfov_y = 39.3077\n";
    assert!(text.contains(table));
    let keys_only = text
        .replacen(table, "", 1)
        .replacen(
            "time = 0.0\nposition = [278.0, 273.0, -800.0]\n",
            "time = 0.0\nposition = [278.0, 273.0, -800.0]\nlook_at = [278.0, 273.0, 0.0]\nfov_y = 39.3077\n",
            1,
        )
        .replacen(
            "look_at = [270.0, 260.0, 10.0]\n",
            "look_at = [270.0, 260.0, 10.0]\nfov_y = 39.3077\n",
            1,
        );
    std::fs::write(&path, keys_only).unwrap();
    let without = scene::load_animated(path.to_str().unwrap()).unwrap();
    for t in [0.0, 0.3, 1.0, 2.0] {
        assert_eq!(without.camera_at(t), with_table.camera_at(t), "at {t} s");
    }
    assert_ne!(without.camera_at(0.0), without.camera_at(1.0));
}

/// The shipped example turns the tall block a quarter turn about its own axis.
#[test]
fn the_shipped_animated_cornell_box_turns_its_tall_block_in_place() {
    let a = scene::load_animated(&format!("{SCENES}/cornell-animated.toml")).unwrap();
    let still = scene::load(&format!("{SCENES}/cornell-box.toml")).unwrap();
    assert_eq!(a.scene.bounds(), still.bounds());
    assert_eq!(a.animation.end_time(), Some(2.0));
    let centre = Vec3::new(368.5, 0.0, 351.25);
    let tall = &a.animation.meshes[1];
    let (rest, turned) = (&a.scene.triangles[tall.range.clone()], a.pose(2.0));
    for (r, t) in rest.iter().zip(&turned.triangles[tall.range.clone()]) {
        for (p, q) in r.p.iter().zip(t.p) {
            // A quarter turn about +y: (x, z) − centre goes to (z, −x) − centre.
            let d = *p - centre;
            let want = centre + Vec3::new(d.z, d.y, -d.x);
            assert!(q.abs_diff_eq(want, 1e-3), "{q} vs {want}");
        }
    }
}

/// Writes the test scene with `from` replaced by `to` and loads it; returns the error.
fn load_error(from: &str, to: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path());
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from}");
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
    match scene::load_animated(path.to_str().unwrap()) {
        Ok(_) => panic!("{from} → {to} loaded"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_animation_input_names_the_file_and_the_problem() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "time = 1.0\ntranslate",
            "time = 0.0\ntranslate",
            &[
                "animated.toml:28:",
                "key 1 at time 0 does not come after key 0",
                "must increase",
            ],
        ),
        (
            "time = 1.0\nposition = [330.0",
            "time = -1.0\nposition = [330.0",
            &[
                "animated.toml:12:",
                "[[camera.keyframe]]",
                "key 1 at time -1",
            ],
        ),
        (
            "last = 2",
            "last = 3",
            &[
                "animated.toml:36:",
                "mesh sequence file 'sheet_03.obj' not found",
            ],
        ),
        (
            // A mistyped last file: named at the first missing file, without first
            // making the names of four billion.
            "last = 2",
            "last = 4000000000",
            &[
                "animated.toml:36:",
                "mesh sequence file 'sheet_03.obj' not found",
            ],
        ),
        (
            "first = 0, last = 2",
            "first = 2, last = 0",
            &["last file 0 comes before first file 2"],
        ),
        (
            "fps = 4.0",
            "fps = 0.0",
            &["fps 0 must be a positive number"],
        ),
        (
            "sequence = { first = 0, last = 2, fps = 4.0 }",
            "",
            &["animated.toml:35:", "a numbered path needs sequence"],
        ),
        (
            "path = \"sheet_{:02}.obj\"",
            "path = \"sheet_{:2}.obj\"",
            &["{:0N}"],
        ),
        (
            "degrees = 3.0 }",
            "degrees = 3.0, quaternion = [0.0, 0.0, 0.0, 1.0] }",
            &[
                "animated.toml:23:",
                "either axis = [x, y, z] and degrees",
                "or quaternion",
            ],
        ),
        (
            "quaternion = [0.0, 0.0871557, 0.0, 0.9961947]",
            "quaternion = [0.0, 0.0, 0.0, 0.0]",
            &["keyframe 1", "quaternion", "must be finite and non-zero"],
        ),
        (
            "scale = [1.0, 1.2, 1.0]",
            "scale = [1.0, -1.2, 1.0]",
            &[
                "keyframe 1",
                "other signs than keyframe 0",
                "passes through zero size",
            ],
        ),
        (
            "time = 0.0\nposition = [278.0, 273.0, -800.0]",
            "time = 0.0",
            &["camera keyframe 0 needs 'position'"],
        ),
        (
            "look_at = [270.0, 260.0, 10.0]",
            "look_at = [330.0, 300.0, -760.0]",
            &[
                "invalid camera",
                "camera keyframe 1",
                "same point as position",
            ],
        ),
    ];
    for (from, to, wants) in cases {
        let e = load_error(from, to);
        for want in *wants {
            assert!(e.contains(want), "{from} → {to}: missing {want:?} in: {e}");
        }
    }
}

#[test]
fn a_sequence_file_with_other_triangles_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path());
    let mut fewer = sheet_obj(10.0, true);
    fewer.truncate(fewer.rfind("f ").unwrap());
    std::fs::write(dir.path().join("sheet_01.obj"), fewer).unwrap();
    let e = scene::load_animated(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    for want in [
        "animated.toml:36:",
        "'sheet_01.obj' has 31 triangles (93 vertices) but 'sheet_00.obj' has 32",
        "same faces in the same order",
    ] {
        assert!(e.contains(want), "missing {want:?} in: {e}");
    }
    // Normals on some files and not on others.
    std::fs::write(dir.path().join("sheet_01.obj"), sheet_obj(10.0, false)).unwrap();
    let e = scene::load_animated(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("has vertex normals on 0 triangles"), "{e}");
    // As many triangles, but the first quad split along its other diagonal.
    let other_diagonal = sheet_obj(10.0, true).replace(
        "f 1//1 7//7 2//2\nf 1//1 6//6 7//7\n",
        "f 1//1 6//6 2//2\nf 2//2 6//6 7//7\n",
    );
    assert_ne!(other_diagonal, sheet_obj(10.0, true));
    std::fs::write(dir.path().join("sheet_01.obj"), other_diagonal).unwrap();
    let e = scene::load_animated(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'sheet_01.obj' joins its vertices into faces otherwise than 'sheet_00.obj'"),
        "{e}"
    );
}

fn options(scene: &Scene, integrator: IntegratorKind, tracer: TracerKind) -> RenderOptions {
    let mut o = RenderOptions::resolve(
        scene,
        Some(20),
        Some(16),
        Some(2),
        Some(7),
        Some(integrator),
        Some(tracer),
    )
    .unwrap();
    o.max_depth = 4;
    o
}

/// Renders `range` of `a` as a sequence.
fn frames(
    gpu: &splitray::vk::Gpu,
    a: &AnimatedScene,
    options: &RenderOptions,
    range: &FrameRange,
) -> Vec<(u32, usize, RenderOutput)> {
    let mut out = Vec::new();
    let run = render_frames(
        gpu,
        a,
        options,
        range,
        FramesControl {
            progress: &mut |_, _| {},
            stop: &|| false,
            frame_done: &mut |f| {
                out.push((f.index, f.changed_triangles, f.output));
                Ok::<(), RenderError>(())
            },
        },
    )
    .unwrap();
    assert_eq!((run.frames, run.stopped), (range.len(), false));
    out
}

fn bits3(v: &[[f32; 3]]) -> Vec<[u32; 3]> {
    v.iter().map(|p| p.map(f32::to_bits)).collect()
}

/// The image and its AOVs, bit for bit.
fn assert_same_image(a: &RenderOutput, b: &RenderOutput, what: &str) {
    assert_eq!(
        bits3(&a.film.mean_rgb_buffer()),
        bits3(&b.film.mean_rgb_buffer()),
        "{what}: rgb"
    );
    assert_eq!(a.sums.passes, b.sums.passes, "{what}");
    let depth = |o: &RenderOutput| -> Vec<u32> {
        o.film
            .depth
            .as_ref()
            .unwrap()
            .iter()
            .map(|d| d.to_bits())
            .collect()
    };
    assert_eq!(depth(a), depth(b), "{what}: depth");
    assert_eq!(
        a.film.triangle_id, b.film.triangle_id,
        "{what}: triangle ids"
    );
    assert_eq!(
        bits3(a.film.normal.as_ref().unwrap()),
        bits3(b.film.normal.as_ref().unwrap()),
        "{what}: normals"
    );
    assert_eq!(
        a.record.fingerprint, b.record.fingerprint,
        "{what}: fingerprint"
    );
    assert_eq!(a.stats.rays_traced, b.stats.rays_traced, "{what}: rays");
}

/// Frame k of a sequence against the still render at time k, for every integrator
/// (PDACRT, which moves its triangles in place), and for every tracer (on `primary`).
/// Frames at 2/s: 0 s, 0.5 s (the sheet at its last file), 1 s (the block at its last
/// key) and 1.5 s (nothing moves any more: no triangle is uploaded).
#[test]
fn every_frame_is_the_still_render_of_the_posed_scene() {
    let gpu = common::gpu();
    let dir = tempfile::tempdir().unwrap();
    let a = load(dir.path());
    let range = FrameRange::parse("0..4", 2.0).unwrap();
    let mut runs: Vec<(IntegratorKind, TracerKind)> = IntegratorKind::ALL
        .iter()
        .filter(|(k, _)| k.animates())
        .map(|(k, _)| (*k, TracerKind::Pdacrt))
        .collect();
    for (tracer, _) in TracerKind::ALL {
        if *tracer == TracerKind::Pdacrt || (*tracer == TracerKind::RayQuery && !gpu.ray_query()) {
            continue;
        }
        runs.push((IntegratorKind::Primary, *tracer));
    }
    for (integrator, tracer) in runs {
        let options = options(&a.scene, integrator, tracer);
        let sequence = frames(&gpu, &a, &options, &range);
        let uploaded: Vec<usize> = sequence.iter().map(|(_, n, _)| *n).collect();
        assert_eq!(uploaded, vec![0, 42, 10, 0], "{integrator}");
        for (k, _, frame) in &sequence {
            let posed = a.pose(range.time(*k));
            let still = render(&gpu, &posed, &options, &mut |_| {}).unwrap();
            let what = format!("{integrator} on {tracer}, frame {k}");
            assert_same_image(frame, &still, &what);
            assert!(frame
                .metadata
                .extra
                .contains(&("frame".into(), k.to_string())));
        }
        // The frames differ: the scene moved.
        assert_ne!(
            sequence[0].2.film.mean_rgb_buffer(),
            sequence[2].2.film.mean_rgb_buffer(),
            "{integrator}"
        );
    }
    common::assert_clean(&gpu);
}

/// A new frame writes the integrators' GPU tables in place: nothing is allocated. The
/// light vertex cache of `lvc-bdpt` and `cis-lbdpt` is sized by a prepass on the posed
/// scene, as a still render of it would be: it grows when the pose makes more cache
/// vertices per light path than any before (the frame at 0.7 s does here), and a frame
/// that needs no more slots than it holds — back to time 0 — allocates nothing.
#[test]
fn a_new_frame_allocates_nothing() {
    let gpu = common::gpu();
    let dir = tempfile::tempdir().unwrap();
    let a = load(dir.path());
    for integrator in [
        IntegratorKind::Primary,
        IntegratorKind::Pt,
        IntegratorKind::LvcBdpt,
        IntegratorKind::CisLbdpt,
        IntegratorKind::Cbpt,
    ] {
        let options = options(&a.scene, integrator, TracerKind::Pdacrt);
        let mut it = create_integrator(&gpu, &a.scene, &options).unwrap();
        let mut posed = a.scene.clone();
        let mut t = 0.0;
        for next in [0.7, 0.0] {
            it.render_passes(0, 1).unwrap();
            gpu.wait_idle().unwrap();
            let before = gpu.memory_bytes().0;
            let changed = a.advance(&mut posed, t, next);
            t = next;
            assert!(!changed.is_empty());
            let triangles = posed.gpu_triangles();
            it.set_frame(&SceneFrame {
                scene: &posed,
                triangles: &triangles,
                changed: &changed,
                camera: posed.camera.frame(options.width, options.height),
            })
            .unwrap();
            gpu.wait_idle().unwrap();
            let cache_grows = next == 0.7
                && matches!(
                    integrator,
                    IntegratorKind::LvcBdpt | IntegratorKind::CisLbdpt
                );
            if !cache_grows {
                assert_eq!(gpu.memory_bytes().0, before, "{integrator} at {next} s");
            }
        }
    }
    common::assert_clean(&gpu);
}

/// A new frame keeps the film, second moments included. They are summed at the
/// brightness scale, which a point light decides by the radiance I / r² it gives at the
/// scene's radius r: a frame that changes the radius rewrites them at the new scale.
#[test]
fn a_frame_that_changes_the_brightness_scale_keeps_the_film() {
    let gpu = common::gpu();
    let mut room = scene::builtin("cornell-box").unwrap();
    room.point_lights.push(scene::PointLight {
        position: Vec3::new(278.0, 400.0, 279.0),
        intensity: Vec3::splat(1e9),
    });
    // A block's triangle eight times as far from the origin: the radius grows several
    // times, and the point light, still the brightest emitter, counts as dimmer.
    let mut posed = room.clone();
    let moved = 10;
    posed.triangles[moved].p = posed.triangles[moved].p.map(|p| p * 8.0);
    let scale = |s: &Scene| LightTable::new(s).brightness_scale(s.bounds().radius());
    assert!(scale(&posed) > scale(&room));
    let triangles = posed.gpu_triangles();
    for integrator in [
        IntegratorKind::Pt,
        IntegratorKind::LvcBdpt,
        IntegratorKind::CisLbdpt,
    ] {
        let options = options(&room, integrator, TracerKind::Pdacrt);
        let mut it = create_integrator(&gpu, &room, &options).unwrap();
        it.render_passes(0, 2).unwrap();
        let kept = it.sums().unwrap();
        assert!(kept.stderr().unwrap().iter().flatten().any(|&v| v > 0.0));
        it.set_frame(&SceneFrame {
            scene: &posed,
            triangles: &triangles,
            changed: std::slice::from_ref(&(moved..moved + 1)),
            camera: posed.camera.frame(options.width, options.height),
        })
        .unwrap();
        assert!(it.sums().unwrap() == kept, "{integrator}: the film changed");
    }
    common::assert_clean(&gpu);
}

fn primary_rays(scene: &Scene) -> Vec<Ray> {
    let frame = scene.camera.frame(24, 24);
    (0..24 * 24)
        .map(|i| {
            Ray::new(
                frame.origin,
                frame.pixel_center_direction(i % 24, i / 24),
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

/// Every tracer — and ray-query refitting its BLAS — traces the moved triangles after
/// `update_geometry`, as brute force on the CPU does.
#[test]
fn every_tracer_follows_moving_geometry() {
    let gpu = common::gpu();
    let dir = tempfile::tempdir().unwrap();
    let a = load(dir.path());
    let gpu_tris = |s: &Scene| -> Vec<GpuTriangle> { s.gpu_triangles() };
    let mut tracers: Vec<(String, Box<dyn Tracer>)> = TracerKind::ALL
        .iter()
        .filter(|(k, _)| *k != TracerKind::RayQuery || gpu.ray_query())
        .map(|(k, _)| {
            (
                k.name().to_string(),
                k.create(&gpu, &gpu_tris(&a.scene)).unwrap(),
            )
        })
        .collect();
    if gpu.ray_query() {
        let refit = RayQueryTracer::refitting(&gpu, &gpu_tris(&a.scene)).unwrap();
        tracers.push(("ray-query refit".into(), Box::new(refit)));
    }
    let mut posed = a.scene.clone();
    let mut t = 0.0;
    for next in [0.3f32, 0.9, 2.0] {
        let changed = a.advance(&mut posed, t, next);
        t = next;
        let triangles = gpu_tris(&posed);
        let rays = primary_rays(&posed);
        let want = cpu::closest_hits(&rays, &triangles);
        let ray_buffer = gpu.upload("rays", &rays).unwrap();
        let hits = gpu.zeroed::<Hit>("hits", rays.len()).unwrap();
        for (name, tracer) in &mut tracers {
            tracer.update_geometry(&triangles, &changed).unwrap();
            let done = tracer
                .trace(
                    &ray_buffer,
                    &hits,
                    rays.len() as u32,
                    Query::ClosestHit,
                    &[],
                )
                .unwrap();
            gpu.wait(&done).unwrap();
            let got = hits.read::<Hit>().unwrap();
            let wrong = got
                .iter()
                .zip(&want)
                .filter(|(g, w)| !cpu::same_hit(g, w, 1e-5, true))
                .count();
            assert_eq!(
                wrong,
                0,
                "{name} at t = {t}: {wrong} of {} hits",
                rays.len()
            );
        }
    }
    common::assert_clean(&gpu);
}

/// `bench dynamic` verifies every tracer's hits on every frame of a moving scene (its
/// times are measured by the benchmark, not here).
#[test]
fn bench_dynamic_verifies_every_tracer_on_every_frame() {
    use splitray::bench::dynamic::{self, Contender, DynamicBenchOptions};
    use splitray::bench::workloads::Workload;
    let gpu = common::gpu();
    let dir = tempfile::tempdir().unwrap();
    let a = load(dir.path());
    let opts = DynamicBenchOptions {
        width: 24,
        height: 16,
        frames: 2,
        fps: 3.0,
        workloads: vec![Workload::Primary, Workload::Shadow],
        verify_rays: 64,
        ..Default::default()
    };
    let report = dynamic::run(&gpu, &a, &opts).unwrap();
    assert_eq!(report.frames, 1..3);
    assert_eq!(report.moved_triangles, 42.0);
    let expected = Contender::ALL.len() - report.skipped.len();
    for w in &report.workloads {
        assert_eq!(w.rows.len(), expected);
        for r in &w.rows {
            assert_eq!(r.mismatches, 0);
            // The warm-up frame and 2 timed frames, 64 rays of each of 2 workloads.
            assert_eq!(r.verified_rays, 3 * 2 * 64, "{:?}", r.tracer);
            assert_eq!(r.frames_ms.len(), 2);
        }
    }
    let text = report.to_string();
    assert!(text.contains("target pdacrt frame time / ray-query") || !gpu.ray_query());
    let still = scene::load_animated("cornell-box").unwrap();
    let e = dynamic::run(&gpu, &still, &opts).unwrap_err().to_string();
    assert!(e.contains("does not move"), "{e}");
    common::assert_clean(&gpu);
}
