//! Counter-based random numbers, the CPU twin of `glsl/common/random.glsl`: a value is a
//! pure function of (index, sample, dimension, seed), so a bidirectional image does not
//! depend on how its work is split among threads. `tests/suite/bidir_random.rs` checks the twin
//! against the GLSL function bit for bit.
//!
//! The bidirectional integrators draw a camera subpath and a light subpath per pixel
//! and pass. Both use the pixel index as `index` and the pass as `sample`; their
//! dimensions ([`dims`]) never overlap, so the two subpaths are independent.

/// PCG-style 32-bit hash (Jarzynski & Olano, "Hash Functions for GPU Rendering", 2020),
/// `pcg_hash` in random.glsl.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Uniform float in [0, 1) with 24 bits of precision, `random01` in random.glsl.
pub fn random01(index: u32, sample: u32, dimension: u32, seed: u32) -> f32 {
    let h = pcg_hash(index ^ pcg_hash(sample ^ pcg_hash(dimension ^ pcg_hash(seed))));
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The 32-bit seed the kernels take from a 64-bit seed (as `pt` folds it).
pub fn fold_seed(seed: u64) -> u32 {
    seed as u32 ^ (seed >> 32) as u32
}

/// The random numbers of one subpath: `index` (a pixel), `sample` (a pass) and the seed
/// fixed, the dimension chosen by the caller from [`dims`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathSampler {
    pub index: u32,
    pub sample: u32,
    pub seed: u32,
}

impl PathSampler {
    pub fn new(index: u32, sample: u32, seed: u32) -> Self {
        Self {
            index,
            sample,
            seed,
        }
    }

    /// The number of dimension `dim`.
    pub fn get(&self, dim: u32) -> f32 {
        random01(self.index, self.sample, dim, self.seed)
    }

    /// Three numbers from consecutive dimensions `dim..dim + 3`.
    pub fn get3(&self, dim: u32) -> [f32; 3] {
        [self.get(dim), self.get(dim + 1), self.get(dim + 2)]
    }
}

/// The dimension layout of the bidirectional integrators. Camera subpaths start like
/// `pt`'s paths (dimensions 0 and 1 jitter the pixel), then take [`dims::PER_VERTEX`]
/// dimensions per vertex; light subpaths live above [`dims::LIGHT_BASE`].
pub mod dims {
    /// Dimensions each subpath vertex owns.
    pub const PER_VERTEX: u32 = 8;
    /// Pixel jitter (x, y) of the camera ray.
    pub const CAMERA_JITTER: u32 = 0;
    /// First dimension of the light subpaths.
    pub const LIGHT_BASE: u32 = 1 << 30;

    /// Offsets within a vertex's dimensions.
    pub const BSDF: u32 = 0; // three: layer choice, then the direction
    pub const ROULETTE: u32 = 3;
    pub const LIGHT_PICK: u32 = 4; // next-event estimation: which light
    pub const LIGHT_POINT: u32 = 5; // two: where on it

    /// Offsets of the emission sample (the light subpath's first vertex).
    pub const EMIT_PICK: u32 = 0;
    pub const EMIT_POINT: u32 = 1; // two
    pub const EMIT_DIRECTION: u32 = 3; // two

    /// Dimension `offset` of camera-subpath vertex `j` (j = 1 is the first hit).
    pub fn camera_vertex(j: u32, offset: u32) -> u32 {
        2 + j * PER_VERTEX + offset
    }

    /// Dimension `offset` of the emission sample.
    pub fn emission(offset: u32) -> u32 {
        LIGHT_BASE + offset
    }

    /// Dimension `offset` of light-subpath vertex `i` (i = 1 is the first hit).
    pub fn light_vertex(i: u32, offset: u32) -> u32 {
        LIGHT_BASE + i * PER_VERTEX + offset
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_lie_in_the_unit_interval_and_fill_it() {
        let mut lo = 1.0f32;
        let mut hi = 0.0f32;
        let mut sum = 0.0f64;
        let n = 100_000;
        for i in 0..n {
            let u = random01(i, 3, 7, 11);
            assert!((0.0..1.0).contains(&u));
            lo = lo.min(u);
            hi = hi.max(u);
            sum += u as f64;
        }
        assert!(lo < 1e-3 && hi > 1.0 - 1e-3);
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
    }

    #[test]
    fn dimensions_of_the_two_subpaths_never_meet() {
        // 2^27 vertices per subpath before a camera dimension could reach LIGHT_BASE.
        assert!(dims::camera_vertex(1 << 20, dims::PER_VERTEX - 1) < dims::LIGHT_BASE);
        assert!(dims::emission(dims::EMIT_DIRECTION + 1) < dims::light_vertex(1, 0));
        assert_eq!(fold_seed(0x1_0000_0002), 3);
    }
}
