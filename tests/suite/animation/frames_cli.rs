//! `render --frames` on the command line: the numbered files of a sequence, bad input
//! refused before any work, and a frame that cannot be written.

use std::path::Path;

use super::write_scene;
use crate::common::cli::{printed, splitray};

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// `render --frames` writes a numbered EXR + PNG per frame (the EXR header naming the
/// frame and its time) and the stats of every frame.
#[test]
fn render_frames_writes_the_numbered_sequence() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let o = splitray(
        &[
            "render",
            scene.to_str().unwrap(),
            "--frames",
            "8..=10",
            "--fps",
            "8",
            "--width",
            "16",
            "--height",
            "12",
            "-o",
            "out/shot.exr",
            "--stats",
            "out/stats.json",
            "--validation",
        ],
        dir.path(),
    );
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{text}");
    assert_eq!(
        files_in(&out),
        [
            "shot_0008.exr",
            "shot_0008.png",
            "shot_0009.exr",
            "shot_0009.png",
            "shot_0010.exr",
            "shot_0010.png",
            "stats.json"
        ]
    );
    assert!(text.contains("frame 9 (t = 1.125 s)"), "{text}");
    let (film, meta) = splitray::film::read_exr(out.join("shot_0009.exr")).unwrap();
    assert_eq!((film.width(), film.height()), (16, 12));
    assert!(
        meta.extra.contains(&("frame".into(), "9".into())),
        "{meta:?}"
    );
    assert!(
        meta.extra.contains(&("time".into(), "1.125".into())),
        "{meta:?}"
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("stats.json")).unwrap()).unwrap();
    let frames = stats["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    assert_eq!(frames[0]["frame"], 8);
    // Frame 8 is at 1 s: everything has come to rest; the rest upload nothing.
    assert_eq!(frames[1]["changed_triangles"], 0);
    assert_eq!(frames[2]["rays_traced"], 16 * 12);
}

/// Bad input to `render --frames` fails before any work with a clear message, a
/// non-zero status and no output file.
#[test]
fn render_frames_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let scene = scene.to_str().unwrap();
    let bad_keys = dir.path().join("bad.toml");
    let text = std::fs::read_to_string(scene).unwrap();
    std::fs::write(
        &bad_keys,
        text.replacen("time = 1.0\ntranslate", "time = 0.0\ntranslate", 1),
    )
    .unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--frames", "5..2"], "frame range '5..2' holds no frames"),
        (&["--frames", "1-4"], "write A..B"),
        (
            &["--frames", "0..4", "--fps", "0"],
            "--fps 0 must be a positive number",
        ),
        (&["--fps", "12"], "--frames"),
        (
            &["--frames", "0..2", "--checkpoint", "c.ckpt"],
            "--checkpoint and --resume work on one image",
        ),
        (
            &["--frames", "0..2", "--shard", "0/2"],
            "its own frame range",
        ),
        (
            &["--frames", "0..2", "-o", "missing/shot.exr"],
            "does not exist",
        ),
        (&["--frames", "0..2", "-o", "shot.png"], "must be an .exr"),
        (
            &[
                "--frames",
                "0..3",
                "-o",
                "shot.exr",
                "--stats",
                "shot_0002.png",
            ],
            "shot_0002.png: its PNG preview and --stats name the same file",
        ),
        (
            &[
                "--frames",
                "4..=6",
                "-o",
                "shot.exr",
                "--stats",
                "./shot_0005.exr",
            ],
            "the image and --stats name the same file",
        ),
    ];
    for (args, want) in cases {
        let mut all = vec!["render", scene, "--width", "8", "--height", "8"];
        all.extend_from_slice(args);
        let o = splitray(&all, dir.path());
        let text = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(text.contains(want), "{args:?}: missing {want:?} in: {text}");
    }
    let o = splitray(
        &["render", bad_keys.to_str().unwrap(), "--frames", "0..2"],
        dir.path(),
    );
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        text.contains("bad.toml:28:1") && text.contains("must increase"),
        "{text}"
    );
    let written: Vec<String> = files_in(dir.path())
        .into_iter()
        .filter(|f| f.ends_with(".exr") || f.ends_with(".png") || f.contains("tmp"))
        .collect();
    assert!(written.is_empty(), "{written:?}");
    assert!(!dir.path().join("out").exists());
}

/// A frame whose image cannot be written (a folder holds its name) ends the sequence
/// there: the frames before it keep their files, the stats file holds those frames, the
/// timeline is written, and the error names the path, the frames written and the range
/// that renders the rest; no temporary file is left.
#[test]
fn a_frame_that_cannot_be_written_ends_the_sequence_keeping_the_other_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("shot_0002.exr")).unwrap();
    let o = splitray(
        &[
            "render",
            scene.to_str().unwrap(),
            "--frames",
            "0..4",
            "--width",
            "16",
            "--height",
            "12",
            "-o",
            "out/shot.exr",
            "--stats",
            "out/stats.json",
            "--timeline",
            "out/timeline.json",
            "--validation",
        ],
        dir.path(),
    );
    let text = printed(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(!text.contains("panicked"), "{text}");
    assert_eq!(
        files_in(&out),
        [
            "shot_0000.exr",
            "shot_0000.png",
            "shot_0001.exr",
            "shot_0001.png",
            "shot_0002.exr",
            "stats.json",
            "timeline.json"
        ],
        "{text}"
    );
    assert!(out.join("shot_0002.exr").is_dir());
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("stats.json")).unwrap()).unwrap();
    let frames: Vec<&serde_json::Value> = stats["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| &f["frame"])
        .collect();
    assert_eq!(frames, [0, 1], "{stats}");
    let timeline: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("timeline.json")).unwrap()).unwrap();
    assert!(timeline["traceEvents"].is_array(), "{timeline}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    let error = &stderr[stderr.find("error: ").expect("an error")..];
    assert!(
        error.contains("out/shot_0002.exr: is a folder, not a file"),
        "{stderr}"
    );
    assert!(
        error.contains(
            "the sequence stopped after 2 frame(s) (0..2); `--frames 2..4` renders the rest"
        ),
        "{stderr}"
    );
}
