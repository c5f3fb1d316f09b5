//! [`PlainBvh::verify`]: the second validation tier, proving what every
//! query relies on.

use super::{PlainBvh, PlainError};
use crate::codec::common::root_matches;
use crate::geom::Aabb;

impl PlainBvh {
    /// Proves what every query relies on, in O(nodes + triangles) without
    /// recursion: every node but the root has exactly one parent (children
    /// in range, no repeats, no cycles, none unreachable), child boxes lie
    /// inside their parent's, leaves hold valid triangle ids (each triangle
    /// in exactly one leaf) and their boxes contain their triangles, vertex
    /// indices are in range and vertices finite, and the root's box is the
    /// triangles' bounds (not looser).
    pub fn verify(&self) -> Result<(), PlainError> {
        let bad = |node: usize, what| PlainError::Corrupt {
            node: node as u64,
            what,
        };
        let (nn, nt, nv) = (self.nodes.len(), self.triangles.len(), self.vertices.len());
        if nn == 0 {
            return Err(bad(0, "the tree has no nodes"));
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            if tri.iter().any(|&i| i as usize >= nv) {
                return Err(bad(t, "triangle refers to a missing vertex"));
            }
        }
        if let Some(v) = self
            .vertices
            .iter()
            .position(|v| v.iter().any(|c| !c.is_finite()))
        {
            return Err(bad(v, "vertex has a non-finite coordinate"));
        }
        let single = self.leaf_ids.is_empty();
        if nt == 0 {
            // The empty tree: one leaf without triangles.
            let r = &self.nodes[0];
            return if nn == 1 && r.is_leaf() && r.leaf_count() == 0 {
                Ok(())
            } else {
                Err(bad(0, "a tree without triangles must be one empty leaf"))
            };
        }
        let mut seen_node = vec![false; nn];
        let mut seen_tri = vec![false; nt];
        seen_node[0] = true;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i];
            let b = n.aabb();
            let finite = n.min.iter().chain(&n.max).all(|c| c.is_finite());
            if !finite || (0..3).any(|a| n.min[a] > n.max[a]) {
                return Err(bad(i, "its box is not finite or inverted"));
            }
            if n.is_leaf() {
                let count = n.leaf_count() as usize;
                let ids: &[u32] = if single {
                    if count != 1 {
                        return Err(bad(i, "a leaf must hold one triangle"));
                    }
                    std::slice::from_ref(&n.left)
                } else {
                    let first = n.left as usize;
                    if count == 0 {
                        return Err(bad(i, "a leaf holds no triangle"));
                    }
                    self.leaf_ids
                        .get(first..first + count)
                        .ok_or_else(|| bad(i, "a leaf's triangle slots are out of range"))?
                };
                for &t in ids {
                    let seen = seen_tri
                        .get_mut(t as usize)
                        .ok_or_else(|| bad(i, "a leaf names a missing triangle"))?;
                    if std::mem::replace(seen, true) {
                        return Err(bad(i, "a triangle is in two leaves"));
                    }
                    let tri = self.triangles[t as usize];
                    if tri
                        .iter()
                        .any(|&v| !b.contains_point(self.vertices[v as usize].into()))
                    {
                        return Err(bad(i, "a leaf's box does not contain its triangle"));
                    }
                }
            } else {
                for c in [n.left, n.right] {
                    let c = c as usize;
                    let slot = seen_node
                        .get_mut(c)
                        .ok_or_else(|| bad(i, "a child index is out of range"))?;
                    if std::mem::replace(slot, true) {
                        return Err(bad(i, "a child has two parents, or the tree has a cycle"));
                    }
                    if !b.contains(&self.nodes[c].aabb()) {
                        return Err(bad(c, "its box is not inside its parent's"));
                    }
                    stack.push(c);
                }
            }
        }
        if let Some(i) = seen_node.iter().position(|s| !s) {
            return Err(bad(i, "no node names it as a child"));
        }
        if let Some(t) = seen_tri.iter().position(|s| !s) {
            return Err(bad(t, "triangle is in no leaf"));
        }
        let mut bounds = Aabb::EMPTY;
        for tri in &self.triangles {
            for &v in tri {
                bounds.grow(self.vertices[v as usize].into());
            }
        }
        if !root_matches(&self.nodes[0].aabb(), &bounds, [0.0; 3]) {
            return Err(bad(0, "the root's box is not its triangles' bounds"));
        }
        Ok(())
    }
}
