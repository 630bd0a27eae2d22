//! Integrator records shared with GLSL (glsl/common/frame.glsl, material.glsl).

use bytemuck::{Pod, Zeroable};

use crate::scene::CameraFrame;

/// Per-dispatch parameters, passed as push constants.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct FrameParams {
    pub origin: [f32; 4],
    pub forward: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub width: u32,
    pub height: u32,
    pub sample_index: u32,
    pub seed: u32,
    pub pixel_offset: u32,
    pub pixel_count: u32,
    pub jitter: u32,
    pub ao_rays: u32,
    pub ao_radius: f32,
    pub ray_epsilon: f32,
    pub bounce: u32,
    pub pad: u32,
    /// Point light of the shadow integrator: position, w = intensity in W/sr.
    pub light: [f32; 4],
}

const _: () = assert!(size_of::<FrameParams>() == 128);

impl FrameParams {
    pub fn new(frame: &CameraFrame) -> Self {
        let [origin, forward, right, up] = frame.gpu_vectors();
        Self {
            origin,
            forward,
            right,
            up,
            width: frame.width,
            height: frame.height,
            ..Default::default()
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct GpuMaterial {
    pub diffuse: [f32; 4],
    pub emission: [f32; 4],
}
