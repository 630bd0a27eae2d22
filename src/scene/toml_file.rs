//! TOML scene files.
//!
//! Paths are relative to the folder of the TOML file. Unknown keys are errors (so a typo
//! like `fov = 40` is reported with its line and column). Numbers may be written as
//! integers or floats. Format:
//!
//! ```toml
//! name = "my scene"                 # optional; default: the file name without .toml
//!
//! [camera]                          # optional; default: frames the geometry like a bare .obj
//! position = [278.0, 273.0, -800.0]
//! look_at  = [278.0, 273.0, 0.0]
//! up       = [0.0, 1.0, 0.0]        # optional; default +y
//! fov_y    = 39.3077                # full vertical field of view, degrees, in (0, 180)
//!
//! [film]                            # optional; default 512 × 512
//! width = 512                       # 1 ..= 16384
//! height = 512
//!
//! [[mesh]]                          # one or more; triangles are appended in this order
//! path = "cornell.obj"              # a Wavefront .obj (its mtllib is loaded too)
//! material = "white"                # optional: every triangle of this mesh uses this material
//! transform = { scale = 2.0, translate = [0.0, 1.0, 0.0] }
//!                                   # optional: p' = p · scale + translate; scale is a number
//!                                   # or [sx, sy, sz] (non-zero); a mirroring scale flips the
//!                                   # vertex order so the front side stays the front side
//!
//! [[material]]                      # define a material, or override fields of every material
//! name = "light"                    # of that name loaded from the MTL files
//! diffuse = [0.78, 0.78, 0.78]      # all fields but name are optional; new materials start
//! specular = [0.0, 0.0, 0.0]        # from diffuse 0.8 grey, no specular, no emission,
//! shininess = 0.0                   # ior 1, dissolve 1, illum 1
//! ior = 1.5
//! dissolve = 1.0
//! illum = 2
//! emission = [17.0, 12.0, 4.0]
//!
//! [[material]]                      # an explicit BSDF (the `pt` integrator) replaces the
//! name = "gold"                     # MTL mapping; it may also override an MTL material
//! bsdf = "conductor"                # lambert | oren-nayar | mirror | glass | rough-glass |
//!                                   # conductor (microfacet reflection) | plastic (diffuse
//!                                   # + glossy coat, F0 from ior; counts as 2 layers)
//! reflectance = [1.0, 0.78, 0.34]   # albedo / tint / F0, each in [0, 1]; default 0.8 grey
//!                                   # (lambert, oren-nayar, plastic), else white
//! roughness = 0.25                  # in (0, 1]: microfacet α, or σ in radians for
//!                                   # oren-nayar; default 0.2; only for the rough kinds
//! distribution = "ggx"              # ggx (default) | beckmann | blinn-phong (microfacet kinds)
//! ior = 1.5                         # > 0; glass, rough-glass, plastic; default 1.5
//!
//! [[material]]                      # or a stack of 1 to 4 weighted layers (thesis §4.4.1),
//! name = "varnished"                # instead of `bsdf` and its keys
//! [[material.layer]]
//! bsdf = "lambert"                  # each layer: bsdf, weight and that kind's keys above
//! reflectance = [0.5, 0.3, 0.1]
//! weight = 0.7                      # in (0, 1]; the weights sum to at most 1
//! [[material.layer]]
//! bsdf = "conductor"
//! roughness = 0.1
//! weight = 0.3
//!
//! [[point_light]]                   # optional, any number
//! position = [278.0, 500.0, 279.5]
//! intensity = [1e5, 1e5, 1e5]       # W/sr, RGB
//!
//! [render]                          # optional overrides for the renderer
//! spp = 64
//! seed = 1
//! integrator = "path"
//! tracer = "gpu"
//! max_depth = 8
//! ```

use std::path::Path;

use glam::Vec3;
use serde::Deserialize;
use toml::Spanned;

use super::obj::{load_obj_mesh, read_text};
use super::{
    framing_camera, validate, BsdfKind, Camera, FilmSize, Location, Material, MaterialBsdf,
    MaterialLayer, MicrofacetModel, PointLight, RenderSettings, Scene, SceneError,
};
use crate::bsdf::MAX_LAYERS;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    camera: Option<Spanned<CameraToml>>,
    film: Option<Spanned<FilmToml>>,
    #[serde(default)]
    mesh: Vec<MeshToml>,
    #[serde(default)]
    material: Vec<MaterialToml>,
    #[serde(default)]
    point_light: Vec<PointLightToml>,
    render: Option<RenderToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraToml {
    position: [f32; 3],
    look_at: [f32; 3],
    up: Option<[f32; 3]>,
    fov_y: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FilmToml {
    width: u32,
    height: u32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshToml {
    path: Spanned<String>,
    material: Option<Spanned<String>>,
    transform: Option<Spanned<TransformToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransformToml {
    scale: Option<Scale>,
    translate: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(untagged, expecting = "a number or [sx, sy, sz]")]
enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialToml {
    name: Spanned<String>,
    diffuse: Option<[f32; 3]>,
    specular: Option<[f32; 3]>,
    shininess: Option<f32>,
    ior: Option<Spanned<f32>>,
    dissolve: Option<f32>,
    illum: Option<u32>,
    emission: Option<[f32; 3]>,
    bsdf: Option<Spanned<String>>,
    reflectance: Option<Spanned<[f32; 3]>>,
    roughness: Option<Spanned<f32>>,
    distribution: Option<Spanned<String>>,
    #[serde(default)]
    layer: Vec<LayerToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LayerToml {
    bsdf: Spanned<String>,
    reflectance: Option<Spanned<[f32; 3]>>,
    roughness: Option<Spanned<f32>>,
    distribution: Option<Spanned<String>>,
    ior: Option<Spanned<f32>>,
    weight: Spanned<f32>,
}

/// The BSDF keys of one layer (of a `[[material.layer]]`, or of the material itself).
struct LayerKeys<'a> {
    bsdf: &'a Spanned<String>,
    reflectance: Option<&'a Spanned<[f32; 3]>>,
    roughness: Option<&'a Spanned<f32>>,
    distribution: Option<&'a Spanned<String>>,
    ior: Option<&'a Spanned<f32>>,
    /// Whether `ior` is the material's MTL `ior` (which every kind may carry).
    shared_ior: bool,
    weight: f32,
}

impl MaterialToml {
    fn apply(&self, m: &mut Material, bsdf: &Option<MaterialBsdf>) {
        if let Some(v) = self.diffuse {
            m.diffuse = v.into();
        }
        if let Some(v) = self.specular {
            m.specular = v.into();
        }
        if let Some(v) = self.shininess {
            m.shininess = v;
        }
        if let Some(v) = &self.ior {
            m.ior = *v.get_ref();
        }
        if let Some(v) = self.dissolve {
            m.dissolve = v;
        }
        if let Some(v) = self.illum {
            m.illum = v;
        }
        if let Some(v) = self.emission {
            m.emission = v.into();
        }
        if bsdf.is_some() {
            m.bsdf = bsdf.clone();
        }
    }

    /// The explicit BSDF of `bsdf = …` or `[[material.layer]]`, validated.
    fn explicit_bsdf(&self, at: &Loc) -> Result<Option<MaterialBsdf>, SceneError> {
        let name = self.name.get_ref();
        let invalid = |span: std::ops::Range<usize>, message: String| SceneError::Invalid {
            at: at(span),
            message: format!("material '{name}': {message}"),
        };
        if let Some(bsdf) = &self.bsdf {
            if !self.layer.is_empty() {
                return Err(invalid(
                    bsdf.span(),
                    "give either 'bsdf' or [[material.layer]] tables, not both".to_string(),
                ));
            }
            let layer = layer_of(
                name,
                &LayerKeys {
                    bsdf,
                    reflectance: self.reflectance.as_ref(),
                    roughness: self.roughness.as_ref(),
                    distribution: self.distribution.as_ref(),
                    ior: self.ior.as_ref(),
                    shared_ior: true,
                    weight: 1.0,
                },
                at,
            )?;
            return Ok(Some(MaterialBsdf {
                layers: vec![layer],
            }));
        }
        let stray = [
            ("reflectance", self.reflectance.as_ref().map(Spanned::span)),
            ("roughness", self.roughness.as_ref().map(Spanned::span)),
            (
                "distribution",
                self.distribution.as_ref().map(Spanned::span),
            ),
        ];
        if let Some((key, Some(span))) = stray.into_iter().find(|(_, s)| s.is_some()) {
            return Err(invalid(
                span,
                format!(
                    "'{key}' needs 'bsdf' next to it (in a layer stack it goes in each [[material.layer]])"
                ),
            ));
        }
        if self.layer.is_empty() {
            return Ok(None);
        }
        let mut layers = Vec::with_capacity(self.layer.len());
        let (mut count, mut total) = (0, 0.0);
        for l in &self.layer {
            let w = *l.weight.get_ref();
            if !(w > 0.0 && w <= 1.0) {
                return Err(invalid(
                    l.weight.span(),
                    format!("layer weight {w} is outside (0, 1]"),
                ));
            }
            let layer = layer_of(
                name,
                &LayerKeys {
                    bsdf: &l.bsdf,
                    reflectance: l.reflectance.as_ref(),
                    roughness: l.roughness.as_ref(),
                    distribution: l.distribution.as_ref(),
                    ior: l.ior.as_ref(),
                    shared_ior: false,
                    weight: w,
                },
                at,
            )?;
            count += layer.kind.layer_count();
            total += w;
            if count > MAX_LAYERS {
                return Err(invalid(
                    l.bsdf.span(),
                    format!("more than {MAX_LAYERS} BSDF layers (a plastic layer counts as 2)"),
                ));
            }
            if total > 1.0 + 1e-4 {
                return Err(invalid(
                    l.weight.span(),
                    format!("layer weights sum to {total}, more than 1"),
                ));
            }
            layers.push(layer);
        }
        Ok(Some(MaterialBsdf { layers }))
    }
}

type Loc<'a> = dyn Fn(std::ops::Range<usize>) -> Location + 'a;

/// One validated layer; `material` names the material in error messages.
fn layer_of(material: &str, k: &LayerKeys, at: &Loc) -> Result<MaterialLayer, SceneError> {
    let invalid = |span: std::ops::Range<usize>, message: String| SceneError::Invalid {
        at: at(span),
        message: format!("material '{material}': {message}"),
    };
    let kind_name = k.bsdf.get_ref();
    let Some(kind) = BsdfKind::from_name(kind_name) else {
        let names: Vec<&str> = BsdfKind::ALL.iter().map(|k| k.name()).collect();
        return Err(SceneError::Unknown {
            at: at(k.bsdf.span()),
            what: "bsdf",
            name: kind_name.clone(),
            hint: format!(" (known: {})", names.join(", ")),
        });
    };
    let not_for = |key: &str, span| {
        invalid(
            span,
            format!("'{key}' does not apply to bsdf '{kind_name}'"),
        )
    };

    let reflectance = match k.reflectance {
        Some(r) => {
            let v = Vec3::from(*r.get_ref());
            if !(v.cmpge(Vec3::ZERO).all() && v.cmple(Vec3::ONE).all()) {
                return Err(invalid(
                    r.span(),
                    format!("reflectance {v} must lie in [0, 1] per channel"),
                ));
            }
            v
        }
        None if matches!(
            kind,
            BsdfKind::Lambert | BsdfKind::OrenNayar | BsdfKind::Plastic
        ) =>
        {
            Vec3::splat(0.8)
        }
        None => Vec3::ONE,
    };
    let roughness = match k.roughness {
        Some(r) if !kind.has_roughness() => return Err(not_for("roughness", r.span())),
        Some(r) => {
            let v = *r.get_ref();
            if !(v > 0.0 && v <= 1.0) {
                return Err(invalid(
                    r.span(),
                    format!("roughness {v} is outside (0, 1]"),
                ));
            }
            v
        }
        None => DEFAULT_ROUGHNESS,
    };
    let distribution = match k.distribution {
        Some(d) if !kind.is_microfacet() => return Err(not_for("distribution", d.span())),
        Some(d) => MicrofacetModel::from_name(d.get_ref()).ok_or_else(|| {
            let names: Vec<&str> = MicrofacetModel::ALL.iter().map(|m| m.name()).collect();
            SceneError::Unknown {
                at: at(d.span()),
                what: "distribution",
                name: d.get_ref().clone(),
                hint: format!(" (known: {})", names.join(", ")),
            }
        })?,
        None => MicrofacetModel::Ggx,
    };
    let ior = match k.ior {
        Some(i) if !kind.has_ior() && !k.shared_ior => return Err(not_for("ior", i.span())),
        Some(i) if kind.has_ior() => {
            let v = *i.get_ref();
            if !(v > 0.0 && v.is_finite()) {
                return Err(invalid(i.span(), format!("ior {v} must be > 0")));
            }
            v
        }
        _ => DEFAULT_IOR,
    };
    Ok(MaterialLayer {
        kind,
        reflectance,
        roughness,
        distribution,
        ior,
        weight: k.weight,
    })
}

/// Roughness when a rough kind has none: α (or σ in radians).
const DEFAULT_ROUGHNESS: f32 = 0.2;
/// ior when glass or plastic has none.
const DEFAULT_IOR: f32 = 1.5;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightToml {
    position: [f32; 3],
    intensity: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderToml {
    spp: Option<u32>,
    seed: Option<u64>,
    integrator: Option<String>,
    tracer: Option<String>,
    max_depth: Option<u32>,
}

/// Loads and validates a TOML scene file (see the module documentation for the format).
pub fn load_toml(path: &Path) -> Result<Scene, SceneError> {
    let text = read_text(path)?;
    let file = path.display().to_string();
    let default_name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".to_string());
    let dir = path.parent().unwrap_or(Path::new(""));
    parse_toml(&text, &file, dir, &default_name)
}

/// Parses TOML scene text; `file` labels error messages, mesh paths are relative to `dir`.
pub fn parse_toml(
    text: &str,
    file: &str,
    dir: &Path,
    default_name: &str,
) -> Result<Scene, SceneError> {
    let at_span = |span: std::ops::Range<usize>| Location::at_offset(file, text, span.start);
    let doc: SceneFile = toml::from_str(text).map_err(|e| SceneError::Syntax {
        at: match e.span() {
            Some(span) => at_span(span),
            None => Location::file(file),
        },
        message: e.message().trim().replace('`', "'"),
    })?;

    let mut triangles = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    // (first triangle, end, material name) for per-mesh overrides, resolved at the end.
    let mut overrides = Vec::new();
    for mesh in &doc.mesh {
        let at = at_span(mesh.path.span());
        let rel = mesh.path.get_ref();
        let full = dir.join(rel);
        let is_obj = full
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if !is_obj {
            return Err(SceneError::Invalid {
                at,
                message: format!(
                    "mesh '{rel}' is not an .obj file (only Wavefront OBJ is supported)"
                ),
            });
        }
        if !full.is_file() {
            return Err(SceneError::MissingReference {
                at,
                what: "mesh",
                name: rel.clone(),
                path: full,
            });
        }
        let loaded = load_obj_mesh(&full)?;
        let offset = materials.len() as u32;
        let start = triangles.len();
        materials.extend(loaded.materials);
        let (scale, translate) = match &mesh.transform {
            None => (Vec3::ONE, Vec3::ZERO),
            Some(t) => {
                let tr = t.get_ref();
                let scale = match tr.scale {
                    None => Vec3::ONE,
                    Some(Scale::Uniform(s)) => Vec3::splat(s),
                    Some(Scale::PerAxis(s)) => s.into(),
                };
                let translate = tr.translate.map_or(Vec3::ZERO, Vec3::from);
                if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() || !translate.is_finite() {
                    return Err(SceneError::Invalid {
                        at: at_span(t.span()),
                        message: format!(
                            "transform of mesh '{rel}': scale {scale} must be finite and non-zero, translate {translate} finite"
                        ),
                    });
                }
                (scale, translate)
            }
        };
        let mirror = scale.x * scale.y * scale.z < 0.0;
        for mut t in loaded.triangles {
            t.material += offset;
            for p in &mut t.p {
                *p = *p * scale + translate;
            }
            if let Some(n) = &mut t.n {
                for v in n.iter_mut() {
                    *v = (*v / scale).normalize_or_zero();
                }
            }
            if mirror {
                t.p.swap(1, 2);
                if let Some(n) = &mut t.n {
                    n.swap(1, 2);
                }
            }
            triangles.push(t);
        }
        if let Some(name) = &mesh.material {
            overrides.push((start, triangles.len(), name));
        }
    }

    for m in &doc.material {
        let bsdf = m.explicit_bsdf(&at_span)?;
        let name = m.name.get_ref();
        let mut found = false;
        for existing in materials.iter_mut().filter(|e| &e.name == name) {
            m.apply(existing, &bsdf);
            found = true;
        }
        if !found {
            let mut new = Material::named(name.clone());
            m.apply(&mut new, &bsdf);
            materials.push(new);
        }
    }

    for (start, end, name) in overrides {
        let Some(index) = materials.iter().position(|m| &m.name == name.get_ref()) else {
            let mut names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            names.dedup();
            return Err(SceneError::Unknown {
                at: at_span(name.span()),
                what: "material",
                name: name.get_ref().clone(),
                hint: format!(" (known: {})", names.join(", ")),
            });
        };
        for t in &mut triangles[start..end] {
            t.material = index as u32;
        }
    }

    let mut scene = Scene {
        name: doc.name.unwrap_or_else(|| default_name.to_string()),
        camera: Camera {
            position: Vec3::ZERO,
            look_at: Vec3::NEG_Z,
            up: Vec3::Y,
            fov_y: 40.0,
        },
        film: FilmSize::default(),
        triangles,
        materials,
        point_lights: doc
            .point_light
            .iter()
            .map(|l| PointLight {
                position: l.position.into(),
                intensity: l.intensity.into(),
            })
            .collect(),
        settings: doc
            .render
            .map(|r| RenderSettings {
                spp: r.spp,
                seed: r.seed,
                integrator: r.integrator,
                tracer: r.tracer,
                max_depth: r.max_depth,
            })
            .unwrap_or_default(),
    };

    let whole = Location::file(file);
    if scene.triangles.is_empty() {
        return Err(SceneError::Empty {
            at: whole,
            message: if doc.mesh.is_empty() {
                "no [[mesh]] entries".to_string()
            } else {
                "the meshes have no triangles".to_string()
            },
        });
    }
    if let Some(f) = &doc.film {
        let film = f.get_ref();
        scene.film = FilmSize {
            width: film.width,
            height: film.height,
        };
        validate::validate_film(&scene.film, &at_span(f.span()))?;
    }
    match &doc.camera {
        Some(c) => {
            let cam = c.get_ref();
            scene.camera = Camera {
                position: cam.position.into(),
                look_at: cam.look_at.into(),
                up: cam.up.map_or(Vec3::Y, Vec3::from),
                fov_y: cam.fov_y,
            };
            validate::validate_camera(&scene.camera, &at_span(c.span()))?;
        }
        None => {
            let bounds = scene.bounds();
            if bounds.min.is_finite() && bounds.max.is_finite() {
                scene.camera = framing_camera(&bounds);
            }
        }
    }
    validate::validate_scene(&scene, &whole)?;
    Ok(scene)
}
