//! Checking a Monte Carlo estimate against a closed-form value, and the materials of the
//! analytic scenes (an enclosure whose every wall emits and reflects alike).

use glam::Vec3;
use splitray::scene::{BsdfKind, Material, MaterialBsdf, MaterialLayer, MicrofacetModel};

/// The mean of independent estimates (passes of a render) and its standard error.
pub fn mean_and_standard_error(estimates: &[f64]) -> (f64, f64) {
    let n = estimates.len() as f64;
    let mean = estimates.iter().sum::<f64>() / n;
    let variance = estimates.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

/// Asserts an estimate `(mean, standard error)` agrees with `expected` within four of its
/// standard errors (and a 1e-4 relative allowance for float summation), and that it is
/// precise enough for the comparison to mean something (standard error under 2 %).
pub fn assert_agrees(what: &str, (mean, se): (f64, f64), expected: f64) {
    eprintln!("{what}: {mean:.5} ± {se:.5}, expected {expected:.5}");
    assert!(
        (mean - expected).abs() < 4.0 * se + 1e-4 * expected,
        "{what}: {mean} vs {expected} (se {se})"
    );
    assert!(se < 0.02 * expected, "{what}: too noisy to say ({se})");
}

/// A Lambertian wall of albedo `albedo` emitting `le`.
pub fn lambert(albedo: f32, le: f32) -> Material {
    Material {
        diffuse: Vec3::splat(albedo),
        emission: Vec3::splat(le),
        ..Material::named("wall")
    }
}

/// Half Lambert (ρ 0.5), half mirror (ρ 0.8): total albedo 0.65; emitting `le`.
pub fn mixed(le: f32) -> Material {
    let layer = |kind, r: f32| MaterialLayer {
        kind,
        reflectance: Vec3::splat(r),
        roughness: 0.0,
        distribution: MicrofacetModel::Ggx,
        ior: 1.5,
        weight: 0.5,
    };
    Material {
        emission: Vec3::splat(le),
        bsdf: Some(MaterialBsdf {
            layers: vec![layer(BsdfKind::Lambert, 0.5), layer(BsdfKind::Mirror, 0.8)],
        }),
        ..Material::named("mixed")
    }
}
