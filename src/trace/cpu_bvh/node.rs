//! The wide nodes the CPU traversal walks: obvhs's compressed 8-wide nodes with their
//! children's boxes stored exactly (f32, padded outwards) instead of quantised to 8 bits,
//! and the conservative ray–box test that decides which children a ray visits.

use glam::Vec3;
use obvhs::cwbvh::node::{extract_byte64, CwBvhNode};

/// One node of the wide BVH. `child_base_idx`, `primitive_base_idx` and `imask` are read
/// by obvhs's `traverse!` loop under exactly these names; `child_meta` encodes which
/// children are leaves, their primitive ranges and their traversal priority (obvhs's
/// layout, decoded by [`CwBvhNode::get_child_and_index_bits`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct WideNode {
    pub child_base_idx: u32,
    pub primitive_base_idx: u32,
    pub imask: u8,
    child_meta: [u8; 8],
    /// Child boxes, structure of arrays: `lo[axis][child]`, `hi[axis][child]`. Empty slots
    /// hold an inverted box that no ray enters.
    lo: [[f32; 8]; 3],
    hi: [[f32; 8]; 3],
}

/// A ray prepared for the box tests.
#[derive(Clone, Copy, Debug)]
pub(super) struct BoxRay {
    pub origin: Vec3,
    /// 1 / direction per axis: ±inf for a zero component, which the test handles.
    pub inv_dir: Vec3,
    /// Whether each direction component's sign bit is set (−0.0 included, so that the
    /// near and far planes match the sign of `inv_dir`).
    pub negative: [bool; 3],
    pub tmin: f32,
}

/// Relative margin on both ends of a ray's segment in a box: the slab distances carry a
/// few ulps of rounding (two operations, Ize 2013 bounds it by 2γ₃ ≈ 3.6·10⁻⁷), and the
/// t of the triangle test inside the box carries its own; 10⁻⁵ covers both with
/// room to spare and costs a few extra box visits, never a hit.
const T_MARGIN: f32 = 1e-5;

impl WideNode {
    /// The node's structure; every child box starts empty (no ray enters it) until
    /// [`WideNode::set_child_box`] stores the exact one.
    pub(super) fn from_compressed(node: &CwBvhNode) -> Self {
        Self {
            child_base_idx: node.child_base_idx,
            primitive_base_idx: node.primitive_base_idx,
            imask: node.imask,
            child_meta: node.child_meta,
            lo: [[f32::INFINITY; 8]; 3],
            hi: [[f32::NEG_INFINITY; 8]; 3],
        }
    }

    pub(super) fn set_child_box(&mut self, child: usize, lo: Vec3, hi: Vec3) {
        for axis in 0..3 {
            self.lo[axis][child] = lo[axis];
            self.hi[axis][child] = hi[axis];
        }
    }

    /// Decodes the child slots the way obvhs stores them: for each occupied slot, its
    /// primitive range (leaf) or its node index (interior).
    pub(super) fn children(&self) -> impl Iterator<Item = (usize, Child)> + '_ {
        let compressed = self.compressed_meta();
        (0..8)
            .filter(move |&c| !compressed.is_child_empty(c))
            .map(move |c| {
                let child = if compressed.is_leaf(c) {
                    let (start, count) = compressed.child_primitives(c);
                    Child::Leaf { start, count }
                } else {
                    Child::Node(compressed.child_node_index(c))
                };
                (c, child)
            })
    }

    /// A compressed node carrying only what obvhs's bit decoding reads.
    fn compressed_meta(&self) -> CwBvhNode {
        CwBvhNode {
            child_base_idx: self.child_base_idx,
            primitive_base_idx: self.primitive_base_idx,
            imask: self.imask,
            child_meta: self.child_meta,
            ..CwBvhNode::default()
        }
    }

    /// The hit mask obvhs's `traverse!` expects from a node test (interior children in the
    /// top byte by traversal priority, leaf primitives in the low 24 bits), for the
    /// children whose box the ray's segment (tmin, `t_far`) meets ([`segment_meets_box`]).
    #[inline(always)]
    pub(super) fn intersect(&self, ray: &BoxRay, t_far: f32, oct_inv4: u32) -> u32 {
        let mut entered = 0u32;
        let near = |axis: usize| {
            if ray.negative[axis] {
                &self.hi[axis]
            } else {
                &self.lo[axis]
            }
        };
        let far = |axis: usize| {
            if ray.negative[axis] {
                &self.lo[axis]
            } else {
                &self.hi[axis]
            }
        };
        let (nx, ny, nz) = (near(0), near(1), near(2));
        let (fx, fy, fz) = (far(0), far(1), far(2));
        for c in 0..8 {
            let near = [nx[c], ny[c], nz[c]];
            let far = [fx[c], fy[c], fz[c]];
            entered |= (segment_meets_box(ray, t_far, near, far) as u32) << c;
        }
        if entered == 0 {
            return 0;
        }
        let (child_bits8, bit_index8) = self.compressed_meta().get_child_and_index_bits(oct_inv4);
        let mut hit_mask = 0;
        while entered != 0 {
            let c = entered.trailing_zeros() as usize;
            entered &= entered - 1;
            hit_mask |= extract_byte64(child_bits8, c) << extract_byte64(bit_index8, c);
        }
        hit_mask
    }
}

/// Whether the segment [max(tmin, box entry), min(`t_far`, box exit)] is non-empty, for
/// a box given by its planes on the ray's near and far side per axis. Conservative:
/// rounding never rejects a box the exact ray enters.
///
/// NaN slab distances (a zero direction component with the origin exactly on a slab
/// plane: 0 · ∞) are skipped, i.e. the slab counts as entered.
#[inline(always)]
fn segment_meets_box(ray: &BoxRay, t_far: f32, near: [f32; 3], far: [f32; 3]) -> bool {
    let mut t0 = ray.tmin;
    let mut t1 = t_far;
    for axis in 0..3 {
        let (o, inv) = (ray.origin[axis], ray.inv_dir[axis]);
        t0 = nan_ignoring_max(t0, (near[axis] - o) * inv);
        t1 = nan_ignoring_min(t1, (far[axis] - o) * inv);
    }
    // t1 widened by both ends' margins: conservative whatever the signs (when t1 < 0 <
    // t0 the exact test rejects too).
    t0 <= t1 + 2.0 * T_MARGIN * t1.abs()
}

/// Whether the ray's segment (tmin, `t_far`) meets the box [lo, hi].
#[inline(always)]
pub(super) fn segment_meets(ray: &BoxRay, t_far: f32, lo: Vec3, hi: Vec3) -> bool {
    let side = |axis: usize| {
        if ray.negative[axis] {
            (hi[axis], lo[axis])
        } else {
            (lo[axis], hi[axis])
        }
    };
    let (x, y, z) = (side(0), side(1), side(2));
    segment_meets_box(ray, t_far, [x.0, y.0, z.0], [x.1, y.1, z.1])
}

/// max(acc, x), keeping `acc` when x is NaN. Written as a comparison so that it compiles
/// to a single `maxps` (`f32::max` adds a NaN fix-up).
#[inline(always)]
fn nan_ignoring_max(acc: f32, x: f32) -> f32 {
    if x > acc {
        x
    } else {
        acc
    }
}

/// min(acc, x), keeping `acc` when x is NaN.
#[inline(always)]
fn nan_ignoring_min(acc: f32, x: f32) -> f32 {
    if x < acc {
        x
    } else {
        acc
    }
}

/// An occupied child slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Child {
    /// Primitives `start..start + count` of the leaf-ordered triangle list.
    Leaf { start: u32, count: u32 },
    /// A node index.
    Node(u32),
}
