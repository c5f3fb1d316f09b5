//! Ray queries: closest hit and any hit.

use super::{RayCursor, Stack, far_first};
use crate::cursor::{Children, MAX_CHILDREN, NodeCursor, TraversalStats};
use crate::geom::{Ray, SLAB_EXIT_SCALE, TriHit, Triangle, ray_triangle};

pub use crate::geom::RayHit;

/// Keeps hit `h` on triangle `id` if it is closer than `best` (nearer, or
/// as near on a smaller triangle id: the tie rule that makes the result
/// independent of the order triangles are tested in), updating `best_t`.
/// Returns whether it was kept.
#[inline]
pub(crate) fn keep_closer(
    best: &mut Option<RayHit>,
    best_t: &mut f32,
    id: u32,
    h: &TriHit,
) -> bool {
    let closer = h.t < *best_t || best.is_none_or(|b| h.t == b.t && id < b.triangle);
    if closer {
        *best_t = h.t;
        *best = Some(RayHit {
            t: h.t,
            triangle: id,
            u: h.u,
            v: h.v,
        });
    }
    closer
}

/// The closest hit of `ray` within `[0, t_max]`, with the two-sided
/// watertight triangle test ([`ray_triangle`]): the cursor's own traversal
/// ([`RayCursor::closest_hit`]) where it has one, else
/// [`closest_hit_generic`]. Every codec gives the same hit.
#[inline]
pub fn closest_hit<C: RayCursor>(
    c: &C,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
) -> Option<RayHit> {
    c.closest_hit(ray, t_max, stats)
}

/// [`closest_hit`] through the generic traversal over the cursor's
/// batches, whatever the codec: the default of
/// [`RayCursor::closest_hit`], and the reference a codec's own traversal
/// is tested against.
pub fn closest_hit_generic<C: NodeCursor>(
    c: &C,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
) -> Option<RayHit> {
    closest_hit_with(c, ray, t_max, stats, |_, tri, t_max| {
        ray_triangle(ray, tri, t_max)
    })
}

/// The closest hit with a caller-given primitive test `test(id, triangle,
/// t_max)`, which returns a hit no farther than `t_max` or `None`.
pub fn closest_hit_with<C: NodeCursor>(
    c: &C,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
    mut test: impl FnMut(u32, &Triangle, f32) -> Option<TriHit>,
) -> Option<RayHit> {
    let (root, root_box) = c.root();
    stats.nodes_visited += 1;
    let t0 = ray.intersect_aabb(&root_box, t_max)?;
    let mut best: Option<RayHit> = None;
    let mut best_t = t_max;
    let mut stack = Stack::new();
    stack.push((root, t0));
    let mut batch = Children::new(root);
    let mut kids: [(f32, C::Node); MAX_CHILDREN] = [(0.0, root); MAX_CHILDREN];
    while let Some((node, t_enter)) = stack.pop() {
        if t_enter > best_t * SLAB_EXIT_SCALE {
            continue;
        }
        if c.is_leaf(&node) {
            c.for_each_triangle(&node, |id, tri| {
                stats.primitive_tests += 1;
                if let Some(h) = test(id, tri, best_t) {
                    keep_closer(&mut best, &mut best_t, id, &h);
                }
            });
            continue;
        }
        c.children(&node, &mut batch);
        let boxes = batch.boxes();
        stats.nodes_visited += boxes.len() as u64;
        let (mask, t) = boxes.slab(ray, best_t);
        let mut n = 0;
        boxes.for_each_in(mask, |i| {
            kids[n] = (t[i], batch.node(i));
            n += 1;
        });
        // Push far children first so the nearest is popped next (children
        // at equal distance in child order, as before batches).
        let kids = &mut kids[..n];
        far_first(kids);
        for &(t, k) in kids.iter() {
            stack.push((k, t));
        }
    }
    best
}

/// Whether `ray` hits any triangle within `[0, t_max]` (shadow rays): the
/// cursor's own traversal ([`RayCursor::any_hit`]) where it has one, else
/// [`any_hit_generic`].
#[inline]
pub fn any_hit<C: RayCursor>(c: &C, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool {
    c.any_hit(ray, t_max, stats)
}

/// [`any_hit`] through the generic traversal (the default of
/// [`RayCursor::any_hit`]).
pub fn any_hit_generic<C: NodeCursor>(
    c: &C,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
) -> bool {
    any_hit_with(c, ray, t_max, stats, |_, tri| {
        ray_triangle(ray, tri, t_max).is_some()
    })
}

/// Any hit with a caller-given primitive test.
pub fn any_hit_with<C: NodeCursor>(
    c: &C,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
    mut test: impl FnMut(u32, &Triangle) -> bool,
) -> bool {
    let (root, root_box) = c.root();
    stats.nodes_visited += 1;
    if ray.intersect_aabb(&root_box, t_max).is_none() {
        return false;
    }
    let mut stack = Stack::new();
    stack.push(root);
    let mut batch = Children::new(root);
    while let Some(node) = stack.pop() {
        if c.is_leaf(&node) {
            let mut hit = false;
            c.for_each_triangle(&node, |id, tri| {
                if !hit {
                    stats.primitive_tests += 1;
                    hit = test(id, tri);
                }
            });
            if hit {
                return true;
            }
            continue;
        }
        // Children in child order (the last one is popped first, as
        // before batches).
        c.children(&node, &mut batch);
        let boxes = batch.boxes();
        stats.nodes_visited += boxes.len() as u64;
        let (mask, _) = boxes.slab(ray, t_max);
        boxes.for_each_in(mask, |i| stack.push(batch.node(i)));
    }
    false
}
