//! The scene exactly as splitray resolved it, as JSON, for reference renderers
//! (`splitray export-scene`, read by `tools/mitsuba_reference.py`).
//!
//! A reference renderer must render *the* scene splitray renders, not its own reading of
//! the scene files: OBJ fan triangulation, mesh transforms and mirroring, `[[material]]`
//! overrides, the MTL → BSDF mapping and the built-in scenes all live in splitray, and a
//! second parser would drift from them silently. So the export is the resolved data:
//!
//! - `triangles`: every triangle of the soup, in order, vertices in their winding order
//!   (the geometric normal is `(p1 − p0) × (p2 − p0)`, the front of one-sided emitters),
//!   with its material index and its shading normals when it has them;
//! - `materials`: per material its emitted radiance (one-sided, front = geometric
//!   normal) and its BSDF stack as the `pt` integrator resolved it (the layers of
//!   [`bsdf_of`], each with its mixture weight, its kind and that kind's parameters);
//! - `point_lights`, the `camera` (position, look_at, up, fov_y: full vertical field of
//!   view in degrees; splitray's image x runs along forward × up) and the `film` size.
//!
//! [`SceneExport`] reads back what it writes (serde), so a test can compare a committed
//! export with the scene as it resolves today.

use serde::{Deserialize, Serialize};

use crate::bsdf::{Bsdf, Distribution};
use crate::integrator::pt::materials::bsdf_of;
use crate::scene::{FilmSize, Scene};

/// The `format` field of every export.
pub const FORMAT: &str = "splitray-scene";
/// The `version` field; bumped on any change of meaning.
pub const VERSION: u32 = 1;

/// A resolved scene (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneExport {
    pub format: String,
    pub version: u32,
    pub name: String,
    pub film: FilmSize,
    pub camera: ExportCamera,
    pub triangles: Vec<ExportTriangle>,
    pub materials: Vec<ExportMaterial>,
    pub point_lights: Vec<ExportPointLight>,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportCamera {
    pub position: [f32; 3],
    pub look_at: [f32; 3],
    pub up: [f32; 3],
    /// Full vertical field of view, degrees.
    pub fov_y: f32,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportTriangle {
    /// Vertices in winding order.
    pub p: [[f32; 3]; 3],
    /// Index into [`SceneExport::materials`].
    pub material: u32,
    /// Per-vertex shading normals, as the scene has them (not normalised).
    pub normals: Option<[[f32; 3]; 3]>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportMaterial {
    pub name: String,
    /// Emitted radiance (RGB), on the front side only; zero for non-emitters.
    pub emission: [f32; 3],
    /// The BSDF stack: f = Σ weight · f_layer.
    pub layers: Vec<ExportLayer>,
}

/// One layer of a BSDF stack with its mixture weight.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExportLayer {
    pub weight: f32,
    #[serde(flatten)]
    pub bsdf: ExportBsdf,
}

/// A BSDF as `src/bsdf` evaluates it. Reflection-only kinds are two-sided; the
/// microfacet kinds use the Smith masking–shadowing of `shadowing` with the
/// distribution's Λ, and sample D(m)·cos θm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ExportBsdf {
    Lambert {
        albedo: [f32; 3],
    },
    OrenNayar {
        albedo: [f32; 3],
        /// σ, radians.
        sigma: f32,
    },
    /// Perfect specular reflection scaled by `tint`.
    Mirror {
        tint: [f32; 3],
    },
    /// Smooth dielectric, η = η_inside / η_outside (outside = the geometric normal's side).
    Dielectric {
        tint: [f32; 3],
        eta: f32,
    },
    /// Microfacet reflection with Schlick Fresnel of normal-incidence reflectance `f0`.
    MicrofacetReflection {
        f0: [f32; 3],
        distribution: ExportDistribution,
        /// α (ggx, beckmann) or the exponent (blinn-phong).
        roughness: f32,
        shadowing: Shadowing,
    },
    /// Rough dielectric (Walter et al. 2007).
    MicrofacetDielectric {
        tint: [f32; 3],
        distribution: ExportDistribution,
        roughness: f32,
        eta: f32,
        shadowing: Shadowing,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExportDistribution {
    Ggx,
    Beckmann,
    BlinnPhong,
}

/// The form of the Smith masking–shadowing term G(wo, wi).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shadowing {
    /// G = 1 / (1 + Λ(wo) + Λ(wi)) ([`crate::bsdf::microfacet::g`]), not the separable
    /// G1(wo)·G1(wi).
    SmithHeightCorrelated,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportPointLight {
    pub position: [f32; 3],
    /// Radiant intensity, W/sr (RGB).
    pub intensity: [f32; 3],
}

impl From<Distribution> for ExportDistribution {
    fn from(d: Distribution) -> Self {
        match d {
            Distribution::Ggx => Self::Ggx,
            Distribution::Beckmann => Self::Beckmann,
            Distribution::BlinnPhong => Self::BlinnPhong,
        }
    }
}

impl From<Bsdf> for ExportBsdf {
    fn from(b: Bsdf) -> Self {
        match b {
            Bsdf::Lambert { albedo } => Self::Lambert {
                albedo: albedo.into(),
            },
            Bsdf::OrenNayar { albedo, sigma } => Self::OrenNayar {
                albedo: albedo.into(),
                sigma,
            },
            Bsdf::Mirror { tint } => Self::Mirror { tint: tint.into() },
            Bsdf::Dielectric { tint, eta } => Self::Dielectric {
                tint: tint.into(),
                eta,
            },
            Bsdf::MicrofacetReflection {
                f0,
                distribution,
                roughness,
            } => Self::MicrofacetReflection {
                f0: f0.into(),
                distribution: distribution.into(),
                roughness,
                shadowing: Shadowing::SmithHeightCorrelated,
            },
            Bsdf::MicrofacetDielectric {
                tint,
                distribution,
                roughness,
                eta,
            } => Self::MicrofacetDielectric {
                tint: tint.into(),
                distribution: distribution.into(),
                roughness,
                eta,
                shadowing: Shadowing::SmithHeightCorrelated,
            },
        }
    }
}

/// The resolved form of `scene` rendered on a film of `film` (the scene's own film size
/// unless the caller overrides it).
pub fn export(scene: &Scene, film: FilmSize) -> SceneExport {
    let materials = scene
        .materials
        .iter()
        .map(|m| ExportMaterial {
            name: m.name.clone(),
            emission: m.emission.max(glam::Vec3::ZERO).into(),
            layers: bsdf_of(m)
                .active()
                .iter()
                .map(|l| ExportLayer {
                    weight: l.tint_weight[3],
                    bsdf: Bsdf::from_layer(l)
                        .expect("bsdf_of builds only known layer kinds")
                        .into(),
                })
                .collect(),
        })
        .collect();
    SceneExport {
        format: FORMAT.to_string(),
        version: VERSION,
        name: scene.name.clone(),
        film,
        camera: ExportCamera {
            position: scene.camera.position.into(),
            look_at: scene.camera.look_at.into(),
            up: scene.camera.up.into(),
            fov_y: scene.camera.fov_y,
        },
        triangles: scene
            .triangles
            .iter()
            .map(|t| ExportTriangle {
                p: t.p.map(Into::into),
                material: t.material,
                normals: t.n.map(|n| n.map(Into::into)),
            })
            .collect(),
        materials,
        point_lights: scene
            .point_lights
            .iter()
            .map(|l| ExportPointLight {
                position: l.position.into(),
                intensity: l.intensity.into(),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    #[test]
    fn cornell_box_exports_every_triangle_and_reads_back() {
        let scene = builtin("cornell-box").unwrap();
        let e = export(
            &scene,
            FilmSize {
                width: 64,
                height: 48,
            },
        );
        assert_eq!(e.triangles.len(), scene.triangles.len());
        for (t, x) in scene.triangles.iter().zip(&e.triangles) {
            assert_eq!(t.p.map(<[f32; 3]>::from), x.p);
            assert_eq!(t.material, x.material);
        }
        assert_eq!(
            e.film,
            FilmSize {
                width: 64,
                height: 48
            }
        );
        let light = &e.materials[scene.material_index("light").unwrap() as usize];
        assert_eq!(light.emission, [17.0, 12.0, 4.0]);
        assert_eq!(
            light.layers,
            [ExportLayer {
                weight: 1.0,
                bsdf: ExportBsdf::Lambert { albedo: [0.78; 3] }
            }]
        );
        let text = serde_json::to_string(&e).unwrap();
        let back: SceneExport = serde_json::from_str(&text).unwrap();
        assert_eq!(back, e);
    }

    #[test]
    fn every_bsdf_kind_reads_back() {
        let kinds = [
            Bsdf::Lambert {
                albedo: glam::Vec3::new(0.1, 0.2, 0.3),
            },
            Bsdf::OrenNayar {
                albedo: glam::Vec3::splat(0.5),
                sigma: 0.3,
            },
            Bsdf::Mirror {
                tint: glam::Vec3::ONE,
            },
            Bsdf::Dielectric {
                tint: glam::Vec3::ONE,
                eta: 1.5,
            },
            Bsdf::MicrofacetReflection {
                f0: glam::Vec3::ONE,
                distribution: Distribution::Ggx,
                roughness: 0.1,
            },
            Bsdf::MicrofacetDielectric {
                tint: glam::Vec3::ONE,
                distribution: Distribution::BlinnPhong,
                roughness: 30.0,
                eta: 1.33,
            },
        ];
        for b in kinds {
            let layer = ExportLayer {
                weight: 0.5,
                bsdf: b.into(),
            };
            let text = serde_json::to_string(&layer).unwrap();
            let back: ExportLayer = serde_json::from_str(&text).unwrap();
            assert_eq!(back, layer, "{text}");
        }
        let text = serde_json::to_string(&ExportLayer {
            weight: 1.0,
            bsdf: kinds[4].into(),
        })
        .unwrap();
        assert!(
            text.contains(r#""kind":"microfacet-reflection""#)
                && text.contains(r#""shadowing":"smith-height-correlated""#),
            "{text}"
        );
    }
}
