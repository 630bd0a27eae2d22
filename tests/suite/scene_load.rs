//! Scene loading: good inputs, every kind of bad input, built-ins, the bunny.

use std::path::{Path, PathBuf};

use glam::Vec3;
use splitray::scene::{self, builtin, builtin_names, obj, Scene};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn load_err(path: &Path) -> String {
    match scene::load(path.to_str().unwrap()) {
        Ok(_) => panic!("{} loaded but should fail", path.display()),
        Err(e) => e.to_string(),
    }
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(
            msg.contains(p),
            "error message {msg:?} should contain {p:?}"
        );
    }
}

const TRI_OBJ: &str =
    "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl red\nf 1 2 3\nf 2 4 3\n";
const TRI_MTL: &str = "newmtl red\nKd 0.6 0.1 0.1\nKs 0.2 0.2 0.2\nNs 20\nNi 1.4\nd 1\nillum 2\n\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n";

const GOOD_TOML: &str = r#"
[camera]
position = [0.5, 0.5, 3]
look_at  = [0.5, 0.5, 0.0]
up       = [0.0, 1.0, 0.0]
fov_y    = 40
[film]
width = 320
height = 200
[[mesh]]
path = "meshes/tri.obj"
[[mesh]]
path = "meshes/tri.obj"
material = "lamp"
transform = { scale = 2.0, translate = [0.0, 0.0, -1.0] }
[[material]]
name = "red"
ior = 1.6
[[material]]
name = "mirror"
specular = [1, 1, 1]
[[point_light]]
position = [0, 2, 2]
intensity = [10, 10, 10]
[render]
spp = 16
seed = 7
integrator = "path"
tracer = "pdacrt"
max_depth = 5
"#;

fn good_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    write(&dir.path().join("meshes"), "tri.obj", TRI_OBJ);
    write(&dir.path().join("meshes"), "tri.mtl", TRI_MTL);
    dir
}

#[test]
fn good_toml_loads_with_relative_paths() {
    let dir = good_dir();
    let p = write(dir.path(), "good.toml", GOOD_TOML);
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.name, "good");
    assert_eq!(s.triangles.len(), 4);
    assert_eq!((s.film.width, s.film.height), (320, 200));
    assert_eq!(s.camera.fov_y, 40.0);
    // First mesh keeps its MTL material, with the TOML override of ior applied.
    let red = &s.materials[s.triangles[0].material as usize];
    assert_eq!(red.name, "red");
    assert_eq!(red.diffuse, Vec3::new(0.6, 0.1, 0.1));
    assert_eq!(red.ior, 1.6);
    assert_eq!(red.illum, 2);
    // Second mesh: material override to the MTL's emissive "lamp", transformed.
    let lamp = &s.materials[s.triangles[2].material as usize];
    assert_eq!(lamp.name, "lamp");
    assert_eq!(lamp.emission, Vec3::splat(5.0));
    assert_eq!(s.triangles[2].p[1], Vec3::new(2.0, 0.0, -1.0));
    assert_eq!(s.emissive_triangle_count(), 2);
    // A new material from [[material]] with defaults elsewhere.
    let mirror = &s.materials[s.material_index("mirror").unwrap() as usize];
    assert_eq!(mirror.specular, Vec3::ONE);
    assert_eq!(mirror.diffuse, Vec3::splat(0.8));
    assert_eq!(s.point_lights.len(), 1);
    assert_eq!(s.settings.spp, Some(16));
    assert_eq!(s.settings.seed, Some(7));
    assert_eq!(s.settings.integrator.as_deref(), Some("path"));
    assert_eq!(s.settings.tracer.as_deref(), Some("pdacrt"));
    assert_eq!(s.settings.max_depth, Some(5));
    // As on the command line, -1 is unbounded: the default.
    let unbounded = GOOD_TOML.replace("max_depth = 5", "max_depth = -1");
    let p = write(dir.path(), "unbounded.toml", &unbounded);
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.settings.max_depth, None);
}

#[test]
fn minimal_toml_and_obj_without_material() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let p = write(dir.path(), "min.toml", "[[mesh]]\npath = \"m.obj\"\n");
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.triangles.len(), 1);
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.materials[0].name, obj::DEFAULT_MATERIAL_NAME);
    assert_eq!(s.materials[0].diffuse, Vec3::splat(0.8));
    assert_eq!((s.film.width, s.film.height), (512, 512));
    // Framing camera looks at the centre from +z.
    assert_eq!(s.camera.look_at, s.bounds().center());
    assert!(s.camera.position.z > 0.0);
}

#[test]
fn toml_errors_have_line_and_column() {
    let dir = good_dir();
    let bad = GOOD_TOML.replace("fov_y    = 40", "fov = 40");
    let p = write(dir.path(), "typo.toml", &bad);
    // Line 6 of GOOD_TOML (it starts with a newline).
    assert_has(&load_err(&p), &["typo.toml:6:1", "unknown field 'fov'"]);

    let p = write(dir.path(), "syntax.toml", "[camera\nposition = 1\n");
    assert_has(&load_err(&p), &["syntax.toml:1:"]);

    let p = write(
        dir.path(),
        "type.toml",
        "[film]\nwidth = \"wide\"\nheight = 4\n",
    );
    assert_has(&load_err(&p), &["type.toml:2:", "string"]);

    let p = write(
        dir.path(),
        "nomesh.toml",
        "[[mesh]]\npath = \"meshes/nothere.obj\"\n",
    );
    assert_has(
        &load_err(&p),
        &["nomesh.toml:2:8", "mesh 'meshes/nothere.obj' not found"],
    );

    let p = write(
        dir.path(),
        "badmat.toml",
        "[[mesh]]\npath = \"meshes/tri.obj\"\nmaterial = \"gold\"\n",
    );
    assert_has(
        &load_err(&p),
        &["badmat.toml:3:", "unknown material 'gold'", "red"],
    );

    let p = write(dir.path(), "empty.toml", "name = \"nothing\"\n");
    assert_has(&load_err(&p), &["empty.toml", "empty scene"]);

    let p = write(
        dir.path(),
        "scale.toml",
        "[[mesh]]\npath = \"meshes/tri.obj\"\ntransform = { scale = 0 }\n",
    );
    assert_has(&load_err(&p), &["scale.toml:3:", "non-zero"]);

    let p = write(
        dir.path(),
        "nanlight.toml",
        "[[mesh]]\npath = \"meshes/tri.obj\"\n[[point_light]]\nposition = [nan, 0, 0]\nintensity = [1, 1, 1]\n",
    );
    assert_has(
        &load_err(&p),
        &["nanlight.toml:4:", "point light 0 position is not finite"],
    );

    let p = write(
        dir.path(),
        "darklight.toml",
        "[[mesh]]\npath = \"meshes/tri.obj\"\n[[point_light]]\nposition = [0, 0, 1]\nintensity = [1, -2, 1]\n",
    );
    assert_has(
        &load_err(&p),
        &[
            "darklight.toml:5:",
            "point light 0 intensity [1, -2, 1] is negative",
        ],
    );

    // A [[material]] table's values are checked at their lines too.
    for (i, (line, expect)) in [
        (
            "diffuse = [-1, 2, 1]",
            "material 'red' diffuse [-1, 2, 1] is negative",
        ),
        (
            "diffuse = [0.5, 1.2, 0.5]",
            "material 'red' diffuse [0.5, 1.2, 0.5] is more than 1: a surface cannot reflect",
        ),
        (
            "specular = [1.5, 1, 1]",
            "material 'red' specular [1.5, 1, 1] is more than 1",
        ),
        (
            "emission = [1, inf, 1]",
            "material 'red' emission is not finite",
        ),
        ("dissolve = nan", "material 'red' dissolve is not finite"),
    ]
    .into_iter()
    .enumerate()
    {
        let name = format!("material{i}.toml");
        let text =
            format!("[[mesh]]\npath = \"meshes/tri.obj\"\n[[material]]\nname = \"red\"\n{line}\n");
        let p = write(dir.path(), &name, &text);
        assert_has(&load_err(&p), &[&format!("{name}:5:"), expect]);
    }

    // A mesh loaded twice brings its materials twice; the list of known names has each once.
    let p = write(
        dir.path(),
        "twice.toml",
        "[[mesh]]\npath = \"meshes/tri.obj\"\n[[mesh]]\npath = \"meshes/tri.obj\"\nmaterial = \"gold\"\n",
    );
    assert_has(&load_err(&p), &["twice.toml:5:", "(known: red, lamp)"]);

    // [render] is checked when the file is read, even where the command line would
    // override it: each bad value is reported at its line.
    for (i, (line, expect)) in [
        ("spp = 0", "spp must be at least 1"),
        ("integrator = \"gpu\"", "unknown integrator 'gpu'"),
        ("tracer = \"gpu\"", "unknown tracer 'gpu'"),
        (
            "max_depth = -2",
            "max_depth -2: expected -1 (unbounded) or a depth from 0 to",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let name = format!("render{i}.toml");
        let text = format!("[[mesh]]\npath = \"meshes/tri.obj\"\n[render]\n{line}\n");
        let p = write(dir.path(), &name, &text);
        assert_has(&load_err(&p), &[&format!("{name}:4:"), expect]);
    }
}

#[test]
fn camera_and_film_errors_name_the_file() {
    let dir = good_dir();
    let cases = [
        (
            "fov_y    = 40",
            "fov_y    = 180",
            "fov_y 180 is outside (0, 180)",
        ),
        (
            "fov_y    = 40",
            "fov_y    = 0",
            "fov_y 0 is outside (0, 180)",
        ),
        (
            "look_at  = [0.5, 0.5, 0.0]",
            "look_at  = [0.5, 0.5, 3]",
            "same point as position",
        ),
        (
            "look_at  = [0.5, 0.5, 0.0]",
            "look_at  = [0.5, 0.5, 2.9999995]",
            "too close to position",
        ),
        (
            "up       = [0.0, 1.0, 0.0]",
            "up       = [0.0, 0.0, 0.0]",
            "up is the zero vector",
        ),
        (
            "up       = [0.0, 1.0, 0.0]",
            "up       = [0.0, 0.0, 1.0]",
            "parallel to the view direction",
        ),
        ("width = 320", "width = 0", "width 0 is outside 1..=16384"),
        (
            "height = 200",
            "height = 20000",
            "height 20000 is outside 1..=16384",
        ),
    ];
    for (i, (from, to, want)) in cases.iter().enumerate() {
        let text = GOOD_TOML.replace(from, to);
        assert_ne!(text, GOOD_TOML);
        let name = format!("cam{i}.toml");
        let p = write(dir.path(), &name, &text);
        let e = load_err(&p);
        assert_has(&e, &[&name, want]);
        // The table's line is named too.
        assert!(e.contains(&format!("{name}:")), "{e}");
    }
}

#[test]
fn missing_files() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("gone.toml");
    assert_has(&load_err(&p), &["gone.toml", "cannot read file"]);
    let p = dir.path().join("gone.obj");
    assert_has(&load_err(&p), &["gone.obj", "cannot read file"]);
    let p = write(
        dir.path(),
        "nomtl.obj",
        "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert_has(
        &load_err(&p),
        &["nomtl.obj:1", "material library 'missing.mtl' not found"],
    );
    let e = scene::load("no-such-scene").unwrap_err().to_string();
    assert_has(&e, &["no-such-scene", "cornell-box", "fixture"]);
}

/// A referenced file that is there but cannot be read (a folder, a name the file system
/// refuses) is named with the line that refers to it: the mistake may be that line's.
#[test]
fn unreadable_references_name_the_line_that_refers_to_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("lib.mtl")).unwrap();
    std::fs::create_dir(d.join("folder.obj")).unwrap();
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    // An empty name would have been the OBJ's own folder.
    let p = write(d, "bare.obj", &format!("# lib\nmtllib \n{tri}"));
    assert_has(
        &load_err(&p),
        &["bare.obj:2", "mtllib without a material library name"],
    );
    let p = write(d, "folder-lib.obj", &format!("mtllib lib.mtl\n{tri}"));
    assert_has(
        &load_err(&p),
        &[
            "folder-lib.obj:1: material library ",
            "lib.mtl cannot be read: it is a folder, not a regular file",
        ],
    );
    let p = write(d, "nul.obj", &format!("mtllib cornell\0box.mtl\n{tri}"));
    assert_has(
        &load_err(&p),
        &[
            "nul.obj:1: material library ",
            "cornell\0box.mtl cannot be read: file name contained an unexpected NUL byte",
        ],
    );
    let p = write(d, "folder.toml", "[[mesh]]\npath = \"folder.obj\"\n");
    assert_has(
        &load_err(&p),
        &[
            "folder.toml:2:8: mesh ",
            "folder.obj cannot be read: it is a folder, not a regular file",
        ],
    );
}

#[test]
fn malformed_obj_and_mtl() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "v 0 0 0\nv 1 0\nf 1 2 1\n",
            "m1.obj",
            &["m1.obj:2", "vertex position needs 3 numbers"],
        ),
        (
            "v 0 0 0\nv 1 0 x\n",
            "m2.obj",
            &["m2.obj:2", "'x' is not a number"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n",
            "m3.obj",
            &["m3.obj:4", "not an index"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nf 1 2\n",
            "m4.obj",
            &["m4.obj:3", "face 1 has 2 vertices"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 inf\nf 1//1 2//1 3//1\n",
            "m5.obj",
            &["m5.obj:4", "normal 1 is not finite"],
        ),
        (
            "v 0 0 0\nv 1 0 0 0.5 0.5\n",
            "m6.obj",
            &[
                "m6.obj:2",
                "vertex 2 has 5 numbers: expected x y z, x y z w or x y z r g b",
            ],
        ),
    ];
    for (text, name, want) in cases {
        let p = write(dir.path(), name, text);
        assert_has(&load_err(&p), want);
    }
    let obj = "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    for (mtl, want) in [
        ("newmtl a\nKd 0.5\n", "bad.mtl:2: Kd needs 3 numbers"),
        (
            "newmtl a\nKd 0.5 0.5 0.5\nNs high\n",
            "bad.mtl:3: Ns: 'high' is not a number",
        ),
        ("newmtl a\nKe 1 nan 1\n", "bad.mtl:2: Ke is not finite"),
        ("newmtl a\nillum x\n", "bad.mtl:2: illum needs an integer"),
        (
            "newmtl a\nKd -1 2 1\n",
            "bad.mtl:2: Kd [-1, 2, 1] is negative",
        ),
        (
            "newmtl a\nKd 0.5 0.5 0.5\nKs 1 1.01 1\n",
            "bad.mtl:3: Ks [1, 1.01, 1] is more than 1: a surface cannot reflect",
        ),
        // Ke is emission, and Ka is not used: neither is a reflectance.
        (
            "newmtl a\nKe 5 5 5\nKa 2 2 2\nKd 2 0 0\n",
            "bad.mtl:4: Kd [2, 0, 0] is more than 1",
        ),
    ] {
        write(dir.path(), "bad.mtl", mtl);
        let p = write(dir.path(), "usesbad.obj", obj);
        assert_has(&load_err(&p), &[want]);
    }
}

/// The triangles' corners and material names of a loaded scene.
fn geometry_and_materials(path: &Path) -> (Vec<[Vec3; 3]>, Vec<String>) {
    let s = scene::load(path.to_str().unwrap()).unwrap();
    let names = s
        .triangles
        .iter()
        .map(|t| s.materials[t.material as usize].name.clone());
    (s.triangles.iter().map(|t| t.p).collect(), names.collect())
}

/// Forms of OBJ that `tobj` alone reads otherwise than the format means load as the
/// plain form of the same file does.
#[test]
fn obj_forms_load_as_the_plain_form() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "a.mtl", "newmtl a\nKd 0.1 0.2 0.3\n");
    write(dir.path(), "b.mtl", "\u{feff}newmtl b\nKd 0.4 0.5 0.6\n");
    let plain = write(
        dir.path(),
        "plain.obj",
        "mtllib a.mtl\nmtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0\n\
         usemtl a\nf 1/1 2/1 3/1\nusemtl b\nf 2 4 3\n",
    );
    let want = geometry_and_materials(&plain);
    assert_eq!(want.1, ["a", "b"]);
    let forms = [
        (
            "a byte-order mark",
            "\u{feff}mtllib a.mtl\nmtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
             vt 0.5 0\nusemtl a\nf 1/1 2/1 3/1\nusemtl b\nf 2 4 3\n",
        ),
        (
            "two libraries on one line",
            "mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0\n\
             usemtl a\nf 1/1 2/1 3/1\nusemtl b\nf 2 4 3\n",
        ),
        (
            "libraries after the usemtl naming them",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0\nusemtl a\nf 1/1 2/1 3/1\n\
             mtllib a.mtl\nusemtl b\nf 2 4 3\nmtllib b.mtl\n",
        ),
        (
            "trailing comments, a one-number vt and colours on some vertices",
            "mtllib a.mtl b.mtl\nv 0 0 0 1 0 0 # red\nv 1 0 0\nv 0 1 0 0 1 0\n\
             v 1 1 0 # fourth\nvt 0.5\nusemtl a\nf 1/1 2/1 3/1 # first\nusemtl b\nf 2 4 3\n",
        ),
        (
            "lines continued by a backslash, and a comment ending in one",
            "mtllib a.mtl\nmtllib b.mtl\n# C:\\models\\\nv 0 0 0\nv 1 0 \\\n 0\nv 0 1 0\nv 1 1 0\n\
             vt 0.5 0\nusemtl a\nf 1/1 \\\n 2/1 \\\n3/1\nusemtl b\nf 2 4 3 \\\n",
        ),
    ];
    for (what, text) in forms {
        let p = write(dir.path(), "form.obj", text);
        assert_eq!(geometry_and_materials(&p), want, "{what}");
    }
    // A name with a space is one library where that file exists.
    write(
        dir.path(),
        "a b.mtl",
        "newmtl a\nKd 0.1 0.2 0.3\nnewmtl b\nKd 0.4 0.5 0.6\n",
    );
    let p = write(
        dir.path(),
        "spaced.obj",
        "mtllib a b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl a\nf 1 2 3\n\
         usemtl b\nf 2 4 3\n",
    );
    assert_eq!(
        geometry_and_materials(&p),
        want,
        "a library named with a space"
    );
}

#[test]
fn lines_after_a_continued_line_keep_their_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "wrapped.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 \\\n 3\nv 0 NaN 0\n",
    );
    assert_has(&load_err(&p), &["wrapped.obj:7", "vertex 4 is not finite"]);
}

#[test]
fn non_finite_coordinates_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "nan.obj",
        "v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n",
    );
    assert_has(
        &load_err(&p),
        &["nan.obj:3", "vertex 3 is not finite", "NaN"],
    );
    let p = write(
        dir.path(),
        "inf.obj",
        "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert_has(&load_err(&p), &["inf.obj:2", "vertex 2 is not finite"]);
    // Built-in/TOML geometry is checked after loading too: the triangle is named.
    let mut s = builtin("cornell-box").unwrap();
    s.triangles[5].p[1].x = f32::NAN;
    let e = scene::validate::validate_scene(&s, &scene::Location::file("x"))
        .unwrap_err()
        .to_string();
    assert_has(&e, &["x: triangle 5 vertex 1 is not finite"]);
}

#[test]
fn out_of_range_indices_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let verts = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: &[(&str, &[&str])] = &[
        (
            "f 1 2 3\nf 1 2 99\n",
            &[":5: face 2 references vertex 99 but the file has 3 vertices"],
        ),
        (
            "f 1 2 -4\n",
            &[":4: face 1 references vertex -4 but the file has 3 vertices"],
        ),
        ("f 0 1 2\n", &[":4: face 1: vertex index 0 is invalid"]),
        (
            "vt 0 0\nf 1/1 2/2 3/1\n",
            &[":5: face 1 references texcoord 2 but the file has 1 texcoord"],
        ),
        (
            "f 1//5 2//5 3//5\n",
            &[":4: face 1 references normal 5 but the file has 0 normals"],
        ),
        ("f 1/-9 2 3\n", &["references texcoord -9"]),
        ("f 1 2 99999999999999999999999\n", &["not an index"]),
    ];
    for (i, (faces, want)) in cases.iter().enumerate() {
        let name = format!("idx{i}.obj");
        let p = write(dir.path(), &name, &format!("{verts}{faces}"));
        let e = load_err(&p);
        assert_has(&e, &[&name]);
        assert_has(&e, want);
    }
}

#[test]
fn degenerate_and_empty() {
    let dir = tempfile::tempdir().unwrap();
    // One good triangle and one degenerate: kept, counted.
    let p = write(
        dir.path(),
        "some.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n",
    );
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.stats().degenerate_triangles, 1);
    // All degenerate: error.
    let p = write(
        dir.path(),
        "flat.obj",
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 1\n",
    );
    assert_has(
        &load_err(&p),
        &["flat.obj", "empty scene", "all 2 triangles", "degenerate"],
    );
    // No faces at all.
    let p = write(dir.path(), "nofaces.obj", "v 0 0 0\nv 1 0 0\n");
    assert_has(&load_err(&p), &["nofaces.obj", "empty scene"]);
}

fn project(s: &Scene, p: Vec3) -> (f32, f32) {
    // Inverse of CameraFrame::direction: d = forward + sx·right + sy·up.
    let f = s.camera_frame();
    let d = p - f.origin;
    let z = d.dot(f.forward);
    let sx = d.dot(f.right) / (z * f.right.length_squared());
    let sy = d.dot(f.up) / (z * f.up.length_squared());
    let x = (sx + 1.0) * 0.5 * f.width as f32;
    let y = (1.0 - sy) * 0.5 * f.height as f32;
    // Sanity: the projection inverts direction().
    let back = f.direction(x, y);
    assert!((back - d.normalize()).length() < 1e-3);
    (x, y)
}

#[test]
fn builtin_cornell_box() {
    let names: Vec<&str> = builtin_names().iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["cornell-box", "fixture", "lamps", "waves", "swarm"]);
    let s = scene::load("cornell-box").unwrap();
    let stats = scene::validate::validate_scene(&s, &scene::Location::file("builtin")).unwrap();
    assert!((32..=36).contains(&stats.triangles));
    assert_eq!(stats.emissive_materials, 1);
    assert_eq!(stats.emissive_triangles, 2);
    assert_eq!(stats.degenerate_triangles, 0);
    let light = s.material_of(s.emissive_triangles()[0] as usize);
    assert_eq!(light.emission, Vec3::new(17.0, 12.0, 4.0));
    for t in &s.triangles[s.emissive_triangles()[0] as usize..][..2] {
        for p in t.p {
            assert!((p.y - 548.7).abs() < 0.2);
            assert!((213.0..=343.0).contains(&p.x) && (227.0..=332.0).contains(&p.z));
        }
    }
    let red = s.material_index("red").unwrap();
    let green = s.material_index("green").unwrap();
    assert_eq!(
        s.materials[red as usize].diffuse,
        Vec3::new(0.63, 0.065, 0.05)
    );
    let mut n_red = 0;
    for t in s.triangles.iter().filter(|t| t.material == red) {
        n_red += 1;
        for p in t.p {
            assert!((p.x - 550.0).abs() < 10.0, "red wall at x ≈ 550");
        }
        let (x, _) = project(&s, t.centroid());
        assert!(
            x < s.film.width as f32 / 2.0,
            "red wall must be on the image's left"
        );
    }
    assert_eq!(n_red, 2);
    for t in s.triangles.iter().filter(|t| t.material == green) {
        let (x, _) = project(&s, t.centroid());
        assert!(
            x > s.film.width as f32 / 2.0,
            "green wall must be on the image's right"
        );
    }
    // The light's centre projects to the upper half of the image (row 0 is the top).
    let lc = s.triangles[s.emissive_triangles()[0] as usize].centroid();
    assert!(project(&s, lc).1 < s.film.height as f32 / 2.0);
}

#[test]
fn builtin_fixture() {
    let s = scene::load("fixture").unwrap();
    let stats = s.stats();
    assert_eq!(stats.emissive_triangles, 2);
    assert_eq!(stats.point_lights, 0);
    assert!(s.bounds().contains(s.camera.position));
}

#[test]
fn cornell_box_files_match_builtin() {
    let file = scene::load("scenes/cornell-box.toml").unwrap();
    let built = builtin("cornell-box").unwrap();
    assert_eq!(file.triangles.len(), built.triangles.len());
    for (i, (a, b)) in file.triangles.iter().zip(&built.triangles).enumerate() {
        assert_eq!(a.p, b.p, "triangle {i}");
        assert_eq!(
            file.materials[a.material as usize], built.materials[b.material as usize],
            "triangle {i}"
        );
    }
    assert_eq!(file.camera, built.camera);
    assert_eq!(file.film, built.film);
    assert_eq!(file.name, built.name);
}

/// `cargo test --test suite -- --ignored scene_load::regenerate` rewrites scenes/cornell-box.{obj,mtl}
/// from the built-in.
#[test]
#[ignore]
fn regenerate_cornell_box_files() {
    let s = builtin("cornell-box").unwrap();
    let (o, m) = obj::to_obj_mtl(&s, "cornell-box.mtl");
    std::fs::write("scenes/cornell-box.obj", o).unwrap();
    std::fs::write("scenes/cornell-box.mtl", m).unwrap();
}

#[test]
fn bunny() {
    let path = Path::new("../shared/meshes/bunny/bunny.obj");
    if !path.exists() {
        eprintln!(
            "note: {} not found; skipping the bunny test",
            path.display()
        );
        return;
    }
    let s = scene::load(path.to_str().unwrap()).unwrap();
    assert_eq!(s.triangles.len(), 69_451);
    assert_eq!(s.name, "bunny");
    assert_eq!((s.film.width, s.film.height), (512, 512));
    let b = s.bounds();
    let (x, y) = project(&s, b.center());
    assert!(
        (x - 256.0).abs() < 0.5 && (y - 256.0).abs() < 0.5,
        "({x}, {y})"
    );
    // All box corners are inside the image.
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        );
        let (x, y) = project(&s, c);
        assert!(
            (0.0..512.0).contains(&x) && (0.0..512.0).contains(&y),
            "corner {c}"
        );
    }
    let stats = s.stats();
    eprintln!("bunny: {stats:?}");
    assert!(stats.degenerate_triangles < 100);
}

// ---- explicit BSDFs in [[material]] ------------------------------------------------

const MAT_HEAD: &str = "[[mesh]]\npath = \"meshes/tri.obj\"\n";

/// Loads `MAT_HEAD + body` as `mat.toml` next to the triangle mesh.
fn load_mat(body: &str) -> (Result<Scene, String>, String) {
    let dir = good_dir();
    let text = format!("{MAT_HEAD}{body}");
    let p = write(dir.path(), "mat.toml", &text);
    (
        scene::load(p.to_str().unwrap()).map_err(|e| e.to_string()),
        text,
    )
}

/// 1-based line of the first line containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("{needle:?} not in the text"))
        + 1
}

#[test]
fn explicit_bsdfs_parse() {
    use splitray::scene::{BsdfKind, MaterialBsdf, MaterialLayer, MicrofacetModel};
    let (s, _) = load_mat(
        r#"
[[material]]
name = "gold"
bsdf = "conductor"
reflectance = [1.0, 0.78, 0.34]
roughness = 0.25
distribution = "beckmann"
emission = [0, 0, 0]
[[material]]
name = "red"
bsdf = "glass"
ior = 1.33
[[material]]
name = "stack"
[[material.layer]]
bsdf = "lambert"
weight = 0.5
[[material.layer]]
bsdf = "plastic"
roughness = 0.1
distribution = "blinn-phong"
weight = 0.5
"#,
    );
    let s = s.unwrap();
    let get = |n: &str| &s.materials[s.material_index(n).unwrap() as usize];
    let layer = |kind, reflectance: Vec3, roughness, distribution, ior, weight| MaterialLayer {
        kind,
        reflectance,
        roughness,
        distribution,
        ior,
        weight,
    };
    assert_eq!(
        get("gold").bsdf,
        Some(MaterialBsdf {
            layers: vec![layer(
                BsdfKind::Conductor,
                Vec3::new(1.0, 0.78, 0.34),
                0.25,
                MicrofacetModel::Beckmann,
                1.5,
                1.0
            )]
        })
    );
    // An override of an MTL material keeps the MTL fields and adds the BSDF.
    let red = get("red");
    assert_eq!(red.diffuse, Vec3::new(0.6, 0.1, 0.1));
    assert_eq!(red.ior, 1.33);
    assert_eq!(
        red.bsdf,
        Some(MaterialBsdf {
            layers: vec![layer(
                BsdfKind::Glass,
                Vec3::ONE,
                0.2,
                MicrofacetModel::Ggx,
                1.33,
                1.0
            )]
        })
    );
    assert_eq!(
        get("stack").bsdf,
        Some(MaterialBsdf {
            layers: vec![
                layer(
                    BsdfKind::Lambert,
                    Vec3::splat(0.8),
                    0.2,
                    MicrofacetModel::Ggx,
                    1.5,
                    0.5
                ),
                layer(
                    BsdfKind::Plastic,
                    Vec3::splat(0.8),
                    0.1,
                    MicrofacetModel::BlinnPhong,
                    1.5,
                    0.5
                ),
            ]
        })
    );
    assert_eq!(get("lamp").bsdf, None);
}

#[test]
fn explicit_bsdf_errors_name_file_and_line() {
    // (body, text on the offending line, message parts)
    let lambert = |w: &str| format!("[[material.layer]]\nbsdf = \"lambert\"\nweight = {w}\n");
    let five = format!("[[material]]\nname = \"m\"\n{}", lambert("0.1").repeat(5));
    let plastic_over = format!(
        "[[material]]\nname = \"m\"\n{}[[material.layer]]\nbsdf = \"plastic\" # 5th\nweight = 0.1\n",
        lambert("0.1").repeat(3)
    );
    let cases: Vec<(String, &str, Vec<&str>)> = vec![
        (
            "[[material]]\nname = \"m\"\nbsdf = \"metal\"\n".into(),
            "metal",
            vec!["unknown bsdf 'metal'", "known: lambert, oren-nayar, mirror"],
        ),
        (
            "[[material]]\nname = \"m\"\nbsdf = \"conductor\"\nroughness = 0\n".into(),
            "roughness",
            vec!["material 'm'", "roughness 0 is outside (0, 1]"],
        ),
        (
            "[[material]]\nname = \"m\"\nbsdf = \"rough-glass\"\nroughness = 1.5\n".into(),
            "roughness",
            vec!["roughness 1.5 is outside (0, 1]"],
        ),
        (
            "[[material]]\nname = \"m\"\nbsdf = \"glass\"\nior = 0\n".into(),
            "ior",
            vec!["material 'm'", "ior 0 must be > 0"],
        ),
        (
            "[[material]]\nname = \"m\"\nbsdf = \"plastic\"\nior = -1.5\n".into(),
            "ior",
            vec!["ior -1.5 must be > 0"],
        ),
        (
            "[[material]]\nname = \"m\"\nbsdf = \"conductor\"\ndistribution = \"phong\"\n".into(),
            "phong",
            vec!["unknown distribution 'phong'", "ggx, beckmann, blinn-phong"],
        ),
        (
            "[[material]]\nname = \"m\"\nbsdf = \"lambert\"\nroughness = 0.5\n".into(),
            "roughness",
            vec!["'roughness' does not apply to bsdf 'lambert'"],
        ),
        (
            "[[material]]\nname = \"m\"\nbsdf = \"conductor\"\nreflectance = [1.2, 0, 0]\n"
                .into(),
            "reflectance",
            vec!["must lie in [0, 1]"],
        ),
        (
            "[[material]]\nname = \"m\"\nroughness = 0.5\n".into(),
            "roughness",
            vec!["'roughness' needs 'bsdf'"],
        ),
        (
            format!("[[material]]\nname = \"m\"\nbsdf = \"lambert\" # both\n{}", lambert("1")),
            "both",
            vec!["either 'bsdf' or [[material.layer]]"],
        ),
        (
            five,
            // the fifth layer's bsdf line
            "",
            vec!["more than 4 BSDF layers"],
        ),
        (
            plastic_over,
            "5th",
            vec!["more than 4 BSDF layers (a plastic layer counts as 2)"],
        ),
        (
            format!("[[material]]\nname = \"m\"\n{}", lambert("0")),
            "weight",
            vec!["layer weight 0 is outside (0, 1]"],
        ),
        (
            format!("[[material]]\nname = \"m\"\n{}", lambert("-0.5")),
            "weight",
            vec!["layer weight -0.5 is outside (0, 1]"],
        ),
        (
            format!(
                "[[material]]\nname = \"m\"\n{}{}",
                lambert("0.6"),
                lambert("0.7 # over")
            ),
            "over",
            vec!["layer weights sum to 1.3", "more than 1"],
        ),
        (
            "[[material]]\nname = \"m\"\n[[material.layer]]\nbsdf = \"lambert\"\nweight = 1\nalbedo = [1, 1, 1]\n"
                .into(),
            "albedo",
            vec!["unknown field 'albedo'"],
        ),
        (
            "[[material]]\nname = \"m\"\n[[material.layer]]\nbsdf = \"lambert\" # no weight\n"
                .into(),
            "[[material.layer]]",
            vec!["missing field 'weight'"],
        ),
    ];
    for (body, needle, parts) in cases {
        let (r, text) = load_mat(&body);
        let msg = match r {
            Ok(_) => panic!("should fail:\n{body}"),
            Err(e) => e,
        };
        let line = if needle.is_empty() {
            // the fifth `bsdf = ` line of the file
            text.lines()
                .enumerate()
                .filter(|(_, l)| l.starts_with("bsdf"))
                .nth(4)
                .unwrap()
                .0
                + 1
        } else {
            line_of(&text, needle)
        };
        let at = format!("mat.toml:{line}:");
        let mut want = parts.clone();
        want.push(&at);
        assert_has(&msg, &want);
    }
}
