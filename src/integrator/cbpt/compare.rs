//! How a GPU combination's data compares with its CPU twin's ([`super::cpu_kernels`]):
//! the rules `bench cbpt`'s check and the tests share.
//!
//! Visibility must agree bit for bit. A shading tuple (f and both densities) agrees when
//! each value is within 1e-4 relative (1e-6 absolute) of the twin's. Two kinds of segment
//! may differ more, because two processors round differently near an edge:
//! - one along its endpoint's tangent plane ([`grazing`]), where the hemisphere tests
//!   that zero a BSDF may fall either way: it must agree on f alone (f·|cos θ| is zero to
//!   within the absolute tolerance there, so the densities weigh nothing);
//! - one straddling a lobe's edge or inside a very peaked lobe: the whole tuple within
//!   1e-2, and at most 1 in 10 000 of the segments.

use glam::Vec3;

use super::layout::{CombinationData, Shading, Tables};

/// Which end of a segment a shading table belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum End {
    /// `camera_shading.comp`: camera-vertex major.
    Camera,
    /// `light_shading.comp`: light-vertex major.
    Light,
}

/// One shading table against its twin.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadingComparison {
    pub segments: usize,
    /// Along the endpoint's tangent plane, agreeing on f alone.
    pub tangent: usize,
    /// Only within 1e-2.
    pub loose: usize,
    /// Beyond 1e-2.
    pub beyond: usize,
    /// The first segment beyond 1e-2.
    pub first_beyond: Option<usize>,
}

impl ShadingComparison {
    /// Whether more than 1 segment in 10 000 agrees only within 1e-2.
    pub fn too_many_loose(&self) -> bool {
        self.loose * 10_000 > self.segments.max(10_000)
    }

    /// Segments that count against the GPU: those beyond 1e-2, and the loose ones too
    /// when there are too many of them.
    pub fn mismatches(&self) -> usize {
        self.beyond + if self.too_many_loose() { self.loose } else { 0 }
    }
}

/// Visibility bits that differ.
pub fn visibility_differences(gpu: &CombinationData, cpu: &CombinationData) -> u64 {
    let lengths = gpu.visibility.len().abs_diff(cpu.visibility.len()) as u64 * 32;
    let bits: u64 = gpu
        .visibility
        .iter()
        .zip(&cpu.visibility)
        .map(|(a, b)| (a ^ b).count_ones() as u64)
        .sum();
    bits + lengths
}

/// `end`'s shading table of the GPU against the CPU's, on the segments of `tables`.
pub fn compare_shading(
    gpu: &Shading,
    cpu: &Shading,
    tables: &Tables,
    end: End,
) -> ShadingComparison {
    let n = gpu.segments.min(cpu.segments);
    let close = |a: f32, b: f32, rel: f32| (a - b).abs() <= 1e-6 + rel * a.abs().max(b.abs());
    let mut out = ShadingComparison {
        segments: gpu.segments.max(cpu.segments),
        beyond: gpu.segments.abs_diff(cpu.segments),
        ..Default::default()
    };
    for s in 0..n {
        let (g, c) = (gpu.get(s), cpu.get(s));
        let f = [(g.f.x, c.f.x), (g.f.y, c.f.y), (g.f.z, c.f.z)];
        let pdfs = [(g.pdf_fwd, c.pdf_fwd), (g.pdf_rev, c.pdf_rev)];
        let f_within = |rel| f.iter().all(|&(a, b)| close(a, b, rel));
        let pdfs_within = |rel| pdfs.iter().all(|&(a, b)| close(a, b, rel));
        if f_within(1e-4) && pdfs_within(1e-4) {
            continue;
        }
        if f_within(1e-4) && grazing(tables, end, s) {
            out.tangent += 1;
        } else if f_within(1e-2) && pdfs_within(1e-2) {
            out.loose += 1;
        } else {
            out.beyond += 1;
            out.first_beyond.get_or_insert(s);
        }
    }
    out
}

/// Whether segment `s` of `end`'s table runs within float rounding of its endpoint's
/// tangent plane (shading or geometric normal): there the hemisphere tests that zero a
/// BSDF may fall either way on two processors (a GPU's fused multiply-adds and
/// approximate square roots against the CPU's), and either answer is right.
pub fn grazing(tables: &Tables, end: End, s: usize) -> bool {
    let (vertex, other) = match end {
        End::Camera => {
            let v_l = tables.light.len();
            (&tables.camera[s / v_l], tables.light[s % v_l].p)
        }
        End::Light => {
            let v_c = tables.camera.len();
            (&tables.light[s / v_c], tables.camera[s % v_c].p)
        }
    };
    let dir = (Vec3::from(other) - Vec3::from(vertex.p)).normalize_or_zero();
    let edge = |n: [f32; 3]| dir.dot(Vec3::from(n)).abs() < 1e-5;
    edge(vertex.ns) || edge(vertex.ng)
}

#[cfg(test)]
mod tests {
    use super::super::layout::GpuVertex;
    use super::*;

    fn vertex(p: [f32; 3]) -> GpuVertex {
        GpuVertex {
            p,
            ng: [0.0, 1.0, 0.0],
            ns: [0.0, 1.0, 0.0],
            ..Default::default()
        }
    }

    /// One camera vertex on the plane y = 0 (normal +y) and two light vertices: one in
    /// that plane (segment 0, grazing), one above it (segment 1).
    fn tables() -> Tables {
        Tables {
            camera: vec![vertex([0.0; 3])],
            light: vec![vertex([1.0, 0.0, 0.0]), vertex([0.0, 1.0, 0.0])],
            light_surface: 2,
            ..Default::default()
        }
    }

    /// Two segments of camera shading, each f = 0.5, densities 0.25 and 0.75.
    fn shading() -> Shading {
        let mut s = Shading::zeroed(2);
        for (plane, value) in [0.5, 0.5, 0.5, 0.25, 0.75].into_iter().enumerate() {
            s.values[plane * 2..plane * 2 + 2].fill(value);
        }
        s
    }

    /// `shading()` with `value` in plane `plane` of segment `segment`.
    fn with(plane: usize, segment: usize, value: f32) -> Shading {
        let mut s = shading();
        s.values[plane * 2 + segment] = value;
        s
    }

    fn compare(gpu: &Shading) -> ShadingComparison {
        compare_shading(gpu, &shading(), &tables(), End::Camera)
    }

    #[test]
    fn equal_tables_agree() {
        let c = compare(&shading());
        assert_eq!(
            c,
            ShadingComparison {
                segments: 2,
                ..Default::default()
            }
        );
        assert_eq!(c.mismatches(), 0);
        let near = with(3, 1, 0.25 * (1.0 + 5e-5));
        assert_eq!(compare(&near).mismatches(), 0);
    }

    #[test]
    fn only_a_grazing_segment_may_differ_in_its_densities() {
        let t = tables();
        assert!(grazing(&t, End::Camera, 0) && !grazing(&t, End::Camera, 1));
        let grazing = compare(&with(3, 0, 0.0));
        assert_eq!((grazing.tangent, grazing.beyond), (1, 0));
        assert_eq!(grazing.mismatches(), 0);
        let facing = compare(&with(3, 1, 0.0));
        assert_eq!((facing.tangent, facing.beyond), (0, 1));
        assert_eq!(facing.first_beyond, Some(1));
        assert_eq!(facing.mismatches(), 1);
        // A grazing segment must still agree on f.
        let f_differs = compare(&with(0, 0, 0.6));
        assert_eq!((f_differs.tangent, f_differs.beyond), (0, 1));
    }

    #[test]
    fn a_few_segments_may_agree_only_within_one_percent() {
        let loose = compare(&with(4, 1, 0.75 * 1.005));
        assert_eq!((loose.loose, loose.beyond), (1, 0));
        // 1 of 2 segments is more than 1 in 10 000 only while 2 < 10 000 segments.
        assert!(!loose.too_many_loose());
        assert_eq!(loose.mismatches(), 0);
        let many = ShadingComparison {
            segments: 20_000,
            loose: 3,
            ..Default::default()
        };
        assert!(many.too_many_loose());
        assert_eq!(many.mismatches(), 3);
    }

    #[test]
    fn tables_of_other_sizes_differ() {
        let c = compare_shading(&Shading::zeroed(3), &shading(), &tables(), End::Camera);
        assert_eq!(c.segments, 3);
        assert!(c.beyond >= 1 && c.mismatches() >= 1);
        let a = CombinationData {
            visibility: vec![0b1011, 0],
            ..Default::default()
        };
        let b = CombinationData {
            visibility: vec![0b0001],
            ..Default::default()
        };
        assert_eq!(visibility_differences(&a, &b), 2 + 32);
        assert_eq!(visibility_differences(&a, &a), 0);
    }
}
