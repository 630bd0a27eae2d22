//! The one interface every integrator renders through: a film after passes 0..n does not
//! depend on how the passes were grouped into calls or whether the film was saved and
//! restored in between, and the render loop stops cleanly at a pass boundary.
use crate::common;

use splitray::integrator::{Integrator, IntegratorKind};
use splitray::render::{create_integrator, render_with, RenderControl};
use splitray::scene::{builtin, Scene};
use splitray::vk::Gpu;

fn integrator(gpu: &Gpu, scene: &Scene, kind: IntegratorKind) -> Box<dyn Integrator> {
    create_integrator(gpu, scene, &common::small_render_options(scene, kind, 6)).unwrap()
}

#[test]
fn grouping_and_restoring_passes_leaves_the_film_bit_identical() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    for kind in [
        IntegratorKind::Pt,
        IntegratorKind::Ao,
        IntegratorKind::Path,
        IntegratorKind::Bpt,
        IntegratorKind::Light,
        IntegratorKind::LvcBdpt,
        IntegratorKind::CisLbdpt,
    ] {
        let mut whole = integrator(&gpu, &scene, kind);
        whole.render_passes(0, 6).unwrap();
        let expected = whole.sums().unwrap();
        assert_eq!(expected.passes, 6);

        let mut split = integrator(&gpu, &scene, kind);
        split.render_passes(0, 1).unwrap();
        split.render_passes(1, 2).unwrap();
        let saved = split.sums().unwrap();
        drop(split);
        // A fresh integrator continues from the saved film, as a resumed render does.
        let mut resumed = integrator(&gpu, &scene, kind);
        resumed.restore(&saved).unwrap();
        resumed.render_passes(3, 3).unwrap();
        assert_eq!(resumed.sums().unwrap(), expected, "{kind}");
        assert!(expected.sum.iter().flatten().any(|&v| v > 0.0), "{kind}");
        assert!(resumed.stats().rays_traced > 0);
    }
    common::assert_clean(&gpu);
}

#[test]
fn restoring_a_film_of_another_size_is_refused() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let mut pt = integrator(&gpu, &scene, IntegratorKind::Pt);
    let wrong = splitray::film::FilmSums::new(8, 8, 1, true);
    let err = pt.restore(&wrong).unwrap_err().to_string();
    assert!(err.contains("8x8") && err.contains("24x16"), "{err}");
    common::assert_clean(&gpu);
}

#[test]
fn the_render_loop_stops_at_a_pass_boundary_when_asked() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let opts = common::small_render_options(&scene, IntegratorKind::Ao, 8);
    let mut seen = Vec::new();
    let calls = std::cell::Cell::new(0);
    let out = render_with(
        &gpu,
        &scene,
        &opts,
        RenderControl {
            progress: &mut |p| seen.push(p.spp),
            stop: &|| {
                calls.set(calls.get() + 1);
                calls.get() > 3
            },
            abandon: &|| false,
        },
    )
    .unwrap();
    // `ao` takes one pass per call: asked to stop before the fourth call, it holds three.
    assert!(out.stats.stopped_early);
    assert_eq!(seen, [1, 2, 3]);
    assert_eq!(out.stats.spp, 3);
    assert_eq!(out.sums.passes as u64, out.stats.spp);
    assert_eq!(out.metadata.spp as u64, out.stats.spp);
    assert!(out
        .metadata
        .extra
        .iter()
        .any(|(k, v)| k == "stopped_early" && v == "true"));
    // Every integrator carries the first-hit AOVs.
    assert!(out.film.depth.is_some() && out.film.triangle_id.is_some());
    common::assert_clean(&gpu);
}

/// The GPU integrators other than the light-vertex-cache ones (whose three streams
/// `lvc_determinism` checks) render under synchronization validation without a message:
/// the eye integrators, `pt` with the tracer's level loops, and `cbpt` with its
/// double-buffered batches. Where a device has several queues the streams run on
/// distinct ones and hazards between queues are checked too.
#[test]
fn gpu_integrators_are_clean_under_synchronization_validation() {
    let gpu = common::gpu_with(splitray::vk::StreamPlacement::Spread, true);
    let scene = builtin("cornell-box").unwrap();
    for kind in [
        IntegratorKind::Primary,
        IntegratorKind::Pt,
        IntegratorKind::Cbpt,
    ] {
        let options = common::small_render_options(&scene, kind, 8);
        let out = splitray::render::render(&gpu, &scene, &options, &mut |_| {}).unwrap();
        assert_eq!(out.metadata.spp, 8, "{kind}");
        common::assert_clean(&gpu);
    }
}
