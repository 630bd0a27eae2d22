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
//! [[camera.keyframe]]               # optional: a moving camera. Each key may leave out any
//! time = 0.0                        # field, which then comes from [camera] (whose position,
//! position = [278.0, 273.0, -800.0] # look_at and fov_y are needed only where a key leaves
//! [[camera.keyframe]]               # them out). Times in seconds, increasing; every field
//! time = 2.0                        # moves linearly between keys; before the first key and
//! position = [400.0, 273.0, -700.0] # after the last the camera holds still
//!
//! [film]                            # optional; default 512 × 512
//! width = 512                       # 1 ..= 16384
//! height = 512
//!
//! [[mesh]]                          # one or more; triangles are appended in this order
//! path = "cornell.obj"              # a Wavefront .obj (its mtllib is loaded too)
//! material = "white"                # optional: every triangle of this mesh uses this material
//! transform = { scale = 2.0, translate = [0.0, 1.0, 0.0], rotate = { axis = [0.0, 1.0, 0.0], degrees = 30.0 } }
//!                                   # optional: p' = translate + rotate · (scale ⊙ p); scale
//!                                   # is a number or [sx, sy, sz] (non-zero); rotate is
//!                                   # { axis = [x, y, z], degrees = a } or
//!                                   # { quaternion = [x, y, z, w] }; a mirroring scale flips
//!                                   # the vertex order so the front side stays the front side
//!
//! [[mesh.keyframe]]                 # optional: the mesh moves; each key is a transform
//! time = 0.0                        # applied after `transform` (scale, rotate, translate as
//! translate = [0.0, 0.0, 0.0]       # above; what a key leaves out is the identity). Times in
//! [[mesh.keyframe]]                 # seconds, increasing; translation and scale move
//! time = 1.0                        # linearly, rotation by slerp along the shorter arc (to
//! translate = [0.0, 2.0, 0.0]       # turn further, add keys less than 180° apart); the
//! rotate = { axis = [0.0, 1.0, 0.0], degrees = 90.0 }
//!                                   # pose holds before the first key and after the last;
//!                                   # a key's scale keeps the signs of the first key's
//!
//! [[mesh]]                          # vertex animation: a numbered OBJ sequence, `{}` or
//! path = "wave_{:04}.obj"           # `{:0N}` (zero-padded to N digits) standing for the number
//! sequence = { first = 0, last = 59, fps = 24.0 }
//!                                   # file `first + k` is the shape at time k / fps; vertices
//!                                   # move linearly between files and hold outside them. Every
//!                                   # file needs the same faces in the same order (and normals
//!                                   # on all of them or none); materials come from the first.
//!                                   # `transform` and keys apply to the sequence's shapes too
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
//! tracer = "pdacrt"
//! max_depth = 8                     # -1: unbounded (the default)
//! ```

use std::path::Path;

use glam::{DVec3, Vec3};
use serde::Deserialize;
use toml::Spanned;

use super::animation::toml::{CameraToml, MeshToml};
use super::animation::{AnimatedScene, Animation, Keyframes};
use super::obj::read_text;
use super::recentre::{self, Anchored, MovingAnchor};
use super::{
    framing_camera, validate, BsdfKind, Camera, FilmSize, Location, Material, MaterialBsdf,
    MaterialLayer, MicrofacetModel, PointLight, RenderSettings, Scene, SceneError, Triangle,
};
use crate::bsdf::MAX_LAYERS;
use crate::integrator::IntegratorKind;
use crate::trace::TracerKind;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    camera: Option<CameraToml>,
    film: Option<FilmToml>,
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
struct FilmToml {
    // Spans on the fields, not the table: see `CameraToml`.
    width: Spanned<u32>,
    height: Spanned<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialToml {
    name: Spanned<String>,
    diffuse: Option<Spanned<[f32; 3]>>,
    specular: Option<Spanned<[f32; 3]>>,
    shininess: Option<Spanned<f32>>,
    ior: Option<Spanned<f32>>,
    dissolve: Option<Spanned<f32>>,
    illum: Option<u32>,
    emission: Option<Spanned<[f32; 3]>>,
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
    /// Checks the colours and numbers the table sets (the checks `validate_scene` makes
    /// of every material), so that a bad one is reported at its line.
    fn check_values(&self, at: &Loc) -> Result<(), SceneError> {
        let name = self.name.get_ref();
        for (what, v, reflectance) in [
            ("diffuse", &self.diffuse, true),
            ("specular", &self.specular, true),
            ("emission", &self.emission, false),
        ] {
            if let Some(v) = v {
                let (c, at) = (Vec3::from(*v.get_ref()), at(v.span()));
                let what = || format!("material '{name}' {what}");
                validate::check_finite(c, &at, what)?;
                if reflectance {
                    validate::check_reflectance(c, &at, what)?;
                } else {
                    validate::check_non_negative(c, &at, what)?;
                }
            }
        }
        for (what, v) in [
            ("shininess", &self.shininess),
            ("ior", &self.ior),
            ("dissolve", &self.dissolve),
        ] {
            if let Some(v) = v.as_ref().filter(|v| !v.get_ref().is_finite()) {
                return Err(SceneError::NonFinite {
                    at: at(v.span()),
                    what: format!("material '{name}' {what}"),
                    value: v.get_ref().to_string(),
                });
            }
        }
        Ok(())
    }

    fn apply(&self, m: &mut Material, bsdf: &Option<MaterialBsdf>) {
        let colour = |v: &Spanned<[f32; 3]>| Vec3::from(*v.get_ref());
        if let Some(v) = &self.diffuse {
            m.diffuse = colour(v);
        }
        if let Some(v) = &self.specular {
            m.specular = colour(v);
        }
        if let Some(v) = &self.shininess {
            m.shininess = *v.get_ref();
        }
        if let Some(v) = &self.ior {
            m.ior = *v.get_ref();
        }
        if let Some(v) = &self.dissolve {
            m.dissolve = *v.get_ref();
        }
        if let Some(v) = self.illum {
            m.illum = v;
        }
        if let Some(v) = &self.emission {
            m.emission = colour(v);
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

type Loc<'a> = super::animation::toml::At<'a>;

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
    /// Read in f64 and moved with the scene before it is rounded ([`recentre::to_scene`]).
    position: Spanned<[f64; 3]>,
    intensity: Spanned<[f32; 3]>,
}

/// The `[[point_light]]` tables, moved by −`offset` (the scene's), each checked as
/// `validate_scene` checks a light, so that a bad value is reported at its line.
fn point_lights(
    tables: &[PointLightToml],
    offset: Option<DVec3>,
    at: &Loc,
) -> Result<Vec<PointLight>, SceneError> {
    let mut lights = Vec::with_capacity(tables.len());
    for (i, l) in tables.iter().enumerate() {
        let position = recentre::to_scene(*l.position.get_ref(), offset);
        let intensity = Vec3::from(*l.intensity.get_ref());
        let (at_position, at_intensity) = (at(l.position.span()), at(l.intensity.span()));
        validate::check_finite(position, &at_position, || {
            format!("point light {i} position")
        })?;
        validate::check_finite(intensity, &at_intensity, || {
            format!("point light {i} intensity")
        })?;
        validate::check_non_negative(intensity, &at_intensity, || {
            format!("point light {i} intensity")
        })?;
        lights.push(PointLight {
            position,
            intensity,
        });
    }
    Ok(lights)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderToml {
    spp: Option<Spanned<u32>>,
    seed: Option<u64>,
    integrator: Option<Spanned<String>>,
    tracer: Option<Spanned<String>>,
    /// As `--max-depth`: −1 is unbounded (the default).
    max_depth: Option<Spanned<i64>>,
}

/// Loads and validates a TOML scene file (see the module documentation for the format),
/// posed at time 0.
pub fn load_toml(path: &Path) -> Result<Scene, SceneError> {
    load_toml_animated(path).map(|a| a.scene)
}

/// Loads and validates a TOML scene file and what moves in it.
pub fn load_toml_animated(path: &Path) -> Result<AnimatedScene, SceneError> {
    let text = read_text(path)?;
    let file = path.display().to_string();
    let default_name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".to_string());
    let dir = path.parent().unwrap_or(Path::new(""));
    parse_toml_animated(&text, &file, dir, &default_name)
}

/// Parses TOML scene text posed at time 0; `file` labels error messages, mesh paths are
/// relative to `dir`.
pub fn parse_toml(
    text: &str,
    file: &str,
    dir: &Path,
    default_name: &str,
) -> Result<Scene, SceneError> {
    parse_toml_animated(text, file, dir, default_name).map(|a| a.scene)
}

/// [`parse_toml`] with what moves in the scene.
pub fn parse_toml_animated(
    text: &str,
    file: &str,
    dir: &Path,
    default_name: &str,
) -> Result<AnimatedScene, SceneError> {
    let at_span = |span: std::ops::Range<usize>| Location::at_offset(file, text, span.start);
    let doc: SceneFile = toml::from_str(text).map_err(|e| SceneError::Syntax {
        at: match e.span() {
            Some(span) => at_span(span),
            None => Location::file(file),
        },
        message: e.message().trim().replace('`', "'"),
    })?;

    let Meshes {
        mut triangles,
        mut materials,
        mut animation,
        overrides,
        anchored,
        moving,
    } = load_meshes(&doc.mesh, dir, &at_span)?;
    apply_material_tables(&doc.material, &mut materials, &at_span)?;
    apply_mesh_materials(&overrides, &materials, &mut triangles, &at_span)?;
    let name = doc.name.unwrap_or_else(|| default_name.to_string());
    // Far from the origin, everything is moved before it is rounded to f32 (`recentre`).
    let offset = recentre::place_soup(&name, &mut triangles, &anchored);

    let mut scene = Scene {
        name,
        camera: Camera {
            position: Vec3::ZERO,
            look_at: Vec3::NEG_Z,
            up: Vec3::Y,
            fov_y: 40.0,
        },
        film: FilmSize::default(),
        triangles,
        materials,
        point_lights: point_lights(&doc.point_light, offset, &at_span)?,
        settings: match doc.render {
            Some(r) => render_settings(r, &at_span)?,
            None => RenderSettings::default(),
        },
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
        scene.film = film_size(f, &at_span)?;
    }
    animation.camera = place_camera(doc.camera.as_ref(), offset, &mut scene, (&at_span, &whole))?;
    validate::validate_scene(&scene, &whole)?;
    let mut animated = AnimatedScene { scene, animation };
    recentre::place_motions(&mut animated, &moving, offset);
    Ok(animated)
}

/// The `[film]` size, validated.
fn film_size(film: &FilmToml, at: &Loc) -> Result<FilmSize, SceneError> {
    let size = FilmSize {
        width: *film.width.get_ref(),
        height: *film.height.get_ref(),
    };
    // At whichever of the two comes first in the file.
    let (width, height) = (film.width.span(), film.height.span());
    let first = if width.start <= height.start {
        width
    } else {
        height
    };
    validate::validate_film(&size, &at(first))?;
    Ok(size)
}

/// Sets the scene's camera: the `[camera]` table's (moved by −`offset`, the scene's),
/// else one framing the geometry (where its bounds are finite; `validate_scene` reports
/// them where not). Returns the camera's keyframes.
fn place_camera(
    camera: Option<&CameraToml>,
    offset: Option<DVec3>,
    scene: &mut Scene,
    (at, file): (&Loc, &Location),
) -> Result<Option<Keyframes<Camera>>, SceneError> {
    match camera {
        Some(c) => {
            let (camera, keys) = c.resolve(at, file, offset)?;
            scene.camera = camera;
            Ok(keys)
        }
        None => {
            let bounds = scene.bounds();
            if bounds.min.is_finite() && bounds.max.is_finite() {
                scene.camera = framing_camera(&bounds);
            }
            Ok(None)
        }
    }
}

/// The triangles and materials of every `[[mesh]]`, in file order, and how they move.
struct Meshes<'d> {
    triangles: Vec<Triangle>,
    materials: Vec<Material>,
    animation: Animation,
    /// (first triangle, end, material name) for per-mesh overrides, resolved once every
    /// material is known.
    overrides: Vec<(usize, usize, &'d Spanned<String>)>,
    /// The still meshes whose positions are relative to an anchor of their own.
    anchored: Vec<Anchored>,
    /// The moving meshes' anchors.
    moving: Vec<MovingAnchor>,
}

/// Loads every mesh, its triangles indexing the materials of all meshes.
fn load_meshes<'d>(meshes: &'d [MeshToml], dir: &Path, at: &Loc) -> Result<Meshes<'d>, SceneError> {
    let mut triangles = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut animation = Animation::default();
    let mut overrides = Vec::new();
    let mut anchored = Vec::new();
    let mut moving = Vec::new();
    for mesh in meshes {
        let loaded = mesh.load(dir, at)?;
        let offset = materials.len() as u32;
        let start = triangles.len();
        materials.extend(loaded.mesh.materials);
        triangles.extend(loaded.mesh.triangles.into_iter().map(|mut t| {
            t.material += offset;
            t
        }));
        if loaded.mesh.origin != DVec3::ZERO {
            anchored.push(Anchored {
                range: start..triangles.len(),
                anchor: loaded.mesh.origin,
            });
        }
        if let Some(mut motion) = loaded.motion {
            motion.range = start..triangles.len();
            moving.push(MovingAnchor {
                mesh: animation.meshes.len(),
                anchor: loaded.motion_anchor,
            });
            animation.meshes.push(motion);
        }
        if let Some(name) = &mesh.material {
            overrides.push((start, triangles.len(), name));
        }
    }
    Ok(Meshes {
        triangles,
        materials,
        animation,
        overrides,
        anchored,
        moving,
    })
}

/// Applies each `[[material]]` to every loaded material of its name, or adds it as a new
/// material when none has that name.
fn apply_material_tables(
    tables: &[MaterialToml],
    materials: &mut Vec<Material>,
    at: &Loc,
) -> Result<(), SceneError> {
    for m in tables {
        m.check_values(at)?;
        let bsdf = m.explicit_bsdf(at)?;
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
    Ok(())
}

/// Gives the triangles of each mesh with a `material` key that material (the first of
/// its name).
fn apply_mesh_materials(
    overrides: &[(usize, usize, &Spanned<String>)],
    materials: &[Material],
    triangles: &mut [Triangle],
    at: &Loc,
) -> Result<(), SceneError> {
    for &(start, end, name) in overrides {
        let Some(index) = materials.iter().position(|m| &m.name == name.get_ref()) else {
            // Each name once, in the order first loaded (a mesh loaded twice brings its
            // materials twice).
            let mut names: Vec<&str> = Vec::new();
            for m in materials {
                if !names.contains(&m.name.as_str()) {
                    names.push(&m.name);
                }
            }
            return Err(SceneError::Unknown {
                at: at(name.span()),
                what: "material",
                name: name.get_ref().clone(),
                hint: format!(" (known: {})", names.join(", ")),
            });
        };
        for t in &mut triangles[start..end] {
            t.material = index as u32;
        }
    }
    Ok(())
}

/// The `[render]` table, checked here so that a bad value is reported with its line even
/// when the command line overrides it.
fn render_settings(r: RenderToml, at: &Loc) -> Result<RenderSettings, SceneError> {
    let invalid = |span: std::ops::Range<usize>, message: String| SceneError::Invalid {
        at: at(span),
        message,
    };
    if let Some(spp) = r.spp.as_ref().filter(|s| *s.get_ref() == 0) {
        return Err(invalid(spp.span(), "spp must be at least 1".into()));
    }
    if let Some(name) = &r.integrator {
        name.get_ref()
            .parse::<IntegratorKind>()
            .map_err(|e| invalid(name.span(), e))?;
    }
    if let Some(name) = &r.tracer {
        name.get_ref()
            .parse::<TracerKind>()
            .map_err(|e| invalid(name.span(), e))?;
    }
    let max_depth = match r.max_depth {
        None => None,
        Some(d) => match *d.get_ref() {
            -1 => None,
            depth => Some(u32::try_from(depth).map_err(|_| {
                invalid(
                    d.span(),
                    format!(
                        "max_depth {depth}: expected -1 (unbounded) or a depth from 0 to {}",
                        u32::MAX
                    ),
                )
            })?),
        },
    };
    Ok(RenderSettings {
        spp: r.spp.map(Spanned::into_inner),
        seed: r.seed,
        integrator: r.integrator.map(Spanned::into_inner),
        tracer: r.tracer.map(Spanned::into_inner),
        max_depth,
    })
}
