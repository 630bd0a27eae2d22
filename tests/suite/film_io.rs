//! File-level tests of the film module: EXR round trips, PNG previews, atomic writes.

use std::path::Path;

use splitray::film::{
    read_exr, write_exr, write_outputs, write_png_preview, AtomicFile, Film, FilmError, ImageFiles,
    RenderMetadata,
};

fn meta() -> RenderMetadata {
    RenderMetadata {
        spp: 1024,
        seed: 0xDEAD_BEEF_CAFE_F00D,
        integrator: "cis-lbdpt".into(),
        tracer: "rq-inline".into(),
        device: "NVIDIA H100 80GB HBM3 (driver 550.54) — ünïcode".into(),
        render_time_s: 12.345_678_9,
        extra: vec![
            ("scene".into(), "cornell-box.obj".into()),
            (
                "a_very_long_metadata_key_that_needs_long_names".into(),
                "x".into(),
            ),
            ("camera".into(), "pinhole fov=40".into()),
        ],
    }
}

/// A film with varied, non-trivial values (including negative and huge ones) and all AOVs.
fn test_film(width: u32, height: u32, aovs: bool) -> Film {
    let n = (width * height) as usize;
    let mut film = Film::new(width, height);
    let pass: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let f = i as f32;
            [f * 0.37 + 0.1, (f * 1.7).sin() * 3.0, 1.0 / (f + 1.0), 0.0]
        })
        .collect();
    film.accumulate(&pass).unwrap();
    if aovs {
        film.set_depth(
            (0..n)
                .map(|i| {
                    if i % 5 == 0 {
                        f32::INFINITY
                    } else {
                        i as f32 * 0.01
                    }
                })
                .collect(),
        )
        .unwrap();
        film.set_triangle_id(
            (0..n)
                .map(|i| {
                    if i % 5 == 0 {
                        u32::MAX
                    } else {
                        (i * 7919) as u32
                    }
                })
                .collect(),
        )
        .unwrap();
        film.set_normal(
            (0..n)
                .map(|i| {
                    let a = i as f32 * 0.1;
                    [a.cos(), a.sin(), -0.0]
                })
                .collect(),
        )
        .unwrap();
        film.set_stderr(
            (0..n)
                .map(|i| [i as f32 * 1e-3, 0.0, f32::MIN_POSITIVE])
                .collect(),
        )
        .unwrap();
    }
    film
}

fn bits3(v: &[[f32; 3]]) -> Vec<[u32; 3]> {
    v.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn dir_entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn exr_round_trip_is_bit_exact_with_aovs_and_metadata() {
    let dir = tempfile::tempdir().unwrap();
    for (w, h) in [(1, 1), (3, 7), (513, 257)] {
        let film = test_film(w, h, true);
        let path = dir.path().join(format!("img_{w}x{h}.exr"));
        write_exr(&path, &film, &meta()).unwrap();
        let (back, m) = read_exr(&path).unwrap();

        assert_eq!((back.width(), back.height()), (w, h));
        assert_eq!(
            bits3(&back.mean_rgb_buffer()),
            bits3(&film.mean_rgb_buffer()),
            "RGB not bit-exact at {w}x{h}"
        );
        let depth_bits = |f: &Film| -> Vec<u32> {
            f.depth
                .as_ref()
                .unwrap()
                .iter()
                .map(|d| d.to_bits())
                .collect()
        };
        assert_eq!(depth_bits(&back), depth_bits(&film));
        assert_eq!(back.triangle_id, film.triangle_id);
        assert_eq!(
            bits3(back.normal.as_ref().unwrap()),
            bits3(film.normal.as_ref().unwrap())
        );
        assert_eq!(
            bits3(back.stderr.as_ref().unwrap()),
            bits3(film.stderr.as_ref().unwrap())
        );

        let mut expected = meta();
        expected.extra.sort();
        assert_eq!(m, expected);
    }
    assert_eq!(
        dir_entries(dir.path()),
        ["img_1x1.exr", "img_3x7.exr", "img_513x257.exr"],
        "no temporary files left behind"
    );
}

#[test]
fn exr_without_aovs_has_none_and_defaults_are_fine() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plain.exr");
    let film = test_film(4, 3, false);
    write_exr(&path, &film, &RenderMetadata::default()).unwrap();
    let (back, m) = read_exr(&path).unwrap();
    assert!(back.depth.is_none() && back.triangle_id.is_none() && back.normal.is_none());
    assert_eq!(m, RenderMetadata::default());
    assert_eq!(
        bits3(&back.mean_rgb_buffer()),
        bits3(&film.mean_rgb_buffer())
    );
}

#[test]
fn exr_rows_are_top_down() {
    // Pixel (x=1, y=0) is the top row; check it lands at row 0 in the file via the exr crate.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("orient.exr");
    let mut film = Film::new(2, 3);
    let mut pass = vec![[0.0f32; 4]; 6];
    pass[film.index(1, 0)] = [5.0, 6.0, 7.0, 0.0];
    film.accumulate(&pass).unwrap();
    write_exr(&path, &film, &RenderMetadata::default()).unwrap();

    let image = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
    let layer = &image.layer_data;
    let r = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == "R")
        .unwrap();
    let values: Vec<f32> = r.sample_data.values_as_f32().collect();
    assert_eq!(values, [0.0, 5.0, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn non_finite_pixels_are_kept_in_exr_and_magenta_in_png() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.exr");
    let mut film = Film::new(3, 1);
    film.accumulate(&[
        [f32::NAN, 0.0, 0.0, 0.0],
        [0.5, 0.5, 0.5, 0.0],
        [0.0, f32::INFINITY, 0.0, 0.0],
    ])
    .unwrap();
    let out = write_outputs(&path, &film, &meta()).unwrap();
    assert_eq!(out.non_finite_pixels, 2);
    assert_eq!(out.png, dir.path().join("nan.png"));

    let (back, _) = read_exr(&path).unwrap();
    assert!(back.mean_rgb(0)[0].is_nan());
    assert_eq!(back.mean_rgb(2)[1], f32::INFINITY);

    let (info, px) = decode_png(&out.png);
    assert_eq!((info.width, info.height), (3, 1));
    assert_eq!(px, [255, 0, 255, 188, 188, 188, 255, 0, 255]);
}

fn decode_png(path: &Path) -> (png::OutputInfo, Vec<u8>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info, buf)
}

#[test]
fn png_preview_size_and_known_values() {
    let dir = tempfile::tempdir().unwrap();
    for (w, h) in [(1, 1), (3, 7), (513, 257)] {
        let n = (w * h) as usize;
        let mut film = Film::new(w, h);
        let mut pass = vec![[0.25f32, 0.0, 2.0, 1.0]; n];
        pass[n - 1] = [0.09, 0.0031308, 1.0, 0.0];
        film.accumulate(&pass).unwrap();
        let path = dir.path().join(format!("p_{w}x{h}.png"));
        // Exposure 2: 0.25 → 0.5 linear → 0.7354 sRGB → 188; 2.0 → 4.0 → clamps to 255.
        write_png_preview(&path, &film, 2.0).unwrap();
        let (info, px) = decode_png(&path);
        assert_eq!((info.width, info.height), (w, h));
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        assert_eq!(px.len(), n * 3);
        if n > 1 {
            assert_eq!(&px[..3], [188, 0, 255]);
        }
        // 0.18 linear → 0.4613 sRGB → 118 (mid grey); 0.0062616 → 0.0724 → 18; 2.0 → 255.
        assert_eq!(&px[(n - 1) * 3..], [118, 18, 255]);
    }
}

#[test]
fn missing_parent_directory_is_an_error_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("does-not-exist");
    let film = test_film(2, 2, true);
    let target = missing.join("out.exr");

    let err = write_exr(&target, &film, &meta()).unwrap_err();
    assert!(
        matches!(&err, FilmError::MissingDirectory { path, folder } if *folder == missing && *path == target)
    );
    assert!(
        err.to_string().contains(&*missing.to_string_lossy()),
        "{err}"
    );

    assert!(write_png_preview(missing.join("out.png"), &film, 1.0).is_err());
    assert!(write_outputs(&target, &film, &meta()).is_err());
    assert!(!missing.exists());
    assert!(dir_entries(dir.path()).is_empty());
}

#[cfg(unix)]
#[test]
fn unwritable_directory_is_an_error_and_keeps_existing_file() {
    use std::os::unix::fs::PermissionsExt;

    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("ro");
    std::fs::create_dir(&sub).unwrap();
    let target = sub.join("out.exr");
    std::fs::write(&target, b"previous render").unwrap();
    std::fs::set_permissions(&sub, std::fs::Permissions::from_mode(0o555)).unwrap();

    // Root ignores directory permissions; the test is meaningless then.
    let probe = sub.join("probe");
    if std::fs::write(&probe, b"").is_ok() {
        std::fs::remove_file(&probe).unwrap();
        std::fs::set_permissions(&sub, std::fs::Permissions::from_mode(0o755)).unwrap();
        eprintln!("skipping: directory permissions are not enforced (running as root?)");
        return;
    }

    let film = test_film(3, 3, true);
    let err = write_exr(&target, &film, &meta()).unwrap_err();
    let err_png = write_outputs(&target, &film, &meta()).unwrap_err();
    std::fs::set_permissions(&sub, std::fs::Permissions::from_mode(0o755)).unwrap();

    assert!(matches!(err, FilmError::Io { .. }), "{err}");
    assert!(err.to_string().contains("ro"), "{err}");
    assert!(matches!(err_png, FilmError::Io { .. }), "{err_png}");
    assert_eq!(std::fs::read(&target).unwrap(), b"previous render");
    assert_eq!(dir_entries(&sub), ["out.exr"]);
}

#[test]
fn failed_write_keeps_existing_outputs_and_leaves_no_temp() {
    let dir = tempfile::tempdir().unwrap();
    let exr_path = dir.path().join("frame.exr");
    let png_path = dir.path().join("frame.png");
    let good = test_film(5, 4, true);
    write_outputs(&exr_path, &good, &meta()).unwrap();
    let exr_before = std::fs::read(&exr_path).unwrap();
    let png_before = std::fs::read(&png_path).unwrap();

    // A film with a mis-sized AOV fails while encoding, after the temp file was created.
    let mut bad = test_film(5, 4, false);
    bad.depth = Some(vec![1.0; 3]);
    let err = write_outputs(&exr_path, &bad, &meta()).unwrap_err();
    assert!(matches!(err, FilmError::SizeMismatch { .. }), "{err}");
    assert!(write_exr(&exr_path, &bad, &meta()).is_err());

    // Metadata that cannot be represented (duplicate key) also fails cleanly.
    let mut dup = meta();
    dup.extra.push(("scene".into(), "other".into()));
    let err = write_exr(&exr_path, &good, &dup).unwrap_err();
    assert!(err.to_string().contains("duplicate"), "{err}");

    assert_eq!(std::fs::read(&exr_path).unwrap(), exr_before);
    assert_eq!(std::fs::read(&png_path).unwrap(), png_before);
    assert_eq!(dir_entries(dir.path()), ["frame.exr", "frame.png"]);
}

#[test]
fn write_outputs_overwrites_and_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let exr_path = dir.path().join("frame.exr");
    write_outputs(
        &exr_path,
        &test_film(2, 2, false),
        &RenderMetadata::default(),
    )
    .unwrap();
    let film = test_film(7, 3, true);
    let out = write_outputs(&exr_path, &film, &meta()).unwrap();
    assert_eq!(out.exr, exr_path);
    assert_eq!(out.non_finite_pixels, 0);
    let (back, m) = read_exr(&exr_path).unwrap();
    assert_eq!(
        bits3(&back.mean_rgb_buffer()),
        bits3(&film.mean_rgb_buffer())
    );
    assert_eq!(m.seed, meta().seed);
    let (info, _) = decode_png(&out.png);
    assert_eq!((info.width, info.height), (7, 3));
    assert_eq!(dir_entries(dir.path()), ["frame.exr", "frame.png"]);
}

#[test]
fn accumulated_film_round_trips_its_mean() {
    // Several passes plus per-pixel samples: the EXR stores the weighted mean.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("acc.exr");
    let mut film = Film::new(2, 1);
    film.accumulate(&[[1.0, 2.0, 3.0, 0.0], [0.0; 4]]).unwrap();
    film.accumulate(&[[3.0, 2.0, 1.0, 0.0], [4.0; 4]]).unwrap();
    film.add_sample_rgb(1, [1.0, 1.0, 1.0]);
    assert_eq!(film.mean_rgb(0), [2.0, 2.0, 2.0]);
    assert_eq!(film.mean_rgb(1), [5.0 / 3.0; 3]);
    write_exr(&path, &film, &meta()).unwrap();
    let (back, _) = read_exr(&path).unwrap();
    assert_eq!(back.mean_rgb(1), [5.0 / 3.0; 3]);
}

#[test]
fn read_errors_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.exr");
    let err = read_exr(&missing).unwrap_err();
    assert!(err.to_string().contains("nope.exr"), "{err}");
    let garbage = dir.path().join("garbage.exr");
    std::fs::write(&garbage, b"not an exr at all").unwrap();
    let err = read_exr(&garbage).unwrap_err();
    assert!(matches!(err, FilmError::Exr { .. }), "{err}");
    assert!(err.to_string().contains("garbage.exr"), "{err}");
}

/// The decoder sizes its buffers by the header: a data window corrupted past any film,
/// or past what the file's bytes could encode, is refused from the header, naming the
/// file, rather than allocated.
#[test]
fn an_exr_whose_header_describes_more_pixels_than_its_file_holds_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("window.exr");
    write_exr(&path, &test_film(3, 2, true), &meta()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let key = b"dataWindow\0box2i\0";
    // After the name, the type and the 4-byte size: x_min, y_min, x_max, y_max.
    let window = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    for (x_max, y_max, want) in [
        (
            0x3fff_fff0_i32,
            1_i32,
            "its data window is 1073741809x2 pixels, larger than any film (16384x16384)",
        ),
        (15_999, 15_999, "more than 4096 times the file's"),
    ] {
        let mut corrupted = bytes.clone();
        corrupted[window + 8..window + 12].copy_from_slice(&x_max.to_le_bytes());
        corrupted[window + 12..window + 16].copy_from_slice(&y_max.to_le_bytes());
        std::fs::write(&path, &corrupted).unwrap();
        let err = read_exr(&path).unwrap_err().to_string();
        assert!(err.contains("window.exr") && err.contains(want), "{err}");
    }
}

#[test]
fn a_folder_in_the_way_is_refused_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("taken.exr");
    put_a_folder_at(&target);
    let err = write_exr(&target, &test_film(3, 2, true), &meta()).unwrap_err();
    assert!(matches!(err, FilmError::Invalid { .. }), "{err}");
    assert!(err.to_string().contains("taken.exr"), "{err}");
    assert!(err.to_string().contains("is a folder"), "{err}");
    assert_only_the_folder_left(dir.path(), &target);
}

/// A folder, with a file in it, where an output file is to go.
fn put_a_folder_at(target: &Path) {
    std::fs::create_dir(target).unwrap();
    std::fs::write(target.join("keep"), b"k").unwrap();
}

/// `dir` holds the folder of [`put_a_folder_at`] as it was, and nothing else.
fn assert_only_the_folder_left(dir: &Path, target: &Path) {
    assert!(target.join("keep").exists());
    assert_eq!(
        dir_entries(dir),
        [target.file_name().unwrap().to_str().unwrap()]
    );
}

#[test]
fn failing_rename_removes_temp() {
    // A folder takes the target's name while the file is written: the final rename
    // fails. (Works as root too, unlike the permission test.)
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("taken.exr");
    let mut file = AtomicFile::create(&target).unwrap();
    std::io::Write::write_all(file.writer(), b"contents").unwrap();
    put_a_folder_at(&target);
    let err = file.commit().unwrap_err();
    assert!(matches!(err, FilmError::Io { .. }), "{err}");
    assert!(err.to_string().contains("taken.exr"), "{err}");
    assert_only_the_folder_left(dir.path(), &target);
}

#[test]
fn parent_that_is_a_file_is_a_missing_directory() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain-file");
    std::fs::write(&file, b"x").unwrap();
    let err = write_png_preview(file.join("out.png"), &test_film(1, 1, false), 1.0).unwrap_err();
    assert!(
        matches!(&err, FilmError::MissingDirectory { folder, .. } if *folder == file),
        "{err}"
    );
    assert_eq!(dir_entries(dir.path()), ["plain-file"]);
}

#[test]
fn empty_film_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let err = write_outputs(dir.path().join("e.exr"), &Film::new(0, 4), &meta()).unwrap_err();
    assert!(err.to_string().contains("empty"), "{err}");
    assert!(dir_entries(dir.path()).is_empty());
}

#[test]
fn exr_channel_names_and_types_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("names.exr");
    write_exr(&path, &test_film(2, 2, true), &meta()).unwrap();
    let image = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
    let chans: Vec<(String, bool)> = image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| {
            let is_u32 = matches!(c.sample_data, exr::image::FlatSamples::U32(_));
            (c.name.to_string(), is_u32)
        })
        .collect();
    let expect = [
        ("B", false),
        ("G", false),
        ("R", false),
        ("depth.Z", false),
        ("normal.X", false),
        ("normal.Y", false),
        ("normal.Z", false),
        ("stderr.B", false),
        ("stderr.G", false),
        ("stderr.R", false),
        ("triangle_id", true),
    ];
    let expect: Vec<(String, bool)> = expect.iter().map(|(n, u)| (n.to_string(), *u)).collect();
    assert_eq!(chans, expect);
    let attrs = &image.layer_data.attributes.other;
    let spp = attrs.get(&exr::meta::attribute::Text::from("splitray.spp"));
    assert!(matches!(
        spp,
        Some(exr::meta::attribute::AttributeValue::I32(1024))
    ));
}

#[test]
fn image_files_are_created_before_the_work_and_leave_nothing_when_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("later.exr");
    let files = ImageFiles::create(&target).unwrap();
    // Both temporary files exist from the start, hidden beside their targets.
    let temps = dir_entries(dir.path());
    assert_eq!(temps.len(), 2, "{temps:?}");
    assert!(temps
        .iter()
        .all(|t| t.starts_with(".later.") && t.contains(".tmp-")));
    drop(files);
    assert!(dir_entries(dir.path()).is_empty());

    let film = test_film(3, 2, true);
    let written = ImageFiles::create(&target)
        .unwrap()
        .write(&film, &meta())
        .unwrap();
    assert_eq!(written.exr, target);
    assert_eq!(dir_entries(dir.path()), ["later.exr", "later.png"]);

    // An unwritable target fails at creation, naming the target once.
    let err = ImageFiles::create("/proc/later.exr")
        .unwrap_err()
        .to_string();
    assert_eq!(err.matches("/proc/later.exr").count(), 1, "{err}");
}
