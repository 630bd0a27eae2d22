//! The combination's data as the kernels see them (§4): the linking vertices of a
//! population couple, uploaded as two arrays, and the combination data of every linking
//! segment, downloaded into host memory. `glsl/integrator/cbpt/cbpt.glsl` is the GLSL
//! side; `tests/suite/cbpt_gpu.rs` checks the layouts against it.
//!
//! **Linking vertices.** The camera table holds every camera vertex past the pinhole that
//! a connection can use (a surface with a non-delta lobe); the light table holds the
//! light vertices on surfaces likewise, then the first vertex (on a light) of every
//! non-empty light path. V_C and V_L are their lengths, V_S ≤ V_L the light vertices on
//! surfaces. Only these O(N_C + N_L) records go up; a linking segment's vertices come
//! from its index (§4, "Low-level details").
//!
//! **Segments.** Visibility and camera shading index the V_C·V_L segments camera-vertex
//! major (segment = c·V_L + l, so the threads of one camera vertex are consecutive and
//! share its BSDF: Fig. 2); light shading indexes the V_S·V_C segments with a light
//! vertex on a surface light-vertex major (segment = l·V_C + c).
//!
//! **Results.** Visibility is one bit per segment (bit b of word w: segment 32w + b);
//! shading is five planes of floats per segment — f·|cos| (r, g, b), the density towards
//! the other endpoint and the reverse density (the tuple (f_s, p, p*) of §3.1, as
//! [`Endpoint`] holds it) — plane after plane (structure of arrays, so that consecutive
//! threads write consecutive floats).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::population::Population;
use crate::bidir::connect::Endpoint;
use crate::bidir::scene::SurfaceHit;
use crate::bidir::vertex::{Vertex, NO_TRIANGLE};

/// Marks a subpath vertex that has no linking record.
pub const NOT_LINKED: u32 = u32::MAX;
/// Floats per shading result.
pub const SHADING_PLANES: usize = 5;

/// A linking vertex (64 bytes; `CbptVertex` in cbpt.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct GpuVertex {
    pub p: [f32; 3],
    /// The BSDF (surfaces) or the light's index (light vertices).
    pub material: u32,
    /// Unit geometric normal; zero for a point light.
    pub ng: [f32; 3],
    pub pad0: f32,
    /// Unit shading normal.
    pub ns: [f32; 3],
    pub pad1: f32,
    /// Unit direction towards the previous vertex of the subpath (zero on a light).
    pub wo: [f32; 3],
    pub pad2: f32,
}

const _: () = assert!(size_of::<GpuVertex>() == 64);

impl GpuVertex {
    pub fn new(v: &Vertex) -> Self {
        Self {
            p: v.p.into(),
            material: v.material,
            ng: v.ng.into(),
            ns: v.ns.into(),
            wo: v.wo.into(),
            ..Default::default()
        }
    }

    /// The surface vertex this record describes, as the CPU twins of the kernels
    /// evaluate it (the same frame, from the shading normal).
    pub fn surface(&self) -> Vertex {
        let hit = SurfaceHit {
            p: Vec3::from(self.p),
            ng: Vec3::from(self.ng),
            ns: Vec3::from(self.ns),
            triangle: NO_TRIANGLE,
            material: self.material,
            t: 0.0,
        };
        Vertex::surface(&hit, Vec3::from(self.wo), true)
    }
}

/// The linking vertices of a population couple and where each subpath vertex went.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tables {
    pub camera: Vec<GpuVertex>,
    /// Light vertices on surfaces (the first [`Tables::light_surface`]), then every
    /// light path's first vertex.
    pub light: Vec<GpuVertex>,
    /// V_S.
    pub light_surface: u32,
    /// Per vertex of the population's camera paths: its camera-table index or
    /// [`NOT_LINKED`].
    pub camera_index: Vec<u32>,
    /// Per vertex of the light paths: its light-table index or [`NOT_LINKED`].
    pub light_index: Vec<u32>,
}

impl Tables {
    pub fn new(population: &Population) -> Self {
        let mut t = Tables {
            camera_index: vec![NOT_LINKED; population.camera.vertices.len()],
            light_index: vec![NOT_LINKED; population.light.vertices.len()],
            ..Default::default()
        };
        for k in 0..population.camera.len() {
            for (j, at) in population.camera.range(k).enumerate() {
                let v = &population.camera.vertices[at];
                if j >= 1 && v.connectible {
                    t.camera_index[at] = t.camera.len() as u32;
                    t.camera.push(GpuVertex::new(v));
                }
            }
        }
        let light = &population.light;
        for k in 0..light.len() {
            for at in light.range(k).skip(1) {
                if light.vertices[at].connectible {
                    t.light_index[at] = t.light.len() as u32;
                    t.light.push(GpuVertex::new(&light.vertices[at]));
                }
            }
        }
        t.light_surface = t.light.len() as u32;
        for k in 0..light.len() {
            if let Some(at) = light.range(k).next() {
                t.light_index[at] = t.light.len() as u32;
                t.light.push(GpuVertex::new(&light.vertices[at]));
            }
        }
        t
    }

    /// V_C·V_L: the segments of visibility and camera shading.
    pub fn segments(&self) -> u64 {
        self.camera.len() as u64 * self.light.len() as u64
    }

    /// V_S·V_C: the segments of light shading.
    pub fn light_segments(&self) -> u64 {
        self.light_surface as u64 * self.camera.len() as u64
    }

    /// Segment of camera vertex `c` and light vertex `l` (camera-vertex major).
    pub fn segment(&self, c: u32, l: u32) -> usize {
        c as usize * self.light.len() + l as usize
    }

    /// Light-shading segment of surface light vertex `l` and camera vertex `c`.
    pub fn light_segment(&self, l: u32, c: u32) -> usize {
        l as usize * self.camera.len() + c as usize
    }
}

/// Which kinds of combination data to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kinds {
    pub visibility: bool,
    pub camera: bool,
    pub light: bool,
}

impl Kinds {
    pub const ALL: Self = Self {
        visibility: true,
        camera: true,
        light: true,
    };
}

/// Shading tuples of `segments` segments, plane after plane.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shading {
    pub segments: usize,
    pub values: Vec<f32>,
}

impl Shading {
    pub fn zeroed(segments: usize) -> Self {
        Self {
            segments,
            values: vec![0.0; segments * SHADING_PLANES],
        }
    }

    /// The planes of segments `first..first + n`, each a slice of `n` floats.
    pub fn planes_mut(&mut self, first: usize, n: usize) -> [&mut [f32]; SHADING_PLANES] {
        let s = self.segments;
        let mut rest: &mut [f32] = &mut self.values;
        let mut out: [&mut [f32]; SHADING_PLANES] = Default::default();
        for plane in out.iter_mut() {
            let (head, tail) = rest.split_at_mut(s);
            *plane = &mut head[first..first + n];
            rest = tail;
        }
        out
    }

    pub fn set(&mut self, segment: usize, e: &Endpoint) {
        let s = self.segments;
        let v = [e.f.x, e.f.y, e.f.z, e.pdf_fwd, e.pdf_rev];
        for (plane, x) in v.into_iter().enumerate() {
            self.values[plane * s + segment] = x;
        }
    }

    pub fn get(&self, segment: usize) -> Endpoint {
        let s = self.segments;
        let v = |plane: usize| self.values[plane * s + segment];
        Endpoint {
            f: Vec3::new(v(0), v(1), v(2)),
            pdf_fwd: v(3),
            pdf_rev: v(4),
        }
    }
}

/// The combination data of one population couple.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CombinationData {
    /// One bit per segment of [`Tables::segments`].
    pub visibility: Vec<u32>,
    /// Camera-vertex shading, per segment of [`Tables::segments`].
    pub camera: Shading,
    /// Light-vertex shading, per segment of [`Tables::light_segments`].
    pub light: Shading,
}

impl CombinationData {
    /// Zeroed data for `tables`.
    pub fn zeroed(tables: &Tables) -> Self {
        Self {
            visibility: vec![0; (tables.segments() as usize).div_ceil(32)],
            camera: Shading::zeroed(tables.segments() as usize),
            light: Shading::zeroed(tables.light_segments() as usize),
        }
    }

    pub fn visible(&self, segment: usize) -> bool {
        self.visibility[segment / 32] >> (segment % 32) & 1 == 1
    }
}
