//! CPU ray casting with a bounding volume hierarchy: closest-hit and occlusion queries of
//! single, incoherent rays from many threads at once, for the CPU integrators (the CPU
//! BPT, CBPT's CPU path sampling) and as the `cpu-bvh` tracer.
//!
//! # The crate: obvhs
//!
//! The hierarchy is built by [`obvhs`]: PLOC (Meister and Bittner 2018) over the
//! triangles' boxes, parallel reinsertion, then collapse into an 8-wide compressed BVH
//! (CWBVH, Ylitie et al. 2017), and traversed with obvhs's own `traverse!` loop (its
//! octant-ordered child groups and stack). `obvhs` and `bvh` were measured on the bunny
//! in one run, alternating (docs/PERFORMANCE.md, "CPU BVH"): obvhs traced 2.7× as many
//! primary rays per second and 3.4× as many diffuse-bounce rays; `bvh` built its tree in
//! about 0.7× the time, which a frame of a million rays does not recover. `bvh` also
//! stores one triangle per leaf of a binary tree, offers closest-hit only as iterators
//! that cannot shrink the ray as hits are found (the ordered one allocates a heap per
//! ray), has no tmin/tmax in its ray, counts a ray lying in a box face as missing the
//! box, and requires Rust 1.90 (this crate targets 1.85).
//!
//! # What splitray adds, and why
//!
//! obvhs's `traverse!` takes the node test and the primitive test as arguments. splitray
//! supplies both, so that every hit equals brute force ([`cpu::closest_hit`]) bit for
//! bit (save on degenerate triangles, below):
//! - **Primitive test**: [`cpu::intersect_triangle`], the arithmetic of every other
//!   tracer and of the GPU kernels; a ray keeps the lexicographic minimum of (t, scene
//!   index), so when two triangles meet a ray at the same t the smaller index wins however
//!   the tree orders them, as in brute force.
//! - **Node test** (`node::WideNode::intersect`): obvhs's own test culls every box the
//!   ray leaves within t = 10⁻⁴ of its origin (an absolute distance: the neighbours of a
//!   ray starting on a surface, or a whole scene smaller than that, are missed), ignores
//!   `tmin`, and reads child boxes quantised to 8 bits without a rounding margin. splitray
//!   keeps each child's exact box (the union of its triangles' boxes, padded outwards by a
//!   small fraction of the scene size), honours `tmin`, and widens the ray's segment by a
//!   relative 10⁻⁵, so rounding can cost an extra box visit but never a hit. Zero
//!   direction components give infinite slab distances and are handled exactly. A ray
//!   that misses the root's box returns before the traversal starts. (Measured against
//!   obvhs's own test on the same tree: 1.3× the primary rays per second.)
//!
//! Degenerate triangles (the scene's test: zero area within f32 precision relative to
//! the edges, or non-finite; repeated vertices, collinear ones) are left out of the tree
//! ([`is_hittable`]): a hit on one would have no normal to shade with. Here alone the BVH
//! departs from brute force, whose determinant (the sum of the three edge functions of
//! the watertight test) is rounded and can be non-zero on such a triangle, so that it
//! sometimes reports a hit on one. A ray with a NaN component or a non-finite origin or
//! direction misses without being traced, as it does in brute force.

mod build;
mod node;
mod tracer;

use glam::{UVec2, Vec3};
use obvhs::faststack::{FastStack, HeapStack, StackStack};
pub use obvhs::BvhBuildParams;
use rayon::prelude::*;

use super::{cpu, GpuTriangle, Hit, Ray};
pub use build::is_hittable;
use node::{BoxRay, WideNode};
pub use tracer::CpuBvhTracer;

/// A BVH over one scene's triangles. Immutable once built, so any number of threads may
/// query it at once (`Send + Sync`); [`CpuBvh::rebuild`] replaces the geometry.
#[derive(Clone, Debug, Default)]
pub struct CpuBvh {
    nodes: Vec<WideNode>,
    /// The triangles in leaf order (obvhs's `primitive_indices`), so that a leaf's
    /// triangles are contiguous in memory.
    triangles: Vec<GpuTriangle>,
    /// Scene index of each entry of `triangles`.
    scene_index: Vec<u32>,
    /// Triangles in the scene, those left out of the tree included.
    triangle_count: usize,
    /// Node levels below the root: the traversal stack needs at most this many entries.
    depth: u32,
    /// The root's box, padded like every child box: rays that miss it skip the traversal.
    bounds: (Vec3, Vec3),
}

// Shared by every thread of the CPU integrators.
const _: () = {
    const fn shareable<T: Send + Sync>() {}
    shareable::<CpuBvh>();
};

/// Traversal state under the names obvhs's `traverse!` loop reads and writes.
struct Traversal<S> {
    stack: S,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

/// obvhs's build preset: PLOC search radius 14, reinsertion of 5% of the nodes, up to 3
/// triangles per leaf.
pub const BUILD_PARAMS: BvhBuildParams = BvhBuildParams::medium_build();

/// Depth up to which the traversal stack lives on the thread's stack; deeper trees
/// (thousands of coincident triangles) use a heap stack of their own size.
const INLINE_STACK: usize = 32;

/// What a traversal looks for.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    Closest,
    Any,
}

impl CpuBvh {
    /// Builds the hierarchy over `triangles` (scene order), in parallel on rayon's pool.
    pub fn new(triangles: &[GpuTriangle]) -> CpuBvh {
        Self::with_params(triangles, BUILD_PARAMS)
    }

    /// Builds with obvhs parameters other than splitray's choice ([`BUILD_PARAMS`]).
    pub fn with_params(triangles: &[GpuTriangle], params: BvhBuildParams) -> CpuBvh {
        build::build(triangles, params)
    }

    /// Replaces the geometry, as a dynamic scene does every frame.
    pub fn rebuild(&mut self, triangles: &[GpuTriangle]) {
        *self = build::build(triangles, BUILD_PARAMS);
    }

    /// Triangles of the scene it was built from (those left out of the tree included).
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// Nodes of the 8-wide tree.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Node levels of the tree (0 when empty).
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// The nearest hit in (tmin, tmax): the same record as [`cpu::closest_hit`].
    pub fn closest_hit(&self, ray: &Ray) -> Hit {
        self.trace(ray, Mode::Closest)
    }

    /// Whether anything blocks the ray in (tmin, tmax); stops at the first blocker found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.trace(ray, Mode::Any).is_hit()
    }

    /// The first blocker found in (tmin, tmax), or [`Hit::NONE`]: a real hit of that
    /// triangle, not necessarily the nearest (what an occlusion query writes).
    pub fn any_hit(&self, ray: &Ray) -> Hit {
        self.trace(ray, Mode::Any)
    }

    /// [`CpuBvh::any_hit`] of every ray, in parallel.
    pub fn any_hits(&self, rays: &[Ray]) -> Vec<Hit> {
        rays.par_iter()
            .with_min_len(RAYS_PER_TASK)
            .map(|r| self.any_hit(r))
            .collect()
    }

    /// [`CpuBvh::closest_hit`] of every ray, in parallel.
    pub fn closest_hits(&self, rays: &[Ray]) -> Vec<Hit> {
        rays.par_iter()
            .with_min_len(RAYS_PER_TASK)
            .map(|r| self.closest_hit(r))
            .collect()
    }

    /// [`CpuBvh::occluded`] of every ray, in parallel.
    pub fn occluded_all(&self, rays: &[Ray]) -> Vec<bool> {
        rays.par_iter()
            .with_min_len(RAYS_PER_TASK)
            .map(|r| self.occluded(r))
            .collect()
    }

    fn trace(&self, ray: &Ray, mode: Mode) -> Hit {
        let origin = Vec3::from(ray.origin);
        let dir = Vec3::from(ray.dir);
        if self.nodes.is_empty()
            || !origin.is_finite()
            || !dir.is_finite()
            || ray.tmin.is_nan()
            || ray.tmax.is_nan()
        {
            return Hit::NONE;
        }
        // The stack holds at most one entry per level; a small one is cheaper to clear.
        if self.depth <= 16 {
            let stack = StackStack::<UVec2, 16>::default();
            self.traverse(stack, ray, origin, dir, mode)
        } else if self.depth as usize <= INLINE_STACK {
            let stack = StackStack::<UVec2, INLINE_STACK>::default();
            self.traverse(stack, ray, origin, dir, mode)
        } else {
            let stack = HeapStack::<UVec2>::new_with_capacity(self.depth as usize + 1);
            self.traverse(stack, ray, origin, dir, mode)
        }
    }

    #[inline(always)]
    fn traverse<S: FastStack<UVec2>>(
        &self,
        stack: S,
        ray: &Ray,
        origin: Vec3,
        dir: Vec3,
        mode: Mode,
    ) -> Hit {
        let box_ray = BoxRay {
            origin,
            inv_dir: dir.recip(),
            negative: [
                dir.x.is_sign_negative(),
                dir.y.is_sign_negative(),
                dir.z.is_sign_negative(),
            ],
            tmin: ray.tmin,
        };
        // Rays that miss the root box skip the rest (the stack's clearing is sunk past this).
        if !node::segment_meets(&box_ray, ray.tmax, self.bounds.0, self.bounds.1) {
            return Hit::NONE;
        }

        // Children are visited in the order of obvhs's octant (its convention: a set bit
        // for each non-negative component).
        let oct_inv4 = (if dir.x < 0.0 { 0 } else { 0x0404_0404 })
            | (if dir.y < 0.0 { 0 } else { 0x0202_0202 })
            | (if dir.z < 0.0 { 0 } else { 0x0101_0101 });
        let mut state = Traversal {
            stack,
            current_group: UVec2::new(0, 0x8000_0000),
            primitive_group: UVec2::ZERO,
            oct_inv4,
            primitive_id: 0,
            hitmask: 0,
        };
        let sheared = cpu::ShearedRay::new(origin, dir);
        let mut best = Hit::NONE;
        let mut node;
        'search: {
            obvhs::traverse!(
                self,
                node,
                state,
                node.intersect(&box_ray, ray.tmax.min(best.t), state.oct_inv4),
                {
                    let i = state.primitive_id as usize;
                    let (t, u, v) = sheared.intersect(ray.tmin, ray.tmax, &self.triangles[i]);
                    if t <= best.t && t.is_finite() {
                        let index = self.scene_index[i];
                        if t < best.t || index < best.triangle {
                            best = Hit {
                                t,
                                triangle: index,
                                u,
                                v,
                            };
                            if mode == Mode::Any {
                                break 'search;
                            }
                        }
                    }
                }
            );
        }
        best
    }
}

/// Rays per rayon task at least: enough to amortise a task, few enough to balance two
/// to hundreds of threads on a million rays.
const RAYS_PER_TASK: usize = 256;
