//! Scenes: geometry, materials, lights and camera, from TOML, OBJ or built-in generators.
//!
//! Conventions a caller must know:
//! - **Units** are whatever the input uses (the Cornell box is in millimetres, the
//!   fixture in metres); nothing is rescaled. Point-light intensity is in W/sr (RGB),
//!   emission is radiance (RGB).
//! - **Winding**: the geometric normal of a triangle is `normalize((p1 − p0) × (p2 − p0))`
//!   ([`Triangle::geometric_normal`]), i.e. counter-clockwise vertices seen from the
//!   front. Built-in scenes wind every wall so that this normal points *into* the room
//!   (towards the camera side) and every block / box face so that it points *out* of the
//!   block; area lights emit on their front (normal) side. OBJ files keep their own
//!   winding.
//! - **Degenerate triangles** (zero area, collinear vertices) are kept in file order
//!   (the triangle soup is never reordered) and counted in [`SceneStats`]; a warning is
//!   logged. A scene whose triangles are *all* degenerate is an error.
//! - Shading normals ([`Triangle::n`]) come from OBJ `vn` data only when every vertex of
//!   the mesh has one; they are not normalised or re-oriented.

pub mod animation;
pub mod builtin;
pub mod camera;
pub mod error;
pub mod obj;
pub mod recentre;
pub mod shapes;
pub mod toml_file;
pub mod validate;

use std::path::Path;

pub use animation::AnimatedScene;
pub use builtin::{builtin, builtin_names};
pub use camera::{Camera, CameraFrame};
pub use error::{Location, SceneError};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Film resolution in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FilmSize {
    pub width: u32,
    pub height: u32,
}

impl Default for FilmSize {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
        }
    }
}

/// One triangle of the flat soup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Per-vertex shading normals, when the source had them for every vertex.
    pub n: Option<[Vec3; 3]>,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

impl Triangle {
    pub fn new(p0: Vec3, p1: Vec3, p2: Vec3, material: u32) -> Self {
        Self {
            p: [p0, p1, p2],
            n: None,
            material,
        }
    }

    /// `(p1 − p0) × (p2 − p0)`: length is twice the area.
    pub fn cross(&self) -> Vec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    /// Unit geometric normal (counter-clockwise front), or zero for a degenerate triangle.
    pub fn geometric_normal(&self) -> Vec3 {
        self.cross().normalize_or_zero()
    }

    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }

    pub fn centroid(&self) -> Vec3 {
        (self.p[0] + self.p[1] + self.p[2]) / 3.0
    }

    /// Zero area (within f32 precision relative to the edge lengths) or non-finite.
    pub fn is_degenerate(&self) -> bool {
        let c = self.cross();
        let e = (self.p[1] - self.p[0])
            .length_squared()
            .max((self.p[2] - self.p[0]).length_squared());
        !c.is_finite() || c.length() <= e * 1e-7
    }
}

/// A material, mirroring the MTL parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub name: String,
    /// Kd: diffuse albedo.
    pub diffuse: Vec3,
    /// Ks: specular colour.
    pub specular: Vec3,
    /// Ns: Phong exponent.
    pub shininess: f32,
    /// Ni: index of refraction.
    pub ior: f32,
    /// d: opacity (1 = opaque).
    pub dissolve: f32,
    /// illum: MTL illumination model.
    pub illum: u32,
    /// Ke: emitted radiance.
    pub emission: Vec3,
    /// An explicit BSDF from a scene file; when set it replaces the MTL mapping above
    /// (`emission` still applies).
    #[serde(default)]
    pub bsdf: Option<MaterialBsdf>,
}

impl Default for Material {
    /// Diffuse 0.8 grey, no specular, no emission, opaque, ior 1, illum 1.
    fn default() -> Self {
        Self {
            name: "default".to_string(),
            diffuse: Vec3::splat(0.8),
            specular: Vec3::ZERO,
            shininess: 0.0,
            ior: 1.0,
            dissolve: 1.0,
            illum: 1,
            emission: Vec3::ZERO,
            bsdf: None,
        }
    }
}

impl Material {
    pub fn named(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            ..Self::default()
        }
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// An explicit BSDF description: a stack of 1 to 4 weighted layers (thesis §4.4.1).
/// The single-BSDF form of a scene file is one layer of weight 1. A `Plastic` layer
/// becomes two BSDF layers (diffuse + glossy coat) and counts twice toward the limit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialBsdf {
    pub layers: Vec<MaterialLayer>,
}

/// One layer of a [`MaterialBsdf`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialLayer {
    pub kind: BsdfKind,
    /// Albedo (lambert, oren-nayar, plastic), tint (mirror, glass, rough-glass) or
    /// normal-incidence reflectance F0 (conductor); each channel in [0, 1].
    pub reflectance: Vec3,
    /// Microfacet α in (0, 1], or Oren–Nayar σ in radians.
    pub roughness: f32,
    pub distribution: MicrofacetModel,
    /// η = η_inside / η_outside (glass, rough-glass; plastic: the coat's Fresnel F0).
    pub ior: f32,
    /// Mixture weight in (0, 1]; the weights of a stack sum to at most 1.
    pub weight: f32,
}

/// The BSDF kinds a scene file can name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BsdfKind {
    Lambert,
    OrenNayar,
    Mirror,
    Glass,
    RoughGlass,
    /// Microfacet reflection with Schlick Fresnel (F0 = reflectance).
    Conductor,
    /// Lambert + microfacet coat whose F0 comes from the ior.
    Plastic,
}

impl BsdfKind {
    pub const ALL: [BsdfKind; 7] = [
        BsdfKind::Lambert,
        BsdfKind::OrenNayar,
        BsdfKind::Mirror,
        BsdfKind::Glass,
        BsdfKind::RoughGlass,
        BsdfKind::Conductor,
        BsdfKind::Plastic,
    ];

    /// The scene-file name (`"rough-glass"` …).
    pub fn name(self) -> &'static str {
        match self {
            BsdfKind::Lambert => "lambert",
            BsdfKind::OrenNayar => "oren-nayar",
            BsdfKind::Mirror => "mirror",
            BsdfKind::Glass => "glass",
            BsdfKind::RoughGlass => "rough-glass",
            BsdfKind::Conductor => "conductor",
            BsdfKind::Plastic => "plastic",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Whether `roughness` means something for this kind.
    pub fn has_roughness(self) -> bool {
        matches!(
            self,
            BsdfKind::OrenNayar | BsdfKind::RoughGlass | BsdfKind::Conductor | BsdfKind::Plastic
        )
    }

    /// Whether `distribution` means something for this kind.
    pub fn is_microfacet(self) -> bool {
        matches!(
            self,
            BsdfKind::RoughGlass | BsdfKind::Conductor | BsdfKind::Plastic
        )
    }

    /// Whether `ior` means something for this kind.
    pub fn has_ior(self) -> bool {
        matches!(
            self,
            BsdfKind::Glass | BsdfKind::RoughGlass | BsdfKind::Plastic
        )
    }

    /// BSDF layers this kind takes in a stack (plastic: 2).
    pub fn layer_count(self) -> usize {
        if self == BsdfKind::Plastic {
            2
        } else {
            1
        }
    }
}

/// Microfacet distributions a scene file can name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MicrofacetModel {
    Ggx,
    Beckmann,
    BlinnPhong,
}

impl MicrofacetModel {
    pub const ALL: [MicrofacetModel; 3] = [
        MicrofacetModel::Ggx,
        MicrofacetModel::Beckmann,
        MicrofacetModel::BlinnPhong,
    ];

    pub fn name(self) -> &'static str {
        match self {
            MicrofacetModel::Ggx => "ggx",
            MicrofacetModel::Beckmann => "beckmann",
            MicrofacetModel::BlinnPhong => "blinn-phong",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// An isotropic point light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointLight {
    pub position: Vec3,
    /// Radiant intensity, W/sr per RGB channel.
    pub intensity: Vec3,
}

/// Optional render overrides carried by a scene file; `None` means "caller decides".
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RenderSettings {
    pub spp: Option<u32>,
    pub seed: Option<u64>,
    pub integrator: Option<String>,
    pub tracer: Option<String>,
    pub max_depth: Option<u32>,
}

/// Axis-aligned bounding box. The empty box has `min = +inf`, `max = −inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Radius of the bounding sphere around [`Aabb::center`] (half the diagonal).
    pub fn radius(&self) -> f32 {
        self.extent().length() * 0.5
    }

    /// How far a ray that leaves a surface inside these bounds starts off it (along the
    /// geometric normal) so that it does not hit that surface again, where rays also
    /// start from `sources` (the camera, point lights): 32 float steps of the largest
    /// coordinate of the bounds and the sources.
    ///
    /// A computed hit point lies off its triangle's plane by the rounding of what it was
    /// computed from (the ray's origin, the triangle's vertices): a few float steps of
    /// the largest of those coordinates, which never exceed the bounds and the sources.
    /// 32 steps leave a margin of about four over that. The offset is not a fraction of
    /// the scene's extent: a wide ground plane would make it as large as the objects on
    /// it, and their shadow rays would start above them (`ray_offset` test: a unit cube
    /// on a plane 2·10⁴ wide). Always positive.
    pub fn ray_epsilon(&self, sources: impl IntoIterator<Item = Vec3>) -> f32 {
        const FLOAT_STEPS: f32 = 32.0 * f32::EPSILON;
        let farthest = sources
            .into_iter()
            .fold(self.min.abs().max(self.max.abs()), |m, p| m.max(p.abs()))
            .max_element();
        (FLOAT_STEPS * farthest).max(f32::MIN_POSITIVE)
    }

    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// Counts describing a scene, for logs and sanity checks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneStats {
    pub triangles: usize,
    /// Zero-area triangles (kept in the soup).
    pub degenerate_triangles: usize,
    /// Triangles whose material emits.
    pub emissive_triangles: usize,
    /// Triangles with per-vertex shading normals.
    pub triangles_with_normals: usize,
    pub materials: usize,
    pub emissive_materials: usize,
    pub point_lights: usize,
}

/// A complete scene: a flat triangle soup (file order), its materials, lights and camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    pub film: FilmSize,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub point_lights: Vec<PointLight>,
    pub settings: RenderSettings,
}

impl Scene {
    /// The triangles as the tracers take them, in the scene's order.
    pub fn gpu_triangles(&self) -> Vec<crate::trace::GpuTriangle> {
        self.triangles
            .iter()
            .map(|t| crate::trace::GpuTriangle::new(t.p))
            .collect()
    }

    /// The points off the surfaces that the light transport integrators start rays
    /// from: the camera and the point lights ([`Aabb::ray_epsilon`]'s sources).
    pub fn ray_sources(&self) -> impl Iterator<Item = Vec3> + '_ {
        let lights = self.point_lights.iter().map(|l| l.position);
        std::iter::once(self.camera.position).chain(lights)
    }

    /// Bounding box of all triangle vertices (empty box for no triangles).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for t in &self.triangles {
            for p in t.p {
                b.grow(p);
            }
        }
        b
    }

    /// Unit geometric normal of triangle `tri` (see the module doc for the winding).
    pub fn geometric_normal(&self, tri: usize) -> Vec3 {
        self.triangles[tri].geometric_normal()
    }

    /// The material of triangle `tri`.
    pub fn material_of(&self, tri: usize) -> &Material {
        &self.materials[self.triangles[tri].material as usize]
    }

    pub fn material_index(&self, name: &str) -> Option<u32> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|i| i as u32)
    }

    /// Triangles whose material has non-zero emission.
    pub fn emissive_triangle_count(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| self.materials[t.material as usize].is_emissive())
            .count()
    }

    /// Indices of the emissive triangles, in soup order.
    pub fn emissive_triangles(&self) -> Vec<u32> {
        (0..self.triangles.len() as u32)
            .filter(|&i| self.material_of(i as usize).is_emissive())
            .collect()
    }

    pub fn stats(&self) -> SceneStats {
        SceneStats {
            triangles: self.triangles.len(),
            degenerate_triangles: self.triangles.iter().filter(|t| t.is_degenerate()).count(),
            emissive_triangles: self.emissive_triangle_count(),
            triangles_with_normals: self.triangles.iter().filter(|t| t.n.is_some()).count(),
            materials: self.materials.len(),
            emissive_materials: self.materials.iter().filter(|m| m.is_emissive()).count(),
            point_lights: self.point_lights.len(),
        }
    }

    /// The camera resolved for this scene's film.
    pub fn camera_frame(&self) -> CameraFrame {
        self.camera.frame(self.film.width, self.film.height)
    }
}

/// A camera that frames `bounds`: it looks at the box centre from the +z side
/// (position = centre + (0, 0, d), looking toward −z, up +y, fov_y 40°), with `d` chosen
/// so that the bounding sphere fits the vertical field of view (with 5% margin).
pub fn framing_camera(bounds: &Aabb) -> Camera {
    let fov_y: f32 = 40.0;
    let center = bounds.center();
    // A scene of any size fits; a single point gets a unit sphere.
    let r = Some(bounds.radius()).filter(|&r| r > 0.0).unwrap_or(1.0);
    let d = 1.05 * r / (fov_y.to_radians() * 0.5).sin();
    Camera {
        position: center + Vec3::new(0.0, 0.0, d),
        look_at: center,
        up: Vec3::Y,
        fov_y,
    }
}

/// Loads a scene and what moves in it, as [`load`] does (an animated scene's
/// [`AnimatedScene::scene`] is posed at time 0; a static one has no animation).
pub fn load_animated(spec: &str) -> Result<AnimatedScene, SceneError> {
    if let Some(animated) = animation::builtin::animated(spec) {
        return Ok(animated);
    }
    let path = Path::new(spec);
    let is_toml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if is_toml {
        let _span = tracing::info_span!("scene load", what = spec).entered();
        return toml_file::load_toml_animated(path);
    }
    load(spec).map(AnimatedScene::from)
}

/// Loads a scene: a built-in name (see [`builtin_names`]), a path to a `.toml` scene
/// file, or a path to an `.obj` mesh (which gets a framing camera and a 512×512 film).
/// The result is validated ([`validate::validate_scene`]) and, when it lies far from
/// the origin, moved to it ([`recentre`]). An animated scene is posed at time 0
/// ([`load_animated`] keeps what moves).
pub fn load(spec: &str) -> Result<Scene, SceneError> {
    let _span = tracing::info_span!("scene load", what = spec).entered();
    if let Some(scene) = builtin(spec) {
        return Ok(scene);
    }
    let path = Path::new(spec);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => toml_file::load_toml(path),
        Some("obj") => obj::load_obj_scene(path),
        _ => {
            let names: Vec<&str> = builtin_names().iter().map(|(n, _)| *n).collect();
            Err(SceneError::BadSpec {
                spec: spec.to_string(),
                message: format!(
                    "not a built-in scene ({}) and not a path ending in .toml or .obj",
                    names.join(", ")
                ),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_and_normal() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
        assert!(!t.is_degenerate());
        assert_eq!(t.geometric_normal(), Vec3::Z);
        assert!((t.area() - 0.5).abs() < 1e-6);
        let d = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0, 0);
        assert!(d.is_degenerate());
        assert_eq!(d.geometric_normal(), Vec3::ZERO);
        let p = Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE, 0);
        assert!(p.is_degenerate());
    }

    #[test]
    fn framing_camera_fits_sphere() {
        let b = Aabb {
            min: Vec3::new(-1.0, -2.0, -3.0),
            max: Vec3::new(3.0, 2.0, 1.0),
        };
        let c = framing_camera(&b);
        assert_eq!(c.look_at, b.center());
        let d = (c.position - c.look_at).length();
        let half = (c.fov_y.to_radians() * 0.5).sin();
        assert!(b.radius() / d <= half);
        assert!(c.position.z > b.max.z);
    }

    #[test]
    fn the_ray_offset_follows_the_farthest_coordinate_rays_start_from() {
        let steps = |x: f32| 32.0 * f32::EPSILON * x;
        let b = Aabb {
            min: Vec3::new(-1e4, 0.0, -1e4),
            max: Vec3::new(1e4, 1.0, 1e4),
        };
        // As wide as the plane, not a fraction of it.
        assert_eq!(b.ray_epsilon([]), steps(1e4));
        assert_eq!(b.ray_epsilon([Vec3::new(0.0, -3e5, 2.0)]), steps(3e5));
        let mut scene = builtin("cornell-box").unwrap();
        let offset = |s: &Scene| s.bounds().ray_epsilon(s.ray_sources());
        let (camera, farthest) = (scene.camera.position, scene.bounds().max.max_element());
        assert_eq!(
            offset(&scene),
            steps(farthest.max(camera.abs().max_element()))
        );
        // Light paths start at point lights: one far away counts.
        scene.point_lights.push(PointLight {
            position: Vec3::new(0.0, 5e6, 0.0),
            intensity: Vec3::ONE,
        });
        assert_eq!(offset(&scene), steps(5e6));
        let tiny = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
        };
        assert_eq!(tiny.ray_epsilon([]), f32::MIN_POSITIVE);
    }
}
