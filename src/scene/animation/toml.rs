//! The `[[mesh]]` and `[camera]` tables of TOML scene files, with their animation keys
//! (the format is documented in [`crate::scene::toml_file`]).

use std::ops::Range;
use std::path::Path;

use glam::{DVec3, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

use super::sequence::{load_sequence, SequencePattern};
use super::{pose_keyed, Keyframes, MeshMotion, Motion, Transform};
use crate::scene::obj::{check_referenced_file, load_obj_mesh, ObjMesh};
use crate::scene::recentre::to_scene;
use crate::scene::{validate, Camera, Location, SceneError};

/// Maps a byte range of the scene file to its place (file:line:col).
pub type At<'a> = dyn Fn(Range<usize>) -> Location + 'a;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshToml {
    pub path: Spanned<String>,
    pub material: Option<Spanned<String>>,
    transform: Option<Spanned<TransformToml>>,
    #[serde(default)]
    keyframe: Vec<Spanned<KeyframeToml>>,
    sequence: Option<Spanned<SequenceToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransformToml {
    scale: Option<Scale>,
    rotate: Option<RotationToml>,
    /// Read in f64: a still mesh is placed at it exactly ([`MeshToml::load`]).
    translate: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(untagged, expecting = "a number or [sx, sy, sz]")]
enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotationToml {
    axis: Option<[f32; 3]>,
    degrees: Option<f32>,
    /// [x, y, z, w]
    quaternion: Option<[f32; 4]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyframeToml {
    time: f32,
    scale: Option<Scale>,
    rotate: Option<RotationToml>,
    translate: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SequenceToml {
    first: u32,
    last: u32,
    fps: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
// The fields carry the spans, not the table: a `[camera]` made only by its
// `[[camera.keyframe]]` headers is an implicit table, and toml has no span for it
// (a `Spanned` table then fails to deserialize).
pub struct CameraToml {
    /// Positions are read in f64 and moved with the scene before they are rounded
    /// ([`to_scene`]).
    position: Option<Spanned<[f64; 3]>>,
    look_at: Option<Spanned<[f64; 3]>>,
    up: Option<Spanned<[f32; 3]>>,
    fov_y: Option<Spanned<f32>>,
    #[serde(default)]
    keyframe: Vec<Spanned<CameraKeyToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraKeyToml {
    time: f32,
    position: Option<[f64; 3]>,
    look_at: Option<[f64; 3]>,
    up: Option<[f32; 3]>,
    fov_y: Option<f32>,
}

/// A `[[mesh]]` entry loaded: its triangles posed at time 0 and its materials (indices
/// local to the mesh), and how it moves (`range` still to be set by the caller).
///
/// Its anchor is its file's origin under its transform plus the transform's translation,
/// in f64 ([`crate::scene::recentre`]). A still mesh's positions (rotated and scaled) are
/// relative to it: it is `mesh.origin`. A moving mesh's triangles are posed with its
/// anchor rounded to f32, `mesh.origin` is zero, and the anchor is `motion_anchor`.
pub struct LoadedMesh {
    pub mesh: ObjMesh,
    pub motion: Option<MeshMotion>,
    /// A moving mesh's anchor (zero for a still mesh).
    pub motion_anchor: DVec3,
}

/// The transform of `scale`, `rotate` and `translate` (each the identity where left
/// out); refuses a part that is not finite, a zero scale, and a zero rotation axis or
/// quaternion.
fn transform_of(
    scale: Option<&Scale>,
    rotate: Option<&RotationToml>,
    translate: Option<[f64; 3]>,
) -> Result<Transform, String> {
    let scale = match scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(*s),
        Some(Scale::PerAxis(s)) => Vec3::from(*s),
    };
    let translate = translate.map_or(Vec3::ZERO, |t| DVec3::from(t).as_vec3());
    if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() || !translate.is_finite() {
        return Err(format!(
            "scale {scale} must be finite and non-zero, translate {translate} finite"
        ));
    }
    let rotate = match rotate {
        None => Quat::IDENTITY,
        Some(r) => rotation_of(r)?,
    };
    Ok(Transform {
        translate,
        rotate,
        scale,
    })
}

fn rotation_of(r: &RotationToml) -> Result<Quat, String> {
    match (r.axis, r.degrees, r.quaternion) {
        (Some(axis), Some(degrees), None) => {
            let axis = Vec3::from(axis);
            if !axis.is_finite() || axis.length_squared() <= f32::MIN_POSITIVE {
                return Err(format!("rotate: axis {axis} must be finite and non-zero"));
            }
            if !degrees.is_finite() {
                return Err(format!("rotate: degrees {degrees} is not finite"));
            }
            Ok(Quat::from_axis_angle(
                axis.normalize(),
                degrees.to_radians(),
            ))
        }
        (None, None, Some(q)) => {
            let q = Quat::from_array(q);
            if !q.is_finite() || q.length_squared() <= f32::MIN_POSITIVE {
                return Err(format!(
                    "rotate: quaternion {q} must be finite and non-zero"
                ));
            }
            Ok(q.normalize())
        }
        _ => Err(
            "rotate needs either axis = [x, y, z] and degrees = a, or quaternion = [x, y, z, w]"
                .to_string(),
        ),
    }
}

/// A still mesh under its `base` transform: its positions rotated and scaled (in f32, as
/// [`pose_keyed`] does, so that near the origin they are the posed ones, bit for bit,
/// once the translation is added), measured from `anchor`.
fn placed_still(mesh: ObjMesh, base: Option<&Transform>, anchor: DVec3) -> ObjMesh {
    let Some(base) = base else {
        return mesh;
    };
    let linear = Transform {
        translate: Vec3::ZERO,
        ..*base
    };
    let mut triangles = mesh.triangles.clone();
    pose_keyed(&mesh.triangles, None, Some(&linear), None, &mut triangles);
    ObjMesh {
        triangles,
        origin: anchor,
        ..mesh
    }
}

impl MeshToml {
    /// Loads the mesh (one OBJ, or every file of a sequence) and its motion; mesh paths
    /// are relative to `dir`.
    pub fn load(&self, dir: &Path, at: &At) -> Result<LoadedMesh, SceneError> {
        let rel = self.path.get_ref();
        let path_at = at(self.path.span());
        let invalid = |span: Range<usize>, message: String| SceneError::Invalid {
            at: at(span),
            message: format!("mesh '{rel}': {message}"),
        };
        let is_obj = Path::new(rel)
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if !is_obj {
            return Err(SceneError::Invalid {
                at: path_at,
                message: format!(
                    "mesh '{rel}' is not an .obj file (only Wavefront OBJ is supported)"
                ),
            });
        }
        let pattern = SequencePattern::parse(rel).map_err(|m| invalid(self.path.span(), m))?;
        let (mesh, sequence) = match (&pattern, &self.sequence) {
            (Some(pattern), Some(s)) => {
                let seq = s.get_ref();
                let (mesh, sequence) = load_sequence(
                    dir,
                    pattern,
                    rel,
                    (seq.first, seq.last, seq.fps),
                    &at(s.span()),
                )?;
                (mesh, Some(sequence))
            }
            (Some(_), None) => {
                return Err(invalid(
                    self.path.span(),
                    "a numbered path needs sequence = { first = N, last = M, fps = F }".to_string(),
                ))
            }
            (None, Some(s)) => {
                return Err(invalid(
                    s.span(),
                    "'sequence' needs a numbered path, e.g. path = \"wave_{:04}.obj\"".to_string(),
                ))
            }
            (None, None) => {
                let full = dir.join(rel);
                check_referenced_file(&full, &path_at, "mesh", rel)?;
                (load_obj_mesh(&full)?, None)
            }
        };
        let base = match &self.transform {
            None => None,
            Some(t) => {
                let tr = t.get_ref();
                Some(
                    transform_of(tr.scale.as_ref(), tr.rotate.as_ref(), tr.translate)
                        .map_err(|m| invalid(t.span(), format!("transform: {m}")))?,
                )
            }
        };
        let keys = self.keys(&invalid)?;
        let anchor = self.anchor(mesh.origin, base.as_ref());
        if keys.is_none() && sequence.is_none() {
            return Ok(LoadedMesh {
                mesh: placed_still(mesh, base.as_ref(), anchor),
                motion: None,
                motion_anchor: DVec3::ZERO,
            });
        }

        // The base takes the shape's origin to the anchor (rounded here; the scene's
        // offset is subtracted from it in f64 once it is known: `recentre::place_motions`).
        let base = match base {
            None if anchor == DVec3::ZERO => None,
            base => Some(Transform {
                translate: anchor.as_vec3(),
                ..base.unwrap_or(Transform::IDENTITY)
            }),
        };
        let rest = mesh.triangles;
        let mut triangles = rest.clone();
        let key0 = keys.as_ref().map(|k| k.sample(0.0));
        let file0 = sequence.as_ref().map(|s| (s, s.segment(0.0)));
        pose_keyed(&rest, file0, base.as_ref(), key0.as_ref(), &mut triangles);
        Ok(LoadedMesh {
            mesh: ObjMesh {
                triangles,
                origin: DVec3::ZERO,
                ..mesh
            },
            motion_anchor: anchor,
            motion: Some(MeshMotion {
                name: rel.clone(),
                range: 0..0,
                motion: Motion::Keyed {
                    rest,
                    base,
                    keys,
                    sequence,
                },
            }),
        })
    }

    /// Where `base` (this mesh's transform) takes a file's `origin`: the rotation and
    /// scale applied in f64, plus the translation as read, in f64.
    fn anchor(&self, origin: DVec3, base: Option<&Transform>) -> DVec3 {
        let Some(base) = base else {
            return origin;
        };
        let mut anchor = origin * base.scale.as_dvec3();
        if base.rotate != Quat::IDENTITY {
            anchor = base.rotate.as_dquat() * anchor;
        }
        let translate = self
            .transform
            .as_ref()
            .and_then(|t| t.get_ref().translate)
            .map_or(DVec3::ZERO, DVec3::from);
        anchor + translate
    }

    /// The `[[mesh.keyframe]]` track: times increasing, and every key's scale with the
    /// same signs as the first key's (else the mesh would pass through zero size and its
    /// winding would flip mid-animation).
    fn keys(
        &self,
        invalid: &dyn Fn(Range<usize>, String) -> SceneError,
    ) -> Result<Option<Keyframes<Transform>>, SceneError> {
        if self.keyframe.is_empty() {
            return Ok(None);
        }
        let mut keys = Vec::with_capacity(self.keyframe.len());
        for (i, k) in self.keyframe.iter().enumerate() {
            let key = k.get_ref();
            let t = transform_of(key.scale.as_ref(), key.rotate.as_ref(), key.translate)
                .map_err(|m| invalid(k.span(), format!("keyframe {i}: {m}")))?;
            if let Some((_, first)) = keys.first() {
                let first: &Transform = first;
                if t.scale.signum() != first.scale.signum() {
                    return Err(invalid(
                        k.span(),
                        format!(
                            "keyframe {i}: scale {} has other signs than keyframe 0's {} \
                             (a scale that changes sign passes through zero size)",
                            t.scale, first.scale
                        ),
                    ));
                }
            }
            keys.push((key.time, t));
        }
        Keyframes::new(keys).map(Some).map_err(|e| {
            let span = match e {
                super::KeyError::NonFiniteTime { index, .. }
                | super::KeyError::NotIncreasing { index, .. } => self.keyframe[index].span(),
                super::KeyError::Empty => self.path.span(),
            };
            invalid(span, format!("[[mesh.keyframe]]: {e}"))
        })
    }
}

impl CameraToml {
    /// The camera at time 0 and its keyframe track, if it has keys. `[camera]`'s own
    /// fields are the defaults of every key; without keys it must give position, look_at
    /// and fov_y (up defaults to +y). Every key's camera is validated. `[camera]`'s own
    /// errors are placed at its first field, or at `file` where it has none.
    /// Positions are moved by −`offset`, the scene's ([`crate::scene::recentre`]).
    pub fn resolve(
        &self,
        at: &At,
        file: &Location,
        offset: Option<DVec3>,
    ) -> Result<(Camera, Option<Keyframes<Camera>>), SceneError> {
        let first_field = [
            self.position.as_ref().map(Spanned::span),
            self.look_at.as_ref().map(Spanned::span),
            self.up.as_ref().map(Spanned::span),
            self.fov_y.as_ref().map(Spanned::span),
        ]
        .into_iter()
        .flatten()
        .min_by_key(|span| span.start);
        let camera_at = first_field.map_or_else(|| file.clone(), at);
        let position = self.position.as_ref().map(|v| *v.get_ref());
        let look_at = self.look_at.as_ref().map(|v| *v.get_ref());
        let up = self.up.as_ref().map(|v| *v.get_ref());
        let fov_y = self.fov_y.as_ref().map(|v| *v.get_ref());
        let err = |at: Location, message: String| SceneError::Camera { at, message };
        let complete = |position: Option<[f64; 3]>,
                        look_at: Option<[f64; 3]>,
                        up: Option<[f32; 3]>,
                        fov_y: Option<f32>,
                        at: &Location,
                        what: &str|
         -> Result<Camera, SceneError> {
            let missing = |key: &str| {
                err(
                    at.clone(),
                    format!("{what} needs '{key}' (in the key or in [camera])"),
                )
            };
            let camera = Camera {
                position: to_scene(position.ok_or_else(|| missing("position"))?, offset),
                look_at: to_scene(look_at.ok_or_else(|| missing("look_at"))?, offset),
                up: up.map_or(Vec3::Y, Vec3::from),
                fov_y: fov_y.ok_or_else(|| missing("fov_y"))?,
            };
            validate::validate_camera(&camera, at).map_err(|e| match e {
                SceneError::Camera { at, message } if what != "[camera]" => SceneError::Camera {
                    at,
                    message: format!("{what}: {message}"),
                },
                e => e,
            })?;
            Ok(camera)
        };
        if self.keyframe.is_empty() {
            let camera = complete(position, look_at, up, fov_y, &camera_at, "[camera]")?;
            return Ok((camera, None));
        }
        let mut keys = Vec::with_capacity(self.keyframe.len());
        for (i, k) in self.keyframe.iter().enumerate() {
            let key = k.get_ref();
            let camera = complete(
                key.position.or(position),
                key.look_at.or(look_at),
                key.up.or(up),
                key.fov_y.or(fov_y),
                &at(k.span()),
                &format!("camera keyframe {i}"),
            )?;
            keys.push((key.time, camera));
        }
        let track = Keyframes::new(keys).map_err(|e| {
            let span = match e {
                super::KeyError::NonFiniteTime { index, .. }
                | super::KeyError::NotIncreasing { index, .. } => self.keyframe[index].span(),
                super::KeyError::Empty => 0..0,
            };
            SceneError::Invalid {
                at: at(span),
                message: format!("[[camera.keyframe]]: {e}"),
            }
        })?;
        Ok((track.sample(0.0), Some(track)))
    }
}
