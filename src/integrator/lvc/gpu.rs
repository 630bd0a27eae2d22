//! Records shared with `glsl/integrator/lvc/lvc.glsl` (sizes asserted here, layouts
//! checked against the GLSL by `tests/suite/lvc_kernels.rs`).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::bidir::mis::TechniqueCounts;
use crate::bidir::PinholeCamera;
use crate::scene::CameraFrame;

/// Settings of a whole render (`LvcConstants`), in one buffer every kernel reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct LvcConstants {
    pub origin: [f32; 3],
    /// A pixel's area on the image plane at distance 1.
    pub pixel_area: f32,
    pub forward: [f32; 3],
    pub ray_epsilon: f32,
    pub right: [f32; 3],
    pub count_connection: f32,
    pub up: [f32; 3],
    pub count_light_trace: f32,
    pub count_emitter_hit: f32,
    pub count_light_sample: f32,
    pub width: u32,
    pub height: u32,
    pub seed: u32,
    /// N_L: light paths per pass.
    pub light_paths: u32,
    pub max_depth: i32,
    pub rr_depth: u32,
    pub light_count: u32,
    pub flags: u32,
    /// M: candidates per camera vertex (resampling).
    pub candidates: u32,
    /// N: connections per camera vertex.
    pub connections: u32,
    /// The power of two the splat film's values and the estimates squared into the
    /// second moments are multiplied by ([`LightTable::brightness_scale`]).
    ///
    /// [`LightTable::brightness_scale`]: crate::integrator::pt::LightTable::brightness_scale
    pub brightness_scale: f32,
    pub pad: [u32; 3],
}

const _: () = assert!(size_of::<LvcConstants>() == 128);

/// Kernels read their items through the material-sorted order.
pub const FLAG_SORTED: u32 = 1;
/// CIS-LBDPT's draws are systematic ([`super::options::Resampling::Systematic`]).
pub const FLAG_SYSTEMATIC: u32 = 2;
/// The normals table holds three per triangle ([`PtScene::has_normals`]).
///
/// [`PtScene::has_normals`]: crate::integrator::pt::PtScene::has_normals
pub const FLAG_NORMALS: u32 = 4;

impl LvcConstants {
    /// The camera part; counts, depths and the rest are the caller's.
    pub fn new(frame: &CameraFrame) -> Self {
        let camera = PinholeCamera::new(frame);
        Self {
            origin: frame.origin.into(),
            pixel_area: camera.pixel_area(),
            forward: frame.forward.into(),
            right: frame.right.into(),
            up: frame.up.into(),
            width: frame.width,
            height: frame.height,
            ..Default::default()
        }
    }

    /// The technique counts of the balance heuristic these constants hold.
    pub fn counts(&self) -> TechniqueCounts {
        TechniqueCounts {
            emitter_hit: self.count_emitter_hit,
            light_sample: self.count_light_sample,
            connection: self.count_connection,
            light_trace: self.count_light_trace,
            light_trace_emitter: 0.0,
        }
    }

    /// Sets the counts; (1, 1)'s must be 0 (the kernels leave emitters seen directly to
    /// s = 0, as `bpt` does).
    pub fn set_counts(&mut self, counts: &TechniqueCounts) {
        debug_assert_eq!(counts.light_trace_emitter, 0.0);
        self.count_emitter_hit = counts.emitter_hit;
        self.count_light_sample = counts.light_sample;
        self.count_connection = counts.connection;
        self.count_light_trace = counts.light_trace;
    }
}

/// Per-dispatch push constants (`LvcPush`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub struct LvcPush {
    pub first_pass: u32,
    pub path_count: u32,
    pub active_count: u32,
    pub bounce: u32,
    pub base: u32,
    pub capacity: u32,
    pub pixel_offset: u32,
    pub pixel_count: u32,
}

const _: () = assert!(size_of::<LvcPush>() == 32);

/// A surface vertex of a light subpath (a cache entry) or of a camera subpath
/// (`LvcVertex`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct LvcVertex {
    pub p: [f32; 3],
    pub material: u32,
    /// Unit shading normal, on the geometric normal's side.
    pub ns: [f32; 3],
    /// The triangle; the geometric normal is its normalize(e1 × e2).
    pub triangle: u32,
    /// Unit direction to the previous vertex.
    pub wo: [f32; 3],
    pub d_vcm: f32,
    pub beta: [f32; 3],
    pub d_vc: f32,
    /// Light path of the chunk (cache) or camera path.
    pub path: u32,
    /// Index in its subpath: 1 = the first hit.
    pub depth: u32,
    pub flags: u32,
    /// Cache: index among its light path's cached vertices.
    pub ordinal: u32,
}

const _: () = assert!(size_of::<LvcVertex>() == 80);

pub const VERTEX_VALID: u32 = 1;
pub const VERTEX_CONNECTIBLE: u32 = 2;
pub const VERTEX_EXTENDS: u32 = 4;

impl LvcVertex {
    pub fn position(&self) -> Vec3 {
        Vec3::from(self.p)
    }
    pub fn is(&self, flags: u32) -> bool {
        self.flags & flags == flags
    }
}

/// A subpath's random walk between two vertices (`WalkState`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct WalkState {
    pub beta: [f32; 3],
    pub d_vcm: f32,
    pub carried: [f32; 3],
    pub d_vc: f32,
    pub prev_p: [f32; 3],
    pub pending_fwd: f32,
    pub prev_ng: [f32; 3],
    pub pending_rev: f32,
    pub pending_count: f32,
    pub depth: u32,
    pub flags: u32,
    pub eta2: f32,
}

const _: () = assert!(size_of::<WalkState>() == 80);

/// One technique's contribution waiting for its shadow ray (`Contribution`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Contribution {
    /// Weighted (and scaled) contribution.
    pub value: [f32; 3],
    /// s | t << 16, or [`CONTRIBUTION_NONE`].
    pub code: u32,
    /// The balance-heuristic weight alone.
    pub weight: f32,
    /// Light tracing: the splat slot pass × pixels + pixel; connections: the cache
    /// vertex; else [`CONTRIBUTION_NONE`].
    pub target: u32,
    pub pad: [u32; 2],
}

const _: () = assert!(size_of::<Contribution>() == 32);

pub const CONTRIBUTION_NONE: u32 = u32::MAX;

impl Contribution {
    pub fn is_some(&self) -> bool {
        self.code != CONTRIBUTION_NONE
    }
    /// The technique (s, t).
    pub fn technique(&self) -> (u32, u32) {
        (self.code & 0xFFFF, self.code >> 16)
    }
    pub fn value(&self) -> Vec3 {
        Vec3::from(self.value)
    }
}

/// Counters the kernels add to (`counters[]`).
pub const COUNTER_NON_FINITE: usize = 0;
pub const COUNTER_CLAMPED: usize = 1;
pub const COUNTERS: usize = 2;

/// A camera bounce's shadow rays that carried a contribution, and those the tracer
/// found unoccluded, of direct lighting and of the connections (`tally[]` of
/// camera_accumulate.comp, in this order). Connections the selection made no ray for
/// (nothing carried, a resampled draw repeated) are not counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub struct VisibilityTally {
    pub direct_rays: u32,
    pub direct_unoccluded: u32,
    pub connection_rays: u32,
    pub connections_unoccluded: u32,
}

const _: () = assert!(size_of::<VisibilityTally>() == 16);

/// Random-number dimensions of the cache-vertex selection (`select_dim` in lvc.glsl),
/// above every dimension of the bidirectional walks ([`crate::bidir::random::dims`]).
pub mod dims {
    pub const SELECT_BASE: u32 = 0x8000_0000;
    pub const PER_SELECTION: u32 = 64;
    /// Offsets from here: the resampling draws (below: the candidates).
    pub const RESAMPLE: u32 = 32;

    /// Dimension `offset` of the selections at camera vertex `j`.
    pub fn select(j: u32, offset: u32) -> u32 {
        SELECT_BASE + j * PER_SELECTION + offset
    }
}
