//! From scene materials (MTL parameters) to BSDF stacks.
//!
//! # The MTL mapping
//!
//! | MTL                                          | BSDF                                                     |
//! |----------------------------------------------|----------------------------------------------------------|
//! | `illum` 4, 6, 7, or `d` < 1 (glass)          | dielectric of η = `Ni` (1.5 when `Ni` ≤ 1), tint 1; smooth when `Ns` is 0 or ≥ 1000, else rough GGX with α = √(2/(Ns+2)) |
//! | `illum` 5 (mirror)                           | perfect mirror of reflectance `Ks` (1 when `Ks` is 0)      |
//! | otherwise, `Ks` = 0 or `illum` < 2           | Lambert of albedo `Kd`                                    |
//! | otherwise (`Ks` > 0, `illum` ≥ 2)            | mixture of Lambert (`Kd`) and microfacet reflection (GGX, α = √(2/(Ns+2)), Schlick F0 = `Ks`) |
//! | `Ke` > 0                                     | additionally a one-sided area emitter of radiance `Ke` (front = geometric normal) |
//!
//! **Roughness.** α = √(2/(Ns+2)) is Walter et al. 2007's match of a Blinn–Phong
//! exponent to a Beckmann width, used here for GGX (whose shape is close at these
//! widths): Ns = 0 → α = 1 (very rough), Ns = 10 → 0.41, Ns = 100 → 0.14,
//! Ns = 1000 → 0.045.
//!
//! **Energy.** The layered mixture is f = w_d f_Lambert + w_s f_spec with weights
//! w_d = k_d / (k_d + k_s), w_s = k_s / (k_d + k_s) (k = the largest channel of `Kd`,
//! `Ks`), the Lambert albedo `Kd / w_d` and F0 `Ks / w_s`, so that the effective
//! colours are `Kd` and `Ks` as in the Phong model of MTL; when k_d + k_s > 1 both are
//! scaled by 1 / (k_d + k_s), so the stack never reflects more than it receives.
//!
//! # Explicit BSDFs
//!
//! A material with [`Material::bsdf`] (`bsdf = …` or `[[material.layer]]` in a scene
//! TOML) ignores the MTL mapping; each layer becomes BSDF layers of its weight:
//!
//! | scene file    | BSDF                                                                   |
//! |---------------|------------------------------------------------------------------------|
//! | `lambert`     | Lambert, albedo = reflectance                                          |
//! | `oren-nayar`  | Oren–Nayar, albedo = reflectance, σ = roughness (radians)             |
//! | `mirror`      | perfect mirror, tint = reflectance                                     |
//! | `glass`       | smooth dielectric, tint = reflectance, η = ior                         |
//! | `rough-glass` | rough dielectric, tint = reflectance, α = roughness, η = ior           |
//! | `conductor`   | microfacet reflection, Schlick F0 = reflectance, α = roughness         |
//! | `plastic`     | two layers: the Lambert + microfacet mixture above with `Kd` = reflectance and `Ks` = F0 = ((η−1)/(η+1))² of the ior (0.04 at 1.5), α = roughness |
//!
//! For `blinn-phong` the α is turned into the exponent n = 2/α² − 2 (the inverse of
//! [`alpha_from_shininess`]); GGX and Beckmann take α as is.

use glam::Vec3;

use crate::bsdf::{material_key, Bsdf, BsdfParams, Distribution, MaterialType};
use crate::scene::{BsdfKind, Material, MaterialBsdf, MaterialLayer, MicrofacetModel};

use super::gpu::PtMaterial;

/// GGX α from a Phong exponent (Walter et al. 2007).
pub fn alpha_from_shininess(ns: f32) -> f32 {
    (2.0 / (ns.max(0.0) + 2.0)).sqrt()
}

/// The BSDF stack of a material (see the module docs).
pub fn bsdf_of(m: &Material) -> BsdfParams {
    if let Some(b) = &m.bsdf {
        return explicit_bsdf(b);
    }
    let glass = matches!(m.illum, 4 | 6 | 7) || m.dissolve < 1.0;
    if glass {
        let eta = if m.ior > 1.0 { m.ior } else { 1.5 };
        let tint = Vec3::ONE;
        if m.shininess <= 0.0 || m.shininess >= 1000.0 {
            return Bsdf::Dielectric { tint, eta }.params();
        }
        return Bsdf::MicrofacetDielectric {
            tint,
            distribution: Distribution::Ggx,
            roughness: alpha_from_shininess(m.shininess),
            eta,
        }
        .params();
    }
    if m.illum == 5 {
        let tint = if m.specular.max_element() > 0.0 {
            m.specular
        } else {
            Vec3::ONE
        };
        return Bsdf::Mirror { tint }.params();
    }
    if m.illum < 2 {
        return Bsdf::Lambert {
            albedo: m.diffuse.max(Vec3::ZERO),
        }
        .params();
    }
    BsdfParams::layered(&diffuse_glossy(
        m.diffuse,
        m.specular,
        Distribution::Ggx,
        alpha_from_shininess(m.shininess),
    ))
}

/// The energy-bounded mixture of Lambert (`kd`) and microfacet reflection (F0 `ks`)
/// of the module docs; one layer when either colour is black.
fn diffuse_glossy(kd: Vec3, ks: Vec3, distribution: Distribution, param: f32) -> Vec<(Bsdf, f32)> {
    let kd = kd.max(Vec3::ZERO);
    let ks = ks.max(Vec3::ZERO);
    let (d, s) = (kd.max_element(), ks.max_element());
    if s <= 0.0 {
        return vec![(Bsdf::Lambert { albedo: kd }, 1.0)];
    }
    let scale = if d + s > 1.0 { 1.0 / (d + s) } else { 1.0 };
    let (wd, ws) = (d / (d + s), s / (d + s));
    let specular = Bsdf::MicrofacetReflection {
        f0: ks * scale / ws,
        distribution,
        roughness: param,
    };
    if d <= 0.0 {
        return vec![(specular, 1.0)];
    }
    vec![
        (
            Bsdf::Lambert {
                albedo: kd * scale / wd,
            },
            wd,
        ),
        (specular, ws),
    ]
}

/// The [`Distribution`] and its parameter for α (Blinn–Phong takes an exponent).
fn distribution_of(model: MicrofacetModel, alpha: f32) -> (Distribution, f32) {
    match model {
        MicrofacetModel::Ggx => (Distribution::Ggx, alpha),
        MicrofacetModel::Beckmann => (Distribution::Beckmann, alpha),
        MicrofacetModel::BlinnPhong => (
            Distribution::BlinnPhong,
            (2.0 / (alpha * alpha) - 2.0).max(0.0),
        ),
    }
}

/// The BSDF layers of one explicit layer, weights already scaled by its weight.
fn layers_of(l: &MaterialLayer) -> Vec<(Bsdf, f32)> {
    let (distribution, roughness) = distribution_of(l.distribution, l.roughness);
    let r = l.reflectance;
    let one = match l.kind {
        BsdfKind::Lambert => Bsdf::Lambert { albedo: r },
        BsdfKind::OrenNayar => Bsdf::OrenNayar {
            albedo: r,
            sigma: l.roughness,
        },
        BsdfKind::Mirror => Bsdf::Mirror { tint: r },
        BsdfKind::Glass => Bsdf::Dielectric {
            tint: r,
            eta: l.ior,
        },
        BsdfKind::RoughGlass => Bsdf::MicrofacetDielectric {
            tint: r,
            distribution,
            roughness,
            eta: l.ior,
        },
        BsdfKind::Conductor => Bsdf::MicrofacetReflection {
            f0: r,
            distribution,
            roughness,
        },
        BsdfKind::Plastic => {
            let f0 = ((l.ior - 1.0) / (l.ior + 1.0)).powi(2);
            return diffuse_glossy(r, Vec3::splat(f0), distribution, roughness)
                .into_iter()
                .map(|(b, w)| (b, w * l.weight))
                .collect();
        }
    };
    vec![(one, l.weight)]
}

/// The BSDF stack of an explicit description (see the module docs).
pub fn explicit_bsdf(b: &MaterialBsdf) -> BsdfParams {
    let layers: Vec<(Bsdf, f32)> = b.layers.iter().flat_map(layers_of).collect();
    BsdfParams::layered(&layers)
}

/// Whether every layer of the stack is a delta lobe.
pub fn all_delta(p: &BsdfParams) -> bool {
    p.active()
        .iter()
        .all(|l| Bsdf::from_layer(l).is_some_and(|b| b.is_delta()))
}

/// The GPU tables of a scene's materials: BSDF stacks and per-material records (with
/// the sort key `material_key(type, index)` and its rank).
pub fn material_tables(materials: &[Material]) -> (Vec<BsdfParams>, Vec<PtMaterial>) {
    let mut bsdfs = Vec::with_capacity(materials.len());
    let mut records = Vec::with_capacity(materials.len());
    for (i, m) in materials.iter().enumerate() {
        let p = bsdf_of(m);
        let ty = MaterialType::of(&p).unwrap_or(MaterialType::Layered);
        records.push(PtMaterial {
            emission: m.emission.max(Vec3::ZERO).extend(0.0).into(),
            key: material_key(ty, i as u32),
            all_delta: all_delta(&p) as u32,
            sort_rank: 0,
            pad: 0,
        });
        bsdfs.push(p);
    }
    let keys: Vec<u32> = records.iter().map(|r| r.key).collect();
    for (r, rank) in records.iter_mut().zip(sort_ranks(&keys)) {
        r.sort_rank = rank;
    }
    (bsdfs, records)
}

/// Each key's rank among `keys` (equal keys share one), in key order. Every rank is
/// below `keys.len()`, so a miss sorts after every key with any value from `keys.len()`
/// up in [`sort_rank_bits`] bits (`sort_keys.comp` writes all ones).
///
/// Sorting the ranks orders paths exactly as sorting the 32-bit keys (type << 24 | id)
/// would, ties included, but a scene's ranks need only [`sort_rank_bits`] bits: one
/// radix pass of 8-bit digits for up to 255 materials instead of four for the keys,
/// whose middle bits are zero in every scene and whose miss key (all ones) makes every
/// digit vary.
pub fn sort_ranks(keys: &[u32]) -> Vec<u32> {
    let mut distinct = keys.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    keys.iter()
        .map(|k| distinct.partition_point(|d| d < k) as u32)
        .collect()
}

/// The bits of a rank of [`sort_ranks`] for `materials` materials (misses included).
pub fn sort_rank_bits(materials: u32) -> u32 {
    u32::BITS - materials.leading_zeros()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::kind;

    #[test]
    fn mtl_mapping() {
        let diffuse = Material::default();
        let p = bsdf_of(&diffuse);
        assert_eq!(p.count, 1);
        assert_eq!(p.layers[0].kind, kind::LAMBERT);
        assert_eq!(p.layers[0].tint_weight, [0.8, 0.8, 0.8, 1.0]);

        let plastic = Material {
            diffuse: Vec3::splat(0.5),
            specular: Vec3::splat(0.25),
            shininess: 98.0,
            illum: 2,
            ..Material::default()
        };
        let p = bsdf_of(&plastic);
        assert_eq!(p.count, 2);
        assert_eq!(p.layers[1].kind, kind::MICROFACET_REFLECTION);
        assert!((p.layers[1].roughness - 0.141_421_4).abs() < 1e-5);
        // Effective colours: weight × layer colour = Kd, Ks.
        let wd = p.layers[0].tint_weight[3];
        let ws = p.layers[1].tint_weight[3];
        assert!((wd * p.layers[0].tint_weight[0] - 0.5).abs() < 1e-6);
        assert!((ws * p.layers[1].tint_weight[0] - 0.25).abs() < 1e-6);

        let bright = Material {
            diffuse: Vec3::splat(0.9),
            specular: Vec3::splat(0.9),
            shininess: 10.0,
            illum: 2,
            ..Material::default()
        };
        let p = bsdf_of(&bright);
        let total: f32 = p
            .active()
            .iter()
            .map(|l| l.tint_weight[3] * l.tint_weight[0])
            .sum();
        assert!(total <= 1.0 + 1e-6, "{total}");

        let glass = Material {
            ior: 1.5,
            illum: 7,
            ..Material::default()
        };
        let p = bsdf_of(&glass);
        assert_eq!(p.layers[0].kind, kind::DIELECTRIC);
        assert_eq!(p.layers[0].ior, 1.5);
        assert!(all_delta(&p));
        let mirror = Material {
            illum: 5,
            ..Material::default()
        };
        assert_eq!(bsdf_of(&mirror).layers[0].kind, kind::MIRROR);
    }

    #[test]
    fn keys_group_by_type() {
        let mats = [
            Material::default(),
            Material {
                illum: 5,
                ..Material::default()
            },
        ];
        let (_, recs) = material_tables(&mats);
        assert_eq!(recs[0].key, material_key(MaterialType::Lambert, 0));
        assert_eq!(recs[1].key, material_key(MaterialType::Mirror, 1));
        assert_eq!(recs[1].all_delta, 1);
        assert_eq!((recs[0].sort_rank, recs[1].sort_rank), (0, 1));
    }

    #[test]
    fn ranks_order_like_the_keys_and_misses_last() {
        let keys = [
            material_key(MaterialType::Mirror, 0),
            material_key(MaterialType::Lambert, 1),
            material_key(MaterialType::Layered, 2),
            material_key(MaterialType::Lambert, 3),
            material_key(MaterialType::Lambert, 1),
        ];
        let ranks = sort_ranks(&keys);
        const MISS: u32 = u32::MAX;
        let miss_rank = keys.len() as u32;
        for (a, ra) in keys
            .iter()
            .chain([&MISS])
            .zip(ranks.iter().chain([&miss_rank]))
        {
            for (b, rb) in keys
                .iter()
                .chain([&MISS])
                .zip(ranks.iter().chain([&miss_rank]))
            {
                assert_eq!(a.cmp(b), ra.cmp(rb), "keys {a:#x} {b:#x}");
            }
        }
        assert!(ranks
            .iter()
            .all(|&r| r < 1 << sort_rank_bits(keys.len() as u32)));
        assert!(miss_rank < 1 << sort_rank_bits(keys.len() as u32));
        assert_eq!(
            (
                sort_rank_bits(0),
                sort_rank_bits(1),
                sort_rank_bits(255),
                sort_rank_bits(256)
            ),
            (0, 1, 8, 9)
        );
        assert!(sort_ranks(&[]).is_empty());
    }
}
