//! Collapsing the binary canonical tree into an 8-wide one.
//!
//! Two passes, neither recursive:
//!
//! 1. Bottom up (canonical nodes in reverse layout order: every layout puts
//!    a parent before its children), the surface area heuristic decides for
//!    each subtree of at most `M` triangles whether it is cheaper as one
//!    leaf (`C_tri · A · n`) or split (`C_node · A + cost(left) +
//!    cost(right)`), and remembers the cheaper cost.
//! 2. Top down, a wide node's children are chosen greedily: start from the
//!    binary node's two children and keep opening the child with the largest
//!    surface area that the SAH wants split, until there are eight or none
//!    is left to open. Opening the largest box first is what minimises the
//!    SAH of the wide node among greedy choices (the largest child is the one
//!    a ray is most likely to enter).

use crate::build::CanonicalBvh;

/// Cost of a triangle test in the SAH, relative to one binary level of box
/// tests. An 8-wide node tests all its boxes at once, so a binary level
/// costs about a third of an 8-wide node; a scalar watertight triangle test
/// costs about as much as that.
pub const TRIANGLE_COST: f32 = 1.0;
/// Cost of one binary level of box tests in the SAH.
pub const NODE_COST: f32 = 1.0;

/// Per canonical node: triangle count and whether the SAH makes the whole
/// subtree one leaf.
pub(super) struct Plan {
    /// Triangles below each canonical node.
    pub count: Vec<u32>,
    /// Whether each canonical node becomes one wide leaf.
    pub as_leaf: Vec<bool>,
    /// Half surface area of each canonical node's box.
    pub area: Vec<f32>,
}

impl Plan {
    /// The plan for `bvh` with leaves of at most `max_leaf` triangles.
    /// Canonical leaves are leaves whatever their size.
    pub fn new(bvh: &CanonicalBvh, max_leaf: usize) -> Plan {
        let n = bvh.nodes.len();
        let mut count = vec![0u32; n];
        let mut as_leaf = vec![false; n];
        let mut cost = vec![0f32; n];
        let area: Vec<f32> = bvh.nodes.iter().map(|c| c.aabb().half_area()).collect();
        for i in (0..n).rev() {
            let node = &bvh.nodes[i];
            if node.is_leaf() {
                count[i] = node.leaf_range().len() as u32;
                as_leaf[i] = true;
                cost[i] = TRIANGLE_COST * area[i] * count[i] as f32;
                continue;
            }
            let [l, r] = node.children().map(|c| c as usize);
            count[i] = count[l] + count[r];
            let split = NODE_COST * area[i] + cost[l] + cost[r];
            let leaf = TRIANGLE_COST * area[i] * count[i] as f32;
            as_leaf[i] = count[i] as usize <= max_leaf && leaf <= split;
            cost[i] = if as_leaf[i] { leaf } else { split };
        }
        Plan {
            count,
            as_leaf,
            area,
        }
    }

    /// The (at most 8) canonical nodes that become the children of a wide
    /// node standing for canonical inner node `root`, in left-to-right
    /// order.
    pub fn children(&self, bvh: &CanonicalBvh, root: u32) -> Vec<u32> {
        let mut kids = bvh.nodes[root as usize].children().to_vec();
        while kids.len() < 8 {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, c)| !self.as_leaf[**c as usize])
                .max_by(|a, b| self.area[*a.1 as usize].total_cmp(&self.area[*b.1 as usize]))
                .map(|(k, _)| k);
            let Some(k) = open else { break };
            let [l, r] = bvh.nodes[kids[k] as usize].children();
            kids[k] = l;
            kids.insert(k + 1, r);
        }
        kids
    }
}

/// The original triangle ids below canonical node `root`, leaf by leaf from
/// left to right.
pub(super) fn triangles_below(bvh: &CanonicalBvh, root: u32, out: &mut Vec<u32>) {
    let mut stack = vec![root];
    while let Some(i) = stack.pop() {
        let n = &bvh.nodes[i as usize];
        if n.is_leaf() {
            out.extend_from_slice(&bvh.leaf_triangles[n.leaf_range()]);
        } else {
            stack.push(n.b);
            stack.push(n.a);
        }
    }
}
