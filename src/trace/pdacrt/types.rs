//! PDACRT records shared with GLSL (glsl/trace/pdacrt/pdacrt.glsl).

use bytemuck::{Pod, Zeroable};

/// A node of the implicit hierarchy: its box and its pivots into the level's id lists,
/// and with [`LevelSplit::PrefixSums`](super::LevelSplit) its first tile in each list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Node {
    pub box_min: [f32; 3],
    pub first_tri_tile: u32,
    pub box_max: [f32; 3],
    pub first_ray_tile: u32,
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
    pub next_tri_tiles: u32,
    pub next_ray_tiles: u32,
}

/// Channels prefix-summed per level (CH_* in pdacrt.glsl), one `LevelTotals` field each.
pub const CHANNELS: u32 = 8;

/// Elements per tile of a level list at most (LevelSplit::PrefixSums; pdacrt.glsl): one
/// workgroup per tile, so a tile should give each of its invocations several elements.
pub const TILE_ITEMS: u32 = 1024;

/// A tile of a level list: elements `start .. start + count` of one node.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub struct Tile {
    pub node: u32,
    pub start: u32,
    pub count: u32,
    pub pad: u32,
}

/// Ids stay below 2^30 so the ranked kernels can keep a status code in the top two bits.
pub const MAX_IDS: u32 = 1 << 30;

const _: () = assert!(size_of::<Node>() == 48);
const _: () = assert!(size_of::<Segment>() == 16);
const _: () = assert!(size_of::<LevelTotals>() == 4 * CHANNELS as usize);
const _: () = assert!(size_of::<Tile>() == 16);
