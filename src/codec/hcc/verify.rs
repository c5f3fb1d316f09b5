//! [`HccBvh::verify`]: the second validation tier, proving everything a
//! query relies on with checked reads.

use super::HccBvh;
use super::HccError;
use super::block::{Block, WIDTH_BITS, slot_bits};
use super::node::{
    HIGH_LEAF, HighNode, INDEX_BITS, INDEX_MASK, Interconnection, MULTI_OFFSET_BITS, TYPE_INNER,
    TYPE_LEAF, TYPE_TEMPLATE_LEAF, field, mask_half, multi_leaf, node_type,
};
use super::template::{TEMPLATE_COUNT, TEMPLATES};
use super::vertices::Vertices;
use crate::codec::common::root_matches;
use crate::cursor::NodeCursor;
use crate::geom::Aabb;

fn bad(tree: usize, node: usize, what: &'static str) -> HccError {
    HccError::Corrupt {
        tree: tree as u32,
        node: node as u32,
        what,
    }
}

impl HccBvh {
    /// Proves everything a query relies on: the high-level tree is a tree
    /// over every low-level tree once; each low-level tree's runs lie in
    /// the arrays; every node word, template id, inter-connection, vertex
    /// index, triangle block and slot is in range; every node is reached
    /// once; every vertex and decoded box is finite and every box inside
    /// its parent's, the root's the vertices' bounds (within a grid
    /// step); the leaves hold `triangle_count` triangles, each rank
    /// once; the id map (when kept) is a permutation whose inverse finds every id; the
    /// vertex ids cover the input vertices, copies decoding alike.
    pub fn verify(&self) -> Result<(), HccError> {
        let nt = self.headers.len();
        let stored = self.stats.tree_vertices;
        let bounds = self.verify_vertices()?;
        if let Some(ids) = &self.ids {
            if ids.len() != self.triangle_count {
                return Err(bad(0, 0, "the id map does not hold the triangle count"));
            }
            ids.verify().map_err(|what| bad(0, 0, what))?;
        }
        if nt == 0 {
            return if self.high.is_empty()
                && self.nodes.is_empty()
                && self.ics.is_empty()
                && stored == 0
                && self.blocks.is_empty()
                && self.triangle_count == 0
            {
                self.verify_vertex_ids()
            } else {
                Err(bad(
                    0,
                    0,
                    "a structure without low-level trees must be empty",
                ))
            };
        }
        // High-level tree: children after parents, each node and tree once.
        let mut tree_seen = vec![false; nt];
        let mut high_seen = vec![false; self.high.len()];
        let mut stack = vec![0usize];
        let inside = |c: &HighNode, p: &HighNode| {
            (0..3).all(|k| c.min[k] >= p.min[k] && c.max[k] <= p.max[k] && c.min[k] <= c.max[k])
        };
        while let Some(i) = stack.pop() {
            let Some(n) = self.high.get(i) else {
                return Err(bad(0, i, "a high-level child index is out of range"));
            };
            if std::mem::replace(&mut high_seen[i], true) {
                return Err(bad(0, i, "a high-level node is reached twice"));
            }
            if n.min.iter().chain(&n.max).any(|c| !c.is_finite()) {
                return Err(bad(0, i, "a high-level box is not finite"));
            }
            if n.is_leaf() {
                if n.b != HIGH_LEAF
                    || n.a as usize >= nt
                    || std::mem::replace(&mut tree_seen[n.a as usize], true)
                {
                    return Err(bad(
                        0,
                        i,
                        "a high-level leaf names a missing or repeated tree",
                    ));
                }
            } else {
                for c in [n.a as usize, n.b as usize] {
                    if c <= i || c >= self.high.len() || !inside(&self.high[c], n) {
                        return Err(bad(
                            0,
                            i,
                            "a high-level child is out of range or outside its parent",
                        ));
                    }
                    stack.push(c);
                }
            }
        }
        let slack = self.vertices.quantized().map_or([0.0; 3], |q| q.step);
        let root = &self.high[0];
        if !root_matches(&Aabb::from_arrays(root.min, root.max), &bounds, slack) {
            return Err(bad(0, 0, "the root's box is not the vertices' bounds"));
        }
        let mut tree_box = vec![Aabb::EMPTY; nt];
        for n in self.high.iter().filter(|n| n.is_leaf()) {
            tree_box[n.a as usize] = Aabb::from_arrays(n.min, n.max);
        }
        if !tree_seen.iter().all(|&s| s) {
            return Err(bad(
                0,
                0,
                "a low-level tree is not under the high-level tree",
            ));
        }
        // Low-level runs: increasing starts inside the arrays.
        if self.multi && self.block_start.len() != nt {
            return Err(bad(0, 0, "the block starts do not match the trees"));
        }
        let mut triangles = 0u64;
        for (k, h) in self.headers.iter().enumerate() {
            let (ne, ie, ve) = self.tree_ends(k);
            let next_first = self
                .headers
                .get(k + 1)
                .map_or(self.triangle_count, |n| n.first_triangle);
            if h.node_start >= ne
                || h.ic_start > ie
                || h.vertex_start > ve
                || ne as usize > self.nodes.len()
                || ie as usize > self.ics.len()
                || ve as usize > stored
                || (ve - h.vertex_start) as usize > super::node::MAX_TREE_VERTICES
                || u64::from(h.first_triangle) != triangles
                || next_first < h.first_triangle
                || next_first > self.triangle_count
            {
                return Err(bad(
                    k,
                    0,
                    "the tree's header is out of order or out of range",
                ));
            }
            if self.multi {
                let end = self.block_start.get(k + 1).copied();
                let end = end.unwrap_or(self.blocks.len() as u32);
                if self.block_start[k] > end || end as usize > self.blocks.len() {
                    return Err(bad(k, 0, "the tree's triangle blocks are out of range"));
                }
            }
            let n = self.verify_tree(k, tree_box[k], (ne, ie, ve))?;
            if n != u64::from(next_first - h.first_triangle) {
                return Err(bad(k, 0, "the tree's leaves do not hold its triangles"));
            }
            triangles += n;
        }
        if triangles != u64::from(self.triangle_count) {
            return Err(bad(0, 0, "the leaves do not hold the triangle count"));
        }
        self.verify_vertex_ids()
    }

    /// Every stored vertex decodes to a finite point (packed runs inside
    /// the data); returns their bounds.
    fn verify_vertices(&self) -> Result<Aabb, HccError> {
        let mut bounds = Aabb::EMPTY;
        let stored = self.stats.tree_vertices;
        match &self.vertices {
            Vertices::F32(v) => {
                if v.len() != stored {
                    return Err(bad(0, 0, "the vertex count does not match"));
                }
                if v.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
                    return Err(bad(0, 0, "a vertex has a non-finite coordinate"));
                }
                for p in v {
                    bounds.grow((*p).into());
                }
            }
            Vertices::Packed(q) => {
                if q.trees.len() != self.headers.len() {
                    return Err(bad(0, 0, "the packed vertex runs do not match the trees"));
                }
                for (k, h) in self.headers.iter().enumerate() {
                    let (_, _, ve) = self.tree_ends(k);
                    if ve < h.vertex_start || ve as usize > stored {
                        return Err(bad(k, 0, "the tree's vertex run is out of range"));
                    }
                    let count = ve - h.vertex_start;
                    q.check_tree(k, count).map_err(|what| bad(k, 0, what))?;
                    for i in 0..count {
                        let p = q.point(k, i);
                        if p.iter().any(|c| !c.is_finite()) {
                            return Err(bad(k, 0, "a vertex decodes to a non-finite point"));
                        }
                        bounds.grow(p.into());
                    }
                }
            }
        }
        Ok(bounds)
    }

    /// With vertex ids: one per stored vertex, each input vertex covered
    /// once by the unused list or by stored copies that decode alike.
    fn verify_vertex_ids(&self) -> Result<(), HccError> {
        let Some(v) = &self.vertex_ids else {
            return Ok(());
        };
        let stored = self.stats.tree_vertices;
        let n = self.mesh_vertices as usize;
        if v.len() as usize != stored || n > stored + v.unused.len() {
            return Err(bad(0, 0, "the vertex ids do not match the vertex counts"));
        }
        let mut at: Vec<Option<[u32; 3]>> = vec![None; n];
        for (k, h) in self.headers.iter().enumerate() {
            let (_, _, ve) = self.tree_ends(k);
            for local in 0..ve - h.vertex_start {
                let i = v.get(h.vertex_start + local) as usize;
                let p = self.point(k as u32, h, local).map(f32::to_bits);
                match at.get_mut(i) {
                    None => return Err(bad(k, 0, "a vertex id is out of range")),
                    Some(slot) if slot.is_some_and(|q| q != p) => {
                        return Err(bad(k, 0, "copies of a vertex decode differently"));
                    }
                    Some(slot) => *slot = Some(p),
                }
            }
        }
        for &(i, p) in &v.unused {
            if p.iter().any(|c| !c.is_finite()) {
                return Err(bad(0, 0, "an unused vertex is not finite"));
            }
            match at.get_mut(i as usize) {
                Some(slot @ None) => *slot = Some([0; 3]),
                _ => return Err(bad(0, 0, "an unused vertex id is out of range or used")),
            }
        }
        if at.iter().any(Option::is_none) {
            return Err(bad(0, 0, "an input vertex is neither stored nor unused"));
        }
        Ok(())
    }

    /// Walks low-level tree `k` (runs ending at `ne`, `ie`, `ve`) with
    /// checked reads; returns its triangle count.
    fn verify_tree(
        &self,
        k: usize,
        hl: Aabb,
        (ne, ie, ve): (u32, u32, u32),
    ) -> Result<u64, HccError> {
        let bad = |node: u32, what: &'static str| bad(k, node as usize, what);
        let h = self.headers[k];
        let nv = ve - h.vertex_start;
        let ni = ie - h.ic_start;
        let tree_tris = self.tree_triangles(k);
        let mut seen = vec![false; (ne - h.node_start) as usize];
        let mut slots = vec![false; tree_tris as usize];
        if !self.multi {
            // Ranks are leaf ranks: the tree's leaf words must number its
            // triangles.
            let leaves = (h.node_start..ne)
                .filter(|&p| node_type(self.nodes[p as usize]) == TYPE_LEAF)
                .count();
            if leaves as u32 != tree_tris {
                return Err(bad(
                    h.node_start,
                    "the tree's leaf words do not number its triangles",
                ));
            }
        }
        let stream_end = if self.multi {
            let end = self.block_start.get(k + 1).copied();
            u64::from(end.unwrap_or(self.blocks.len() as u32)) * 8
        } else {
            0
        };
        let mut triangles = 0u64;
        // Check a word's vertex fields, inter-connection or block first.
        let mut check_word = |pos: u32| -> Result<(), HccError> {
            let w = self.nodes[pos as usize];
            let ty = node_type(w);
            if ty > TYPE_LEAF {
                return Err(bad(pos, "a node word has an unknown type"));
            }
            if ty == TYPE_LEAF && self.multi {
                let (off, count) = multi_leaf(w);
                let sb = slot_bits(tree_tris);
                let at = u64::from(self.block_start[k]) * 8 + u64::from(off);
                if at + u64::from(sb + INDEX_BITS + WIDTH_BITS) > stream_end {
                    return Err(bad(pos, "a leaf's block lies past the tree's blocks"));
                }
                debug_assert!(off < 1 << MULTI_OFFSET_BITS);
                let b = Block::read(&self.blocks, at, sb);
                if b.width > INDEX_BITS || b.end(count) > stream_end {
                    return Err(bad(pos, "a leaf's block is malformed or too long"));
                }
                let end = u64::from(b.slot) + u64::from(count);
                if end > u64::from(tree_tris) {
                    return Err(bad(pos, "a leaf's triangles are out of range"));
                }
                for s in b.slot..end as u32 {
                    if std::mem::replace(&mut slots[s as usize], true) {
                        return Err(bad(pos, "two leaves hold the same triangle"));
                    }
                }
                for j in 0..count {
                    if b.corners(&self.blocks, j).iter().any(|&c| c >= nv) {
                        return Err(bad(pos, "a triangle's corner is out of range"));
                    }
                }
                return Ok(());
            }
            for j in 0..3 {
                let v = if j == 2 && ty == TYPE_TEMPLATE_LEAF {
                    if field(w, 2) >= ni {
                        return Err(bad(pos, "an inter-connection index is out of range"));
                    }
                    self.ics[(h.ic_start + field(w, 2)) as usize] & INDEX_MASK
                } else {
                    field(w, j)
                };
                if v >= nv {
                    return Err(bad(pos, "a vertex index is out of range"));
                }
            }
            Ok(())
        };
        let rw = self.nodes[h.node_start as usize];
        if node_type(rw) != TYPE_LEAF && (rw & 31) as usize >= TEMPLATE_COUNT {
            return Err(bad(h.node_start, "the root's template id is out of range"));
        }
        // An inner root's fields hold its template id, not vertices (it
        // has no sibling; its box is the high-level leaf's).
        if node_type(rw) != TYPE_INNER {
            check_word(h.node_start)?;
        }
        let start = self.low_root(k as u32, hl);
        let mut stack = vec![start];
        while let Some(n) = stack.pop() {
            let local = (n.pos() - h.node_start) as usize;
            if std::mem::replace(&mut seen[local], true) {
                return Err(bad(n.pos(), "a node is reached twice"));
            }
            if self.is_leaf(&n) {
                let mut inside = true;
                let b = n.bounds();
                self.for_each_triangle(&n, |_, t| {
                    triangles += 1;
                    inside &= b.contains(&Aabb::of_triangle(t));
                });
                if !inside {
                    return Err(bad(n.pos(), "a leaf's box does not contain its triangles"));
                }
                continue;
            }
            // Children's positions, checked before any decode reads them.
            let w = self.nodes[n.pos() as usize];
            let (l, r) = if node_type(w) == TYPE_TEMPLATE_LEAF {
                let ic = Interconnection::unpack(self.ics[(h.ic_start + field(w, 2)) as usize]);
                if ic.left_template as usize >= TEMPLATE_COUNT
                    || ic.right_template as usize >= TEMPLATE_COUNT
                {
                    return Err(bad(
                        n.pos(),
                        "an inter-connection's template id is out of range",
                    ));
                }
                let l = h.node_start + ic.left_start;
                let r = l + u32::from(TEMPLATES[ic.left_template as usize].nodes);
                let rend = r + u32::from(TEMPLATES[ic.right_template as usize].nodes);
                if rend > ne {
                    return Err(bad(n.pos(), "an inter-connection points past the tree"));
                }
                (l, r)
            } else {
                let t = &TEMPLATES[n.template().unwrap_or(0) as usize];
                let local = n.pos() - n.block();
                if !t.has_children(local) || n.block() + u32::from(t.nodes) > ne {
                    return Err(bad(
                        n.pos(),
                        "a template node has no children or lies past the tree",
                    ));
                }
                let l = n.block() + t.children(local);
                (l, l + 1)
            };
            check_word(l)?;
            check_word(r)?;
            let (wl, wr) = (self.nodes[l as usize], self.nodes[r as usize]);
            let mask = mask_half(wl) | mask_half(wr) << 3;
            if (node_type(wl) == TYPE_LEAF) != (node_type(wr) == TYPE_LEAF) && mask.count_ones() < 3
            {
                return Err(bad(
                    n.pos(),
                    "an inner child beside a leaf codes more than three extents",
                ));
            }
            let parent = n.bounds();
            let mut ok = true;
            self.for_each_child(&n, |c, b| {
                let finite = b.min.is_finite() && b.max.is_finite();
                ok &= finite && parent.contains(&b);
                stack.push(c);
            });
            if !ok {
                return Err(bad(
                    n.pos(),
                    "a child's box is not finite or not inside its parent's",
                ));
            }
        }
        Ok(triangles)
    }
}

#[cfg(test)]
mod tests {
    use super::super::HccOptions;
    use super::*;
    use crate::build::{BuildOptions, build};
    use crate::scene::{Kind, generate};

    /// Random corruptions of every array: `verify` never panics, rejects
    /// most, and whatever it accepts traverses without panicking.
    #[test]
    fn verify_never_panics_on_corrupted_structures() {
        let mesh = generate(Kind::Statue, 1500, 3, &mut |_, _| {}).unwrap();
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for (leaf, bits) in [(1, None), (4, Some(16))] {
            let opts = BuildOptions {
                max_leaf_triangles: leaf,
                ..Default::default()
            };
            let tree = build(&mesh, &opts, &|_, _| {}).unwrap();
            let options = HccOptions {
                vertex_bits: bits,
                ..Default::default()
            };
            let good = HccBvh::encode_with(&tree, &mesh, &options).unwrap();
            good.verify().unwrap();
            let mut rejected = 0;
            for round in 0..400 {
                let mut h = good.clone();
                let r = next();
                let bit = 1u32 << (r % 32);
                let i = (r >> 8) as usize;
                match round % 6 {
                    0 => h.nodes[i % good.nodes.len()] ^= bit,
                    1 => h.ics[i % good.ics.len()] ^= bit,
                    2 => h.headers[i % good.headers.len()].node_start ^= bit,
                    3 => h.high[i % good.high.len()].a ^= bit,
                    4 if leaf > 1 => h.blocks[i % good.blocks.len()] ^= bit as u8 | 1,
                    _ => match &mut h.vertices {
                        Vertices::F32(v) => {
                            let p = &mut v[i % good.stats.tree_vertices];
                            p[(r >> 40) as usize % 3] = f32::from_bits(p[0].to_bits() ^ bit);
                        }
                        Vertices::Packed(q) => {
                            let n = q.data.len();
                            q.data[i % n] ^= 1 << (r % 8);
                        }
                    },
                }
                h.build_leaf_ranks();
                match h.verify() {
                    Err(_) => rejected += 1,
                    Ok(()) => {
                        // Accepted: a full traversal must not panic.
                        let (root, _) = h.root();
                        let mut stack = vec![root];
                        while let Some(n) = stack.pop() {
                            if h.is_leaf(&n) {
                                h.for_each_triangle(&n, |id, _| {
                                    let _ = h.triangle(id);
                                });
                            } else {
                                h.for_each_child(&n, |c, _| stack.push(c));
                            }
                        }
                    }
                }
            }
            assert!(
                rejected > 150,
                "leaf {leaf}: only {rejected} of 400 corruptions rejected"
            );
        }
    }
}
