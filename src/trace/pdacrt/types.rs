//! PDACRT records shared with GLSL (glsl/trace/pdacrt/pdacrt.glsl).

use bytemuck::{Pod, Zeroable};

/// A node of the implicit hierarchy: its box and its pivots into the level's id lists.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Node {
    pub box_min: [f32; 4],
    pub box_max: [f32; 4],
    pub tri_start: u32,
    pub tri_count: u32,
    pub ray_start: u32,
    pub ray_count: u32,
}

/// A terminal node in the terminal-node buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub struct Segment {
    pub tri_start: u32,
    pub tri_count: u32,
    pub ray_start: u32,
    pub ray_count: u32,
}

/// Bytes of the GLSL `Child` record (two vec4 and eight u32).
pub const CHILD_BYTES: u64 = 64;

/// The per-level totals the host reads back (glsl level_summary.comp).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub struct LevelTotals {
    pub next_nodes: u32,
    pub next_tris: u32,
    pub next_rays: u32,
    pub term_nodes: u32,
    pub term_tris: u32,
    pub term_rays: u32,
}

const _: () = assert!(size_of::<Node>() == 48);
const _: () = assert!(size_of::<Segment>() == 16);
const _: () = assert!(size_of::<LevelTotals>() == 24);
