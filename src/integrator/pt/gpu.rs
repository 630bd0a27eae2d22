//! Records shared with `glsl/integrator/pt/pt.glsl`.

use bytemuck::{Pod, Zeroable};

use crate::scene::CameraFrame;

/// Push constants of every pt kernel (`PtParams` in pt.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct PtParams {
    pub origin: [f32; 4],
    pub forward: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub width: u32,
    pub height: u32,
    pub sample_index: u32,
    pub seed: u32,
    pub pixel_offset: u32,
    pub path_count: u32,
    pub active_count: u32,
    pub bounce: u32,
    pub max_depth: i32,
    pub rr_depth: u32,
    pub light_count: u32,
    pub flags: u32,
    pub ray_epsilon: f32,
    /// Pixels in the chunk: path p takes pixel `pixel_offset + p % pixel_count` and
    /// sample `sample_index + p / pixel_count`.
    pub pixel_count: u32,
    /// `finish` adds (s L)² to the second moments, s this power of two
    /// ([`LightTable::brightness_scale`](super::LightTable::brightness_scale)).
    pub brightness_scale: f32,
    pub pad: u32,
}

const _: () = assert!(size_of::<PtParams>() == 128);

pub const FLAG_SORTED: u32 = 1;
pub const FLAG_NEE: u32 = 2;
pub const FLAG_BSDF: u32 = 4;
/// The normals table holds three per triangle (else one dummy entry, never read).
pub const FLAG_NORMALS: u32 = 8;

impl PtParams {
    pub fn new(frame: &CameraFrame) -> Self {
        let [origin, forward, right, up] = frame.gpu_vectors();
        Self {
            origin,
            forward,
            right,
            up,
            width: frame.width,
            height: frame.height,
            // No scaling until the integrator sets the scene's (`finish` squares s·L).
            brightness_scale: 1.0,
            ..Default::default()
        }
    }
}

/// Per-path state (`PathState` in pt.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct PathState {
    pub throughput: [f32; 4],
    pub radiance: [f32; 4],
    pub depth: u32,
    pub flags: u32,
    pub pad: [u32; 2],
}

const _: () = assert!(size_of::<PathState>() == 48);

/// One entry of the light table (`Light` in pt.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct GpuLight {
    /// xyz: vertex 0 (triangles) or position (points); w: the type's bits.
    pub p0_type: [f32; 4],
    /// xyz: edge 1; w: area.
    pub e1_area: [f32; 4],
    /// xyz: edge 2; w: the triangle index's bits.
    pub e2_tri: [f32; 4],
    /// rgb: radiance (triangles) or intensity (points); w: probability of choice.
    pub emission_pmf: [f32; 4],
}

const _: () = assert!(size_of::<GpuLight>() == 64);

pub const LIGHT_TRIANGLE: u32 = 0;
pub const LIGHT_POINT: u32 = 1;

/// Per-material record (`PtMaterial` in pt.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct PtMaterial {
    pub emission: [f32; 4],
    /// `material_key(type, id)`: the sort key.
    pub key: u32,
    /// 1 when every layer is a delta lobe (no next-event estimation there).
    pub all_delta: u32,
    /// The key's rank among the scene's keys: what the radix sort sorts ([`sort_ranks`]).
    ///
    /// [`sort_ranks`]: super::materials::sort_ranks
    pub sort_rank: u32,
    pub pad: u32,
}

const _: () = assert!(size_of::<PtMaterial>() == 32);
