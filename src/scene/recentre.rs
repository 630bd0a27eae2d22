//! Scenes far from the origin, moved to it when they are loaded.
//!
//! Positions are f32, whose steps grow with the distance from the origin: at 10⁵ one step
//! is 0.008, and the ray offset ([`Aabb::ray_epsilon`], 32 steps of the largest
//! coordinate rays meet) is 0.4. A room of a few units placed there renders with rays
//! that start past the walls they leave: light leaks, shadows detach, and the
//! integrators disagree by several percent. Light transport does not depend on where the
//! origin is, so a scene whose centre lies far from the origin compared with its size is
//! translated by that centre: every position — the triangles, the camera, the point
//! lights and the keys of what moves — less the same offset. Its image is then the one
//! the scene renders near the origin, and the offset is logged.
//!
//! What the files gave in f32 keeps their rounding (a vertex at 10⁵ is already 0.004 off
//! its exact place); only the ray offset and the arithmetic of rendering gain. Scenes
//! near the origin (every built-in one) are left as they are, bit for bit, and so are
//! scenes moved by code ([`Motion::Procedural`], which writes world positions itself).

use glam::{Quat, Vec3};

use super::animation::{AnimatedScene, Keyframes, Motion, Transform};
use super::Aabb;

/// How many bounding radii the centre must lie from the origin (along some axis) for
/// the scene to be moved: there the offset rays need is at least this many times what
/// the scene needs at the origin.
pub const FAR: f32 = 4.0;

/// The offset a scene with time-0 `bounds` is moved by, when it is far from the origin.
pub fn offset_for(bounds: &Aabb) -> Option<Vec3> {
    if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
        return None;
    }
    let centre = bounds.center();
    let far = centre.abs().max_element() > FAR * bounds.radius();
    far.then_some(centre)
}

/// Moves `animated` by its offset ([`offset_for`] its time-0 bounds) when it is far
/// from the origin; returns the offset subtracted from every position.
pub fn recentre(animated: &mut AnimatedScene) -> Option<Vec3> {
    let offset = offset_for(&animated.scene.bounds())?;
    let moved_by_code = animated
        .animation
        .meshes
        .iter()
        .any(|m| matches!(m.motion, Motion::Procedural(_)));
    if moved_by_code {
        return None;
    }
    let scene = &mut animated.scene;
    for t in &mut scene.triangles {
        t.p = t.p.map(|p| p - offset);
    }
    for light in &mut scene.point_lights {
        light.position -= offset;
    }
    scene.camera.position -= offset;
    scene.camera.look_at -= offset;
    for mesh in &mut animated.animation.meshes {
        if let Motion::Keyed { base, keys, .. } = &mut mesh.motion {
            shift_keyed(base, keys.as_mut(), offset);
        }
    }
    if let Some(keys) = &mut animated.animation.camera {
        keys.map_values(|c| {
            c.position -= offset;
            c.look_at -= offset;
        });
    }
    // The moving meshes as their motions now pose them, so that the scene stays its own
    // pose at time 0, bit for bit.
    animated.pose_in_place(0.0);
    log::info!(
        "scene '{}' lies far from the origin: moved by {} (positions are relative to its \
         centre)",
        animated.scene.name,
        -offset
    );
    Some(offset)
}

/// Moves a keyed mesh, p(t) = key(t) · (base · shape), by −`offset`. Where the keys only
/// translate, the fixed base translates less: the far translation and the offset cancel
/// before the keys' small motion is added, so that the motion keeps its precision. Keys
/// that turn or scale act about the origin, so they themselves translate less (every
/// key alike: the keys interpolate their translations linearly); without keys, the base
/// does, or a new one.
fn shift_keyed(
    base: &mut Option<Transform>,
    keys: Option<&mut Keyframes<Transform>>,
    offset: Vec3,
) {
    let only_translate = |k: &Transform| k.rotate == Quat::IDENTITY && k.scale == Vec3::ONE;
    match (keys, base) {
        (Some(keys), Some(base)) if keys.values().iter().all(only_translate) => {
            base.translate -= offset
        }
        (Some(keys), _) => keys.map_values(|k| k.translate -= offset),
        (None, Some(base)) => base.translate -= offset,
        (None, base @ None) => {
            *base = Some(Transform {
                translate: -offset,
                ..Transform::IDENTITY
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn aabb(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    #[test]
    fn only_scenes_far_from_the_origin_for_their_size_move() {
        let near = aabb(Vec3::ZERO, Vec3::splat(556.0));
        assert_eq!(offset_for(&near), None);
        let unit_at = |c: Vec3| aabb(c - Vec3::ONE, c + Vec3::ONE);
        // Radius √3: far beyond 4√3 ≈ 6.93 along some axis.
        assert_eq!(offset_for(&unit_at(Vec3::new(6.0, 0.0, 0.0))), None);
        let c = Vec3::new(0.0, -7.0, 0.0);
        assert_eq!(offset_for(&unit_at(c)), Some(c));
        let c = Vec3::splat(1e5);
        assert_eq!(offset_for(&unit_at(c)), Some(c));
        assert_eq!(offset_for(&Aabb::EMPTY), None);
        let inf = aabb(Vec3::ZERO, Vec3::new(f32::INFINITY, 1.0, 1.0));
        assert_eq!(offset_for(&inf), None);
    }
}
