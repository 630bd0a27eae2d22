//! Explicit scene-file BSDFs: the BsdfParams each kind maps to, and a smoke render of
//! `scenes/materials.toml` with the `pt` integrator.

use crate::common;

use glam::Vec3;
use splitray::bsdf::{Bsdf, BsdfParams, Distribution};
use splitray::integrator::pt::materials::bsdf_of;
use splitray::integrator::IntegratorKind;
use splitray::render::{render, RenderOptions};
use splitray::scene::{self, BsdfKind, Material, MaterialBsdf, MaterialLayer, MicrofacetModel};

fn layer(kind: BsdfKind, reflectance: Vec3, roughness: f32, weight: f32) -> MaterialLayer {
    MaterialLayer {
        kind,
        reflectance,
        roughness,
        distribution: MicrofacetModel::Ggx,
        ior: 1.5,
        weight,
    }
}

fn with(layers: Vec<MaterialLayer>) -> Material {
    Material {
        // MTL fields that alone would map to a mirror: the explicit BSDF must win.
        illum: 5,
        bsdf: Some(MaterialBsdf { layers }),
        ..Material::named("m")
    }
}

/// Equal up to f32 rounding.
fn assert_close(a: &BsdfParams, b: &BsdfParams) {
    assert_eq!(a.count, b.count, "{a:?}\n{b:?}");
    for (x, y) in a.active().iter().zip(b.active()) {
        assert_eq!((x.kind, x.distribution), (y.kind, y.distribution));
        let (fx, fy) = (
            [x.tint_weight.as_slice(), &[x.roughness, x.ior]].concat(),
            [y.tint_weight.as_slice(), &[y.roughness, y.ior]].concat(),
        );
        for (u, v) in fx.iter().zip(&fy) {
            assert!((u - v).abs() < 1e-6, "{a:?}\n{b:?}");
        }
    }
}

fn single(l: MaterialLayer) -> BsdfParams {
    bsdf_of(&with(vec![l]))
}

#[test]
fn each_kind_maps_to_its_bsdf() {
    let c = Vec3::new(0.9, 0.5, 0.2);
    assert_eq!(
        single(layer(BsdfKind::Lambert, c, 0.2, 1.0)),
        Bsdf::Lambert { albedo: c }.params()
    );
    assert_eq!(
        single(layer(BsdfKind::OrenNayar, c, 0.35, 1.0)),
        Bsdf::OrenNayar {
            albedo: c,
            sigma: 0.35
        }
        .params()
    );
    assert_eq!(
        single(layer(BsdfKind::Mirror, c, 0.2, 1.0)),
        Bsdf::Mirror { tint: c }.params()
    );
    assert_eq!(
        single(MaterialLayer {
            ior: 1.33,
            ..layer(BsdfKind::Glass, c, 0.2, 1.0)
        }),
        Bsdf::Dielectric { tint: c, eta: 1.33 }.params()
    );
    assert_eq!(
        single(MaterialLayer {
            distribution: MicrofacetModel::Beckmann,
            ..layer(BsdfKind::RoughGlass, c, 0.3, 1.0)
        }),
        Bsdf::MicrofacetDielectric {
            tint: c,
            distribution: Distribution::Beckmann,
            roughness: 0.3,
            eta: 1.5
        }
        .params()
    );
    assert_eq!(
        single(layer(BsdfKind::Conductor, c, 0.25, 1.0)),
        Bsdf::MicrofacetReflection {
            f0: c,
            distribution: Distribution::Ggx,
            roughness: 0.25
        }
        .params()
    );
    // Blinn–Phong takes the exponent n = 2/α² − 2.
    let p = single(MaterialLayer {
        distribution: MicrofacetModel::BlinnPhong,
        ..layer(BsdfKind::Conductor, c, 0.5, 1.0)
    });
    assert_eq!(p.layers[0].distribution, Distribution::BlinnPhong as u32);
    assert!((p.layers[0].roughness - 6.0).abs() < 1e-5);

    // Plastic: Lambert + GGX coat with F0 = 0.04 (η 1.5); effective colours are the
    // reflectance and F0, weights sum to 1.
    let p = single(layer(BsdfKind::Plastic, Vec3::splat(0.5), 0.1, 1.0));
    assert_eq!(p.count, 2);
    let (wd, ws) = (0.5 / 0.54, 0.04 / 0.54);
    assert_close(
        &p,
        &BsdfParams::layered(&[
            (
                Bsdf::Lambert {
                    albedo: Vec3::splat(0.5 / wd),
                },
                wd,
            ),
            (
                Bsdf::MicrofacetReflection {
                    f0: Vec3::splat(0.04 / ws),
                    distribution: Distribution::Ggx,
                    roughness: 0.1,
                },
                ws,
            ),
        ]),
    );
}

#[test]
fn layer_stacks_keep_their_weights() {
    let p = bsdf_of(&with(vec![
        layer(BsdfKind::Lambert, Vec3::splat(0.7), 0.2, 0.6),
        layer(BsdfKind::Conductor, Vec3::ONE, 0.1, 0.3),
    ]));
    assert_eq!(
        p,
        BsdfParams::layered(&[
            (
                Bsdf::Lambert {
                    albedo: Vec3::splat(0.7)
                },
                0.6
            ),
            (
                Bsdf::MicrofacetReflection {
                    f0: Vec3::ONE,
                    distribution: Distribution::Ggx,
                    roughness: 0.1
                },
                0.3
            ),
        ])
    );
    // A plastic layer is two BSDF layers whose weights sum to its own.
    let p = bsdf_of(&with(vec![
        layer(BsdfKind::Mirror, Vec3::ONE, 0.2, 0.5),
        layer(BsdfKind::Plastic, Vec3::splat(0.5), 0.2, 0.5),
    ]));
    assert_eq!(p.count, 3);
    let sum: f32 = p.active().iter().map(|l| l.tint_weight[3]).sum();
    assert!((sum - 1.0).abs() < 1e-6, "{sum}");
    // Without an explicit BSDF the MTL mapping still applies (illum 5: mirror).
    let mtl = Material {
        illum: 5,
        ..Material::named("m")
    };
    assert_eq!(bsdf_of(&mtl), Bsdf::Mirror { tint: Vec3::ONE }.params());
}

#[test]
fn example_scene_maps_and_renders() {
    use splitray::bsdf::kind;
    let scene = scene::load("scenes/materials.toml").unwrap();
    let kinds = |name: &str| -> Vec<u32> {
        let m = &scene.materials[scene.material_index(name).unwrap() as usize];
        bsdf_of(m).active().iter().map(|l| l.kind).collect()
    };
    assert_eq!(kinds("white"), [kind::LAMBERT, kind::MICROFACET_REFLECTION]);
    assert_eq!(kinds("red"), [kind::MICROFACET_REFLECTION]);
    assert_eq!(
        kinds("green"),
        [kind::OREN_NAYAR, kind::MICROFACET_REFLECTION]
    );
    assert_eq!(kinds("light"), [kind::MICROFACET_DIELECTRIC]);

    let gpu = common::gpu();
    let opts = RenderOptions::resolve(
        &scene,
        Some(24),
        Some(24),
        Some(2),
        Some(1),
        Some(IntegratorKind::Pt),
        None,
    )
    .unwrap();
    let out = render(&gpu, &scene, &opts, &mut |_| {}).unwrap();
    assert_eq!(out.film.count_non_finite(), 0);
    let pixels = out.film.mean_rgb_buffer();
    let mean = pixels.iter().map(|&p| Vec3::from(p)).sum::<Vec3>() / pixels.len() as f32;
    assert!(mean.max_element() > 0.0, "black image: {mean}");
    common::assert_clean(&gpu);
}
