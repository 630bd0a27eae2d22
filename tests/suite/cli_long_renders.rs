//! Long renders on the command line: outputs that cannot be written fail before any
//! work; SIGINT/SIGTERM stop a render at a pass boundary and write what it reached (exit
//! 130/143), a second signal exits at once leaving no partial file; a stopped render
//! resumes bit-identically; shards rendered apart merge into one image; bad checkpoints
//! and parts fail naming the file; an output that cannot be written at the end costs
//! none of the others (of a sequence, none of the frames before it).

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use splitray::film::read_exr;
use splitray::render::Checkpoint;

use crate::common::cli::{command, printed as text, splitray};

/// Names in `dir` that are outputs or temporary files.
fn outputs(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| {
            [".exr", ".png", ".json", ".ckpt"]
                .iter()
                .any(|e| n.ends_with(e))
                || n.contains(".tmp-")
        })
        .collect();
    names.sort();
    names
}

fn temporaries(dir: &Path) -> Vec<String> {
    outputs(dir)
        .into_iter()
        .filter(|n| n.contains(".tmp-"))
        .collect()
}

/// A render running in the background, its stderr lines sent to `lines`.
struct Running {
    child: Child,
    lines: mpsc::Receiver<String>,
    stderr: Vec<String>,
}

impl Running {
    fn start(args: &[&str], cwd: &Path) -> Self {
        let mut child = command(args, cwd)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start splitray");
        let stderr = child.stderr.take().unwrap();
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        Self {
            child,
            lines,
            stderr: Vec::new(),
        }
    }

    fn signal(&self, name: &str) {
        let status = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    }

    /// Waits for a stderr line containing `needle`.
    fn wait_for_line(&mut self, needle: &str) {
        let deadline = Instant::now() + Duration::from_secs(60);
        while !self.stderr.iter().any(|l| l.contains(needle)) {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => self.stderr.push(line),
                Err(_) => panic!("no {needle:?} on stderr: {:?}", self.stderr),
            }
        }
    }

    /// Waits for the process to end; its exit code and whole stderr.
    fn finish(mut self) -> (Option<i32>, String) {
        let deadline = Instant::now() + Duration::from_secs(120);
        let status = loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                break status;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("splitray did not exit: {:?}", self.stderr);
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        // The reader thread ends with the pipe; collect what it sent.
        while let Ok(line) = self.lines.recv_timeout(Duration::from_secs(5)) {
            self.stderr.push(line);
        }
        (status.code(), self.stderr.join("\n"))
    }
}

/// Waits until `path` exists (a render's first checkpoint: passes are being rendered).
fn wait_for_file(path: &Path) {
    let deadline = Instant::now() + Duration::from_secs(120);
    while !path.exists() {
        assert!(
            Instant::now() < deadline,
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn rgb_bits(path: &Path) -> Vec<[u32; 3]> {
    let (film, _) = read_exr(path).unwrap();
    film.mean_rgb_buffer()
        .iter()
        .map(|p| p.map(f32::to_bits))
        .collect()
}

#[test]
fn outputs_that_cannot_be_written_fail_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // --device names no device: an error about the path shows that it came first.
    let base = [
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--device",
        "no-such-gpu",
    ];
    for (extra, path) in [
        (["-o", "/proc/x.exr"], "/proc/x.exr"),
        (["--stats", "/proc/x.json"], "/proc/x.json"),
        (["--checkpoint", "/proc/x.ckpt"], "/proc/x.ckpt"),
        (["--timeline", "/proc/t.json"], "/proc/t.json"),
    ] {
        let mut args: Vec<&str> = base.to_vec();
        args.extend(extra);
        if extra[0] != "-o" {
            args.extend(["-o", "img.exr"]);
        }
        let out = splitray(&args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{t}");
        assert_eq!(t.matches(path).count(), 1, "the path named once:\n{t}");
        assert!(!t.contains("no-such-gpu") && !t.contains("panicked"), "{t}");
        assert!(outputs(d).is_empty(), "{args:?} left {:?}", outputs(d));
    }
    // merge checks its output before it reads a part.
    let out = splitray(&["merge", "missing.exr", "-o", "/proc/m.exr"], d);
    let t = text(&out);
    assert!(!out.status.success() && t.contains("/proc/m.exr"), "{t}");
    assert!(!t.contains("missing.exr"), "{t}");
}

#[test]
fn sigint_writes_the_samples_reached_and_the_render_resumes_bit_identically() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = ["--integrator", "pt", "--width", "32", "--height", "24"];
    let mut args = vec![
        "render", "-o", "img.exr", "--time", "60", "--stats", "st.json",
    ];
    args.extend(scene);
    args.extend(["--checkpoint", "run.ckpt", "--checkpoint-every", "0"]);
    let mut render = Running::start(&args, d);
    wait_for_file(&d.join("run.ckpt"));
    render.signal("INT");
    render.wait_for_line("SIGINT: stopping after the passes in flight");
    let (code, stderr) = render.finish();
    assert_eq!(code, Some(130), "{stderr}");
    assert!(stderr.contains("SIGINT: the render stopped at"), "{stderr}");
    assert!(temporaries(d).is_empty(), "{:?}", temporaries(d));

    let (_, meta) = read_exr(d.join("img.exr")).unwrap();
    let checkpoint = Checkpoint::read(d.join("run.ckpt")).unwrap();
    let reached = checkpoint.header.passes;
    assert!(
        reached > 0 && meta.spp == reached,
        "{} vs {reached}",
        meta.spp
    );
    assert!(meta
        .extra
        .contains(&("stopped_early".to_string(), "true".to_string())));
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("st.json")).unwrap()).unwrap();
    assert_eq!(stats["stopped_early"], true);
    assert_eq!(stats["spp"], reached);

    // Resumed to more samples, it equals an uninterrupted render of as many, bit for bit.
    let target = (reached + 3).to_string();
    let out = splitray(
        &[
            "render",
            "--resume",
            "run.ckpt",
            "--spp",
            &target,
            "-o",
            "resumed.exr",
        ],
        d,
    );
    assert!(out.status.success(), "{}", text(&out));
    let mut direct = vec!["render", "-o", "direct.exr", "--spp", &target];
    direct.extend(scene);
    let out = splitray(&direct, d);
    assert!(out.status.success(), "{}", text(&out));
    assert!(rgb_bits(&d.join("resumed.exr")) == rgb_bits(&d.join("direct.exr")));
    let (resumed, _) = read_exr(d.join("resumed.exr")).unwrap();
    let (uninterrupted, _) = read_exr(d.join("direct.exr")).unwrap();
    assert!(resumed.stderr.is_some() && resumed.stderr == uninterrupted.stderr);
    // Without --checkpoint, the resumed render went on saving to the one it resumed.
    let held = Checkpoint::read(d.join("run.ckpt")).unwrap().header.passes;
    assert_eq!(held, reached + 3);

    // A changed setting is refused, naming the checkpoint, and writes nothing.
    let out = splitray(
        &[
            "render",
            "--resume",
            "run.ckpt",
            "--seed",
            "9",
            "-o",
            "other.exr",
        ],
        d,
    );
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(
        t.contains("run.ckpt") && t.contains("seed 0 in the checkpoint, 9"),
        "{t}"
    );
    assert!(!d.join("other.exr").exists() && temporaries(d).is_empty());

    // Asking for no more samples than it holds is refused rather than rewriting its image.
    let held = held.to_string();
    let out = splitray(
        &[
            "render", "--resume", "run.ckpt", "--spp", &held, "-o", "same.exr",
        ],
        d,
    );
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(
        t.contains("run.ckpt") && t.contains(&format!("holds {held} spp already")),
        "{t}"
    );
    assert!(!d.join("same.exr").exists() && temporaries(d).is_empty());
}

/// SIGTERM, and SIGHUP (the terminal or ssh connection went away), stop a render as SIGINT
/// does: the samples reached are written, and the exit status is 128 + the signal.
#[test]
fn sigterm_and_sighup_write_the_samples_reached_and_exit_143_and_129() {
    for (signal, code) in [("TERM", 143), ("HUP", 129)] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let args = [
            "render",
            "-o",
            "img.exr",
            "--time",
            "60",
            "--integrator",
            "ao",
            "--width",
            "32",
            "--height",
            "24",
            "--checkpoint",
            "run.ckpt",
            "--checkpoint-every",
            "0",
        ];
        let mut render = Running::start(&args, d);
        wait_for_file(&d.join("run.ckpt"));
        render.signal(signal);
        render.wait_for_line(&format!("SIG{signal}: stopping"));
        let (status, stderr) = render.finish();
        assert_eq!(status, Some(code), "{stderr}");
        let (_, meta) = read_exr(d.join("img.exr")).unwrap();
        assert_eq!(
            meta.spp,
            Checkpoint::read(d.join("run.ckpt")).unwrap().header.passes
        );
        assert!(meta.spp > 0);
        assert!(temporaries(d).is_empty(), "{:?}", temporaries(d));
    }
}

#[test]
fn a_second_signal_exits_at_once_leaving_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Passes of a 512×512 path-traced film last long enough on a CPU device that the
    // second signal lands while the first waits for the passes in flight.
    let args = [
        "render",
        "-o",
        "img.exr",
        "--time",
        "60",
        "--integrator",
        "pt",
        "--width",
        "512",
        "--height",
        "512",
        "--stats",
        "st.json",
        "--checkpoint",
        "run.ckpt",
        "--checkpoint-every",
        "0",
    ];
    let mut render = Running::start(&args, d);
    wait_for_file(&d.join("run.ckpt"));
    render.signal("INT");
    render.wait_for_line("SIGINT: stopping");
    render.signal("INT");
    let (code, stderr) = render.finish();
    assert_eq!(code, Some(130), "{stderr}");
    assert!(stderr.contains("SIGINT again: exiting at once"), "{stderr}");
    // Only the checkpoint saved before the signals is left, and it is whole.
    assert_eq!(outputs(d), ["run.ckpt"], "{stderr}");
    assert!(Checkpoint::read(d.join("run.ckpt")).is_ok());
}

#[test]
fn shards_rendered_apart_merge_into_one_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let common = [
        "--integrator",
        "ao",
        "--width",
        "24",
        "--height",
        "16",
        "--spp",
        "4",
    ];
    let run = |extra: &[&str], env: &[(&str, &str)]| {
        let mut args = vec!["render"];
        args.extend(common);
        args.extend(extra);
        let out = command(&args, d)
            .envs(env.iter().copied())
            .output()
            .unwrap();
        assert!(out.status.success(), "{args:?}: {}", text(&out));
    };
    run(&["--shard", "0/2", "-o", "part0.exr"], &[]);
    // As a Slurm array task would: --array=5-6 runs tasks 5 and 6.
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "6"),
        ("SLURM_ARRAY_TASK_MIN", "5"),
        ("SLURM_ARRAY_TASK_COUNT", "2"),
    ];
    run(&["--shard", "auto", "-o", "part1.exr"], &slurm);
    run(&["-o", "whole.exr"], &[]);
    let out = splitray(&["merge", "part0.exr", "part1.exr", "-o", "merged.exr"], d);
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("merged 2 parts: 24x16 4 spp (passes 0..4)"),
        "{}",
        text(&out)
    );
    let (merged, meta) = read_exr(d.join("merged.exr")).unwrap();
    let (whole, _) = read_exr(d.join("whole.exr")).unwrap();
    assert_eq!(meta.spp, 4);
    // The same samples: equal up to the rounding of f32 sums of 4 passes (8·u relative).
    let u = 1.0 / (1u64 << 24) as f32;
    for (a, b) in merged.mean_rgb_buffer().iter().zip(whole.mean_rgb_buffer()) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 8.0 * u * a[c].abs().max(b[c].abs()));
        }
    }

    let out = splitray(&["merge", "part0.exr", "part0.exr", "-o", "twice.exr"], d);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out).contains("the same shard twice"),
        "{}",
        text(&out)
    );
    assert!(!d.join("twice.exr").exists() && temporaries(d).is_empty());

    // A merged image is a part too, first or not; its header counts the renders in it.
    let out = splitray(&["merge", "part0.exr", "-o", "m0.exr"], d);
    assert!(out.status.success(), "{}", text(&out));
    let out = splitray(&["merge", "m0.exr", "part1.exr", "-o", "again.exr"], d);
    assert!(out.status.success(), "{}", text(&out));
    let (again, meta) = read_exr(d.join("again.exr")).unwrap();
    assert_eq!(again.mean_rgb_buffer(), merged.mean_rgb_buffer());
    let renders = meta.extra.iter().find(|(k, _)| k == "merged_parts");
    assert_eq!(renders.map(|(_, v)| v.as_str()), Some("2"));

    // Shards of renders of different lengths merge, with a warning for the passes
    // neither holds: shard 1/2 of 8 spp is passes 4..8, shard 0/2 of 4 spp 0..2.
    let mut args = vec!["render"];
    args.extend(&common[..6]);
    args.extend(["--spp", "8", "--shard", "1/2", "-o", "longer1.exr"]);
    let out = splitray(&args, d);
    assert!(out.status.success(), "{}", text(&out));
    let out = splitray(&["merge", "part0.exr", "longer1.exr", "-o", "gap.exr"], d);
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("warning: no part holds passes 2..4"),
        "{}",
        text(&out)
    );
}

#[test]
fn bad_checkpoints_and_parts_fail_naming_the_file_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("short.ckpt"), b"\x89splitray-ck").unwrap();
    std::fs::write(d.join("notes.txt"), "not a checkpoint, not an image").unwrap();
    let film = splitray::film::Film::from_mean_rgb(2, 2, &[[1.0; 3]; 4]).unwrap();
    splitray::film::write_exr(d.join("plain.exr"), &film, &Default::default()).unwrap();
    let cases: [(&[&str], &str, &str); 6] = [
        (
            &["render", "--resume", "gone.ckpt"],
            "gone.ckpt",
            "No such file",
        ),
        (
            &["render", "--resume", "short.ckpt"],
            "short.ckpt",
            "truncated",
        ),
        (
            &["render", "--resume", "plain.exr"],
            "plain.exr",
            "is an EXR image",
        ),
        (
            &["merge", "gone.exr", "plain.exr"],
            "gone.exr",
            "No such file",
        ),
        (
            &["merge", "plain.exr"],
            "plain.exr",
            "not a part of a splitray render",
        ),
        (&["merge", "notes.txt"], "notes.txt", "EXR"),
    ];
    for (args, file, why) in cases {
        let mut args = args.to_vec();
        args.extend(["-o", "out.exr"]);
        let out = splitray(&args, d);
        let t = text(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {t}");
        assert!(t.contains(file) && t.contains(why), "{args:?}: {t}");
        assert!(!t.contains("panicked"), "{t}");
        assert_eq!(outputs(d), ["plain.exr", "short.ckpt"], "{args:?}");
    }
}

/// A checkpoint names its scene file by an absolute path: `--resume` finds it from any
/// folder; where the file has gone, the error says whose scene it was.
#[test]
fn a_checkpoint_finds_its_scene_from_another_folder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir_all(d.join("scn")).unwrap();
    std::fs::create_dir_all(d.join("elsewhere")).unwrap();
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(d.join("scn/tri.obj"), triangle).unwrap();
    let small = ["--integrator", "ao", "--width", "8", "--height", "8"];
    let mut args = vec![
        "render",
        "scn/tri.obj",
        "--spp",
        "2",
        "--checkpoint",
        "run.ckpt",
    ];
    args.extend(small);
    args.extend(["-o", "a.exr"]);
    let out = splitray(&args, d);
    assert!(out.status.success(), "{}", text(&out));
    let resume = [
        "render",
        "--resume",
        "../run.ckpt",
        "--spp",
        "4",
        "-o",
        "b.exr",
    ];
    let out = splitray(&resume, &d.join("elsewhere"));
    assert!(out.status.success(), "{}", text(&out));

    std::fs::rename(d.join("scn"), d.join("moved")).unwrap();
    let out = splitray(&resume, &d.join("elsewhere"));
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(
        text(&out)
            .contains("(the scene ../run.ckpt was saved from: give its path as SCENE if it moved)"),
        "{}",
        text(&out)
    );
}

/// `--cbpt-nc auto` measures this machine: its checkpoint keeps what it measured, so the
/// render resumes as it would have gone on; shards, which would each measure their own
/// machine, are refused before any work.
#[test]
fn cbpt_auto_populations_resume_and_are_refused_for_shards() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cbpt = [
        "render",
        "--integrator",
        "cbpt",
        "--cbpt-nc",
        "auto",
        "--width",
        "16",
        "--height",
        "8",
    ];
    let run = |extra: &[&str]| {
        let mut args = cbpt.to_vec();
        args.extend(extra);
        splitray(&args, d)
    };
    let out = run(&["--spp", "4", "--checkpoint", "run.ckpt", "-o", "a.exr"]);
    assert!(out.status.success(), "{}", text(&out));
    let checkpoint = Checkpoint::read(d.join("run.ckpt")).unwrap();
    let measured = checkpoint.header.fingerprint.setting("cbpt_camera_paths");
    let saved = checkpoint.header.options.cbpt.camera_paths.fixed();
    assert_eq!(measured, saved.map(|n| n.to_string()).as_deref());
    let out = splitray(
        &[
            "render", "--resume", "run.ckpt", "--spp", "8", "-o", "b.exr",
        ],
        d,
    );
    assert!(out.status.success(), "{}", text(&out));

    let out = run(&["--spp", "8", "--shard", "0/2", "-o", "s0.exr"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(
        text(&out).contains("--cbpt-nc auto measures the machine it runs on"),
        "{}",
        text(&out)
    );
    assert!(!d.join("s0.exr").exists());
}

/// Waits until a temporary file of `name` exists in `dir`: the command has checked its
/// outputs and is at work.
fn wait_for_temporary(dir: &Path, name: &str) {
    let prefix = format!(".{name}.tmp-");
    let deadline = Instant::now() + Duration::from_secs(120);
    while !temporaries(dir).iter().any(|n| n.starts_with(&prefix)) {
        assert!(Instant::now() < deadline, "no temporary file of {name}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// An image that cannot be written at the end (a folder took its path during the render)
/// costs neither the checkpoint nor the stats; the error names it and says how to write
/// the image from the checkpoint, which does.
#[test]
fn an_image_that_cannot_be_written_keeps_the_other_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = "render --width 16 --height 16 --spp 1000000 --time 1 -o img.exr \
                --checkpoint run.ckpt --stats st.json";
    let args: Vec<&str> = args.split_whitespace().collect();
    let render = Running::start(&args, d);
    wait_for_temporary(d, "img.exr");
    std::fs::create_dir(d.join("img.exr")).unwrap();
    let (code, stderr) = render.finish();
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("error: img.exr: cannot rename"), "{stderr}");
    let held = Checkpoint::read(d.join("run.ckpt")).unwrap().header.passes;
    assert!(held > 0 && d.join("st.json").is_file(), "{stderr}");
    let hint = "`splitray render --resume run.ckpt --spp N -o OUT.exr`";
    assert!(stderr.contains(hint), "{stderr}");
    assert!(temporaries(d).is_empty(), "{:?}", temporaries(d));
    let more = (held + 1).to_string();
    let out = splitray(
        &[
            "render",
            "--resume",
            "run.ckpt",
            "--spp",
            &more,
            "-o",
            "again.exr",
        ],
        d,
    );
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(read_exr(d.join("again.exr")).unwrap().1.spp, held + 1);
}

/// A periodic checkpoint that cannot be saved is a warning naming the file: the render
/// goes on to its target and writes its image; the last checkpoint's failure is the
/// command's error.
#[test]
fn a_checkpoint_that_cannot_be_saved_warns_and_the_render_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A sample count, not a time: under load the first pass (shader compilation
    // included) can outlast a short --time, leaving only the final checkpoint.
    let args = "render --width 16 --height 16 --spp 8 -o img.exr \
                --checkpoint run.ckpt --checkpoint-every 0";
    let args: Vec<&str> = args.split_whitespace().collect();
    let render = Running::start(&args, d);
    wait_for_temporary(d, "run.ckpt");
    std::fs::create_dir(d.join("run.ckpt")).unwrap();
    let (code, stderr) = render.finish();
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("run.ckpt: cannot rename its temporary file over it")
            && stderr.contains("the render goes on"),
        "{stderr}"
    );
    let last = stderr.lines().find(|l| l.starts_with("error: ")).unwrap();
    assert!(last.contains("run.ckpt"), "{stderr}");
    let (_, meta) = read_exr(d.join("img.exr")).unwrap();
    assert_eq!(meta.spp, 8, "{stderr}");
    assert!(temporaries(d).is_empty(), "{:?}", temporaries(d));
}

/// A frame of a sequence that cannot be written once rendered (a folder took its name
/// during its render) ends the sequence: the frame before keeps its files, the stats
/// hold the frames written (not the failed one), and the error lists every output that
/// failed (the timeline too, here) with the frames left to render; no temporary file is
/// left.
#[test]
fn a_sequence_frame_that_cannot_be_written_keeps_the_frames_before() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = "render --width 16 --height 16 --spp 1000000 --time 1 --frames 0..3 \
                -o img.exr --stats st.json --timeline tl.json";
    let args: Vec<&str> = args.split_whitespace().collect();
    let render = Running::start(&args, d);
    // Frame 1's temporary files exist once frame 0 is written.
    wait_for_temporary(d, "img_0001.exr");
    std::fs::create_dir(d.join("img_0001.exr")).unwrap();
    std::fs::create_dir(d.join("tl.json")).unwrap();
    let (code, stderr) = render.finish();
    assert_eq!(code, Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(
        outputs(d),
        [
            "img_0000.exr",
            "img_0000.png",
            "img_0001.exr",
            "st.json",
            "tl.json"
        ],
        "{stderr}"
    );
    assert_eq!(read_exr(d.join("img_0000.exr")).unwrap().0.width(), 16);
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("st.json")).unwrap()).unwrap();
    let frames = stats["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 1, "{stats}");
    assert_eq!(frames[0]["frame"], 0, "{stats}");
    let error = &stderr[stderr.find("error: ").expect("an error")..];
    let lines = [
        "error: 2 outputs were not written:",
        "  img_0001.exr: cannot rename its temporary file over it",
        "  tl.json: cannot rename its temporary file over it",
        "the sequence stopped after 1 frame(s) (0..1); `--frames 1..3` renders the rest",
    ];
    for (line, want) in error.lines().zip(lines) {
        assert!(line.starts_with(want), "{stderr}");
    }
    assert_eq!(error.lines().count(), lines.len(), "{stderr}");
}

/// A signal ends a command other than render at once, removing its temporary files.
#[test]
fn a_signal_ends_a_bench_at_once_leaving_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = [
        "bench",
        "primitives",
        "--timeline",
        "t.json",
        "--json",
        "b.json",
    ];
    let mut bench = Running::start(&args, d);
    wait_for_temporary(d, "t.json");
    bench.signal("TERM");
    bench.wait_for_line("SIGTERM: exiting at once; 1 unfinished output file(s) removed");
    let (code, stderr) = bench.finish();
    assert_eq!(code, Some(143), "{stderr}");
    assert!(outputs(d).is_empty(), "{:?}", outputs(d));
}
