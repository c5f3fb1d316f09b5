//! Box-pruned traversal and box overlap enumeration.

use std::ops::ControlFlow;

use crate::cursor::{NodeCursor, TraversalStats};
use crate::geom::{Aabb, Triangle};

/// Visits every triangle of every leaf whose path of boxes all pass
/// `node_test`; `leaf_test(id, triangle)` may stop the visit early with
/// `ControlFlow::Break`. Returns whether it was stopped.
pub fn visit<C: NodeCursor>(
    c: &C,
    stats: &mut TraversalStats,
    mut node_test: impl FnMut(&Aabb) -> bool,
    mut leaf_test: impl FnMut(u32, &Triangle) -> ControlFlow<()>,
) -> bool {
    let (root, root_box) = c.root();
    stats.nodes_visited += 1;
    if !node_test(&root_box) {
        return false;
    }
    let mut stack = super::Stack::new(root);
    stack.push(root);
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
        c.for_each_child(&node, |child, b| {
            stats.nodes_visited += 1;
            if node_test(&b) {
                stack.push(child);
            }
        });
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
    visit(
        c,
        stats,
        |b| b.intersects(query),
        |id, tri| {
            if Aabb::of_triangle(tri).intersects(query) {
                f(id, tri)
            } else {
                ControlFlow::Continue(())
            }
        },
    )
}
