//! [`ClBvh::verify`]: proves what every query relies on.

use std::collections::HashMap;

use glam::Vec3A;

use super::node::{
    ENDS_WORDS, MULTI_WORDS, MultiLeafNode, TAG_INNER, TAG_LEAF, TAG_MULTI, ref_index, ref_tag,
};
use super::{ClBvh, ClError, LeafKind};
use crate::cursor::NodeCursor;
use crate::geom::{Aabb, Triangle};

fn bad(at: usize, what: &'static str) -> ClError {
    ClError::Corrupt {
        at: at as u64,
        what,
    }
}

struct Walk<'a> {
    t: &'a ClBvh,
    seen_tri: Vec<bool>,
    /// Compact: first slot of each block, by word offset.
    first_slot: HashMap<u32, (u32, u32)>,
    blocks_seen: usize,
}

impl Walk<'_> {
    /// Checks the leaf block at word `at` and returns its triangles' ids and
    /// corners.
    fn block(&mut self, at: usize) -> Result<Vec<(u32, Triangle)>, ClError> {
        let t = self.t;
        let a = &t.arena;
        let hdr = *a
            .get(at)
            .ok_or(bad(at, "a leaf block starts past the arena"))?;
        let (n, u) = ((hdr & 0xFFFF) as usize, (hdr >> 16) as usize);
        let nt = self.seen_tri.len();
        // The block's words, bounded by the arena before anything is
        // allocated for its triangles (a forged count must not buy a large
        // allocation).
        let words = match t.options.leaves {
            LeafKind::Fast => 10 * n,
            LeafKind::Compact => u + n + (3 * n).div_ceil(4),
        };
        let body = a
            .get(at + 1..at + 1 + words)
            .ok_or(bad(at, "a leaf block runs past the arena"))?;
        let mut out = Vec::with_capacity(n);
        match t.options.leaves {
            LeafKind::Fast => {
                if u != 0 {
                    return Err(bad(at, "a fast leaf block has a vertex list"));
                }
                for j in 0..n {
                    let id = body[j];
                    let c = &body[n + 9 * j..n + 9 * j + 9];
                    let p = |k: usize| {
                        Vec3A::new(
                            f32::from_bits(c[3 * k]),
                            f32::from_bits(c[3 * k + 1]),
                            f32::from_bits(c[3 * k + 2]),
                        )
                    };
                    if id as usize >= nt {
                        return Err(bad(at, "a leaf names a missing triangle"));
                    }
                    let tri = [p(0), p(1), p(2)];
                    if tri != t.triangle(id) {
                        return Err(bad(
                            id as usize,
                            "a leaf's corners are not the mesh triangle's",
                        ));
                    }
                    out.push((id, tri));
                }
            }
            LeafKind::Compact => {
                if u > 256 {
                    return Err(bad(at, "a leaf block lists more than 256 vertices"));
                }
                let local: &[u8] = bytemuck::cast_slice(&body[u + n..]);
                let nv = t.vertices.len();
                if body[..u].iter().any(|&v| v as usize >= nv) {
                    return Err(bad(at, "a leaf block names a missing vertex"));
                }
                if local[..3 * n].iter().any(|&l| l as usize >= u) {
                    return Err(bad(at, "a local corner index is past the vertex list"));
                }
                let &(first, count) = self
                    .first_slot
                    .get(&(at as u32))
                    .ok_or(bad(at, "a leaf block is not in the block table"))?;
                if count as usize != n {
                    return Err(bad(at, "the block table's size for a block is wrong"));
                }
                self.blocks_seen += 1;
                for j in 0..n {
                    let id = body[u + j];
                    if id as usize >= nt {
                        return Err(bad(at, "a leaf names a missing triangle"));
                    }
                    if t.slot_of[id as usize] != first + j as u32 {
                        return Err(bad(id as usize, "the triangle's slot is not its block's"));
                    }
                    let v = [0, 1, 2].map(|k| body[local[3 * j + k] as usize]);
                    out.push((id, t.corners(v)));
                }
            }
        }
        for &(id, _) in &out {
            if std::mem::replace(&mut self.seen_tri[id as usize], true) {
                return Err(bad(id as usize, "a triangle is in two leaves"));
            }
        }
        Ok(out)
    }
}

fn inside(b: &Aabb, tris: &[(u32, Triangle)]) -> bool {
    tris.iter()
        .all(|(_, t)| t.iter().all(|&p| b.contains_point(p)))
}

fn grow(b: &mut Aabb, tris: &[(u32, Triangle)]) {
    for (_, t) in tris {
        t.iter().for_each(|&p| b.grow(p));
    }
}

fn good_box(b: &Aabb) -> bool {
    b.min.is_finite() && b.max.is_finite() && b.min.cmple(b.max).all()
}

impl ClBvh {
    /// Proves what every query relies on, in O(nodes + triangles) without
    /// recursion: every inner node is reached once, child references are in
    /// range with used lanes first, inner boxes are finite and nested, leaf
    /// blocks lie inside the arena and hold each triangle exactly once with
    /// the mesh's corners (fast) or valid vertex and slot indices (compact),
    /// every box (float or decoded) contains the triangles below it, no
    /// leaf or multi-leaf node holds more than `8 · M` triangles (the
    /// multi-leaf threshold), multi-leaf nodes appear only
    /// where the flags allow them, and the root box is exactly the
    /// triangles' bounds (the renderer frames its camera from it).
    pub fn verify(&self) -> Result<(), ClError> {
        let nt = self.triangle_count();
        if let Some(v) = self
            .vertices
            .iter()
            .position(|v| v.iter().any(|c| !c.is_finite()))
        {
            return Err(bad(v, "vertex has a non-finite coordinate"));
        }
        if let Some(t) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= self.vertices.len()))
        {
            return Err(bad(t, "triangle refers to a missing vertex"));
        }
        let mut first_slot = HashMap::new();
        for (k, &[first, at]) in self.blocks.iter().enumerate() {
            let end = self.blocks.get(k + 1).map_or(nt as u32, |b| b[0]);
            if end < first {
                return Err(bad(k, "block table slots are not in order"));
            }
            if first_slot.insert(at, (first, end - first)).is_some() {
                return Err(bad(k, "two block table entries for one block"));
            }
        }
        let mut w = Walk {
            t: self,
            seen_tri: vec![false; nt],
            first_slot,
            blocks_seen: 0,
        };
        let mut seen_inner = vec![false; self.inner.len()];
        let mut multi = 0usize;
        let mut bounds = Aabb::EMPTY;
        if nt > 0 && !good_box(&self.root_box) {
            return Err(bad(0, "the root box is not finite or inverted"));
        }
        let mut stack = vec![(self.root, self.root_box)];
        while let Some((r, b)) = stack.pop() {
            let at = ref_index(r);
            match ref_tag(r) {
                TAG_INNER => {
                    let slot = seen_inner
                        .get_mut(at)
                        .ok_or(bad(at, "an inner node index is out of range"))?;
                    if std::mem::replace(slot, true) {
                        return Err(bad(at, "an inner node has two parents or is in a cycle"));
                    }
                    let n = &self.inner[at];
                    let used = n.child.iter().take_while(|&&c| c != 0).count();
                    if used == 0 || n.child[used..].iter().any(|&c| c != 0) {
                        return Err(bad(at, "an inner node's used lanes are not first"));
                    }
                    for k in 0..used {
                        let cb = n.child_box(k);
                        if !good_box(&cb) || !b.contains(&cb) {
                            return Err(bad(at, "a child box is bad or not inside its parent's"));
                        }
                        stack.push((n.child[k], cb));
                    }
                }
                TAG_LEAF => {
                    let tris = w.block(at)?;
                    if !inside(&b, &tris) {
                        return Err(bad(at, "a leaf's box does not contain its triangles"));
                    }
                    if tris.len() > 8 * self.options.leaf_size {
                        return Err(bad(at, "a leaf holds more than 8 · M triangles"));
                    }
                    grow(&mut bounds, &tris);
                }
                TAG_MULTI => {
                    multi += 1;
                    if at + MULTI_WORDS + ENDS_WORDS > self.arena.len() {
                        return Err(bad(at, "a multi-leaf node runs past the arena"));
                    }
                    let m = MultiLeafNode::read(&self.arena, at);
                    if m.start.iter().chain(&m.step).any(|v| !v.is_finite())
                        || m.step.iter().any(|&s| s < 0.0)
                    {
                        return Err(bad(at, "a multi-leaf node's frame is not finite"));
                    }
                    let ends = self.ends(at);
                    let tris = w.block(at + MULTI_WORDS + ENDS_WORDS)?;
                    if ends.windows(2).any(|e| e[0] > e[1]) || ends[7] as usize != tris.len() {
                        return Err(bad(at, "a multi-leaf node's leaf ends are wrong"));
                    }
                    if tris.len() > 8 * self.options.leaf_size {
                        return Err(bad(at, "a multi-leaf node holds more than 8 · M triangles"));
                    }
                    grow(&mut bounds, &tris);
                    let mut prev = 0;
                    for (k, &end) in ends.iter().enumerate() {
                        let lane = &tris[prev..end as usize];
                        if !inside(&b, lane) || !inside(&m.child_box(k), lane) {
                            return Err(bad(at, "a lane's box does not contain its triangles"));
                        }
                        prev = end as usize;
                    }
                }
                _ => return Err(bad(at, "an empty child reference is used")),
            }
        }
        if multi != self.multi_nodes {
            return Err(bad(multi, "the multi-leaf node count is wrong"));
        }
        if multi > 0 && !self.options.multi_leaf {
            return Err(bad(
                multi,
                "multi-leaf nodes in a tree whose flags say none",
            ));
        }
        if nt > 0 && (bounds.min != self.root_box.min || bounds.max != self.root_box.max) {
            return Err(bad(0, "the root box is not the triangles' bounds"));
        }
        if let Some(i) = seen_inner.iter().position(|s| !s) {
            return Err(bad(i, "no node names this inner node as a child"));
        }
        if let Some(t) = w.seen_tri.iter().position(|s| !s) {
            return Err(bad(t, "triangle is in no leaf"));
        }
        if w.blocks_seen != self.blocks.len() {
            return Err(bad(w.blocks_seen, "the block table lists unused blocks"));
        }
        Ok(())
    }
}
