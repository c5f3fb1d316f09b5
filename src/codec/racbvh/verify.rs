//! [`RacBvh::verify`]: the second validation tier, proving everything a
//! query relies on.

use super::node::qbox_of;
use super::{RacBvh, RacError};
use crate::build::LEAF_FLAG;
use crate::codec::common::root_matches;
use crate::geom::Aabb;

impl RacBvh {
    /// Proves everything a query relies on: every cluster decodes and
    /// completes with a matching checksum; every node but the root has
    /// exactly one parent, and children come after their parent (so no
    /// repeats and no cycles: a query visits each node at most once); child
    /// boxes lie inside their parent's; every triangle id is in exactly one
    /// leaf and leaf boxes contain their triangles, the root's box is the
    /// triangles' bounds (within a step of the boxes' grid); the mesh
    /// sections'
    /// checksum matches and every vertex index is in range. Runs in
    /// O(nodes + triangles) without recursion; uses (and fills) the cache.
    pub fn verify(&self) -> Result<(), RacError> {
        let corrupt = |node: u32, what: &'static str| RacError::CorruptNode { node, what };
        self.check_mesh()?;
        let n = self.header.node_count;
        // Bit sets: a forged header's counts cannot make this allocate
        // more than the file (open checks a bit of cluster data per node).
        let mut seen = BitSet::new(self.header.triangle_count as usize);
        let mut has_parent = BitSet::new(n as usize);
        let mut bounds = Aabb::EMPTY;
        for g in 0..n {
            let w = self.try_words(g)?;
            if w[7] & LEAF_FLAG != 0 {
                let b = self.box_of(&w);
                let mut bad: Option<&'static str> = None;
                self.try_leaf_ids(g, &mut |id| {
                    if seen.set(id as usize) {
                        bad = bad.or(Some("a triangle id appears in two leaves"));
                    }
                    let t = self.mesh.triangle(id);
                    for &v in &t {
                        bounds.grow(v);
                    }
                    if !self.header.empty && t.iter().any(|&v| !b.contains_point(v)) {
                        bad = bad.or(Some("the leaf's box does not contain its triangle"));
                    }
                })?;
                if let Some(what) = bad {
                    return Err(corrupt(g, what));
                }
            } else {
                let pq = qbox_of(&w);
                for c in [w[6], w[7]] {
                    if c <= g || c >= n {
                        return Err(corrupt(g, "a child does not come after it"));
                    }
                    if has_parent.set(c as usize) {
                        return Err(corrupt(c, "the node has two parents"));
                    }
                    let cq = qbox_of(&self.try_words(c)?);
                    let inside = (0..3).all(|a| pq.min[a] <= cq.min[a] && cq.max[a] <= pq.max[a]);
                    if !inside {
                        return Err(corrupt(c, "its box is not inside its parent's"));
                    }
                }
            }
        }
        if let Some(g) = (1..n as usize).find(|&g| !has_parent.get(g)) {
            return Err(corrupt(g as u32, "no node names it as a child"));
        }
        if (0..self.header.triangle_count as usize).any(|t| !seen.get(t)) {
            return Err(RacError::Corrupt("a triangle id appears in no leaf"));
        }
        if n > 0 && !self.header.empty {
            let root = self.box_of(&self.try_words(0)?);
            if !root_matches(&root, &bounds, self.header.grid.step.to_array()) {
                return Err(corrupt(0, "the root's box is not its triangles' bounds"));
            }
        }
        Ok(())
    }
}

/// A fixed-size set of bits.
struct BitSet(Vec<u64>);

impl BitSet {
    fn new(n: usize) -> Self {
        Self(vec![0; n.div_ceil(64)])
    }

    /// Sets bit `i`; returns whether it was already set.
    fn set(&mut self, i: usize) -> bool {
        let (w, b) = (i / 64, 1u64 << (i % 64));
        let was = self.0[w] & b != 0;
        self.0[w] |= b;
        was
    }

    fn get(&self, i: usize) -> bool {
        self.0[i / 64] & (1u64 << (i % 64)) != 0
    }
}
