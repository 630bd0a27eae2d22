//! Orthonormal bases: the local shading frame (+z = shading normal).

use glam::Vec3;

/// An orthonormal basis `(s, t, n)`; local coordinates are (x along s, y along t, z
/// along n).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// A frame with +z = `n` (unit), branchless (Duff et al. 2017, "Building an
    /// Orthonormal Basis, Revisited"); `bsdf_frame` in `bsdf.glsl` is the twin.
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// World → local.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local → world.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(-0.2, 0.1, -0.97).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5);
            assert!((f.s.cross(f.t) - n).length() < 1e-5);
            let v = Vec3::new(0.1, 0.7, -0.3);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
            assert!((f.to_local(n) - Vec3::Z).length() < 1e-5);
        }
    }
}
