//! Building a [`CpuBvh`]: obvhs builds and collapses the tree; splitray then stores each
//! child's exact box (see the module docs of `cpu_bvh` for why).

use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::PlocBuilder;
use obvhs::BvhBuildParams;

use super::node::{Child, WideNode};
use super::CpuBvh;
use crate::trace::GpuTriangle;

/// Builds the tree with `params` (obvhs presets).
pub(super) fn build(triangles: &[GpuTriangle], params: BvhBuildParams) -> CpuBvh {
    let kept: Vec<u32> = (0..triangles.len() as u32)
        .filter(|&i| is_hittable(&triangles[i as usize]))
        .collect();
    let empty = CpuBvh {
        triangle_count: triangles.len(),
        ..CpuBvh::default()
    };
    if kept.is_empty() {
        return empty;
    }
    let bounds: Vec<(Vec3, Vec3)> = kept
        .iter()
        .map(|&i| triangles[i as usize].bounds())
        .collect();
    let aabbs: Vec<Aabb> = bounds
        .iter()
        .map(|(lo, hi)| Aabb::new(lo.to_array().into(), hi.to_array().into()))
        .collect();
    let cwbvh = build_cwbvh(&aabbs, &params);
    if cwbvh.nodes.is_empty() {
        return empty;
    }
    let order = &cwbvh.primitive_indices;
    let leaf_bounds: Vec<(Vec3, Vec3)> = order.iter().map(|&p| bounds[p as usize]).collect();
    let scene_index: Vec<u32> = order.iter().map(|&p| kept[p as usize]).collect();
    let mut nodes: Vec<WideNode> = cwbvh.nodes.iter().map(WideNode::from_compressed).collect();
    let pad = box_padding(&leaf_bounds);
    let (depth, (lo, hi)) = set_exact_boxes(&mut nodes, &leaf_bounds, pad);
    CpuBvh {
        nodes,
        triangles: scene_index.iter().map(|&i| triangles[i as usize]).collect(),
        scene_index,
        triangle_count: triangles.len(),
        depth,
        bounds: (lo - pad, hi + pad),
    }
}

/// Whether a triangle goes into the tree: not degenerate by the scene's own test
/// ([`crate::scene::Triangle::is_degenerate`]: non-finite, or an area within f32
/// precision of zero relative to its edges). A degenerate triangle has no normal to shade
/// with, so it is never hit, although the triangle test can return a hit on one by
/// rounding (its determinant, a sum of three rounded edge functions, need not be zero).
pub fn is_hittable(t: &GpuTriangle) -> bool {
    let (e1, e2) = (t.e1(), t.e2());
    let c = e1.cross(e2);
    let e = e1.length_squared().max(e2.length_squared());
    t.v0().is_finite() && c.is_finite() && c.length() > e * 1e-7
}

/// obvhs's `build_cwbvh` less its debug-build validation, which rejects trees deeper than
/// its own traversal stack (32 levels; thousands of coincident triangles go deeper):
/// splitray's traversal sizes its stack to the tree.
fn build_cwbvh(aabbs: &[Aabb], params: &BvhBuildParams) -> CwBvh {
    let indices = (0..aabbs.len() as u32).collect();
    let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
        params.ploc_search_distance,
        aabbs,
        indices,
        params.sort_precision,
        params.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false)
}

/// Outward padding of every child box: a small fraction of the scene's size plus a few
/// ulps of its coordinates (the triangles' vertices v0 + e1, v0 + e2 are rounded).
fn box_padding(bounds: &[(Vec3, Vec3)]) -> f32 {
    let (lo, hi) = bounds
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (l, h)| {
            (lo.min(*l), hi.max(*h))
        });
    let size = (hi - lo).max_element();
    let magnitude = lo.abs().max(hi.abs()).max_element();
    if size.is_finite() {
        1e-5 * size + 1e-6 * magnitude + f32::MIN_POSITIVE
    } else {
        0.0
    }
}

/// Replaces every child's quantised box by the exact union of its triangles' boxes,
/// padded by `pad`, and returns the tree's depth in node levels and the root's box. Children always come
/// after their parent in obvhs's node order, so one backwards pass sees every child
/// before its parent.
fn set_exact_boxes(
    nodes: &mut [WideNode],
    leaf_bounds: &[(Vec3, Vec3)],
    pad: f32,
) -> (u32, (Vec3, Vec3)) {
    let mut node_bounds = vec![(Vec3::INFINITY, Vec3::NEG_INFINITY); nodes.len()];
    let mut depth = vec![1u32; nodes.len()];
    for n in (0..nodes.len()).rev() {
        let mut union = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let node = nodes[n];
        for (slot, child) in node.children() {
            let (lo, hi) = match child {
                Child::Leaf { start, count } => leaf_bounds
                    [start as usize..(start + count) as usize]
                    .iter()
                    .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (l, h)| {
                        (lo.min(*l), hi.max(*h))
                    }),
                Child::Node(c) => {
                    let c = c as usize;
                    debug_assert!(c > n, "obvhs stores children after their parent");
                    depth[n] = depth[n].max(depth[c] + 1);
                    node_bounds[c]
                }
            };
            nodes[n].set_child_box(slot, lo - pad, hi + pad);
            union = (union.0.min(lo), union.1.max(hi));
        }
        node_bounds[n] = union;
    }
    (depth[0], node_bounds[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Triangle;

    #[test]
    fn hittable_is_the_scene_s_non_degenerate() {
        let v = Vec3::new;
        let cases = [
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)],
            [v(0.3, 0.3, 0.3); 3],
            [v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0), v(0.5, 0.5, 0.5)],
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, 1e-9, 0.0)],
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, 1e-6, 0.0)],
            [
                v(0.0, 0.0, 0.0),
                v(f32::INFINITY, 0.0, 0.0),
                v(0.0, 1.0, 0.0),
            ],
            [v(1e20, 0.0, 0.0), v(1e20, 1.0, 0.0), v(1e20, 0.0, 1.0)],
        ];
        for p in cases {
            let scene = Triangle::new(p[0], p[1], p[2], 0);
            assert_eq!(
                is_hittable(&GpuTriangle::new(p)),
                !scene.is_degenerate(),
                "{p:?}"
            );
        }
    }
}
