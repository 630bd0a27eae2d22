//! Animated scenes: meshes that move by keyframed transforms, deform through a numbered
//! OBJ sequence or by a procedure (built-in scenes), and a keyframed camera.
//!
//! An [`AnimatedScene`] is a [`Scene`] posed at time 0 plus what moves. Its pose at a
//! time is a pure function of that time ([`AnimatedScene::pose`]): each moving mesh is
//! posed from its rest shape, never from the previous frame, so the frame at time t of
//! a sequence is the scene posed at t, bit for bit. Between two frames,
//! [`AnimatedScene::advance`] poses only the meshes whose pose differs and returns their
//! triangle ranges: what a renderer must upload again.
//!
//! Everything but vertex positions, shading normals and the camera is fixed: the
//! triangle count, the materials, the point lights and the film.

pub mod builtin;
pub mod keyframes;
pub mod sequence;
pub mod toml;

use std::ops::Range;
use std::sync::Arc;

pub use keyframes::{Interpolate, KeyError, Keyframes, Transform};
pub use sequence::{SequencePattern, VertexSequence};

use super::{Camera, Scene, Triangle};

/// A procedure that writes a mesh's triangle positions (and normals) at a time; it must
/// keep the triangle count and materials and depend on nothing but the time.
pub type Procedure = Arc<dyn Fn(f32, &mut [Triangle]) + Send + Sync>;

/// How one mesh moves.
#[derive(Clone)]
pub enum Motion {
    /// The rest shape (or the shape of a vertex sequence) under a fixed transform, then
    /// a keyframed one: `p(t) = keys(t) · (base · shape(t))`.
    Keyed {
        /// The mesh as loaded (positions, normals, materials), before any transform.
        rest: Vec<Triangle>,
        /// The scene file's fixed `transform`, if it gave one.
        base: Option<Transform>,
        keys: Option<Keyframes<Transform>>,
        sequence: Option<VertexSequence>,
    },
    /// Positions written by code (built-in scenes).
    Procedural(Procedure),
}

impl std::fmt::Debug for Motion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Motion::Keyed {
                rest,
                base,
                keys,
                sequence,
            } => f
                .debug_struct("Keyed")
                .field("triangles", &rest.len())
                .field("base", base)
                .field("keys", &keys.as_ref().map(|k| k.times().len()))
                .field("sequence_files", &sequence.as_ref().map(|s| s.len()))
                .finish(),
            Motion::Procedural(_) => f.write_str("Procedural"),
        }
    }
}

/// What decides a mesh's pose at a time: two times with equal states pose it alike.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PoseState {
    Keyed {
        key: Option<Transform>,
        file: Option<(usize, f32)>,
    },
    Procedural(f32),
}

impl Motion {
    fn state(&self, t: f32) -> PoseState {
        match self {
            Motion::Keyed { keys, sequence, .. } => PoseState::Keyed {
                key: keys.as_ref().map(|k| k.sample(t)),
                file: sequence.as_ref().map(|s| s.segment(t)),
            },
            Motion::Procedural(_) => PoseState::Procedural(t),
        }
    }

    /// Writes the mesh's triangles at time `t` into `out` (positions and normals; the
    /// materials are left alone).
    fn pose(&self, t: f32, out: &mut [Triangle]) {
        match self {
            Motion::Procedural(write) => write(t, out),
            Motion::Keyed {
                rest,
                base,
                keys,
                sequence,
            } => {
                let key = keys.as_ref().map(|k| k.sample(t));
                let file = sequence.as_ref().map(|s| (s, s.segment(t)));
                pose_keyed(rest, file, base.as_ref(), key.as_ref(), out);
            }
        }
    }
}

/// `rest` (or the sequence's shape at `file`) under `base`, then `key`, into `out`.
/// Normals are transformed (and normalised) only where a transform applies, so a mesh
/// without one keeps its file's normals as they are. A mirroring transform flips each
/// triangle's vertex order so that its front stays its front.
pub fn pose_keyed(
    rest: &[Triangle],
    file: Option<(&VertexSequence, (usize, f32))>,
    base: Option<&Transform>,
    key: Option<&Transform>,
    out: &mut [Triangle],
) {
    let mirror = base.is_some_and(Transform::mirrors) != key.is_some_and(Transform::mirrors);
    for (j, (r, o)) in rest.iter().zip(out.iter_mut()).enumerate() {
        let (mut p, mut n) = match file {
            Some((s, at)) => s.vertex(at, j),
            None => (r.p, r.n),
        };
        for t in [base, key].into_iter().flatten() {
            p = p.map(|v| t.apply_point(v));
            n = n.map(|n| n.map(|v| t.apply_normal(v)));
        }
        if mirror {
            p.swap(1, 2);
            if let Some(n) = &mut n {
                n.swap(1, 2);
            }
        }
        o.p = p;
        o.n = n;
    }
}

/// One moving mesh of a scene.
#[derive(Clone, Debug)]
pub struct MeshMotion {
    /// The mesh as the scene names it (its path), for messages.
    pub name: String,
    /// Its triangles in the scene's soup.
    pub range: Range<usize>,
    pub motion: Motion,
}

/// What moves in a scene.
#[derive(Clone, Debug, Default)]
pub struct Animation {
    pub meshes: Vec<MeshMotion>,
    pub camera: Option<Keyframes<Camera>>,
}

impl Animation {
    pub fn is_empty(&self) -> bool {
        self.meshes.is_empty() && self.camera.is_none()
    }

    /// Writes the moving meshes and the camera of `scene` (this animation's scene or a
    /// copy of it) at time `t`.
    fn pose_into(&self, t: f32, scene: &mut Scene) {
        for m in &self.meshes {
            m.motion.pose(t, &mut scene.triangles[m.range.clone()]);
        }
        if let Some(keys) = &self.camera {
            scene.camera = keys.sample(t);
        }
    }

    /// The time after which nothing changes any more (the last key, the last file of a
    /// sequence), or `None` when something moves for ever (a procedure).
    pub fn end_time(&self) -> Option<f32> {
        let mut end = self
            .camera
            .as_ref()
            .map_or(0.0, |k| *k.times().last().unwrap());
        for m in &self.meshes {
            match &m.motion {
                Motion::Procedural(_) => return None,
                Motion::Keyed { keys, sequence, .. } => {
                    if let Some(k) = keys {
                        end = end.max(*k.times().last().unwrap());
                    }
                    if let Some(s) = sequence {
                        end = end.max(s.duration() as f32);
                    }
                }
            }
        }
        Some(end)
    }
}

/// A scene posed at time 0, and what moves in it.
#[derive(Clone, Debug)]
pub struct AnimatedScene {
    pub scene: Scene,
    pub animation: Animation,
}

impl From<Scene> for AnimatedScene {
    /// A scene in which nothing moves.
    fn from(scene: Scene) -> Self {
        Self {
            scene,
            animation: Animation::default(),
        }
    }
}

impl AnimatedScene {
    pub fn is_animated(&self) -> bool {
        !self.animation.is_empty()
    }

    /// The camera at time `t`.
    pub fn camera_at(&self, t: f32) -> Camera {
        match &self.animation.camera {
            Some(keys) => keys.sample(t),
            None => self.scene.camera,
        }
    }

    /// The scene posed at time `t`.
    pub fn pose(&self, t: f32) -> Scene {
        let mut scene = self.scene.clone();
        self.animation.pose_into(t, &mut scene);
        scene
    }

    /// Poses the scene itself at time `t`: [`Self::pose`] without the copy.
    pub fn pose_in_place(&mut self, t: f32) {
        self.animation.pose_into(t, &mut self.scene);
    }

    /// Moves `scene`, posed at time `from`, to time `to`: poses again only the meshes
    /// whose pose differs between the two times, and returns their triangle ranges (in
    /// soup order). The result equals [`Self::pose`]`(to)`.
    pub fn advance(&self, scene: &mut Scene, from: f32, to: f32) -> Vec<Range<usize>> {
        let mut changed = Vec::new();
        for m in &self.animation.meshes {
            if m.motion.state(from) != m.motion.state(to) {
                m.motion.pose(to, &mut scene.triangles[m.range.clone()]);
                changed.push(m.range.clone());
            }
        }
        scene.camera = self.camera_at(to);
        changed
    }
}

/// The time of frame `frame` at `fps` frames per second.
pub fn frame_time(frame: u32, fps: f64) -> f32 {
    (frame as f64 / fps) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{FilmSize, Material, RenderSettings};
    use glam::{Quat, Vec3};

    fn unit_triangle() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0)
    }

    /// Three meshes of one triangle each: static, keyed (moves during 0..1 s), and
    /// procedural.
    fn scene() -> AnimatedScene {
        let keys = Keyframes::new(vec![
            (0.0, Transform::IDENTITY),
            (
                1.0,
                Transform {
                    translate: Vec3::new(0.0, 0.0, 5.0),
                    rotate: Quat::from_rotation_z(1.0),
                    scale: Vec3::ONE,
                },
            ),
        ])
        .unwrap();
        let procedure: Procedure = Arc::new(|t, out: &mut [Triangle]| {
            for tri in out {
                tri.p = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0 + t, 0.0)];
            }
        });
        let mut base = Scene {
            name: "test".into(),
            camera: Camera {
                position: Vec3::new(0.0, 0.0, 10.0),
                look_at: Vec3::ZERO,
                up: Vec3::Y,
                fov_y: 40.0,
            },
            film: FilmSize::default(),
            triangles: vec![unit_triangle(); 3],
            materials: vec![Material::default()],
            point_lights: vec![],
            settings: RenderSettings::default(),
        };
        let animation = Animation {
            meshes: vec![
                MeshMotion {
                    name: "keyed".into(),
                    range: 1..2,
                    motion: Motion::Keyed {
                        rest: vec![unit_triangle()],
                        base: None,
                        keys: Some(keys),
                        sequence: None,
                    },
                },
                MeshMotion {
                    name: "procedural".into(),
                    range: 2..3,
                    motion: Motion::Procedural(procedure),
                },
            ],
            camera: None,
        };
        let posed = AnimatedScene {
            scene: base.clone(),
            animation: animation.clone(),
        }
        .pose(0.0);
        base.triangles = posed.triangles;
        AnimatedScene {
            scene: base,
            animation,
        }
    }

    #[test]
    fn advance_poses_what_changed_and_equals_pose() {
        let a = scene();
        let mut s = a.pose(0.0);
        let changed = a.advance(&mut s, 0.0, 0.5);
        assert_eq!(changed, vec![1..2, 2..3]);
        assert_eq!(s, a.pose(0.5));
        assert_eq!(s.triangles[0], unit_triangle());
        // After the last key the keyed mesh holds still; the procedure moves on.
        let changed = a.advance(&mut s, 0.5, 1.5);
        assert_eq!(changed, vec![1..2, 2..3]);
        let changed = a.advance(&mut s, 1.5, 2.5);
        assert_eq!(changed, vec![2..3]);
        assert_eq!(s, a.pose(2.5));
        assert!((s.triangles[1].p[0].z - 5.0).abs() < 1e-6);
        assert_eq!(a.animation.end_time(), None);
    }

    #[test]
    fn mirroring_keys_flip_the_winding() {
        let mirror = Transform {
            scale: Vec3::new(-1.0, 1.0, 1.0),
            ..Transform::IDENTITY
        };
        let rest = [unit_triangle()];
        let mut out = rest;
        pose_keyed(&rest, None, None, Some(&mirror), &mut out);
        // Mirrored in x, with vertices 1 and 2 swapped: the normal still points +z.
        assert_eq!(out[0].p, [Vec3::ZERO, Vec3::Y, Vec3::NEG_X]);
        assert!(out[0].geometric_normal().abs_diff_eq(Vec3::Z, 1e-6));
        // Two mirrors cancel.
        pose_keyed(&rest, None, Some(&mirror), Some(&mirror), &mut out);
        assert_eq!(out[0].p, rest[0].p);
    }

    #[test]
    fn frame_times() {
        assert_eq!(frame_time(0, 24.0), 0.0);
        assert_eq!(frame_time(48, 24.0), 2.0);
        assert_eq!(frame_time(1, 3.0), (1.0f64 / 3.0) as f32);
    }
}
