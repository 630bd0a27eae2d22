//! `lvc-bdpt` and `cis-lbdpt` against Mitsuba 3's references and the CPU `bpt`
//! (tests/data/reference/,
//! made by tools/mitsuba_reference.py; the comparison and its bounds are
//! `tests/suite/common/reference.rs`'s: image mean within 1%, under 2% of pixel channels
//! beyond 3σ, every 8×8 block within 4.5σ): the Cornell box, `glossy` (GGX-conductor
//! blocks), `mirror` (two mirror sides hidden from the camera, casting a caustic) and
//! `fixture` (the light hidden in a box), all 64×64, with the reference's max_depth and
//! rr_depth; and `lvc-bdpt` against `bpt` (on the CPU: its own walks and techniques) on
//! the same scenes by the same comparison, each image with its own standard error.
use crate::common;

use common::reference::{compare_images, Reference};
use splitray::film::FilmSums;
use splitray::integrator::IntegratorKind;
use splitray::render::{create_integrator, RenderOptions};
use splitray::scene::Scene;
use splitray::vk::Gpu;

/// `kind` on `scene` with `reference`'s depths, `size` × `size` (the reference's film
/// when `None`), seed `seed`.
fn render(
    gpu: &Gpu,
    scene: &Scene,
    reference: &Reference,
    kind: IntegratorKind,
    size: Option<u32>,
    passes: u32,
    seed: u64,
) -> FilmSums {
    let mut options = RenderOptions::resolve(
        scene,
        size,
        size,
        Some(passes),
        Some(seed),
        Some(kind),
        None,
    )
    .unwrap();
    options.max_depth = reference.info.max_depth;
    options.rr_depth = reference.info.rr_depth;
    let mut integrator = create_integrator(gpu, scene, &options).unwrap();
    integrator.render_passes(0, passes).unwrap();
    let stats = integrator.stats();
    assert_eq!(stats.counters["non_finite_dropped"], 0, "{kind}");
    if let Some(clamped) = stats.counters.get("splats_clamped") {
        assert_eq!(*clamped, 0, "{kind}");
    }
    integrator.sums().unwrap()
}

/// Both integrators at 128 passes against reference `name`; `lvc-bdpt` also against
/// `bpt` at 128 passes (independent seeds: for one seed the two would share their
/// subpaths, and correlated estimates would hide differences). At these counts the image
/// mean's standard error is about 0.2% (the light's edge pixels carry most of it), so a
/// 1% difference between two of them is more than 3σ.
fn both(name: &str) {
    let reference = Reference::load(name);
    let scene = reference.scene();
    let gpu = common::gpu();
    let mut lvc = None;
    for kind in [IntegratorKind::LvcBdpt, IntegratorKind::CisLbdpt] {
        let sums = render(&gpu, &scene, &reference, kind, None, 128, 1);
        let (mean, stderr) = (sums.mean(), sums.stderr().unwrap());
        reference
            .compare(&mean, &stderr)
            .assert_agrees(&format!("{kind} {name} 128 passes"));
        lvc.get_or_insert((mean, stderr));
    }
    let bpt = render(&gpu, &scene, &reference, IntegratorKind::Bpt, None, 128, 2);
    common::assert_clean(&gpu);
    let (mean, stderr) = lvc.unwrap();
    let width = reference.info.width as usize;
    compare_images(
        &format!("bpt {name} 128 passes"),
        width,
        (&mean, &stderr),
        (&bpt.mean(), &bpt.stderr().unwrap()),
    )
    .assert_agrees(&format!("lvc-bdpt {name} 128 passes"));
}

#[test]
fn cornell_box_matches_mitsuba_and_bpt() {
    both("cornell_path_64");
}

#[test]
fn glossy_conductor_matches_mitsuba_and_bpt() {
    both("glossy_path_64");
}

#[test]
fn mirror_caustic_matches_mitsuba_and_bpt() {
    both("mirror_path_64");
}

#[test]
fn fixture_matches_mitsuba_and_bpt() {
    both("fixture_ptracer_64");
}
