//! Wavefront OBJ + MTL loading (through `tobj`) and export.
//!
//! Before `tobj` sees a file it is pre-scanned (`prescan`), so that malformed numbers,
//! NaN / inf coordinates and out-of-range face indices are reported with their line number
//! (and so that inputs on which `tobj` would panic never reach it), and rewritten where
//! `tobj` would read it otherwise than the OBJ format means (`for_tobj`: libraries named
//! after a `usemtl` or several to a line, trailing comments, one-number texture
//! coordinates, vertex colours on some vertices only). Faces are triangulated;
//! vertex normals are kept when every vertex of a `tobj` mesh has one. Faces without a
//! material (no `usemtl`, or a `usemtl` naming a material no MTL defines — the latter
//! logs a warning) get a default material ([`DEFAULT_MATERIAL_NAME`]) appended after the
//! MTL materials.
//!
//! MTL mapping: Kd → diffuse, Ks → specular, Ns → shininess, Ni → ior, d (or 1 − Tr) →
//! dissolve, illum → illum, Ke → emission. Missing parameters take [`Material::default`].

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use glam::{DVec3, Vec3};

use super::recentre::{self, Anchored};
use super::{
    framing_camera, validate, FilmSize, Location, Material, RenderSettings, Scene, SceneError,
    Triangle,
};

mod for_tobj;
mod prescan;

use for_tobj::{libraries, text_for_tobj, Library};
use prescan::{prescan_mtl, prescan_obj, ObjScan};

/// Name of the material given to faces that have none.
pub const DEFAULT_MATERIAL_NAME: &str = "obj-default";

/// Triangles of one OBJ file and the materials they index (local indices).
#[derive(Clone, Debug, Default)]
pub struct ObjMesh {
    /// Positions relative to [`Self::origin`].
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    /// How the file's faces join its vertices, as a hash: two files with the same faces
    /// (over vertices at any positions, listed in any order) have the same value.
    pub connectivity: u64,
    /// Where the triangles' positions are measured from: the centre of the file's
    /// bounds, read in f64, when the file lies far from the origin for its size
    /// ([`recentre::offset_for`]), else zero. So a file at 5·10⁶ keeps the precision of
    /// its positions, which f32 would round to steps of 0.5 there.
    pub origin: DVec3,
}

impl ObjMesh {
    /// The mesh with its positions measured from `origin` instead, the difference of the
    /// two origins taken in f64 (the files of a sequence share their first file's).
    pub fn measured_from(mut self, origin: DVec3) -> Self {
        let shift = self.origin - origin;
        if shift != DVec3::ZERO {
            for t in &mut self.triangles {
                t.p = t.p.map(|p| (shift + p.as_dvec3()).as_vec3());
            }
        }
        self.origin = origin;
        self
    }
}

/// The text of a scene, OBJ or MTL file, without the byte-order mark some editors write
/// at its start (a BOM is no part of the text: left in, it would hide the first
/// keyword).
pub(crate) fn read_text(path: &Path) -> Result<String, SceneError> {
    crate::input::read_to_string(path)
        .map(without_byte_order_mark)
        .map_err(|error| SceneError::Io {
            path: path.to_path_buf(),
            error,
        })
}

/// Fails unless the file `name` that `at` refers to as a `what` (a mesh, a mesh sequence
/// file), looked for at `full`, can be read: a missing file is named as the reference
/// that is missing, one that is not a regular file (a FIFO, a folder) as such.
pub(crate) fn check_referenced_file(
    full: &Path,
    at: &Location,
    what: &'static str,
    name: &str,
) -> Result<(), SceneError> {
    crate::input::check_regular_file(full)
        .map_err(|error| reference_error(error, full, at.clone(), what, name.to_string()))
}

/// The error of reading `full`, the file `at` refers to as the `what` `name`: missing,
/// or there but not readable.
fn reference_error(
    error: std::io::Error,
    full: &Path,
    at: Location,
    what: &'static str,
    name: String,
) -> SceneError {
    let path = full.to_path_buf();
    match error.kind() {
        std::io::ErrorKind::NotFound => SceneError::MissingReference {
            at,
            what,
            name,
            path,
        },
        _ => SceneError::UnreadableReference {
            at,
            what,
            path,
            error,
        },
    }
}

fn without_byte_order_mark(text: String) -> String {
    match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    }
}

/// `text` with each line that ends in a backslash joined to the next (the OBJ
/// specification's line continuation, used to wrap long faces). The joined line keeps
/// the first line's number, and empty lines follow it in place of the lines it took in,
/// so that the lines after it keep their numbers for the pre-scan's messages.
fn with_continuations_joined(text: &str) -> Cow<'_, str> {
    if !text.lines().any(|line| continued(line).is_some()) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    let mut taken_in = 0;
    for line in text.lines() {
        match continued(line) {
            Some(head) => {
                out.push_str(head);
                out.push(' ');
                taken_in += 1;
            }
            None => {
                out.push_str(line);
                out.push('\n');
                out.extend(std::iter::repeat_n('\n', taken_in));
                taken_in = 0;
            }
        }
    }
    // A backslash on the last line continues nothing.
    out.extend(std::iter::repeat_n('\n', taken_in));
    Cow::Owned(out)
}

/// The line without its continuing backslash, if it is continued. A comment ends at
/// its line: one ending in a backslash (a Windows folder) takes in nothing.
fn continued(line: &str) -> Option<&str> {
    let line = line.trim_end();
    if line.trim_start().starts_with('#') {
        return None;
    }
    line.strip_suffix('\\')
}

fn label(path: &Path) -> String {
    path.display().to_string()
}

/// Loads an `.obj` file as a whole scene: its triangles and materials, a camera framing
/// its bounding box ([`framing_camera`]) and a 512×512 film; moved to the origin when
/// it lies far from it ([`recentre`]).
pub fn load_obj_scene(path: &Path) -> Result<Scene, SceneError> {
    let mesh = load_obj_mesh(path)?;
    let at = Location::file(label(path));
    if mesh.triangles.is_empty() {
        return Err(SceneError::Empty {
            at,
            message: "the file has no faces".to_string(),
        });
    }
    let mut scene = Scene {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "obj".to_string()),
        camera: framing_camera(&super::Aabb::EMPTY),
        film: FilmSize::default(),
        triangles: mesh.triangles,
        materials: mesh.materials,
        point_lights: Vec::new(),
        settings: RenderSettings::default(),
    };
    let whole = Anchored {
        range: 0..scene.triangles.len(),
        anchor: mesh.origin,
    };
    recentre::place_soup(&scene.name, &mut scene.triangles, &[whole]);
    // The pre-scan has rejected non-finite vertices, so the bounds are finite.
    scene.camera = framing_camera(&scene.bounds());
    validate::validate_scene(&scene, &at)?;
    Ok(scene)
}

/// Loads the triangles and materials of an `.obj` file (and the MTL files it names,
/// relative to its folder).
pub fn load_obj_mesh(path: &Path) -> Result<ObjMesh, SceneError> {
    let text = read_text(path)?;
    let text = with_continuations_joined(&text);
    let file = label(path);
    let scan = prescan_obj(&text, &file)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let (models, tobj_materials) = parse_obj(&text, &file, &dir, &scan)?;

    let mut out = ObjMesh {
        triangles: Vec::new(),
        materials: tobj_materials.iter().map(convert_material).collect(),
        connectivity: scan.connectivity,
        origin: file_origin(&models),
    };
    warn_of_unknown_materials(&scan, &out.materials, &file);
    let mut default_index: Option<u32> = None;
    for model in &models {
        let material = match model.mesh.material_id {
            Some(id) if id < out.materials.len() => id as u32,
            _ => *default_index.get_or_insert_with(|| {
                out.materials.push(Material::named(DEFAULT_MATERIAL_NAME));
                (out.materials.len() - 1) as u32
            }),
        };
        push_model_triangles(model, material, out.origin, &file, &mut out.triangles)?;
    }
    Ok(out)
}

/// The origin of a file's positions ([`ObjMesh::origin`]), from its bounds in f64.
fn file_origin(models: &[tobj::Model]) -> DVec3 {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for model in models {
        for p in model.mesh.positions.chunks_exact(3) {
            let p = DVec3::from_slice(p);
            min = min.min(p);
            max = max.max(p);
        }
    }
    recentre::offset_for(min, max).unwrap_or(DVec3::ZERO)
}

/// Parses pre-scanned OBJ text with `tobj`, with the MTL files it names (relative to
/// `dir`): its models and their materials.
fn parse_obj(
    text: &str,
    file: &str,
    dir: &Path,
    scan: &ObjScan,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>), SceneError> {
    let libraries = libraries(scan, dir);
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
    let loader = |mtl: &Path| -> tobj::MTLLoadResult {
        let name = mtl.to_string_lossy().into_owned();
        let full = dir.join(mtl);
        let at = mtllib_location(&libraries, file, &name);
        let result = read_mtl(&full, at, name).and_then(|mtl_text| {
            tobj::load_mtl_buf(&mut mtl_text.as_bytes()).map_err(|e| SceneError::Syntax {
                at: Location::file(label(&full)),
                message: format!("malformed MTL: {e}"),
            })
        });
        result.map_err(|e| {
            let mut slot = mtl_error.borrow_mut();
            if slot.is_none() {
                *slot = Some(e);
            }
            tobj::LoadError::OpenFileFailed
        })
    };

    // Some LoadOptions fields exist only with tobj features; keep `..Default` for those.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // The pre-scan rejects every input known to make tobj panic; catching an unwind here
    // is a last line of defence so that a loader bug becomes an error, not a crash.
    let text = text_for_tobj(text, scan, &libraries);
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut text.as_bytes(), &options, loader)
    }));
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, materials) = match loaded {
        Err(_) => {
            return Err(SceneError::Syntax {
                at: Location::file(file),
                message: "malformed OBJ (the OBJ parser panicked)".to_string(),
            })
        }
        Ok(Err(e)) => {
            return Err(SceneError::Syntax {
                at: Location::file(file),
                message: format!("malformed OBJ: {e}"),
            })
        }
        Ok(Ok(v)) => v,
    };
    // An Err here can only be "no mtllib at all" style failures already reported above.
    Ok((models, materials.unwrap_or_default()))
}

/// Where `file` names the material library `name`: its `mtllib` line, else the file.
fn mtllib_location(libraries: &[Library], file: &str, name: &str) -> Location {
    let line = libraries.iter().find(|l| l.name == name).map(|l| l.line);
    match line {
        Some(l) => Location::line(file, l),
        None => Location::file(file),
    }
}

/// The text of the MTL file `full` (named at `at` as `name`), pre-scanned.
fn read_mtl(full: &Path, at: Location, name: String) -> Result<String, SceneError> {
    let text = crate::input::read_to_string(full)
        .map(without_byte_order_mark)
        .map_err(|error| reference_error(error, full, at, "material library", name))?;
    prescan_mtl(&text, &label(full)).map(|()| text)
}

/// Warns of each `usemtl` that names none of `materials` (its faces get the default
/// material).
fn warn_of_unknown_materials(scan: &ObjScan, materials: &[Material], file: &str) {
    for (name, line) in &scan.usemtl {
        if !materials.iter().any(|m| &m.name == name) {
            log::warn!(
                "{file}:{line}: usemtl '{name}' names no material of the MTL files; using the default material"
            );
        }
    }
}

/// The triangles of one `tobj` model, all of `material`, appended to `triangles` with
/// their positions measured from `origin`; with normals where every vertex of the model
/// has one.
fn push_model_triangles(
    model: &tobj::Model,
    material: u32,
    origin: DVec3,
    file: &str,
    triangles: &mut Vec<Triangle>,
) -> Result<(), SceneError> {
    let m = &model.mesh;
    let has_normals = !m.normals.is_empty() && m.normals.len() == m.positions.len();
    for (k, tri) in m.indices.chunks_exact(3).enumerate() {
        let from_origin = |i: u32| vec3_at(&m.positions, i).map(|p| (p - origin).as_vec3());
        let p = [
            from_origin(tri[0]),
            from_origin(tri[1]),
            from_origin(tri[2]),
        ];
        let [Some(p0), Some(p1), Some(p2)] = p else {
            return Err(SceneError::Syntax {
                at: Location::file(file),
                message: format!(
                    "object '{}' triangle {k} has an index out of range",
                    model.name
                ),
            });
        };
        let n = if has_normals {
            match (
                vec3_at(&m.normals, tri[0]),
                vec3_at(&m.normals, tri[1]),
                vec3_at(&m.normals, tri[2]),
            ) {
                (Some(a), Some(b), Some(c)) => Some([a, b, c].map(|n| n.as_vec3())),
                _ => None,
            }
        } else {
            None
        };
        triangles.push(Triangle {
            p: [p0, p1, p2],
            n,
            material,
        });
    }
    Ok(())
}

/// Vector `i` of flat xyz `data` (read in f64: `tobj`'s `use_f64`), if it has one.
fn vec3_at(data: &[f64], i: u32) -> Option<DVec3> {
    let i = i as usize * 3;
    data.get(i..i + 3).map(DVec3::from_slice)
}

/// The material of an MTL entry. `tobj` reads its numbers in f64 (`use_f64`, for the
/// positions); they are rounded to f32 as the renderer holds them.
fn convert_material(m: &tobj::Material) -> Material {
    let d = Material::default();
    let v3 = |a: Option<[f64; 3]>, default: Vec3| a.map_or(default, |a| DVec3::from(a).as_vec3());
    let f = |a: Option<f64>, default: f32| a.map_or(default, |a| a as f32);
    let param3 = |key: &str| -> Option<[f64; 3]> {
        let vals: Vec<f64> = m
            .unknown_param
            .get(key)?
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .ok()?;
        vals.get(..3).map(|s| [s[0], s[1], s[2]])
    };
    let dissolve = m.dissolve.or_else(|| {
        m.unknown_param
            .get("Tr")
            .and_then(|t| t.trim().parse::<f64>().ok())
            .map(|tr| 1.0 - tr)
    });
    Material {
        name: m.name.clone(),
        diffuse: v3(m.diffuse, d.diffuse),
        specular: v3(m.specular, d.specular),
        shininess: f(m.shininess, d.shininess),
        ior: f(m.optical_density, d.ior),
        dissolve: f(dissolve, d.dissolve),
        illum: m.illumination_model.map_or(d.illum, u32::from),
        emission: v3(m.emissive.or_else(|| param3("Ke")), d.emission),
        bsdf: None,
    }
}

/// Writes `scene`'s triangles as OBJ text (one `o`/`usemtl` group per run of triangles
/// with the same material, explicit triangles, file order kept) and its materials as MTL
/// text. The OBJ refers to the MTL as `mtl_file_name`. Positions are written with
/// round-trip precision, so loading the pair gives back the same triangles.
pub fn to_obj_mtl(scene: &Scene, mtl_file_name: &str) -> (String, String) {
    let mut obj = String::new();
    let mut mtl = String::new();
    let _ = writeln!(obj, "# {} — written by splitray", scene.name);
    let _ = writeln!(obj, "mtllib {mtl_file_name}");
    let mut vertex_index: HashMap<[u32; 3], usize> = HashMap::new();
    let mut verts = String::new();
    let mut faces = String::new();
    let mut current: Option<u32> = None;
    for t in &scene.triangles {
        if current != Some(t.material) {
            current = Some(t.material);
            let name = &scene.materials[t.material as usize].name;
            let _ = writeln!(faces, "usemtl {name}");
        }
        let mut idx = [0usize; 3];
        for (k, p) in t.p.iter().enumerate() {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let next = vertex_index.len() + 1;
            idx[k] = *vertex_index.entry(key).or_insert_with(|| {
                let _ = writeln!(verts, "v {} {} {}", p.x, p.y, p.z);
                next
            });
        }
        let _ = writeln!(faces, "f {} {} {}", idx[0], idx[1], idx[2]);
    }
    obj.push_str(&verts);
    obj.push_str(&faces);
    for m in &scene.materials {
        let _ = writeln!(mtl, "newmtl {}", m.name);
        let _ = writeln!(mtl, "Kd {} {} {}", m.diffuse.x, m.diffuse.y, m.diffuse.z);
        let _ = writeln!(mtl, "Ks {} {} {}", m.specular.x, m.specular.y, m.specular.z);
        let _ = writeln!(mtl, "Ke {} {} {}", m.emission.x, m.emission.y, m.emission.z);
        let _ = writeln!(mtl, "Ns {}", m.shininess);
        let _ = writeln!(mtl, "Ni {}", m.ior);
        let _ = writeln!(mtl, "d {}", m.dissolve);
        let _ = writeln!(mtl, "illum {}\n", m.illum);
    }
    (obj, mtl)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn material_mapping() {
        let text = "newmtl lamp\nKd 0.1 0.2 0.3\nKs 0.4 0.5 0.6\nNs 10\nNi 1.5\nd 0.5\nillum 7\nKe 17 12 4\n";
        let (mats, _) = tobj::load_mtl_buf(&mut text.as_bytes()).unwrap();
        let m = convert_material(&mats[0]);
        assert_eq!(m.name, "lamp");
        assert_eq!(m.diffuse, Vec3::new(0.1, 0.2, 0.3));
        assert_eq!(m.specular, Vec3::new(0.4, 0.5, 0.6));
        assert_eq!(m.shininess, 10.0);
        assert_eq!(m.ior, 1.5);
        assert_eq!(m.dissolve, 0.5);
        assert_eq!(m.illum, 7);
        assert_eq!(m.emission, Vec3::new(17.0, 12.0, 4.0));
    }
}
