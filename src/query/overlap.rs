//! Box-pruned traversal and box overlap enumeration.

use std::ops::ControlFlow;

use crate::cursor::{ChildBoxes, Children, NodeCursor, TraversalStats};
use crate::geom::{Aabb, Triangle};

/// Visits every triangle of every leaf whose path of boxes all pass
/// `node_test`; `leaf_test(id, triangle)` may stop the visit early with
/// `ControlFlow::Break`. Returns whether it was stopped.
///
/// `node_test` sees one box at a time; [`visit_batch`] takes a test over a
/// node's children at once.
pub fn visit<C: NodeCursor>(
    c: &C,
    stats: &mut TraversalStats,
    mut node_test: impl FnMut(&Aabb) -> bool,
    leaf_test: impl FnMut(u32, &Triangle) -> ControlFlow<()>,
) -> bool {
    visit_batch(
        c,
        stats,
        |b| {
            let mut m = 0;
            for i in 0..b.len() {
                m |= u32::from(node_test(&b.get(i))) << i;
            }
            m
        },
        leaf_test,
    )
}

/// [`visit`] with a node test over a batch of boxes: `node_test(boxes)`
/// returns the mask of the lanes that pass (see [`ChildBoxes`]; bits of
/// padding lanes are ignored). The root is tested as a batch of one.
/// Children are visited in child order, the last pushed first.
pub fn visit_batch<C: NodeCursor>(
    c: &C,
    stats: &mut TraversalStats,
    mut node_test: impl FnMut(&ChildBoxes) -> u32,
    mut leaf_test: impl FnMut(u32, &Triangle) -> ControlFlow<()>,
) -> bool {
    let (root, root_box) = c.root();
    stats.nodes_visited += 1;
    let root_batch = ChildBoxes::from_boxes(&[root_box]);
    if node_test(&root_batch) & 1 == 0 {
        return false;
    }
    let mut stack = super::Stack::new();
    stack.push(root);
    let mut batch = Children::new(root);
    while let Some(node) = stack.pop() {
        if c.is_leaf(&node) {
            let mut stop = false;
            c.for_each_triangle(&node, |id, tri| {
                if !stop {
                    stats.primitive_tests += 1;
                    stop = leaf_test(id, tri).is_break();
                }
            });
            if stop {
                return true;
            }
            continue;
        }
        c.children(&node, &mut batch);
        let boxes = batch.boxes();
        stats.nodes_visited += boxes.len() as u64;
        let mask = node_test(boxes) & boxes.lanes();
        boxes.for_each_in(mask, |i| stack.push(batch.node(i)));
    }
    false
}

/// Calls `f` with each triangle whose tight box intersects `query`
/// (touching counts). `f` may stop early; returns whether it did.
pub fn overlap<C: NodeCursor>(
    c: &C,
    query: &Aabb,
    stats: &mut TraversalStats,
    mut f: impl FnMut(u32, &Triangle) -> ControlFlow<()>,
) -> bool {
    visit_batch(
        c,
        stats,
        |b| b.overlaps(query),
        |id, tri| {
            if Aabb::of_triangle(tri).intersects(query) {
                f(id, tri)
            } else {
                ControlFlow::Continue(())
            }
        },
    )
}
