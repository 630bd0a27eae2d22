//! A level's lists on the device and what filtering a level leaves for the next one.

use super::pool::BufferPool;
use super::types::{LevelTotals, Tile, TILE_ITEMS};
use crate::vk::{self, Buffer};

/// Level lists: the ids of each node's triangles and rays, with keys (node << 2 | code).
pub(super) struct Level {
    pub(super) nodes: Buffer,
    pub(super) node_count: u32,
    pub(super) tris: IdList,
    pub(super) rays: IdList,
    /// The children's triangle bounds with tight boxes (filter_triangles.comp): 8 words
    /// per child, all ones ("none yet") when the level is made — filled in the
    /// submission that writes the level, so filtering it needs no fill and barrier of
    /// its own. Without tight boxes the kernels never touch it: one word stands in.
    pub(super) bounds: Buffer,
}

impl Level {
    /// Bytes of the bounds of a level of `node_count` nodes.
    pub(super) fn bounds_bytes(node_count: u32, tight_boxes: bool) -> u64 {
        if tight_boxes {
            node_count as u64 * 2 * 32
        } else {
            4
        }
    }

    /// Records the fill that readies the bounds ("none yet"), when they are used; the
    /// caller's barrier orders it before the filters.
    pub(super) fn record_bounds_fill(
        &self,
        rec: &mut vk::Recorder,
        tight_boxes: bool,
    ) -> vk::Result<()> {
        if tight_boxes {
            let bytes = Self::bounds_bytes(self.node_count, true);
            rec.fill_range(&self.bounds, 0, bytes, u32::MAX)?;
        }
        Ok(())
    }

    /// Returns the level's buffers to the pool.
    pub(super) fn give(self, pool: &mut BufferPool) {
        self.tris.give(pool);
        self.rays.give(pool);
        pool.give(self.nodes);
        pool.give(self.bounds);
    }
}

/// One of a level's two id lists and which node owns each id.
pub(super) struct IdList {
    pub(super) ids: Buffer,
    /// Per-id keys (node << 2 | code) when the level is split by sorting, `tiles` tiles
    /// (pdacrt.glsl) when by prefix sums.
    pub(super) owner: Buffer,
    /// Tiles of the list (prefix-sum split; else 0).
    pub(super) tiles: u32,
    /// Ids in the list.
    pub(super) total: u32,
}

/// Which of a level's lists: names its buffers.
#[derive(Clone, Copy)]
pub(super) enum ListKind {
    Triangles,
    Rays,
}

impl IdList {
    /// The buffers of a list of `total` ids, cut into `tiles` tiles when the level is
    /// split by prefix sums (`None`: per-id keys). `idle`: taken right after a host
    /// wait ([`BufferPool::take_while_idle`]).
    pub(super) fn take(
        pool: &mut BufferPool,
        kind: ListKind,
        total: u32,
        tiles: Option<u32>,
        idle: bool,
    ) -> vk::Result<Self> {
        let (ids_name, owner_name) = match kind {
            ListKind::Triangles => ("pdacrt-tri-ids", "pdacrt-tri-owner"),
            ListKind::Rays => ("pdacrt-ray-ids", "pdacrt-ray-owner"),
        };
        let owner_bytes = tiles.map_or(total as u64 * 4, |t| t as u64 * size_of::<Tile>() as u64);
        let mut take = |name, bytes| {
            if idle {
                pool.take_while_idle(name, bytes)
            } else {
                pool.take(name, bytes)
            }
        };
        Ok(Self {
            ids: take(ids_name, total as u64 * 4)?,
            owner: take(owner_name, owner_bytes)?,
            tiles: tiles.unwrap_or(0),
            total,
        })
    }

    pub(super) fn give(self, pool: &mut BufferPool) {
        pool.give(self.ids);
        pool.give(self.owner);
    }
}

/// The tiles of one node's `count` elements from `start` (pdacrt.glsl).
pub(super) fn node_tiles(node: u32, start: u32, count: u32) -> impl Iterator<Item = Tile> {
    (0..count.div_ceil(TILE_ITEMS)).map(move |k| Tile {
        node,
        start: start + k * TILE_ITEMS,
        count: TILE_ITEMS.min(count - k * TILE_ITEMS),
        pad: 0,
    })
}

/// The side counts of a level split by prefix sums, per tile: four arrays (triangles
/// left and right, rays left and right) of tile count + 1 in one buffer, scanned
/// together into each tile's rank within its child.
pub(super) struct Ranks {
    pub(super) buffer: Buffer,
    pub(super) tri_left: u32,
    pub(super) tri_right: u32,
    pub(super) ray_left: u32,
    pub(super) ray_right: u32,
}

impl Ranks {
    /// Where the (left, right) arrays of the triangle and of the ray list start; zeros
    /// when the level is split by sorting (the kernels then ignore them).
    pub(super) fn bases(ranks: Option<&Ranks>) -> ((u32, u32), (u32, u32)) {
        ranks.map_or(((0, 0), (0, 0)), |r| {
            ((r.tri_left, r.tri_right), (r.ray_left, r.ray_right))
        })
    }

    /// Words in all four arrays.
    pub(super) fn len(&self) -> u32 {
        2 * self.tri_right + 2 * (self.ray_right - self.ray_left)
    }
}

/// What filtering a level leaves for building the next one.
pub(super) struct Filtered {
    pub(super) totals: LevelTotals,
    /// Per-child records (children.comp).
    pub(super) children: Buffer,
    /// The prefix-summed channels, `stride` words each.
    pub(super) offsets: Buffer,
    pub(super) stride: u32,
    pub(super) ranks: Option<Ranks>,
}

/// Where a level's write_nodes and scatter put the next level: its buffers, or where
/// there is no next level, one stand-in for each (bound, never written then).
pub(super) struct NextBuffers<'a> {
    pub(super) nodes: &'a Buffer,
    pub(super) tri_ids: &'a Buffer,
    pub(super) tri_owner: &'a Buffer,
    pub(super) ray_ids: &'a Buffer,
    pub(super) ray_owner: &'a Buffer,
}

impl<'a> NextBuffers<'a> {
    pub(super) fn new(next: Option<&'a Level>, empty: &'a Buffer) -> Self {
        match next {
            Some(l) => Self {
                nodes: &l.nodes,
                tri_ids: &l.tris.ids,
                tri_owner: &l.tris.owner,
                ray_ids: &l.rays.ids,
                ray_owner: &l.rays.owner,
            },
            None => Self {
                nodes: empty,
                tri_ids: empty,
                tri_owner: empty,
                ray_ids: empty,
                ray_owner: empty,
            },
        }
    }
}
