//! Scenes far from the origin, moved to it when they are loaded.
//!
//! Positions are f32, whose steps grow with the distance from the origin: at 10⁵ one step
//! is 0.008, at 5·10⁶ (a UTM northing) 0.5. There a room of a few units loses its shape,
//! and the ray offset ([`Aabb::ray_epsilon`], 32 steps of the largest coordinate rays
//! meet) is larger than the room: light leaks, shadows detach, and the integrators
//! disagree. Light transport does not depend on where the origin is, so a scene whose
//! centre lies far from the origin compared with its size is translated by that centre:
//! every position — the triangles, the camera, the point lights and the keys of what
//! moves — less the same offset. Its image is then the one the scene renders near the
//! origin, and the offset is logged.
//!
//! **Nothing is rounded to f32 before the offset is taken off.** The loaders read in f64
//! what a far scene needs exactly:
//! - an OBJ file far from the origin keeps its positions relative to its own centre
//!   ([`ObjMesh::origin`](crate::scene::obj::ObjMesh::origin)), and the files of an OBJ
//!   sequence relative to its first file's;
//! - a mesh is placed at an f64 anchor: its transform's translation, plus its file's
//!   origin transformed, while its f32 positions carry only the rotation and scale. A
//!   still mesh's triangles are placed there ([`Anchored`]); a moving mesh's base
//!   transform translates by it ([`MovingAnchor`]);
//! - the camera's and the point lights' positions are read in f64 and moved in f64
//!   ([`to_scene`]).
//!
//! The offset is chosen from the f64 bounds ([`offset_of`]), and each position becomes
//! f32 once, after the offset is subtracted. A moving mesh is posed in f32 at every frame
//! from its small positions and a base translation that is its anchor less the offset
//! ([`place_motions`]); only keys that turn or scale it, which act about the origin, see
//! its far translation. Scenes near the origin (every built-in one) are left as they
//! are, bit for bit, and so are scenes moved by code ([`Motion::Procedural`], which
//! writes world positions itself).

use std::ops::Range;

use glam::{DVec3, Quat, Vec3};

use super::animation::{AnimatedScene, Keyframes, Motion, Transform};
use super::{Aabb, Triangle};

/// How many bounding radii the centre must lie from the origin (along some axis) for
/// the scene to be moved: there the offset rays need is at least this many times what
/// the scene needs at the origin.
pub const FAR: f64 = 4.0;

/// The offset a scene (or a file) whose positions span `min..=max` is moved by, when
/// it is far from the origin: the centre of its bounds.
pub fn offset_for(min: DVec3, max: DVec3) -> Option<DVec3> {
    if !min.is_finite() || !max.is_finite() || min.cmpgt(max).any() {
        return None;
    }
    let centre = (min + max) * 0.5;
    let radius = (max - min).length() * 0.5;
    (centre.abs().max_element() > FAR * radius).then_some(centre)
}

/// Triangles `range` of a scene's soup, whose positions are relative to `anchor`.
#[derive(Clone, Debug, PartialEq)]
pub struct Anchored {
    pub range: Range<usize>,
    pub anchor: DVec3,
}

/// The soup of `n` triangles in runs: each of `anchored`'s ranges (in order, disjoint) at
/// its anchor, the triangles between them at the origin.
fn runs(n: usize, anchored: &[Anchored]) -> Vec<(Range<usize>, DVec3)> {
    let mut out = Vec::with_capacity(2 * anchored.len() + 1);
    let mut next = 0;
    for a in anchored {
        debug_assert!(next <= a.range.start && a.range.end <= n, "{a:?}");
        if next < a.range.start {
            out.push((next..a.range.start, DVec3::ZERO));
        }
        out.push((a.range.clone(), a.anchor));
        next = a.range.end;
    }
    if next < n {
        out.push((next..n, DVec3::ZERO));
    }
    out
}

/// The offset ([`offset_for`]) of the soup `triangles` whose `anchored` ranges lie at
/// their anchors, from its bounds in f64.
pub fn offset_of(triangles: &[Triangle], anchored: &[Anchored]) -> Option<DVec3> {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for (range, anchor) in runs(triangles.len(), anchored) {
        let mut b = Aabb::EMPTY;
        for t in &triangles[range] {
            for p in t.p {
                b.grow(p);
            }
        }
        if !b.is_empty() {
            min = min.min(anchor + b.min.as_dvec3());
            max = max.max(anchor + b.max.as_dvec3());
        }
    }
    offset_for(min, max)
}

/// Writes every triangle of the soup at its anchor less `offset`: the difference is
/// taken in f64 and added, as f32, to the small f32 positions. Runs whose anchor is the
/// offset (both zero, for a scene near the origin) keep their positions bit for bit.
pub fn place(triangles: &mut [Triangle], anchored: &[Anchored], offset: Option<DVec3>) {
    let offset = offset.unwrap_or(DVec3::ZERO);
    for (range, anchor) in runs(triangles.len(), anchored) {
        let shift = (anchor - offset).as_vec3();
        if shift == Vec3::ZERO {
            continue;
        }
        for t in &mut triangles[range] {
            t.p = t.p.map(|p| p + shift);
        }
    }
}

/// Chooses the offset of a loaded soup ([`offset_of`]), places its triangles there
/// ([`place`]) and logs the move; returns the offset, for the rest of the scene.
pub fn place_soup(
    scene_name: &str,
    triangles: &mut [Triangle],
    anchored: &[Anchored],
) -> Option<DVec3> {
    let offset = offset_of(triangles, anchored);
    place(triangles, anchored, offset);
    if let Some(offset) = offset {
        log::info!(
            "scene '{scene_name}' lies far from the origin: moved by {} (positions are \
             relative to its centre)",
            -offset
        );
    }
    offset
}

/// A position read in f64, less the scene's `offset`, as the scene holds it.
pub fn to_scene(position: [f64; 3], offset: Option<DVec3>) -> Vec3 {
    (DVec3::from(position) - offset.unwrap_or(DVec3::ZERO)).as_vec3()
}

/// A moving mesh of a loaded scene (its index among the animation's meshes) and the f64
/// translation its base transform stands for: its file's origin under the transform,
/// plus the transform's translation as read ([`place_motions`] rounds it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovingAnchor {
    pub mesh: usize,
    pub anchor: DVec3,
}

/// Gives each keyed mesh of `animated` its base translation, its anchor less `offset`
/// (the scene's), and, where that moved a mesh, poses what moves at time 0 again, so
/// that the scene stays its own pose at time 0, bit for bit. The soup's still triangles, the camera (its keys too)
/// and the point lights are the loader's to move.
pub fn place_motions(animated: &mut AnimatedScene, moving: &[MovingAnchor], offset: Option<DVec3>) {
    let mut moved = false;
    for m in moving {
        match &mut animated.animation.meshes[m.mesh].motion {
            Motion::Keyed { base, keys, .. } => {
                moved |= place_keyed(base, keys.as_mut(), m.anchor, offset)
            }
            // Only built-in scenes move by code, and they are not loaded.
            Motion::Procedural(_) => {}
        }
    }
    // Near the origin the loader's pose at time 0 already is the scene's.
    if moved {
        animated.pose_in_place(0.0);
    }
}

/// Places a keyed mesh, p(t) = key(t) · (base · shape), whose shape is measured from a
/// point that `base` takes to `anchor`, in a scene moved by −`offset`. Where the keys only
/// translate (or there are none), the base's translation is the anchor less the offset,
/// subtracted in f64: the far translation and the offset cancel before anything is
/// rounded, and the keys' small motion is added to small numbers. Keys that turn or
/// scale act about the origin, so the base keeps the anchor (rounded to f32) and the keys
/// translate less, every key alike (they interpolate their translations linearly).
/// Returns whether that changed the motion.
fn place_keyed(
    base: &mut Option<Transform>,
    keys: Option<&mut Keyframes<Transform>>,
    anchor: DVec3,
    offset: Option<DVec3>,
) -> bool {
    let offset = offset.unwrap_or(DVec3::ZERO);
    let only_translate = |k: &Transform| k.rotate == Quat::IDENTITY && k.scale == Vec3::ONE;
    let mut keys_moved = false;
    let translate = match keys {
        Some(keys) if !keys.values().iter().all(only_translate) => {
            if offset != DVec3::ZERO {
                let offset = offset.as_vec3();
                keys.map_values(|k| k.translate -= offset);
                keys_moved = true;
            }
            anchor.as_vec3()
        }
        _ => (anchor - offset).as_vec3(),
    };
    let base_moved = match base {
        Some(base) => std::mem::replace(&mut base.translate, translate) != translate,
        None if translate == Vec3::ZERO => false,
        None => {
            *base = Some(Transform {
                translate,
                ..Transform::IDENTITY
            });
            true
        }
    };
    keys_moved || base_moved
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_scenes_far_from_the_origin_for_their_size_move() {
        assert_eq!(offset_for(DVec3::ZERO, DVec3::splat(556.0)), None);
        let unit_at = |c: DVec3| offset_for(c - DVec3::ONE, c + DVec3::ONE);
        // Radius √3: far beyond 4√3 ≈ 6.93 along some axis.
        assert_eq!(unit_at(DVec3::new(6.0, 0.0, 0.0)), None);
        let c = DVec3::new(0.0, -7.0, 0.0);
        assert_eq!(unit_at(c), Some(c));
        let c = DVec3::new(500_000.125, 5_000_000.25, 0.0);
        assert_eq!(unit_at(c), Some(c));
        assert_eq!(offset_for(DVec3::INFINITY, DVec3::NEG_INFINITY), None);
        let inf = DVec3::new(f64::INFINITY, 1.0, 1.0);
        assert_eq!(offset_for(DVec3::ZERO, inf), None);
    }

    fn triangle(p: [f32; 3]) -> Triangle {
        Triangle {
            p: [
                p.into(),
                (Vec3::from(p) + Vec3::X),
                (Vec3::from(p) + Vec3::Y),
            ],
            n: None,
            material: 0,
        }
    }

    #[test]
    fn anchored_runs_are_placed_from_the_f64_difference() {
        // Triangle 1 is relative to an anchor at 5·10⁶ + 0.1, where f32 steps are 0.5:
        // placed, it lies 0.1 (to f32 precision) from triangle 0, which is relative to
        // an anchor at 5·10⁶ exactly; triangle 2 is at the origin, unanchored.
        let mut soup = vec![triangle([0.0; 3]), triangle([0.0; 3]), triangle([-0.0; 3])];
        let far = DVec3::new(0.0, 5e6, 0.0);
        let anchored = [
            Anchored {
                range: 0..1,
                anchor: far,
            },
            Anchored {
                range: 1..2,
                anchor: far + DVec3::new(0.0, 0.1, 0.0),
            },
        ];
        let runs = runs(soup.len(), &anchored);
        assert_eq!(runs.len(), 3);
        assert_eq!(runs[2], (2..3, DVec3::ZERO));
        // Not far for its size: the soup spans the origin to 5·10⁶.
        assert_eq!(offset_of(&soup, &anchored), None);
        let offset = Some(far);
        place(&mut soup, &anchored, offset);
        assert_eq!(soup[0].p[0], Vec3::ZERO);
        assert_eq!(soup[1].p[0], Vec3::new(0.0, 0.1, 0.0));
        assert_eq!(soup[2].p[0], Vec3::new(0.0, -5e6, 0.0));
        // A run at the offset keeps its bits, the sign of a zero too.
        let mut near = vec![triangle([-0.0; 3])];
        place(&mut near, &[], None);
        assert!(near[0].p[0].x.is_sign_negative());
    }

    #[test]
    fn positions_read_in_f64_are_moved_before_rounding() {
        let offset = Some(DVec3::new(500_000.0, 5_000_000.0, 0.0));
        let p = to_scene([500_000.123, 5_000_001.5, 2.0], offset);
        assert!(
            (p - Vec3::new(0.123, 1.5, 2.0)).abs().max_element() < 1e-6,
            "{p}"
        );
        assert_eq!(to_scene([1.0, -0.0, 3.5], None), Vec3::new(1.0, -0.0, 3.5));
    }
}
