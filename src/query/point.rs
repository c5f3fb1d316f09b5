//! Closest point of a mesh to a point.

use glam::Vec3A;

use super::far_first;
use crate::cursor::{Children, MAX_CHILDREN, NodeCursor, TraversalStats};
use crate::geom::closest_point_on_triangle;

/// The closest point found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointHit {
    /// Distance from the query point.
    pub distance: f32,
    /// The triangle the closest point lies on.
    pub triangle: u32,
    /// The closest point.
    pub point: Vec3A,
}

/// The point of the mesh closest to `p` among points within `max_dist`
/// (`f32::INFINITY` for no limit). Ties go to the lower triangle id.
pub fn closest_point<C: NodeCursor>(
    c: &C,
    p: Vec3A,
    max_dist: f32,
    stats: &mut TraversalStats,
) -> Option<PointHit> {
    let (root, root_box) = c.root();
    stats.nodes_visited += 1;
    let mut best_d2 = max_dist * max_dist;
    let d0 = root_box.distance_squared(p);
    if d0 > best_d2 {
        return None;
    }
    let mut best: Option<(f32, u32, Vec3A)> = None;
    let mut stack = super::Stack::new();
    stack.push((root, d0));
    let mut batch = Children::new(root);
    let mut kids: [(f32, C::Node); MAX_CHILDREN] = [(0.0, root); MAX_CHILDREN];
    while let Some((node, d2)) = stack.pop() {
        if d2 > best_d2 {
            continue;
        }
        if c.is_leaf(&node) {
            c.for_each_triangle(&node, |id, tri| {
                stats.primitive_tests += 1;
                let (q, _, _) = closest_point_on_triangle(p, tri);
                let dd = (q - p).length_squared();
                let better = dd < best_d2 || (dd == best_d2 && best.is_none_or(|b| id < b.1));
                if better {
                    best_d2 = dd;
                    best = Some((dd, id, q));
                }
            });
            continue;
        }
        c.children(&node, &mut batch);
        let boxes = batch.boxes();
        stats.nodes_visited += boxes.len() as u64;
        let d = boxes.distance_squared(p);
        let mut n = 0;
        boxes.for_each_in(boxes.lanes(), |i| {
            if d[i] <= best_d2 {
                kids[n] = (d[i], batch.node(i));
                n += 1;
            }
        });
        let kids = &mut kids[..n];
        far_first(kids);
        for &(d, k) in kids.iter() {
            stack.push((k, d));
        }
    }
    best.map(|(d2, triangle, point)| PointHit {
        distance: d2.sqrt(),
        triangle,
        point,
    })
}
