//! i-HCCMesh's own ray traversal, behind
//! [`RayCursor::closest_hit`](crate::query::RayCursor::closest_hit) and
//! [`RayCursor::any_hit`](crate::query::RayCursor::any_hit).
//!
//! The generic traversal ([`closest_hit_generic`](crate::query::ray::closest_hit_generic))
//! writes every expanded pair into a batch, copies the hit children into a
//! list, sorts it and pushes both onto the stack, to pop the nearer one
//! right away. An i-HCCMesh node handle carries its decoded box (48
//! bytes when this was written, 32 now), so those copies cost more here
//! than the box tests. This
//! traversal decodes a pair ([`HccBvh::children_of`]), tests both boxes
//! and descends into the nearer child directly; only the farther one goes
//! onto the stack. The box test ([`Ray::intersect_aabb`]), the culling
//! against the best hit, the tie rule ([`keep_closer`]) and the order
//! nodes are visited in (the nearer child first, the right one on a tie)
//! are the generic traversal's, so the hit is the same, bit for bit. The
//! order matters on degenerate triangles (a collinear grid): there the
//! first of two traversal orders to reach a hit can cull the other's.
//! `tests/suite/hcc.rs` and `tests/suite/hcc_ooc.rs` (paged trees) check both against
//! each other.
//!
//! `peers` (1 M statue, 512² camera rays, one thread, AMD EPYC): 3.61 M
//! rays/s through the generic traversal, 4.67 through this one (plain
//! 6.15: from 0.64× to 0.76× plain's).

use super::node::HccNode;
use crate::cursor::{NodeCursor, TraversalStats};
use crate::geom::{Aabb, Ray, SLAB_EXIT_SCALE, ray_triangle};
use crate::query::Stack;
use crate::query::ray::{RayHit, keep_closer};

/// The children of an inner node with their boxes: [`HccBvh::children_of`](super::HccBvh::children_of)
/// for a whole i-HCCMesh, the paged one's for an out-of-core one.
pub(super) trait Pairs {
    /// The two children of inner node `node`.
    fn pair(&self, node: &HccNode) -> [(HccNode, Aabb); 2];
}

/// The closest hit of `ray` within `[0, t_max]` in `h`, whose inner nodes
/// `pairs` expands (see the module docs).
pub(super) fn closest_hit<C: NodeCursor<Node = HccNode>>(
    h: &C,
    pairs: &impl Pairs,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
) -> Option<RayHit> {
    let (root, root_box) = h.root();
    stats.nodes_visited += 1;
    let mut t_enter = ray.intersect_aabb(&root_box, t_max)?;
    let mut best: Option<RayHit> = None;
    let mut best_t = t_max;
    let mut stack: Stack<(f32, HccNode)> = Stack::new();
    let mut node = root;
    loop {
        // Culled as the generic traversal culls a popped node (a NaN
        // limit culls nothing).
        let culled = t_enter > best_t * SLAB_EXIT_SCALE;
        if !culled {
            if h.is_leaf(&node) {
                h.for_each_triangle(&node, |id, tri| {
                    stats.primitive_tests += 1;
                    if let Some(hit) = ray_triangle(ray, tri, best_t) {
                        keep_closer(&mut best, &mut best_t, id, &hit);
                    }
                });
            } else {
                let [(a, ba), (b, bb)] = pairs.pair(&node);
                stats.nodes_visited += 2;
                match (
                    ray.intersect_aabb(&ba, best_t),
                    ray.intersect_aabb(&bb, best_t),
                ) {
                    (Some(ta), Some(tb)) => {
                        // The nearer first; the right one on a tie, as
                        // the generic traversal pops them.
                        let ((tn, near), (tf, far)) = if tb <= ta {
                            ((tb, b), (ta, a))
                        } else {
                            ((ta, a), (tb, b))
                        };
                        stack.push((tf, far));
                        (t_enter, node) = (tn, near);
                        continue;
                    }
                    (Some(ta), None) => {
                        (t_enter, node) = (ta, a);
                        continue;
                    }
                    (None, Some(tb)) => {
                        (t_enter, node) = (tb, b);
                        continue;
                    }
                    (None, None) => {}
                }
            }
        }
        match stack.pop() {
            Some((t, n)) => (t_enter, node) = (t, n),
            None => return best,
        }
    }
}

/// Whether `ray` hits a triangle within `[0, t_max]` in `h`, whose inner
/// nodes `pairs` expands (see the module docs); children are taken in
/// child order, as the generic traversal takes them.
pub(super) fn any_hit<C: NodeCursor<Node = HccNode>>(
    h: &C,
    pairs: &impl Pairs,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
) -> bool {
    let (root, root_box) = h.root();
    stats.nodes_visited += 1;
    if ray.intersect_aabb(&root_box, t_max).is_none() {
        return false;
    }
    let mut stack: Stack<HccNode> = Stack::new();
    let mut node = root;
    loop {
        if h.is_leaf(&node) {
            let mut hit = false;
            h.for_each_triangle(&node, |_, tri| {
                if !hit {
                    stats.primitive_tests += 1;
                    hit = ray_triangle(ray, tri, t_max).is_some();
                }
            });
            if hit {
                return true;
            }
        } else {
            let [(a, ba), (b, bb)] = pairs.pair(&node);
            stats.nodes_visited += 2;
            match (
                ray.intersect_aabb(&ba, t_max).is_some(),
                ray.intersect_aabb(&bb, t_max).is_some(),
            ) {
                (true, true) => {
                    stack.push(a);
                    node = b;
                    continue;
                }
                (true, false) => {
                    node = a;
                    continue;
                }
                (false, true) => {
                    node = b;
                    continue;
                }
                (false, false) => {}
            }
        }
        match stack.pop() {
            Some(n) => node = n,
            None => return false,
        }
    }
}
