//! `bench bdpt`: a quick run under validation (what it measures and names, not how
//! fast): each resampling listed is one `cis-lbdpt` contestant, named after the draws
//! where they are not the default's, a repeated one measured once, and every
//! contestant renders and is compared with the reference.

use std::sync::Arc;

use crate::common;

use splitray::bench::bdpt::{run, BdptBenchOptions};
use splitray::bench::lvc::SppPlan;
use splitray::film::Reference;
use splitray::integrator::lvc::Resampling;
use splitray::integrator::IntegratorKind;
use splitray::scene::builtin;

#[test]
fn each_resampling_is_a_contestant() {
    let gpu = common::gpu();
    let scene = builtin("cornell-box").unwrap();
    let (width, height) = (12, 7);
    // Any image of the film's size serves as the reference of a check that the errors
    // are computed: a flat grey one.
    let reference = Arc::new(Reference {
        mean: vec![[0.5; 3]; (width * height) as usize],
        stderr: None,
        path: "grey".into(),
        stderr_path: None,
    });
    let report = run(
        &gpu,
        &scene,
        &BdptBenchOptions {
            width,
            height,
            integrators: vec![IntegratorKind::LvcBdpt, IntegratorKind::CisLbdpt],
            seconds: 0.2,
            rounds: 2,
            reference: Some(reference),
            resampling: vec![
                Resampling::Independent,
                Resampling::Systematic,
                Resampling::Independent,
            ],
            equal_spp: SppPlan {
                passes: 0,
                ..Default::default()
            },
            ..Default::default()
        },
    )
    .unwrap();
    let names: Vec<&str> = report.rows.iter().map(|r| r.integrator.as_str()).collect();
    assert_eq!(names, ["lvc-bdpt", "cis-lbdpt independent", "cis-lbdpt"]);
    for r in &report.rows {
        assert!(r.passes >= 2, "{}: {} passes", r.integrator, r.passes);
        assert!(r.relative_mse.is_some_and(|e| e > 0.0), "{}", r.integrator);
    }
    let text = report.to_string();
    for name in ["cis-lbdpt", "cis-lbdpt independent"] {
        let line = format!("relative MSE × seconds {name} / lvc-bdpt: ");
        assert!(text.contains(&line), "no line '{line}' in\n{text}");
    }
    common::assert_clean(&gpu);
}
