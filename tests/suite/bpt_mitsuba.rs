//! `bpt` and `light` against Mitsuba 3's references (tests/data/reference/, made by
//! tools/mitsuba_reference.py; the comparison and its bounds are
//! `tests/suite/common/reference.rs`'s: image mean within 1%, under 2% of pixel channels
//! beyond 3σ, every 8×8 block within 4.5σ). Every reference, both integrators: the
//! Cornell box, `glossy` (GGX-conductor blocks), `mirror` (two mirror sides hidden from
//! the camera, casting a caustic: light tracing can render it, since the camera never
//! looks at a mirror) and `fixture` (the light hidden in a box), all 64×64, with the
//! reference's max_depth and rr_depth. The CPU integrators need no GPU.
use crate::common;

use common::reference::{Comparison, Reference};
use splitray::integrator::bpt::{BidirMode, BptIntegrator, BptOptions};
use splitray::integrator::Integrator;

/// `mode` on reference `name`'s scene for `passes` passes, compared.
fn against(name: &str, mode: BidirMode, passes: u32, seed: u64) -> Comparison {
    let reference = Reference::load(name);
    let scene = reference.scene();
    let options = BptOptions {
        seed,
        max_depth: reference.info.max_depth,
        rr_depth: reference.info.rr_depth,
        ..Default::default()
    };
    let mut b = BptIntegrator::new(mode, &scene, &scene.camera_frame(), &options);
    b.render_passes(0, passes).unwrap();
    assert_eq!(
        b.counters().non_finite,
        0,
        "{name}: non-finite contributions"
    );
    let sums = b.sums().unwrap();
    reference.compare(&sums.mean(), &sums.stderr().unwrap())
}

fn both(name: &str, bpt_passes: u32, light_passes: u32) {
    against(name, BidirMode::Bpt, bpt_passes, 1)
        .assert_agrees(&format!("bpt {name} {bpt_passes} passes"));
    against(name, BidirMode::Light, light_passes, 1)
        .assert_agrees(&format!("light {name} {light_passes} passes"));
}

#[test]
fn cornell_box_matches_mitsuba() {
    both("cornell_path_64", 128, 256);
}

#[test]
fn glossy_conductor_matches_mitsuba() {
    both("glossy_path_64", 128, 256);
}

#[test]
fn mirror_caustic_matches_mitsuba() {
    both("mirror_path_64", 128, 256);
}

#[test]
fn fixture_matches_mitsuba() {
    both("fixture_ptracer_64", 128, 256);
}
