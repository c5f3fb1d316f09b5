//! Node layouts: the order in which a tree's nodes are stored.
//!
//! Each layout computes an order of the reachable build nodes (root first),
//! then the nodes are copied into that order with child indices remapped and
//! parents recorded.
//!
//! - **Depth-first**: pre-order, left child right after its parent.
//! - **van Emde Boas**: a subtree of height `h` is laid out as its top
//!   `⌊h/2⌋` levels (recursively), then each subtree hanging below them, left
//!   to right (recursively). Heights are those of the actual, unbalanced
//!   subtrees.
//! - **Cache-efficient** (Yoon & Manocha 2006, "Cache-efficient layouts of
//!   bounding volume hierarchies"; RACBVH §4.1, Table 3). Yoon & Manocha model
//!   the probability that a child is visited when its parent is as the ratio
//!   of their surface areas, so the probability of reaching node `n` from a
//!   cluster root `r` is `area(n) / area(r)`. They grow clusters of a cache
//!   block's worth of nodes greedily by that probability, and nest the
//!   decomposition for several block sizes. **Our simplification** keeps two
//!   levels, which is what cbvh's consumers have: outer clusters of
//!   [`CACHE_EFFICIENT_BLOCKS`]`.0` nodes (4096, RACBVH's default cluster, a
//!   few pages of plain nodes), each laid out as inner clusters of
//!   [`CACHE_EFFICIENT_BLOCKS`]`.1` nodes (16 plain nodes = 512 bytes, eight
//!   cache lines). Within an inner cluster nodes are stored in the greedy
//!   order (most probable first, so a parent always precedes its children);
//!   the frontier left when a cluster is full becomes the roots of the next
//!   clusters, visited depth-first, most probable first. Yoon & Manocha's
//!   full cache-oblivious recursion over all block sizes is left out: two
//!   levels already match the two granularities (cache line, RACBVH cluster)
//!   that cbvh's traversals touch.

use std::collections::BinaryHeap;

use super::sah::BuiltTree;
use super::{BuildOptions, CanonicalBvh, CanonicalNode, Layout};

/// `(outer, inner)` cluster sizes in nodes of the cache-efficient layout.
pub const CACHE_EFFICIENT_BLOCKS: (usize, usize) = (4096, 16);

pub(super) fn apply(
    built: BuiltTree,
    options: &BuildOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> CanonicalBvh {
    let BuiltTree {
        nodes: old,
        leaf_triangles,
    } = built;
    let order = match options.layout {
        Layout::DepthFirst => depth_first(&old),
        Layout::VanEmdeBoas => van_emde_boas(&old),
        Layout::CacheEfficient => cache_efficient(&old),
    };
    let total = order.len() as u64;
    progress(total / 2, total);
    let mut new_index = vec![u32::MAX; old.len()];
    for (new, &o) in order.iter().enumerate() {
        new_index[o as usize] = new as u32;
    }
    let mut nodes = Vec::with_capacity(order.len());
    let mut parents = vec![u32::MAX; order.len()];
    for (new, &o) in order.iter().enumerate() {
        let mut n = old[o as usize];
        if !n.is_leaf() {
            n.a = new_index[n.a as usize];
            n.b = new_index[n.b as usize];
            parents[n.a as usize] = new as u32;
            parents[n.b as usize] = new as u32;
        }
        nodes.push(n);
    }
    progress(total, total);
    CanonicalBvh {
        nodes,
        parents,
        leaf_triangles,
        layout: options.layout,
        max_leaf_triangles: options.max_leaf_triangles,
    }
}

fn depth_first(nodes: &[CanonicalNode]) -> Vec<u32> {
    let mut order = Vec::with_capacity(nodes.len());
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        order.push(i);
        let n = &nodes[i as usize];
        if !n.is_leaf() {
            stack.push(n.b);
            stack.push(n.a);
        }
    }
    order
}

/// Heights of all reachable nodes (leaf = 1), by a reverse pre-order sweep.
fn heights(nodes: &[CanonicalNode]) -> Vec<u32> {
    let pre = depth_first(nodes);
    let mut h = vec![0u32; nodes.len()];
    for &i in pre.iter().rev() {
        let n = &nodes[i as usize];
        h[i as usize] = if n.is_leaf() {
            1
        } else {
            1 + h[n.a as usize].max(h[n.b as usize])
        };
    }
    h
}

fn van_emde_boas(nodes: &[CanonicalNode]) -> Vec<u32> {
    let h = heights(nodes);
    let mut order = Vec::with_capacity(nodes.len());
    let mut frontier = Vec::new();
    veb(nodes, &h, 0, h[0], &mut order, &mut frontier);
    order
}

/// Lays out the first `levels` levels of the subtree at `root`.
fn veb(
    nodes: &[CanonicalNode],
    h: &[u32],
    root: u32,
    levels: u32,
    order: &mut Vec<u32>,
    scratch: &mut Vec<u32>,
) {
    let levels = levels.min(h[root as usize]);
    if levels <= 2 {
        // One or two levels: pre-order is the vEB order.
        let mut stack = vec![(root, 1u32)];
        while let Some((i, d)) = stack.pop() {
            order.push(i);
            let n = &nodes[i as usize];
            if d < levels && !n.is_leaf() {
                stack.push((n.b, d + 1));
                stack.push((n.a, d + 1));
            }
        }
        return;
    }
    let top = levels / 2;
    veb(nodes, h, root, top, order, scratch);
    // Roots of the bottom subtrees: nodes at relative depth `top`, left to right.
    let start = scratch.len();
    let mut stack = vec![(root, 0u32)];
    while let Some((i, d)) = stack.pop() {
        let n = &nodes[i as usize];
        if d == top {
            scratch.push(i);
        } else if !n.is_leaf() {
            stack.push((n.b, d + 1));
            stack.push((n.a, d + 1));
        }
    }
    let end = scratch.len();
    for k in start..end {
        let r = scratch[k];
        veb(nodes, h, r, levels - top, order, scratch);
    }
    scratch.truncate(start);
}

#[derive(PartialEq)]
struct Prob(f32, u32);
impl Eq for Prob {}
impl PartialOrd for Prob {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Prob {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        // Highest probability first; ties by lower index (deterministic).
        self.0.total_cmp(&o.0).then(o.1.cmp(&self.1))
    }
}

/// Greedily grows a cluster of at most `size` nodes from `root`, restricted
/// to nodes accepted by `allowed`. Returns the cluster in greedy order and
/// appends the leftover frontier (most probable first) to `frontier`.
fn grow(
    nodes: &[CanonicalNode],
    root: u32,
    size: usize,
    allowed: impl Fn(u32) -> bool,
    cluster: &mut Vec<u32>,
    frontier: &mut Vec<u32>,
) {
    let area = |i: u32| nodes[i as usize].aabb().half_area();
    let root_area = area(root).max(f32::MIN_POSITIVE);
    let mut heap = BinaryHeap::new();
    heap.push(Prob(1.0, root));
    while cluster.len() < size {
        let Some(Prob(_, i)) = heap.pop() else { break };
        cluster.push(i);
        let n = &nodes[i as usize];
        if !n.is_leaf() {
            for c in n.children() {
                if allowed(c) {
                    heap.push(Prob(area(c) / root_area, c));
                }
            }
        }
    }
    frontier.extend(heap.into_sorted_vec().into_iter().rev().map(|p| p.1));
}

fn cache_efficient(nodes: &[CanonicalNode]) -> Vec<u32> {
    let (outer, inner) = CACHE_EFFICIENT_BLOCKS;
    let mut order = Vec::with_capacity(nodes.len());
    // Which outer cluster each node belongs to (u32::MAX: not yet assigned).
    let mut member = vec![u32::MAX; nodes.len()];
    let mut outer_roots = vec![0u32];
    let mut cluster = Vec::with_capacity(outer);
    let mut outer_frontier = Vec::new();
    let mut inner_cluster = Vec::with_capacity(inner);
    let mut inner_frontier = Vec::new();
    let mut cluster_id = 0u32;
    while let Some(root) = outer_roots.pop() {
        cluster.clear();
        outer_frontier.clear();
        grow(
            nodes,
            root,
            outer,
            |_| true,
            &mut cluster,
            &mut outer_frontier,
        );
        for &i in &cluster {
            member[i as usize] = cluster_id;
        }
        // Lay out this outer cluster as inner clusters, depth-first.
        let mut inner_roots = vec![root];
        while let Some(r) = inner_roots.pop() {
            inner_cluster.clear();
            inner_frontier.clear();
            grow(
                nodes,
                r,
                inner,
                |c| member[c as usize] == cluster_id,
                &mut inner_cluster,
                &mut inner_frontier,
            );
            order.extend_from_slice(&inner_cluster);
            // Push least probable first so the most probable pops next.
            inner_roots.extend(inner_frontier.iter().rev());
        }
        outer_roots.extend(outer_frontier.iter().rev());
        cluster_id += 1;
    }
    order
}
