//! Best-first search: the leaf minimising a cost, with node costs as lower
//! bounds (for shape casts and other branch-and-bound queries).

use super::far_first;
use crate::cursor::{Children, MAX_CHILDREN, NodeCursor, TraversalStats};
use crate::geom::{Aabb, Triangle};

/// Finds the triangle with the smallest cost below `max_cost`.
///
/// `node_cost(box)` must be a lower bound of the cost of every triangle
/// below a node with that box (`f32::INFINITY`, or anything `>= max_cost`,
/// prunes it). `leaf(id, triangle, best_so_far)` returns the triangle's
/// cost and a payload if the cost is below `best_so_far`. Returns the best
/// triangle id, cost and payload.
pub fn find_best<C: NodeCursor, T>(
    c: &C,
    max_cost: f32,
    stats: &mut TraversalStats,
    mut node_cost: impl FnMut(&Aabb) -> f32,
    mut leaf: impl FnMut(u32, &Triangle, f32) -> Option<(f32, T)>,
) -> Option<(u32, f32, T)> {
    let (root, root_box) = c.root();
    stats.nodes_visited += 1;
    let c0 = node_cost(&root_box);
    // Written so that a NaN cost prunes too.
    if c0.is_nan() || c0 >= max_cost {
        return None;
    }
    let mut best_cost = max_cost;
    let mut best: Option<(u32, f32, T)> = None;
    let mut stack: Vec<(C::Node, f32)> = vec![(root, c0)];
    let mut batch = Children::new(root);
    let mut kids: [(f32, C::Node); MAX_CHILDREN] = [(0.0, root); MAX_CHILDREN];
    while let Some((node, cost)) = stack.pop() {
        if cost >= best_cost {
            continue;
        }
        if c.is_leaf(&node) {
            c.for_each_triangle(&node, |id, tri| {
                stats.primitive_tests += 1;
                if let Some((k, payload)) = leaf(id, tri, best_cost)
                    && k < best_cost
                {
                    best_cost = k;
                    best = Some((id, k, payload));
                }
            });
            continue;
        }
        // The cost is the caller's closure, so the batch is walked lane by
        // lane, in child order.
        c.children(&node, &mut batch);
        let boxes = batch.boxes();
        let mut n = 0;
        for i in 0..boxes.len() {
            stats.nodes_visited += 1;
            let k = node_cost(&boxes.get(i));
            if k < best_cost {
                kids[n] = (k, batch.node(i));
                n += 1;
            }
        }
        let kids = &mut kids[..n];
        far_first(kids);
        for &(k, node) in kids.iter() {
            stack.push((node, k));
        }
    }
    best
}
