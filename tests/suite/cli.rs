//! The `splitray` binary as a user runs it: info, scenes, a tiny render, and bad input
//! giving a clear error, a non-zero exit status and no output file.

use std::path::Path;
use std::process::{Output, Stdio};

use crate::common::cli::{command, printed as text, splitray};

#[test]
fn info_lists_devices_streams_and_validation() {
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(&["info"], dir.path());
    assert!(out.status.success(), "{}", text(&out));
    let t = text(&out);
    for part in [
        "validation layer: available",
        "queue families",
        "streams:",
        "main",
        "aux0",
        "transfer",
        "maxStorageBufferRange",
    ] {
        assert!(t.contains(part), "missing {part:?} in:\n{t}");
    }

    let out = splitray(&["info", "--json"], dir.path());
    assert!(out.status.success(), "{}", text(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let devices = json["devices"].as_array().unwrap();
    assert!(!devices.is_empty());
    assert_eq!(devices.iter().filter(|d| d["selected"] == true).count(), 1);
    assert!(devices[0]["streams"]["slots"].as_array().unwrap().len() == 4);
    assert!(devices[0]["driver_info"].is_string());

    // A device named that does not exist is an error, as it is for `render`, not a
    // listing with nothing marked.
    let out = splitray(&["info", "--json", "--device", "no-such-gpu"], dir.path());
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(text(&out).contains("--device no-such-gpu: no such device"));
    // A number past the devices is no device, even where a name holds its digits
    // (lavapipe's "llvmpipe (LLVM 15.0.6, 256 bits)" holds a 5).
    let past = devices.len().to_string() + "5";
    let out = splitray(&["info", "--json", "--device", &past], dir.path());
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(text(&out).contains(&format!("--device {past}: no such device")));
    // An empty `--device` names nothing; an empty SPLITRAY_DEVICE is an unset one, and
    // a device the variable names that does not exist is reported as the variable's.
    let out = splitray(&["info", "--json", "--device", ""], dir.path());
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(text(&out).contains("--device"), "{}", text(&out));
    let with_env = |value: &str| {
        let tiny = [
            "render", "--width", "4", "--height", "4", "--spp", "1", "-o", "t.exr",
        ];
        crate::common::cli::command(&tiny, dir.path())
            .env("SPLITRAY_DEVICE", value)
            .output()
            .unwrap()
    };
    assert!(with_env("").status.success());
    let out = with_env("no-such-gpu");
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(text(&out).contains("SPLITRAY_DEVICE=no-such-gpu: no such device"));
    let out = splitray(&["info", "--json", "--device", "0"], dir.path());
    assert!(out.status.success(), "{}", text(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["devices"][0]["selected"], true);
}

#[test]
fn scenes_lists_the_builtins() {
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(&["scenes"], dir.path());
    assert!(out.status.success());
    let t = text(&out);
    assert!(t.contains("cornell-box") && t.contains("fixture"), "{t}");
}

#[test]
fn tiny_render_writes_exr_png_and_stats_with_validation_on() {
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(
        &[
            "render",
            "cornell-box",
            "-o",
            "img.exr",
            "--width",
            "40",
            "--height",
            "30",
            "--spp",
            "2",
            "--seed",
            "7",
            "--validation",
            "--stats",
            "stats.json",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out));
    let (film, meta) = splitray::film::read_exr(dir.path().join("img.exr")).unwrap();
    assert_eq!((film.width(), film.height()), (40, 30));
    assert_eq!((meta.spp, meta.seed), (2, 7));
    assert_eq!(meta.integrator, "primary");
    assert_eq!(meta.tracer, "pdacrt");
    assert!(film.depth.is_some() && film.triangle_id.is_some() && film.normal.is_some());
    assert!(dir.path().join("img.png").is_file());
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["rays_traced"], 40 * 30 * 2);
    assert!(stats["rays_per_second"].as_f64().unwrap() > 0.0);
    assert!(stats["peak_gpu_bytes"].as_u64().unwrap() > 0);
    let kernels: Vec<_> = stats["kernels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| k["name"].as_str().unwrap().to_string())
        .collect();
    // PDACRT's intersection ran and was timed (its variant depends on the device).
    assert!(
        kernels
            .iter()
            .any(|k| k.starts_with("trace_pdacrt_segmented_intersect")),
        "{kernels:?}"
    );
}

/// A render runs whole passes: `cbpt`'s add 4 samples per pixel, so `--spp 6` renders 8,
/// and says so; a whole number of passes says nothing.
#[test]
fn spp_rounds_up_to_whole_passes_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    for (spp, rendered, warned) in [("6", 8, true), ("4", 4, false)] {
        let render = "render cornell-box -o img.exr --width 8 --height 8 --integrator cbpt";
        let args: Vec<&str> = render
            .split_whitespace()
            .chain(["--validation", "--spp", spp])
            .collect();
        let out = splitray(&args, dir.path());
        assert!(out.status.success(), "{}", text(&out));
        let said = text(&out).contains("samples per pixel a pass");
        assert_eq!(said, warned, "{}", text(&out));
        if warned {
            let warning = "cbpt renders 4 samples per pixel a pass: 6 spp asked, 8 rendered";
            assert!(text(&out).contains(warning), "{}", text(&out));
        }
        let (_, meta) = splitray::film::read_exr(dir.path().join("img.exr")).unwrap();
        assert_eq!(meta.spp, rendered);
    }
}

#[test]
fn bpt_render_writes_technique_images_and_its_counters() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("tech")).unwrap();
    let out = splitray(
        &[
            "render",
            "cornell-box",
            "-o",
            "bpt.exr",
            "--width",
            "16",
            "--height",
            "12",
            "--spp",
            "2",
            "--integrator",
            "bpt",
            "--max-depth",
            "4",
            "--bdpt-techniques",
            "tech",
            "--stats",
            "stats.json",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out));
    let (film, meta) = splitray::film::read_exr(dir.path().join("bpt.exr")).unwrap();
    assert_eq!((film.width(), film.height(), meta.spp), (16, 12, 2));
    assert_eq!(meta.integrator, "bpt");
    let (nee, _) = splitray::film::read_exr(dir.path().join("tech/s1_t2.exr")).unwrap();
    assert_eq!((nee.width(), nee.height()), (16, 12));
    // Paths of at most 4 segments: no image of a longer technique.
    assert!(dir.path().join("tech/s2_t3.exr").is_file());
    assert!(!dir.path().join("tech/s3_t3.exr").exists());
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("stats.json")).unwrap()).unwrap();
    for counter in [
        "camera_paths",
        "light_paths",
        "connections",
        "basic_contributions",
    ] {
        assert!(
            stats["counters"][counter].as_u64().unwrap() > 0,
            "{counter}"
        );
    }
    assert_eq!(stats["counters"]["camera_paths"], 16 * 12 * 2);
    assert_eq!(stats["counters"]["non_finite_dropped"], 0);
}

/// `--bdpt-techniques` for the GPU integrators: one EXR per technique, summing to the
/// image; the header and stats name the integrator and its cache.
#[test]
fn lvc_renders_write_technique_images_that_sum_to_the_image() {
    for integrator in ["lvc-bdpt", "cis-lbdpt"] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("tech")).unwrap();
        let out = splitray(
            &[
                "render",
                "cornell-box",
                "-o",
                "img.exr",
                "--width",
                "12",
                "--height",
                "10",
                "--spp",
                "2",
                "--integrator",
                integrator,
                "--connections",
                "2",
                "--streams",
                "1",
                "--bdpt-techniques",
                "tech",
                "--stats",
                "stats.json",
            ],
            dir.path(),
        );
        assert!(out.status.success(), "{integrator}: {}", text(&out));
        let (film, meta) = splitray::film::read_exr(dir.path().join("img.exr")).unwrap();
        assert_eq!(meta.integrator, integrator);
        let mut sum = vec![[0.0f64; 3]; film.pixel_count()];
        let mut names = Vec::new();
        for entry in std::fs::read_dir(dir.path().join("tech")).unwrap() {
            let path = entry.unwrap().path();
            names.push(path.file_name().unwrap().to_string_lossy().into_owned());
            let (t, _) = splitray::film::read_exr(&path).unwrap();
            assert_eq!((t.width(), t.height()), (12, 10));
            for (p, s) in sum.iter_mut().enumerate() {
                for (c, v) in t.mean_rgb(p).iter().enumerate() {
                    s[c] += *v as f64;
                }
            }
        }
        // Emitter hits (at 12×10 no camera ray need meet the light itself: any length),
        // direct lighting, connections and light tracing all appear.
        for name in ["s0_t", "s1_t2.exr", "s2_t2.exr", "s2_t1.exr"] {
            assert!(
                names.iter().any(|n| n.starts_with(name)),
                "{integrator}: {names:?}"
            );
        }
        for (p, s) in sum.iter().enumerate() {
            let want = film.mean_rgb(p);
            for c in 0..3 {
                let w = want[c] as f64;
                assert!(
                    (s[c] - w).abs() <= 1e-4 * w.abs().max(1e-3),
                    "{integrator}, pixel {p}: techniques sum to {}, the image is {w}",
                    s[c]
                );
            }
        }
        let stats: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("stats.json")).unwrap()).unwrap();
        assert!(stats["counters"]["cache_vertices"].as_u64().unwrap() > 0);
        assert_eq!(stats["counters"]["camera_paths"], 12 * 10 * 2);
    }
}

#[test]
fn default_output_goes_to_out_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(
        &[
            "render",
            "--width",
            "8",
            "--height",
            "8",
            "--integrator",
            "ao",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out));
    assert!(dir.path().join("out/cornell-box.exr").is_file());
    assert!(dir.path().join("out/cornell-box.png").is_file());
}

/// Outputs that would overwrite one another or an input, or a folder, are refused before
/// the render, and the files already there are left as they were.
#[test]
fn outputs_that_would_replace_another_file_of_the_render_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let small = ["--width", "8", "--height", "8", "--integrator", "ao"];
    let render = |extra: &[&str]| splitray(&[&["render"][..], &small, extra].concat(), d);
    let out = render(&["--spp", "2", "-o", "ref.exr", "--checkpoint", "run.ckpt"]);
    assert!(out.status.success(), "{}", text(&out));
    std::fs::create_dir(d.join("folder.exr")).unwrap();
    let before: Vec<_> = ["ref.exr", "ref.png", "run.ckpt"]
        .map(|f| std::fs::read(d.join(f)).unwrap())
        .into();
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["-o", "a.exr", "--stats", "a.exr"],
            &["the image and --stats"],
        ),
        (
            &["-o", "a.exr", "--stats", "./a.png"],
            &["its PNG preview and --stats"],
        ),
        (
            &["-o", "a.exr", "--stats", "s.json", "--timeline", "s.json"],
            &["--stats and --timeline"],
        ),
        (
            &["-o", "ref.exr", "--reference", "ref.exr"],
            &["the image and --reference"],
        ),
        (
            &["-o", "a.exr", "--stats", "run.ckpt", "--resume", "run.ckpt"],
            &["--stats and --resume"],
        ),
        (&["-o", "folder.exr"], &["folder.exr", "is a folder"]),
        (
            &["-o", "a.exr/"],
            &["a.exr/", "not a folder (the path ends in a separator)"],
        ),
        (
            &["-o", "a.exr", "--stats", "s.json/"],
            &["s.json/", "ends in a separator"],
        ),
        (
            &["-o", "a.exr", "--checkpoint", "run2.ckpt/"],
            &["run2.ckpt/", "ends in a separator"],
        ),
    ];
    for (args, expect) in cases {
        let out = render(args);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        for e in *expect {
            assert!(t.contains(e), "{args:?}: expected {e:?} in:\n{t}");
        }
    }
    let after: Vec<_> = ["ref.exr", "ref.png", "run.ckpt"]
        .map(|f| std::fs::read(d.join(f)).unwrap())
        .into();
    assert!(before == after, "a refused render changed an existing file");
    let mut names: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["folder.exr", "ref.exr", "ref.png", "run.ckpt"]);
    // A resumed render saves its checkpoint over the one it resumed.
    let out = splitray(
        &[
            "render",
            "--resume",
            "run.ckpt",
            "--checkpoint",
            "run.ckpt",
            "--spp",
            "4",
            "-o",
            "b.exr",
        ],
        d,
    );
    assert!(out.status.success(), "{}", text(&out));
}

/// The scene's own files — the scene file, its meshes and their material libraries —
/// are inputs too: an output on one of them is refused, and the file left as it was.
#[test]
fn outputs_over_the_scenes_own_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files = [
        ("scene.toml", "[[mesh]]\npath = \"mesh.obj\"\n"),
        (
            "mesh.obj",
            "mtllib grey.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl grey\nf 1 2 3\n",
        ),
        ("grey.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n"),
    ];
    for (name, text) in files {
        std::fs::write(d.join(name), text).unwrap();
    }
    let tiny = [
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--integrator",
        "ao",
    ];
    for (option, path) in [
        ("--stats", "scene.toml"),
        ("--checkpoint", "./mesh.obj"),
        ("--stats", "grey.mtl"),
    ] {
        let args = [
            &["render", "scene.toml", "-o", "a.exr", option, path][..],
            &tiny,
        ]
        .concat();
        let out = splitray(&args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        let clash = format!("{option} and a file of the scene name the same file");
        assert!(t.contains(&clash), "{args:?}: {t}");
    }
    for (name, text) in files {
        assert_eq!(std::fs::read_to_string(d.join(name)).unwrap(), text);
    }
    assert_eq!(std::fs::read_dir(d).unwrap().count(), files.len());
}

/// Standard output that cannot take the summary — a closed pipe (`| head`), a full
/// disk — costs none of the render's files: the failure is noted once on standard error
/// and the render goes on to write them, exiting 0.
#[test]
fn a_closed_or_full_standard_output_costs_no_file() {
    let args = [
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--integrator",
        "ao",
        "-o",
        "a.exr",
        "--stats",
        "s.json",
    ];
    let closed_pipe = |d: &Path| {
        let mut child = command(&args, d)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        child.wait_with_output().unwrap()
    };
    let full_disk = |d: &Path| {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        command(&args, d).stdout(full).output().unwrap()
    };
    for (what, run) in [
        ("a closed pipe", &closed_pipe as &dyn Fn(&Path) -> Output),
        ("a full disk", &full_disk),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let out = run(d);
        let t = text(&out);
        assert!(out.status.success(), "{what}: {t}");
        assert!(t.contains("note: standard output failed"), "{what}: {t}");
        for file in ["a.exr", "a.png", "s.json"] {
            assert!(d.join(file).is_file(), "{what}: no {file}: {t}");
        }
    }
}

/// Runs a render expected to fail; checks the message and that no file was written.
fn assert_fails(dir: &Path, args: &[&str], expect: &[&str]) {
    let out = splitray(args, dir);
    let t = text(&out);
    assert!(!out.status.success(), "{args:?} succeeded:\n{t}");
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(!t.contains("panicked"), "{t}");
    for e in expect {
        assert!(t.contains(e), "{args:?}: expected {e:?} in:\n{t}");
    }
    assert_each_cause_once(&t);
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".exr") || n.ends_with(".png") || n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{args:?} left {leftovers:?}");
}

/// The `error:` line names each cause once: an error whose message includes its cause
/// must not also report it as its source, or the printed chain ends "…: E: E".
fn assert_each_cause_once(printed: &str) {
    for line in printed.lines().filter(|l| l.starts_with("error: ")) {
        let parts: Vec<&str> = line.split(": ").collect();
        let n = parts.len();
        for k in 1..=n / 2 {
            assert_ne!(
                parts[n - 2 * k..n - k],
                parts[n - k..],
                "the cause is printed twice: {line}"
            );
        }
    }
}

#[test]
fn bad_input_gives_a_clear_error_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("bad.toml"),
        "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nfov = 40\n",
    )
    .unwrap();
    std::fs::write(d.join("nan.obj"), "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(d.join("idx.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    std::fs::write(d.join("empty.obj"), "# nothing\n").unwrap();
    std::fs::write(d.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    std::fs::write(d.join("nomesh.toml"), "[[mesh]]\npath = \"missing.obj\"\n").unwrap();
    assert_fails(
        d,
        &["render", "missing.toml", "-o", "a.exr"],
        &["missing.toml", "cannot read file", "No such file"],
    );
    std::fs::write(d.join("bad.json"), "{nope").unwrap();
    assert_fails(
        d,
        &["timeline", "bad.json", "-o", "t.svg"],
        &["bad.json", "not a trace-event JSON file", "line 1 column 2"],
    );
    assert_fails(
        d,
        &["render", "bad.toml", "-o", "a.exr"],
        &["bad.toml:4", "fov"],
    );
    assert_fails(d, &["render", "nan.obj", "-o", "a.exr"], &["nan.obj:2"]);
    assert_fails(
        d,
        &["render", "idx.obj", "-o", "a.exr"],
        &["idx.obj:4", "vertex 7"],
    );
    assert_fails(d, &["render", "empty.obj", "-o", "a.exr"], &["empty.obj"]);
    assert_fails(d, &["render", "flat.obj", "-o", "a.exr"], &["flat.obj"]);
    assert_fails(
        d,
        &["render", "nomesh.toml", "-o", "a.exr"],
        &["missing.obj", "nomesh.toml"],
    );
    assert_fails(
        d,
        &["render", "no-such-scene", "-o", "a.exr"],
        &["no-such-scene"],
    );
    assert_fails(
        d,
        &[
            "render",
            "-o",
            "nowhere/a.exr",
            "--width",
            "4",
            "--height",
            "4",
        ],
        &["nowhere"],
    );
    assert_fails(d, &["render", "-o", "a.png"], &[".exr"]);
    assert_fails(d, &["render", "--spp", "0", "-o", "a.exr"], &["spp"]);
    assert_fails(d, &["render", "--width", "0", "-o", "a.exr"], &["0x"]);
    assert_fails(
        d,
        &["render", "--device", "no-such-gpu", "-o", "a.exr"],
        &["no-such-gpu"],
    );
    assert_fails(
        d,
        &[
            "render",
            "--integrator",
            "bpt",
            "--bdpt-techniques",
            "nodir",
            "-o",
            "a.exr",
        ],
        &["nodir", "existing folder"],
    );
    assert_fails(
        d,
        &["bench", "bdpt", "cornell-box", "--streams", "1,2"],
        &["--streams", "2 streams"],
    );
    assert_fails(
        d,
        &["render", "--bdpt-techniques", ".", "-o", "a.exr"],
        &["--bdpt-techniques", "bpt, light, lvc-bdpt or cis-lbdpt"],
    );
    // An option of other integrators changes nothing: refused, not ignored, also for
    // the integrator a render takes by default (primary).
    for (args, expect) in [
        (
            &["--integrator", "lvc-bdpt", "--candidates", "4"][..],
            "--candidates is an option of cis-lbdpt, not of lvc-bdpt",
        ),
        (
            &["--integrator", "pt", "--connections", "3"],
            "--connections is an option of lvc-bdpt, cis-lbdpt, not of pt",
        ),
        (
            &["--integrator", "bpt", "--strategy", "nee"],
            "--strategy is an option of pt, not of bpt",
        ),
        (
            &["--integrator", "path", "--max-depth", "3"],
            "--max-depth is an option of pt, bpt, light, lvc-bdpt, cis-lbdpt, cbpt, not of path",
        ),
        (
            &["--cbpt-nl", "3"],
            "--cbpt-nl is an option of cbpt, not of primary",
        ),
    ] {
        let mut all = vec!["render", "-o", "a.exr"];
        all.extend(args);
        assert_fails(d, &all, &[expect]);
    }
    // Benches: outputs checked before any work, lists without repeats, PDACRT's
    // parameters within the device's limits, frame numbers within u32.
    let trace = "bench trace cornell-box --width 8 --height 8";
    for (args, expect) in [
        (
            "bench primitives --n 64 --json nowhere/p.json".to_string(),
            "nowhere",
        ),
        (
            format!("{trace} --tracers pdacrt,cpu-bvh,pdacrt"),
            "--tracers names pdacrt twice",
        ),
        (
            format!("{trace} --tile-workgroup 4096"),
            "--tile-workgroup 4096 is more than the device's",
        ),
        (
            format!("{trace} --alpha 0"),
            "α (--alpha) and β (--beta) must be at least 1",
        ),
        (
            "bench dynamic waves --first 4294967295 --frames 1".to_string(),
            "frames past 4294967295 cannot be numbered",
        ),
    ] {
        let args: Vec<&str> = args.split_whitespace().collect();
        assert_fails(d, &args, &[expect]);
    }
    // A population this large ran the host out of memory before it was bounded.
    assert_fails(
        d,
        &[
            "render",
            "--integrator",
            "cbpt",
            "--cbpt-nt",
            "4000000000",
            "-o",
            "a.exr",
        ],
        &["--cbpt-nt 4000000000", "1048576 paths per step"],
    );
    // A negative number of seconds is a value that splitray refuses, not an unknown
    // option.
    assert_fails(
        d,
        &["render", "--time", "-1", "-o", "a.exr"],
        &["--time must be a positive number"],
    );
    assert_fails(
        d,
        &[
            "render",
            "--checkpoint",
            "c.ckpt",
            "--checkpoint-every",
            "-5",
            "-o",
            "a.exr",
        ],
        &["--checkpoint-every must be"],
    );
    assert_fails(
        d,
        &["render", "--frames", "0..2", "--fps", "-24", "-o", "a.exr"],
        &["--fps -24 must be a positive number"],
    );
    assert_fails(
        d,
        &["bench", "bdpt", "cornell-box", "--time", "-1"],
        &["--time must be a positive, finite number"],
    );
    // An endless budget ran forever.
    assert_fails(
        d,
        &["bench", "bdpt", "cornell-box", "--time", "inf"],
        &["--time must be a positive, finite number"],
    );
    assert_fails(
        d,
        &["bench", "dynamic", "waves", "--fps", "-24"],
        &["--fps -24 must be a positive number"],
    );
    // clap's own usage errors exit with 2; an unknown integrator is one of them.
    let out = splitray(&["render", "--integrator", "bogus"], d);
    assert!(!out.status.success() && text(&out).contains("bogus"));
    // Mitsuba's max_depth is -1 (unbounded) or 0 and up; -5 is not "unbounded".
    for command in [&["render"][..], &["bench", "bdpt"]] {
        let mut args = command.to_vec();
        args.extend(["--max-depth", "-5"]);
        let out = splitray(&args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {t}");
        assert!(t.contains("--max-depth") && t.contains("-5"), "{t}");
    }
}

/// A negative number given to an option is its value, refused as such (not read as an
/// unknown option `-3` with advice to write `-- -3`).
#[test]
fn a_negative_number_is_refused_as_the_value_of_its_option() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (
            &["render", "cornell-box", "--width", "-3"],
            "'--width <WIDTH>'",
        ),
        (&["render", "cornell-box", "--spp", "-1"], "'--spp <SPP>'"),
        (
            &["render", "cornell-box", "--seed", "-5"],
            "'--seed <SEED>'",
        ),
        (
            &["render", "cornell-box", "--connections", "-1"],
            "'--connections <N>'",
        ),
        (
            &["bench", "bdpt", "cornell-box", "--rounds", "-2"],
            "'--rounds <ROUNDS>'",
        ),
    ];
    for (args, option) in cases {
        let t = usage_error(args, dir.path());
        let value = args[args.len() - 1];
        assert!(
            t.contains(&format!("invalid value '{value}' for {option}"))
                && !t.contains("unexpected argument"),
            "{args:?}: {t}"
        );
    }
}

/// What `splitray args` printed, having checked that clap refused it as a usage error
/// (exit code 2) and nothing panicked.
fn usage_error(args: &[&str], dir: &Path) -> String {
    let out = splitray(args, dir);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {t}");
    assert!(!t.contains("panicked"), "{args:?}: {t}");
    t
}

/// Every benchmark refuses a film side of 0 or past 16384, and counts that would
/// measure nothing, with clap's usage error (exit 2) naming the option, before it opens
/// a device (two of them used to panic on a width of 0).
#[test]
fn benches_refuse_empty_films_and_zero_counts() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["bench", "pt", "cornell-box", "--width", "0"], "--width"),
        (&["bench", "pt", "cornell-box", "--spp", "0"], "--spp"),
        (&["bench", "cbpt", "cornell-box", "--width", "0"], "--width"),
        (&["bench", "cbpt", "cornell-box", "--steps", "0"], "--steps"),
        (
            &["bench", "cbpt", "cornell-box", "--rounds", "0"],
            "--rounds",
        ),
        (
            &["bench", "trace", "cornell-box", "--height", "0"],
            "--height",
        ),
        (
            &["bench", "trace", "cornell-box", "--width", "16385"],
            "--width",
        ),
        (&["bench", "dynamic", "waves", "--height", "0"], "--height"),
        (&["bench", "bdpt", "cornell-box", "--width", "0"], "--width"),
        (
            &["bench", "bdpt", "cornell-box", "--rounds", "0"],
            "--rounds",
        ),
        (
            &["bench", "bdpt", "cornell-box", "--spp-rounds", "0"],
            "--spp-rounds",
        ),
    ];
    for (args, option) in cases {
        let t = usage_error(args, dir.path());
        assert!(t.contains(option), "{args:?}: {t}");
    }
    // A count no device can hold (16 TB of keys) is refused before its host data is made.
    let out = splitray(&["bench", "primitives", "--n", "4000000000000"], dir.path());
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(
        t.contains("'bench-keys' needs 16000000000000 bytes") && !t.contains("panicked"),
        "{t}"
    );
}

#[test]
fn bench_trace_verifies_and_compares_tracers() {
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(
        &[
            "bench",
            "trace",
            "cornell-box",
            "--width",
            "24",
            "--height",
            "16",
            "--workload",
            "ao",
            "--tracers",
            "pdacrt,brute-force,cpu-dacrt",
            "--levels",
            "--json",
            "trace.json",
            "--dump-hits",
            "hits.bin",
            "--validation",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out));
    let t = text(&out);
    for part in [
        "pdacrt",
        "brute-force",
        "cpu-dacrt",
        "Mrays/s",
        "faster than",
    ] {
        assert!(t.contains(part), "missing {part:?} in:\n{t}");
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("trace.json")).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert!(rows
        .iter()
        .all(|r| r["mismatches"] == 0 && r["verified_rays"].as_u64().unwrap() > 0));
    // 8 AO rays per primary hit.
    assert_eq!(json["rays"].as_u64().unwrap() % 8, 0);
    // Primary hits: 8 bytes per pixel, row 0 first.
    assert_eq!(
        std::fs::read(dir.path().join("hits.bin")).unwrap().len(),
        24 * 16 * 8
    );
}

/// The paper's own PDACRT steps can be chosen from the command line, the benchmark says
/// which ran, and their hits still verify against brute force.
#[test]
fn bench_trace_runs_the_papers_pdacrt_steps_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let out = splitray(
        &[
            "bench",
            "trace",
            "cornell-box",
            "--width",
            "32",
            "--height",
            "24",
            "--tracers",
            "pdacrt",
            "--alpha",
            "4",
            "--beta",
            "4",
            "--split",
            "sort",
            "--flush",
            "sort",
            "--stage-triangles",
            "true",
            "--json",
            "trace.json",
            "--validation",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out));
    let t = text(&out);
    assert!(
        t.contains("split SortByKey, flush SortByRay, triangles staged"),
        "{t}"
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("trace.json")).unwrap()).unwrap();
    assert_eq!(json["pdacrt_params"]["split"], "SortByKey");
    assert_eq!(json["pdacrt_params"]["flush_reduce"], "SortByRay");
    assert_eq!(json["rows"][0]["mismatches"], 0);
    assert!(json["rows"][0]["levels"].as_u64().unwrap() > 0);
}

#[test]
fn export_scene_writes_the_resolved_scene_or_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let glossy = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/glossy.toml");
    let glossy = glossy.to_str().unwrap();
    let args = [
        "export-scene",
        glossy,
        "-o",
        "glossy.json",
        "--width",
        "64",
        "--height",
        "48",
    ];
    let out = splitray(&args, d);
    assert!(out.status.success(), "{}", text(&out));
    let text_json = std::fs::read_to_string(d.join("glossy.json")).unwrap();
    let written: splitray::scene_export::SceneExport = serde_json::from_str(&text_json).unwrap();
    let scene = splitray::scene::load(glossy).unwrap();
    let film = splitray::scene::FilmSize {
        width: 64,
        height: 48,
    };
    assert_eq!(written, splitray::scene_export::export(&scene, film));
    let metal = written
        .materials
        .iter()
        .find(|m| m.name == "metal")
        .unwrap();
    assert!(
        matches!(
            metal.layers[0].bsdf,
            splitray::scene_export::ExportBsdf::MicrofacetReflection { roughness, .. }
                if roughness == 0.3
        ),
        "{metal:?}"
    );
    // Extensions are matched as scenes' are: in any case.
    let out = splitray(&["export-scene", "cornell-box", "-o", "BOX.JSON"], d);
    assert!(
        out.status.success() && d.join("BOX.JSON").is_file(),
        "{}",
        text(&out)
    );

    for (args, expect) in [
        (
            &["export-scene", "no-such-scene", "-o", "a.json"][..],
            "no-such-scene",
        ),
        (&["export-scene", "cornell-box", "-o", "a.txt"][..], ".json"),
        (
            &[
                "export-scene",
                "cornell-box",
                "-o",
                "a.json",
                "--width",
                "0",
            ][..],
            "width 0",
        ),
        (
            &["export-scene", "cornell-box", "-o", "nowhere/a.json"][..],
            "nowhere",
        ),
    ] {
        let out = splitray(args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        assert!(
            !t.contains("panicked") && t.contains(expect),
            "{args:?}: {t}"
        );
    }
    let mut files: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(files, ["BOX.JSON", "glossy.json"]);
}

/// The committed Mitsuba reference of `fixture` at 64×64: `NAME_mean.exr`, with its
/// standard errors in `NAME_stderr.exr` beside it.
fn fixture_reference() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/reference/fixture_ptracer_64_mean.exr")
}

/// (1/n) Σ se² / (r² + 0.01) of a reference's mean and standard-error images.
fn reference_noise(mean: &Path, stderr: &Path) -> f64 {
    let (r, _) = splitray::film::read_exr(mean).unwrap();
    let (s, _) = splitray::film::read_exr(stderr).unwrap();
    let (r, s) = (r.mean_rgb_buffer(), s.mean_rgb_buffer());
    let sum: f64 = r
        .iter()
        .zip(&s)
        .flat_map(|(r, s)| (0..3).map(move |c| (r[c] as f64, s[c] as f64)))
        .map(|(r, s)| s * s / (r * r + 0.01))
        .sum();
    sum / (3 * r.len()) as f64
}

/// `splitray render fixture` with `pt` at 64×64 against `reference`, writing img.exr and
/// `extra` arguments.
fn render_fixture_against(reference: &str, dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "render",
        "fixture",
        "--integrator",
        "pt",
        "--width",
        "64",
        "--height",
        "64",
        "--spp",
        "2",
        "--reference",
        reference,
        "-o",
        "img.exr",
    ];
    args.extend_from_slice(extra);
    splitray(&args, dir)
}

#[test]
fn render_against_a_reference_takes_out_its_noise() {
    let dir = tempfile::tempdir().unwrap();
    let reference = fixture_reference();
    let out = render_fixture_against(
        reference.to_str().unwrap(),
        dir.path(),
        &["--stats", "stats.json"],
    );
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("without the reference's own noise"),
        "{}",
        text(&out)
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("stats.json")).unwrap()).unwrap();
    let raw = stats["relative_mse"].as_f64().unwrap();
    let excess = stats["relative_mse_excess"].as_f64().unwrap();
    let noise = reference_noise(
        &reference,
        &reference.with_file_name("fixture_ptracer_64_stderr.exr"),
    );
    assert!(noise > 0.0);
    assert!(
        (raw - excess - noise).abs() <= 1e-9 * raw,
        "relative MSE {raw} less {excess} is not the reference's noise {noise}"
    );
}

#[test]
fn a_reference_with_unusable_standard_errors_is_refused() {
    use splitray::film::{write_exr, Film, RenderMetadata};
    let dir = tempfile::tempdir().unwrap();
    let mean = dir.path().join("ref_mean.exr");
    std::fs::copy(fixture_reference(), &mean).unwrap();
    let stderr = dir.path().join("ref_stderr.exr");
    let cases = [
        (
            Film::from_mean_rgb(32, 32, &[[0.01; 3]; 32 * 32]).unwrap(),
            "32x32",
        ),
        (
            Film::from_mean_rgb(64, 64, &[[-0.01; 3]; 64 * 64]).unwrap(),
            "must be finite and not negative",
        ),
    ];
    for (film, problem) in cases {
        write_exr(&stderr, &film, &RenderMetadata::default()).unwrap();
        let out = render_fixture_against("ref_mean.exr", dir.path(), &[]);
        let t = text(&out);
        assert!(!out.status.success(), "accepted: {t}");
        assert!(t.contains("ref_stderr.exr") && t.contains(problem), "{t}");
        assert!(!t.contains("panicked"), "{t}");
        assert!(!dir.path().join("img.exr").exists());
    }
}

/// Renders shard `shard` of two of a tiny image to `name` in `dir`.
fn tiny_shard(dir: &Path, shard: &str, name: &str) {
    let args = [
        "render", "--width", "8", "--height", "8", "--spp", "2", "--shard", shard, "-o", name,
    ];
    let out = splitray(&args, dir);
    assert!(out.status.success(), "{}", text(&out));
}

/// `merge` refuses an output, or the PNG beside it, that is one of its parts however the
/// path is written, and leaves the parts as they were; an upper-case `.EXR` is an EXR.
#[test]
fn merge_refuses_to_overwrite_a_part_however_its_path_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tiny_shard(d, "0/2", "p0.exr");
    tiny_shard(d, "1/2", "p1.exr");
    std::fs::copy(d.join("p1.png"), d.join("q.png")).unwrap();
    let before: Vec<_> = ["p0.exr", "p1.exr", "q.png"]
        .map(|f| std::fs::read(d.join(f)).unwrap())
        .into();
    let absolute = d.join("p1.exr");
    let cases: [(&[&str], &str); 3] = [
        (
            &["./p0.exr", "p1.exr", "-o", "p0.exr"],
            "the output and a part",
        ),
        (
            &["p0.exr", "p1.exr", "-o", absolute.to_str().unwrap()],
            "the output and a part",
        ),
        (
            &["p0.exr", "q.png", "-o", "q.exr"],
            "its PNG preview and a part",
        ),
    ];
    for (args, expect) in cases {
        let out = splitray(&[&["merge"][..], args].concat(), d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        assert!(
            t.contains(expect) && t.contains("name the same file"),
            "{t}"
        );
    }
    let after: Vec<_> = ["p0.exr", "p1.exr", "q.png"]
        .map(|f| std::fs::read(d.join(f)).unwrap())
        .into();
    assert!(before == after, "a refused merge changed a part");
    let out = splitray(&["merge", "p0.exr", "p1.exr", "-o", "m.EXR"], d);
    assert!(out.status.success(), "{}", text(&out));
    assert!(d.join("m.EXR").is_file() && d.join("m.png").is_file());
}

/// A bench's outputs may not name one file, nor a reference it reads: refused before
/// any work.
#[test]
fn bench_outputs_that_would_overwrite_one_another_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("ref.exr"), "kept").unwrap();
    let trace = "bench trace cornell-box --width 8 --height 8";
    for (args, expect) in [
        (
            "bench primitives --n 64 --json x.json --timeline x.json".to_string(),
            "--json and --timeline name the same file",
        ),
        (
            format!("{trace} --json x.json --dump-hits ./x.json"),
            "--json and --dump-hits name the same file",
        ),
        (
            format!("{trace} --dump-hits hits.bin --timeline hits.bin"),
            "--dump-hits and --timeline name the same file",
        ),
        (
            "bench cbpt cornell-box --reference ref.exr --json ref.exr".to_string(),
            "--json and --reference name the same file",
        ),
        (
            "bench bdpt cornell-box --reference ref.exr --timeline ./ref.exr".to_string(),
            "--timeline and --reference name the same file",
        ),
    ] {
        let args: Vec<&str> = args.split_whitespace().collect();
        let out = splitray(&args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        assert!(t.contains(expect), "{args:?}: {t}");
    }
    let mut names: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["ref.exr"]);
    assert_eq!(std::fs::read(d.join("ref.exr")).unwrap(), b"kept");
}

/// A file of the render that a technique image of `--bdpt-techniques DIR` would replace
/// is refused before the render; names that no technique image takes are not.
#[test]
fn technique_images_may_not_replace_another_file_of_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("td")).unwrap();
    let small = [
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--integrator",
        "bpt",
    ];
    let render = |extra: &[&str]| splitray(&[&small[..], extra].concat(), d);
    for (args, expect) in [
        (
            &["-o", "td/s1_t2.exr", "--bdpt-techniques", "td"][..],
            "td/s1_t2.exr: the image and a technique image",
        ),
        (
            &[
                "-o",
                "a.exr",
                "--stats",
                "td/longer.exr",
                "--bdpt-techniques",
                "./td/",
            ],
            "--stats and a technique image",
        ),
        (
            &[
                "-o",
                "a.exr",
                "--checkpoint",
                "td/s0_t3.exr",
                "--bdpt-techniques",
                "td",
            ],
            "--checkpoint and a technique image",
        ),
    ] {
        let out = render(args);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        assert!(t.contains(expect), "{args:?}: {t}");
    }
    assert_eq!(std::fs::read_dir(d.join("td")).unwrap().count(), 0);
    // A path of 9 segments has no image of its own (it is in longer.exr).
    let out = render(&["-o", "td/s1_t9.exr", "--bdpt-techniques", "td"]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(d.join("td/s1_t9.exr").is_file() && d.join("td/s1_t2.exr").is_file());
}

/// Runs `splitray ARGS` in `dir`, failing the test unless it exits within 60 s.
fn splitray_within_a_minute(args: &[&str], dir: &Path) -> Output {
    let mut child = crate::common::cli::command(args, dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start splitray");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            child.kill().unwrap();
            panic!("{args:?} still runs after 60 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A FIFO given as an input is refused at once, naming it, rather than waiting forever
/// in open() for a writer.
#[test]
fn a_fifo_given_as_an_input_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fifos = [
        "scene.toml",
        "mesh.obj",
        "run.ckpt",
        "part.exr",
        "trace.json",
    ];
    for name in fifos {
        let made = std::process::Command::new("mkfifo")
            .arg(d.join(name))
            .status()
            .expect("run mkfifo");
        assert!(made.success());
    }
    tiny_shard(d, "1/2", "p1.exr");
    std::fs::write(d.join("mesh.toml"), "[[mesh]]\npath = \"mesh.obj\"\n").unwrap();
    let tiny = ["--width", "8", "--height", "8", "--spp", "1"];
    for (args, fifo) in [
        (&["render", "scene.toml", "-o", "a.exr"][..], "scene.toml"),
        (&["render", "mesh.obj", "-o", "a.exr"], "mesh.obj"),
        (&["render", "mesh.toml", "-o", "a.exr"], "mesh.obj"),
        (
            &["render", "--resume", "run.ckpt", "-o", "a.exr"],
            "run.ckpt",
        ),
        (
            &[
                &["render", "--reference", "part.exr", "-o", "a.exr"][..],
                &tiny,
            ]
            .concat(),
            "part.exr",
        ),
        (&["merge", "part.exr", "p1.exr", "-o", "m.exr"], "part.exr"),
        (&["timeline", "trace.json", "-o", "t.svg"], "trace.json"),
        (
            &["export-scene", "scene.toml", "-o", "s.json"],
            "scene.toml",
        ),
    ] {
        let out = splitray_within_a_minute(args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        assert!(
            t.contains(fifo) && t.contains("it is a FIFO, not a regular file"),
            "{args:?}: {t}"
        );
        for output in ["a.exr", "m.exr", "t.svg", "s.json"] {
            assert!(!d.join(output).exists(), "{args:?} wrote {output}");
        }
    }
}

/// Output paths: an extension in any case, a file name near the file system's limit, a
/// file where the folder should be, and write errors that name the path once.
#[test]
fn output_paths_are_taken_or_refused_as_they_should_be() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tiny = ["render", "--width", "8", "--height", "8", "--spp", "1"];
    let render = |extra: &[&str]| splitray(&[&tiny[..], extra].concat(), d);
    let out = render(&["-o", "upper.EXR", "--timeline", "trace.JSON"]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(d.join("upper.EXR").is_file() && d.join("upper.png").is_file());
    // 246 bytes, a legal name: its temporary file's would not be.
    let long = format!("{}.exr", "n".repeat(242));
    let out = render(&["-o", &long]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(d.join(&long).is_file());
    std::fs::write(d.join("plain"), "").unwrap();
    let out = render(&["-o", "plain/x.exr"]);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(t.contains("plain/x.exr: plain is not a folder"), "{t}");
    // An output that cannot be written, named once in the error.
    std::fs::create_dir(d.join("taken.json")).unwrap();
    std::fs::create_dir(d.join("taken.svg")).unwrap();
    for args in [
        &["export-scene", "cornell-box", "-o", "taken.json"][..],
        &["timeline", "trace.JSON", "-o", "taken.svg"],
    ] {
        let out = splitray(args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        let error = t.lines().find(|l| l.starts_with("error: ")).unwrap();
        assert_eq!(error.matches("taken.").count(), 1, "{error}");
        assert!(error.contains("is a folder"), "{error}");
    }
}
