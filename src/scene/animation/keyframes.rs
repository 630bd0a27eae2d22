//! Keyframe tracks and the values they interpolate: rigid transforms (translation and
//! scale interpolated linearly, rotation by spherical linear interpolation) and the
//! camera (every field linearly).
//!
//! A track is sampled with its value held before the first key and after the last
//! (clamping); a track of one key is constant. At a key's own time, and at the clamped
//! ends, the sample is that key's value bit for bit, so a pose at a key time does not
//! depend on the interpolation's rounding.

use glam::{Quat, Vec3};

use crate::scene::Camera;

/// Values a track can interpolate between two keys.
pub trait Interpolate: Clone {
    /// The value a fraction `w` ∈ (0, 1) of the way from `self` to `other`.
    fn interpolate(&self, other: &Self, w: f32) -> Self;
}

/// Why a list of keys is not a track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KeyError {
    /// No keys at all.
    Empty,
    /// Key `index` has a NaN or infinite time.
    NonFiniteTime { index: usize, time: f32 },
    /// Key `index` does not come after the key before it.
    NotIncreasing {
        index: usize,
        time: f32,
        previous: f32,
    },
}

impl std::fmt::Display for KeyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KeyError::Empty => write!(f, "a track needs at least one key"),
            KeyError::NonFiniteTime { index, time } => {
                write!(f, "key {index} has time {time}, which is not finite")
            }
            KeyError::NotIncreasing {
                index,
                time,
                previous,
            } => write!(
                f,
                "key {index} at time {time} does not come after key {} at time {previous} \
                 (key times must increase)",
                index - 1
            ),
        }
    }
}

/// Keys `(time, value)` at strictly increasing times (seconds).
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframes<T> {
    times: Vec<f32>,
    values: Vec<T>,
}

impl<T: Interpolate> Keyframes<T> {
    /// A track over `keys`, whose times must be finite and strictly increasing.
    pub fn new(keys: Vec<(f32, T)>) -> Result<Self, KeyError> {
        if keys.is_empty() {
            return Err(KeyError::Empty);
        }
        for (index, (time, _)) in keys.iter().enumerate() {
            if !time.is_finite() {
                return Err(KeyError::NonFiniteTime { index, time: *time });
            }
            if index > 0 && *time <= keys[index - 1].0 {
                return Err(KeyError::NotIncreasing {
                    index,
                    time: *time,
                    previous: keys[index - 1].0,
                });
            }
        }
        let (times, values) = keys.into_iter().unzip();
        Ok(Self { times, values })
    }

    /// Where `t` falls: the key before it and the fraction of the way to the next key
    /// (0 at a key's own time and outside the keys' span).
    pub fn segment(&self, t: f32) -> (usize, f32) {
        let last = self.times.len() - 1;
        if t.is_nan() || t <= self.times[0] {
            return (0, 0.0);
        }
        if t >= self.times[last] {
            return (last, 0.0);
        }
        // The first key after t; 1 ..= last because times[0] < t < times[last].
        let next = self.times.partition_point(|&k| k <= t);
        let (a, b) = (self.times[next - 1], self.times[next]);
        (next - 1, (t - a) / (b - a))
    }

    /// The value at time `t` (held before the first key and after the last).
    pub fn sample(&self, t: f32) -> T {
        let (i, w) = self.segment(t);
        if w <= 0.0 {
            return self.values[i].clone();
        }
        self.values[i].interpolate(&self.values[i + 1], w)
    }

    pub fn times(&self) -> &[f32] {
        &self.times
    }

    pub fn values(&self) -> &[T] {
        &self.values
    }

    /// Changes every key's value by `f`; the times stay.
    pub fn map_values(&mut self, f: impl FnMut(&mut T)) {
        self.values.iter_mut().for_each(f);
    }
}

/// A rigid transform with scale: `p' = translate + rotate · (scale ⊙ p)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub translate: Vec3,
    /// A unit quaternion.
    pub rotate: Quat,
    /// Per axis; no component is zero.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    pub const IDENTITY: Transform = Transform {
        translate: Vec3::ZERO,
        rotate: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    pub fn apply_point(&self, p: Vec3) -> Vec3 {
        let scaled = p * self.scale;
        // Without a rotation this is the scale-and-translate of scene files that have
        // no `rotate`, to the bit.
        if self.rotate == Quat::IDENTITY {
            scaled + self.translate
        } else {
            self.rotate * scaled + self.translate
        }
    }

    /// A normal transformed by the inverse transpose (rotation and 1 / scale), unit
    /// length (or zero).
    pub fn apply_normal(&self, n: Vec3) -> Vec3 {
        let scaled = n / self.scale;
        if self.rotate == Quat::IDENTITY {
            scaled.normalize_or_zero()
        } else {
            (self.rotate * scaled).normalize_or_zero()
        }
    }

    /// Whether the transform mirrors (an odd number of negative scale components): the
    /// vertex order of a triangle must then flip to keep its front side.
    pub fn mirrors(&self) -> bool {
        self.scale.x * self.scale.y * self.scale.z < 0.0
    }
}

impl Interpolate for Transform {
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        Self {
            translate: self.translate.lerp(other.translate, w),
            // glam's slerp takes the shorter of the two arcs between the rotations.
            rotate: self.rotate.slerp(other.rotate, w),
            scale: self.scale.lerp(other.scale, w),
        }
    }
}

impl Interpolate for Camera {
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        Camera {
            position: self.position.lerp(other.position, w),
            look_at: self.look_at.lerp(other.look_at, w),
            up: self.up.lerp(other.up, w),
            fov_y: self.fov_y + (other.fov_y - self.fov_y) * w,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    impl Interpolate for f32 {
        fn interpolate(&self, other: &Self, w: f32) -> Self {
            self + (other - self) * w
        }
    }

    fn track(keys: &[(f32, f32)]) -> Keyframes<f32> {
        Keyframes::new(keys.to_vec()).unwrap()
    }

    #[test]
    fn lerp_between_keys_and_exact_at_keys() {
        let k = track(&[(0.0, 1.0), (2.0, 5.0), (3.0, -1.0)]);
        assert_eq!(k.sample(1.0), 3.0);
        assert_eq!(k.sample(0.5), 2.0);
        assert_eq!(k.sample(2.5), 2.0);
        for (t, v) in [(0.0, 1.0), (2.0, 5.0), (3.0, -1.0)] {
            assert_eq!(k.sample(t).to_bits(), f32::to_bits(v), "key at {t}");
        }
    }

    #[test]
    fn clamps_outside_the_keys() {
        let k = track(&[(1.0, 10.0), (2.0, 20.0)]);
        assert_eq!(k.sample(-5.0), 10.0);
        assert_eq!(k.sample(0.999), 10.0);
        assert_eq!(k.sample(2.001), 20.0);
        assert_eq!(k.sample(1e9), 20.0);
        assert_eq!(k.sample(f32::NAN), 10.0);
        assert_eq!(k.segment(7.0), (1, 0.0));
    }

    #[test]
    fn one_key_is_constant() {
        let k = track(&[(4.0, 7.0)]);
        for t in [-1.0, 0.0, 4.0, 100.0] {
            assert_eq!(k.sample(t), 7.0);
        }
    }

    #[test]
    fn rejects_bad_key_times() {
        assert_eq!(Keyframes::<f32>::new(vec![]).unwrap_err(), KeyError::Empty);
        let e = Keyframes::new(vec![(0.0, 0.0), (1.0, 0.0), (1.0, 0.0)]).unwrap_err();
        assert_eq!(
            e,
            KeyError::NotIncreasing {
                index: 2,
                time: 1.0,
                previous: 1.0
            }
        );
        assert!(e
            .to_string()
            .contains("key 2 at time 1 does not come after key 1"));
        let e = Keyframes::new(vec![(0.0, 0.0), (f32::INFINITY, 0.0)]).unwrap_err();
        assert!(matches!(e, KeyError::NonFiniteTime { index: 1, .. }));
        assert!(Keyframes::new(vec![(2.0, 0.0), (1.0, 0.0)]).is_err());
    }

    fn turn(degrees: f32) -> Transform {
        Transform {
            rotate: Quat::from_axis_angle(Vec3::Y, degrees.to_radians()),
            ..Transform::IDENTITY
        }
    }

    #[test]
    fn slerp_halves_the_angle_about_a_fixed_axis() {
        let k = Keyframes::new(vec![(0.0, turn(0.0)), (1.0, turn(120.0))]).unwrap();
        for (t, want) in [(0.25f32, 30.0f32), (0.5, 60.0), (0.75, 90.0)] {
            let q = k.sample(t).rotate;
            let (axis, angle) = q.to_axis_angle();
            assert!((angle.to_degrees() - want).abs() < 1e-2, "{t}: {angle}");
            assert!(axis.abs_diff_eq(Vec3::Y, 1e-4), "{axis}");
            assert!((q.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn slerp_takes_the_shorter_arc() {
        // 350° is −10°: halfway from 0° is −5°, not 175°.
        let k = Keyframes::new(vec![(0.0, turn(0.0)), (1.0, turn(350.0))]).unwrap();
        let p = k.sample(0.5).apply_point(Vec3::X);
        let want = Quat::from_axis_angle(Vec3::Y, (-5.0f32).to_radians()) * Vec3::X;
        assert!(p.abs_diff_eq(want, 1e-4), "{p} vs {want}");
    }

    #[test]
    fn translation_and_scale_interpolate_linearly() {
        let a = Transform {
            translate: Vec3::new(0.0, 0.0, 0.0),
            scale: Vec3::splat(1.0),
            ..Transform::IDENTITY
        };
        let b = Transform {
            translate: Vec3::new(4.0, -2.0, 8.0),
            scale: Vec3::new(3.0, 1.0, 2.0),
            ..Transform::IDENTITY
        };
        let m = a.interpolate(&b, 0.25);
        assert_eq!(m.translate, Vec3::new(1.0, -0.5, 2.0));
        assert_eq!(m.scale, Vec3::new(1.5, 1.0, 1.25));
        assert_eq!(m.rotate, Quat::IDENTITY);
    }

    #[test]
    fn transform_scales_then_rotates_then_translates() {
        let t = Transform {
            translate: Vec3::new(10.0, 0.0, 0.0),
            rotate: Quat::from_axis_angle(Vec3::Z, std::f32::consts::FRAC_PI_2),
            scale: Vec3::new(2.0, 1.0, 1.0),
        };
        // (1, 0, 0) → scale (2, 0, 0) → rotate 90° about z (0, 2, 0) → (10, 2, 0).
        assert!(t
            .apply_point(Vec3::X)
            .abs_diff_eq(Vec3::new(10.0, 2.0, 0.0), 1e-5));
        // A normal of a plane x = c stays perpendicular to the scaled plane.
        assert!(t.apply_normal(Vec3::X).abs_diff_eq(Vec3::Y, 1e-5));
        assert!(!t.mirrors());
        let m = Transform {
            scale: Vec3::new(-1.0, 1.0, 1.0),
            ..Transform::IDENTITY
        };
        assert!(m.mirrors());
        // No rotation: exactly p · scale + translate.
        let s = Transform {
            translate: Vec3::new(0.1, 0.2, 0.3),
            scale: Vec3::splat(3.7),
            ..Transform::IDENTITY
        };
        let p = Vec3::new(1.3, -2.9, 0.7);
        assert_eq!(
            s.apply_point(p),
            p * Vec3::splat(3.7) + Vec3::new(0.1, 0.2, 0.3)
        );
    }

    #[test]
    fn camera_fields_interpolate_linearly() {
        let a = Camera {
            position: Vec3::ZERO,
            look_at: Vec3::NEG_Z,
            up: Vec3::Y,
            fov_y: 40.0,
        };
        let b = Camera {
            position: Vec3::new(2.0, 0.0, 0.0),
            look_at: Vec3::new(2.0, 0.0, -1.0),
            up: Vec3::Y,
            fov_y: 60.0,
        };
        let k = Keyframes::new(vec![(0.0, a), (2.0, b)]).unwrap();
        let m = k.sample(1.0);
        assert_eq!(m.position, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(m.look_at, Vec3::new(1.0, 0.0, -1.0));
        assert_eq!(m.fov_y, 50.0);
        assert_eq!(k.sample(2.0), b);
    }
}
