//! Checkpoints: a render stopped, saved, read back and continued is bit-identical to an
//! uninterrupted render of the same samples, for every integrator (and, with its standard
//! error, for films of lights 2^70 and 2^-80 as bright); a checkpoint of
//! another scene or settings is refused; a missing, truncated, corrupted or foreign
//! checkpoint gets an error naming the file.
use crate::common;

use std::cell::Cell;
use std::path::Path;

use splitray::film::{AtomicFile, FilmSums};
use splitray::integrator::lvc::options::{LvcOptions, LvcSettings, Variant};
use splitray::integrator::IntegratorKind;
use splitray::render::checkpoint::{CheckpointHeader, SavedOptions, SIGNATURE};
use splitray::render::{
    render_from, render_with, Checkpoint, CheckpointHook, FilmSnapshot, Fingerprint, RenderControl,
    RenderError, RenderOptions, RenderOutput, RenderPlan, Resume, Shard,
};
use splitray::scene::{builtin, Scene};
use splitray::vk::Gpu;

/// A render that stops before its `batches + 1`-th batch of passes.
fn interrupted(gpu: &Gpu, scene: &Scene, opts: &RenderOptions, batches: u32) -> RenderOutput {
    let calls = Cell::new(0);
    render_with(
        gpu,
        scene,
        opts,
        RenderControl {
            progress: &mut |_| {},
            stop: &|| {
                calls.set(calls.get() + 1);
                calls.get() > batches
            },
            abandon: &|| false,
        },
    )
    .unwrap()
}

/// A whole render that hands its film to `save` whenever the render loop offers a
/// checkpoint (an interval of 0 s).
fn checkpointed(
    gpu: &Gpu,
    scene: &Scene,
    opts: &RenderOptions,
    save: &mut dyn FnMut(&FilmSnapshot<'_>) -> Result<(), RenderError>,
) -> RenderOutput {
    render_from(
        gpu,
        scene,
        opts,
        RenderPlan {
            checkpoint: Some(CheckpointHook { every_s: 0.0, save }),
            ..Default::default()
        },
        RenderControl {
            progress: &mut |_| {},
            stop: &|| false,
            abandon: &|| false,
        },
    )
    .unwrap()
}

/// A whole render of the Cornell box and the checkpoint of its first batch of passes.
fn whole_and_first_checkpoint(
    gpu: &Gpu,
    scene: &Scene,
    opts: &RenderOptions,
) -> (RenderOutput, Checkpoint) {
    let mut first: Option<Checkpoint> = None;
    let mut hook = |s: &FilmSnapshot<'_>| -> Result<(), RenderError> {
        first.get_or_insert_with(|| Checkpoint::new("cornell-box", opts, s));
        Ok(())
    };
    let whole = checkpointed(gpu, scene, opts, &mut hook);
    (whole, first.expect("a checkpoint before the last batch"))
}

fn resumed(
    gpu: &Gpu,
    scene: &Scene,
    opts: &RenderOptions,
    checkpoint: &Checkpoint,
    path: &Path,
) -> Result<RenderOutput, RenderError> {
    render_from(
        gpu,
        scene,
        opts,
        RenderPlan {
            resume: Some(Resume { checkpoint, path }),
            ..Default::default()
        },
        RenderControl {
            progress: &mut |_| {},
            stop: &|| false,
            abandon: &|| false,
        },
    )
}

fn save(dir: &Path, name: &str, checkpoint: &Checkpoint) -> std::path::PathBuf {
    let path = dir.join(name);
    checkpoint
        .write(AtomicFile::create(&path).unwrap())
        .unwrap();
    path
}

#[test]
fn an_interrupted_and_resumed_render_is_bit_identical_for_every_integrator() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let dir = tempfile::tempdir().unwrap();
    for (kind, _) in IntegratorKind::ALL {
        // Six passes: a pass of cbpt holds four samples per pixel.
        let spp = if *kind == IntegratorKind::Cbpt { 24 } else { 6 };
        let opts = common::small_render_options(&scene, *kind, spp);
        // The uninterrupted render saves its film after its first batch of passes (one
        // pass): that checkpoint is what an interrupted render leaves.
        let (whole, saved) = whole_and_first_checkpoint(&gpu, &scene, &opts);
        assert_eq!(whole.sums.passes, 6, "{kind}");
        assert_eq!(saved.header.passes, 1, "{kind}");
        let path = save(dir.path(), &format!("{kind}.ckpt"), &saved);
        let read = Checkpoint::read(&path).unwrap();
        assert_eq!(read.header, saved.header, "{kind}");
        assert!(read.sums == saved.sums, "{kind}: the sums read back differ");

        let out = resumed(&gpu, &scene, &opts, &read, &path).unwrap();
        assert!(out.sums == whole.sums, "{kind}: the resumed film differs");
        assert_eq!(out.film.mean_rgb_buffer(), whole.film.mean_rgb_buffer());
        assert_eq!(out.film.stderr, whole.film.stderr, "{kind}");
        assert_eq!(out.record, whole.record, "{kind}");
        assert_eq!(out.metadata.spp, spp);
        assert!(out.total_render_time_s > saved.header.render_time_s);
    }
    common::assert_clean(&gpu);
}

#[test]
fn a_film_of_lights_far_from_one_resumes_bit_identical_with_its_standard_error() {
    // The GPU sums second moments of estimates times a power of two (their squares
    // would leave f32's range); the checkpoint holds them unscaled, and restoring puts
    // the scale back exactly.
    let gpu = common::gpu();
    let dir = tempfile::tempdir().unwrap();
    for exponent in [-80, 70] {
        let factor = 2f32.powi(exponent);
        let scene = common::scenes::brighter(&builtin("cornell-box").unwrap(), factor);
        for kind in [
            IntegratorKind::Pt,
            IntegratorKind::LvcBdpt,
            IntegratorKind::CisLbdpt,
        ] {
            let what = format!("{kind}, lights × 2^{exponent}");
            let opts = common::small_render_options(&scene, kind, 6);
            let (whole, saved) = whole_and_first_checkpoint(&gpu, &scene, &opts);
            let path = save(dir.path(), &format!("{kind}{exponent}.ckpt"), &saved);
            let read = Checkpoint::read(&path).unwrap();
            assert!(read.sums == saved.sums, "{what}: the sums read back differ");
            let out = resumed(&gpu, &scene, &opts, &read, &path).unwrap();
            assert!(out.sums == whole.sums, "{what}: the resumed film differs");
            let se = whole.film.stderr.as_ref().expect("a standard error");
            assert_eq!(out.film.stderr.as_ref(), Some(se), "{what}");
            assert!(se.iter().flatten().all(|v| v.is_finite()), "{what}");
            assert!(se.iter().flatten().any(|&v| v > 0.0), "{what}");
            assert!(
                common::scenes::squares_leave_f32(&whole.sums.mean()),
                "{what}: no mean whose square leaves f32's range"
            );
        }
    }
    common::assert_clean(&gpu);
}

/// A cache integrator's checkpoint keeps N, M and the draws it ran with even where the
/// render left them to the defaults, so that a build with other defaults continues the
/// same estimator; the options read back from it (what `render --resume` starts from)
/// continue the render bit for bit.
#[test]
fn a_cache_integrators_checkpoint_keeps_its_estimator_explicit() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let opts = common::small_render_options(&scene, IntegratorKind::CisLbdpt, 4);
    assert_eq!(opts.lvc, LvcSettings::default(), "the defaults, left unset");
    let (whole, first) = whole_and_first_checkpoint(&gpu, &scene, &opts);
    let path = save(dir.path(), "cis.ckpt", &first);
    let read = Checkpoint::read(&path).unwrap();
    let defaults = LvcOptions::new(Variant::CisLbdpt, false);
    let kept = read.header.options.lvc;
    assert_eq!(kept.connections, Some(defaults.connections));
    assert_eq!(kept.candidates, Some(defaults.candidates));
    assert_eq!(kept.resampling, Some(defaults.resampling));
    // Neither changes the image; sorting's default is the device's.
    assert_eq!((kept.streams, kept.sort), (None, None));

    let again = read.header.options.to_options().unwrap();
    let out = resumed(&gpu, &scene, &again, &read, &path).unwrap();
    assert!(out.sums == whole.sums, "the resumed film differs");
    common::assert_clean(&gpu);
}

#[test]
fn the_render_loop_hands_its_film_to_the_checkpoint_hook_as_it_goes() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let opts = common::small_render_options(&scene, IntegratorKind::Ao, 5);
    let mut saved: Vec<Checkpoint> = Vec::new();
    let mut hook = |s: &FilmSnapshot<'_>| -> Result<(), RenderError> {
        saved.push(Checkpoint::new("cornell-box", &opts, s));
        Ok(())
    };
    let whole = checkpointed(&gpu, &scene, &opts, &mut hook);
    // `ao` renders one pass per batch: saved after each but the last.
    let passes: Vec<u32> = saved.iter().map(|c| c.header.passes).collect();
    assert_eq!(passes, [1, 2, 3, 4]);
    let dir = tempfile::tempdir().unwrap();
    let path = save(dir.path(), "ao.ckpt", &saved[2]);
    let out = resumed(
        &gpu,
        &scene,
        &opts,
        &Checkpoint::read(&path).unwrap(),
        &path,
    )
    .unwrap();
    assert!(out.sums == whole.sums, "the resumed film differs");
    common::assert_clean(&gpu);
}

#[test]
fn a_checkpoint_of_another_scene_or_settings_is_refused_naming_the_file() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let opts = common::small_render_options(&scene, IntegratorKind::Pt, 4);
    let part = interrupted(&gpu, &scene, &opts, 1);
    let checkpoint = Checkpoint::new("cornell-box", &opts, &part.snapshot());
    let path = save(dir.path(), "pt.ckpt", &checkpoint);

    let mut other_scene = scene.clone();
    other_scene.materials[0].diffuse.x *= 0.5;
    let mut other_seed = opts.clone();
    other_seed.seed = 8;
    let mut other_depth = opts.clone();
    other_depth.max_depth = 3;
    let cases = [
        (&other_scene, &opts, "scene's geometry, materials"),
        (
            &scene,
            &other_seed,
            "seed 7 in the checkpoint, 8 in this render",
        ),
        (
            &scene,
            &other_depth,
            "max_depth -1 in the checkpoint, 3 in this render",
        ),
    ];
    for (s, o, expected) in cases {
        let err = resumed(&gpu, s, o, &checkpoint, &path)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("pt.ckpt") && err.contains(expected), "{err}");
    }

    // A one-sample eye render goes through pixel centres: it cannot become a jittered one.
    let ao1 = common::small_render_options(&scene, IntegratorKind::Ao, 1);
    let single = interrupted(&gpu, &scene, &ao1, 1);
    let c = Checkpoint::new("cornell-box", &ao1, &single.snapshot());
    let ao4 = common::small_render_options(&scene, IntegratorKind::Ao, 4);
    let err = resumed(&gpu, &scene, &ao4, &c, &path)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("jitter false in the checkpoint, true"),
        "{err}"
    );
    common::assert_clean(&gpu);
}

#[test]
fn a_shard_continues_only_its_own_block_of_passes() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let opts = common::small_render_options(&scene, IntegratorKind::Ao, 8);
    let shard = Shard::new(1, 2).unwrap();
    let run_as = |opts: &RenderOptions, plan: RenderPlan<'_>, stop_after: u32| {
        let calls = Cell::new(0);
        render_from(
            &gpu,
            &scene,
            opts,
            plan,
            RenderControl {
                progress: &mut |_| {},
                stop: &|| {
                    calls.set(calls.get() + 1);
                    calls.get() > stop_after
                },
                abandon: &|| false,
            },
        )
    };
    let run = |plan: RenderPlan<'_>, stop_after: u32| run_as(&opts, plan, stop_after);
    let whole_shard = run(
        RenderPlan {
            shard,
            ..Default::default()
        },
        u32::MAX,
    )
    .unwrap();
    assert_eq!((whole_shard.first_pass, whole_shard.sums.passes), (4, 4));
    let part = run(
        RenderPlan {
            shard,
            ..Default::default()
        },
        2,
    )
    .unwrap();
    let checkpoint = Checkpoint::new("cornell-box", &opts, &part.snapshot());
    assert_eq!(checkpoint.header.shard, shard);
    let path = Path::new("shard.ckpt");
    let resume = || Resume {
        checkpoint: &checkpoint,
        path,
    };
    let out = run(
        RenderPlan {
            shard,
            resume: Some(resume()),
            ..Default::default()
        },
        u32::MAX,
    )
    .unwrap();
    assert!(out.sums == whole_shard.sums, "the resumed shard differs");
    let err = run(
        RenderPlan {
            shard: Shard::new(0, 2).unwrap(),
            resume: Some(resume()),
            ..Default::default()
        },
        u32::MAX,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        err.contains("shard.ckpt: was saved as shard 1/2, not 0/2"),
        "{err}"
    );

    // Continued to another length, a shard's block would move: shard 0/2 of 8 passes
    // is 0..4, of 12 passes 0..6 (which its neighbour's 6..12 would not meet).
    let first = Shard::new(0, 2).unwrap();
    let part = run(
        RenderPlan {
            shard: first,
            ..Default::default()
        },
        2,
    )
    .unwrap();
    let checkpoint = Checkpoint::new("cornell-box", &opts, &part.snapshot());
    let longer = common::small_render_options(&scene, IntegratorKind::Ao, 12);
    let resumed = |opts: &RenderOptions| {
        let resume = Some(Resume {
            checkpoint: &checkpoint,
            path,
        });
        run_as(
            opts,
            RenderPlan {
                shard: first,
                resume,
                ..Default::default()
            },
            u32::MAX,
        )
    };
    let err = resumed(&longer).err().unwrap().to_string();
    assert!(
        err.contains(
            "shard.ckpt: was saved as shard 0/2 of a render of 8 spp (passes 0..4); this \
             render's shard 0/2 is passes 0..6"
        ),
        "{err}"
    );
    let out = resumed(&opts).unwrap();
    assert_eq!((out.first_pass, out.sums.passes), (0, 4));
    common::assert_clean(&gpu);
}

/// A checkpoint of a 3×2 film made on the CPU: the file format needs no device.
pub(crate) fn small_checkpoint() -> Checkpoint {
    let scene = builtin("cornell-box").unwrap();
    let mut sums = FilmSums::new(3, 2, 1, true);
    sums.add_pass(&[
        [0.5, 1.0, 1.5],
        [0.0; 3],
        [1e-30, 3e30, -2.0],
        [1.0; 3],
        [2.0; 3],
        [3.0; 3],
    ]);
    let mut opts = common::small_render_options(&scene, IntegratorKind::Pt, 4);
    (opts.width, opts.height) = (3, 2);
    Checkpoint {
        header: CheckpointHeader {
            software: "splitray test".into(),
            scene: "cornell-box".into(),
            fingerprint: Fingerprint::new(&scene, 3, 2, 7, "pt", 1, Vec::new()),
            options: SavedOptions::new(&opts),
            shard: Shard::WHOLE,
            first_pass: 0,
            passes: 1,
            samples_per_pass: 1,
            width: 3,
            height: 2,
            second_moments: true,
            render_time_s: 1.5,
        },
        sums,
    }
}

fn read_error(path: &Path) -> String {
    let err = match Checkpoint::read(path) {
        Ok(_) => panic!("{} was read", path.display()),
        Err(e) => e.to_string(),
    };
    assert!(err.contains(&*path.to_string_lossy()), "{err}");
    err
}

#[test]
fn missing_truncated_corrupted_and_foreign_checkpoints_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let checkpoint = small_checkpoint();
    let path = save(d, "good.ckpt", &checkpoint);
    assert!(Checkpoint::read(&path).unwrap() == checkpoint);
    let bytes = std::fs::read(&path).unwrap();

    assert!(read_error(&d.join("missing.ckpt")).contains("No such file"));
    for (cut, expected) in [
        (0, "is empty"),
        (5, "ends inside the checkpoint signature"),
        (SIGNATURE.len() + 6, "ends inside its header"),
        (SIGNATURE.len() + 20, "ends inside its header"),
        (bytes.len() - 40, "is truncated"),
        (bytes.len() - 1, "is truncated"),
    ] {
        let cut_path = d.join(format!("cut-{cut}.ckpt"));
        std::fs::write(&cut_path, &bytes[..cut]).unwrap();
        let err = read_error(&cut_path);
        assert!(err.contains(expected), "cut at {cut}: {err}");
    }
    let mut longer = bytes.clone();
    longer.push(0);
    std::fs::write(d.join("longer.ckpt"), &longer).unwrap();
    assert!(read_error(&d.join("longer.ckpt")).contains("trailing bytes"));

    let mut flipped = bytes.clone();
    let at = bytes.len() - 40;
    flipped[at] ^= 1;
    std::fs::write(d.join("flipped.ckpt"), &flipped).unwrap();
    assert!(read_error(&d.join("flipped.ckpt")).contains("checksum does not match"));

    let mut version = bytes.clone();
    version[SIGNATURE.len()] = 2;
    std::fs::write(d.join("v2.ckpt"), &version).unwrap();
    assert!(read_error(&d.join("v2.ckpt")).contains("version 2 checkpoint"));

    let film = splitray::film::Film::from_mean_rgb(1, 1, &[[1.0; 3]]).unwrap();
    let exr = d.join("image.exr");
    splitray::film::write_exr(&exr, &film, &Default::default()).unwrap();
    assert!(read_error(&exr).contains("is an EXR image"));
    std::fs::write(
        d.join("notes.txt"),
        "a text file, long enough to hold a header",
    )
    .unwrap();
    assert!(read_error(&d.join("notes.txt")).contains("not a splitray checkpoint"));
}

/// A periodic checkpoint that cannot be saved does not stop the render: it goes on,
/// and the next save is tried at the next interval.
#[test]
fn a_failed_periodic_checkpoint_lets_the_render_go_on() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let opts = common::small_render_options(&scene, IntegratorKind::Ao, 5);
    let mut offered: Vec<u32> = Vec::new();
    let mut hook = |s: &FilmSnapshot<'_>| -> Result<(), RenderError> {
        offered.push(s.sums.passes);
        match offered.len() {
            1 => Err(RenderError::from(splitray::film::FilmError::Io {
                path: "full/disk.ckpt".into(),
                op: "write",
                error: std::io::Error::other("No space left on device"),
            })),
            _ => Ok(()),
        }
    };
    let whole = checkpointed(&gpu, &scene, &opts, &mut hook);
    assert_eq!(whole.sums.passes, 5);
    // `ao` renders one pass per batch: offered after each but the last, the failure
    // included.
    assert_eq!(offered, [1, 2, 3, 4]);
    common::assert_clean(&gpu);
}

/// A header no render could have saved, under a checksum that matches (a writer's bug
/// or a hand-made file), is refused when read, naming the file and the contradiction.
#[test]
fn a_checkpoint_whose_header_contradicts_itself_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("odd.ckpt");
    type Edit = fn(&mut CheckpointHeader);
    let cases: [(Edit, &str); 5] = [
        (
            |h| h.options.width = 4,
            "its film is 3x2 but its options ask for 4x2",
        ),
        (|h| h.samples_per_pass = 0, "its passes have no samples"),
        (
            |h| (h.first_pass, h.passes) = (u32::MAX, 1),
            "run past the last pass number",
        ),
        (|h| h.shard = Shard { index: 2, count: 2 }, "shard 2/2"),
        (|h| h.render_time_s = -1.0, "its render time is -1 s"),
    ];
    let good = small_checkpoint();
    good.write(AtomicFile::create(&path).unwrap()).unwrap();
    assert_eq!(Checkpoint::read(&path).unwrap(), good);
    for (edit, want) in cases {
        let mut odd = small_checkpoint();
        edit(&mut odd.header);
        odd.write(AtomicFile::create(&path).unwrap()).unwrap();
        let err = Checkpoint::read(&path).unwrap_err().to_string();
        assert!(
            err.contains("odd.ckpt") && err.contains("corrupted header") && err.contains(want),
            "{err}"
        );
    }
}
