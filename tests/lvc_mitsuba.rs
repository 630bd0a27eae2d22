//! `lvc-bdpt` and `cis-lbdpt` against Mitsuba 3's references (tests/data/reference/,
//! made by tools/mitsuba_reference.py; the comparison and its bounds are
//! `tests/common/reference.rs`'s: image mean within 1%, under 2% of pixel channels
//! beyond 3σ, every 8×8 block within 4.5σ): the Cornell box, `glossy` (GGX-conductor
//! blocks), `mirror` (two mirror sides hidden from the camera, casting a caustic) and
//! `fixture` (the light hidden in a box), all 64×64, with the reference's max_depth and
//! rr_depth.
mod common;

use common::reference::{Comparison, Reference};
use splitray::integrator::IntegratorKind;
use splitray::render::{create_integrator, RenderOptions};

/// `kind` on reference `name`'s scene for `passes` passes, compared.
fn against(name: &str, kind: IntegratorKind, passes: u32, seed: u64) -> Comparison {
    let reference = Reference::load(name);
    let scene = reference.scene();
    let gpu = common::gpu();
    let mut options = RenderOptions::resolve(
        &scene,
        None,
        None,
        Some(passes),
        Some(seed),
        Some(kind),
        None,
    )
    .unwrap();
    options.max_depth = reference.info.max_depth;
    options.rr_depth = reference.info.rr_depth;
    let mut integrator = create_integrator(&gpu, &scene, &options).unwrap();
    integrator.render_passes(0, passes).unwrap();
    let sums = integrator.sums().unwrap();
    let stats = integrator.stats();
    assert_eq!(stats.counters["non_finite_dropped"], 0, "{name}");
    assert_eq!(stats.counters["splats_clamped"], 0, "{name}");
    drop(integrator);
    common::assert_clean(&gpu);
    reference.compare(&sums.mean(), &sums.stderr().unwrap())
}

fn both(name: &str, passes: u32) {
    for kind in [IntegratorKind::LvcBdpt, IntegratorKind::CisLbdpt] {
        against(name, kind, passes, 1).assert_agrees(&format!("{kind} {name} {passes} passes"));
    }
}

#[test]
fn cornell_box_matches_mitsuba() {
    both("cornell_path_64", 64);
}

#[test]
fn glossy_conductor_matches_mitsuba() {
    both("glossy_path_64", 64);
}

#[test]
fn mirror_caustic_matches_mitsuba() {
    both("mirror_path_64", 64);
}

#[test]
fn fixture_matches_mitsuba() {
    both("fixture_ptracer_64", 64);
}
