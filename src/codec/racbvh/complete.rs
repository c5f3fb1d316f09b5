//! BV completion (§5.2): the box of an *incomplete* node (one whose local
//! root's parent is in an earlier cluster) is rebuilt from that parent's
//! box, walking the chain of local roots' parents with a loop.

use super::cache;
use super::decode::{Cluster, LocalRoot};
use super::node::{INCOMPLETE, apply, qbox_of};
use super::{RacBvh, RacError};
use crate::build::LEAF_FLAG;
use crate::codec::common::quant::QBox;

impl RacBvh {
    /// The complete words of node `g`, completing it if needed (§5.2).
    ///
    /// Completing a node needs its local root's parent, which may itself be
    /// incomplete in an earlier cluster, and so on: the chain is walked
    /// with a loop and an explicit list (never recursion, whose depth a
    /// crafted file could make overflow the stack). Parent clusters come
    /// strictly before their children's (checked when a cluster is
    /// decoded), so the chain has at most one entry per cluster.
    pub(super) fn try_words(&self, g: u32) -> Result<[u32; 8], RacError> {
        let cb = self.header.cluster_bits;
        let split = |x: u32| -> Result<(u32, usize), RacError> {
            if x >= self.header.node_count {
                return Err(RacError::NoSuchNode {
                    node: x,
                    count: self.header.node_count,
                });
            }
            let c = x >> cb;
            Ok((c, (x - (c << cb)) as usize))
        };
        let (c, l) = split(g)?;
        if let Some(w) = self.nodes.as_ref().and_then(|n| n.get(g)) {
            return Ok(w);
        }
        let fast = cache::with_pinned(self.id, c, |cl: &Cluster| {
            let w = cl.nodes[l].words();
            (w[0] & INCOMPLETE == 0).then(|| {
                self.remember(g, &w, cl);
                w
            })
        });
        if let Some(w) = fast {
            return Ok(w);
        }
        // Walk up: (cluster, local index of the node, its local root) for
        // every incomplete node of the chain, until a complete one (in the
        // node cache, or in its cluster).
        let mut chain: Vec<(u32, usize, LocalRoot)> = Vec::new();
        let mut x = g;
        let mut top = loop {
            let (c, l) = split(x)?;
            if x != g
                && let Some(w) = self.nodes.as_ref().and_then(|n| n.get(x))
            {
                break w;
            }
            let cl = self.cluster(c)?;
            let w = cl.nodes[l].words();
            if w[0] & INCOMPLETE == 0 {
                if chain.is_empty() {
                    self.remember(g, &w, &cl);
                    cache::pin(self.id, c, cl);
                }
                break w;
            }
            let root = cl.roots[usize::from(cl.root_of[l])];
            // Hold nothing while the parent's cluster loads.
            drop(cl);
            if chain.len() > self.meta.len() {
                return Err(RacError::CorruptCluster {
                    cluster: c,
                    what: "the chain of local roots' parents does not end",
                });
            }
            chain.push((c, l, root));
            x = root.parent;
        };
        // Walk down, completing each local root's subtree from its parent.
        while let Some((c, l, root)) = chain.pop() {
            if top[7] & LEAF_FLAG != 0 || top[6 + usize::from(root.right)] != c << cb | root.local {
                return Err(RacError::CorruptCluster {
                    cluster: c,
                    what: "a local root's parent does not name it as child",
                });
            }
            let cl = self.cluster(c)?;
            complete(&cl, root, &qbox_of(&top), self.header.grid.max_q)
                .map_err(|what| RacError::CorruptCluster { cluster: c, what })?;
            top = cl.nodes[l].words();
            if top[0] & INCOMPLETE != 0 {
                return Err(RacError::CorruptCluster {
                    cluster: c,
                    what: "a node is not below its local root",
                });
            }
            if chain.is_empty() {
                self.remember(g, &top, &cl);
                cache::pin(self.id, c, cl);
            }
        }
        Ok(top)
    }

    /// Puts the complete words `w` of node `g` of cluster `cl` in the node
    /// cache, if there is one, with a leaf's triangle ids if it holds
    /// several and the cache's entries have room for them.
    #[inline]
    pub(super) fn remember(&self, g: u32, w: &[u32; 8], cl: &Cluster) {
        let Some(n) = &self.nodes else {
            return;
        };
        let count = (w[7] & !LEAF_FLAG) as usize;
        if w[7] & LEAF_FLAG == 0 || count <= 1 || count > n.leaf_ids() {
            n.insert(g, w, &[]);
        } else if let Some(ids) = cl.tris.get(w[6] as usize..w[6] as usize + count) {
            n.insert(g, w, ids);
        }
    }
}

/// Completes the subtree of local root `root` in `cl`, given the parent's
/// quantized box.
fn complete(cl: &Cluster, root: LocalRoot, parent: &QBox, max_q: u32) -> Result<(), &'static str> {
    let _guard = cl.lock.lock().unwrap_or_else(|e| e.into_inner());
    if cl.nodes[root.local as usize].is_complete() {
        return Ok(());
    }
    let n = cl.nodes.len() as u32;
    let mut stack = vec![(root.local, *parent, root.right)];
    while let Some((l, pq, right)) = stack.pop() {
        let node = &cl.nodes[l as usize];
        let mut w = node.words();
        if w[0] & INCOMPLETE == 0 {
            return Err("a node below a local root is already complete");
        }
        w[0] &= !INCOMPLETE;
        let res = [w[0], w[1], w[2], w[3], w[4], w[5]];
        let q = apply(&pq, right, &res, max_q).ok_or("a completed box leaves the grid")?;
        node.set_box(&q);
        if w[7] & LEAF_FLAG == 0 {
            for (side, child) in [(false, w[6]), (true, w[7])] {
                if let Some(cl_local) = child.checked_sub(cl.first).filter(|&x| x < n) {
                    stack.push((cl_local, q, side));
                }
            }
        }
    }
    Ok(())
}
