//! Rebuilding a low-level tree's i-HCCMesh words from its decoded
//! structure and vertices (§5.1: "we traverse the decompressed tree in a
//! bottom-up manner and re-construct the AABB information"): tight boxes
//! bottom-up, then each sibling pair coded top-down against the box its
//! parent decodes to, with the i-HCCMesh encoder's own pair coding
//! ([`code_pair`]), so that the words come out as that encoder writes them.
//! Linear in the tree's nodes, no recursion (children always sit at larger
//! positions than their parent, so one reverse and one forward sweep over
//! the nodes with children do, after one sweep over the leaves; the
//! layout lists both kinds, so no sweep branches on node types).

use super::super::HccStats;
use super::super::block;
use super::super::node::{
    INDEX_BITS, Interconnection, MASK_SHIFT, MULTI_COUNT_SHIFT, MULTI_OFFSET_BITS, TYPE_INNER,
    TYPE_LEAF, TYPE_SHIFT, TYPE_TEMPLATE_LEAF, pack_node,
};
use super::super::pair::{EMPTY, Extents, code_pair, outer};
use super::model::Layout;
use crate::codec::common::bits::BitWriter;

/// Buffers reused from tree to tree.
#[derive(Default)]
pub struct Rebuild {
    /// Per position, the tight box and the vertex attaining each extent.
    tight: Vec<(Extents, [u32; 6])>,
    decoded: Vec<Extents>,
    ic_vertex: Vec<u32>,
}

/// The tight box of `tris` over vertices `pts` and the vertex attaining
/// each extent (ties go to the first corner).
#[inline(always)]
fn leaf_box(tris: &[[u32; 3]], pts: &[[f32; 3]]) -> (Extents, [u32; 6]) {
    let (mut b, mut v) = (EMPTY, [0u32; 6]);
    for &c in tris.iter().flatten() {
        let pt = pts[c as usize];
        for a in 0..3 {
            let lo = pt[a] < b[a];
            b[a] = if lo { pt[a] } else { b[a] };
            v[a] = if lo { c } else { v[a] };
            let hi = pt[a] > b[a + 3];
            b[a + 3] = if hi { pt[a] } else { b[a + 3] };
            v[a + 3] = if hi { c } else { v[a + 3] };
        }
    }
    (b, v)
}

/// [`leaf_box`] of one triangle `c`, unrolled.
#[inline(always)]
fn triangle_box(c: [u32; 3], pts: &[[f32; 3]]) -> (Extents, [u32; 6]) {
    let p = c.map(|v| pts[v as usize]);
    let (mut b, mut v) = (EMPTY, [0u32; 6]);
    for k in 0..3 {
        for a in 0..3 {
            let lo = p[k][a] < b[a];
            b[a] = if lo { p[k][a] } else { b[a] };
            v[a] = if lo { c[k] } else { v[a] };
            let hi = p[k][a] > b[a + 3];
            b[a + 3] = if hi { p[k][a] } else { b[a + 3] };
            v[a + 3] = if hi { c[k] } else { v[a + 3] };
        }
    }
    (b, v)
}

impl Rebuild {
    /// Appends the node words and inter-connections of the tree laid out
    /// in `lay` to `nodes` and `ics` (and, for multi-triangle leaves, its
    /// triangle blocks to `blocks` and their start to `block_start`); the
    /// `i`-th leaf (in `lay.leaves`) holds `tris[spans[i].0..][..spans[i].1]`
    /// (`tris[i]` alone when `spans` is empty, which it must be exactly
    /// when `multi` is `None`), over vertices `pts`. Counts its pairs and templates in `stats`;
    /// returns the tree's tight box.
    #[allow(clippy::type_complexity)]
    pub fn tree(
        &mut self,
        lay: &Layout,
        (spans, tris): (&[(u32, u32)], &[[u32; 3]]),
        pts: &[[f32; 3]],
        (nodes, ics, multi): (
            &mut Vec<u32>,
            &mut Vec<u32>,
            Option<(&mut Vec<u8>, &mut Vec<u32>)>,
        ),
        stats: &mut HccStats,
    ) -> Extents {
        let leaf = |i: usize| {
            let (first, count) = spans[i];
            &tris[first as usize..(first + count) as usize]
        };
        let n = lay.types.len();
        let types = &lay.types[..n];
        let kids = &lay.kids[..n];
        self.tight.resize(n, (EMPTY, [0; 6]));
        self.decoded.resize(n, EMPTY);
        // Tight boxes and the vertices attaining them: the leaves, then the
        // other nodes bottom-up (children sit at larger positions than
        // their parent); ties go to the first corner and to the left
        // child, as the encoder's.
        if spans.is_empty() {
            for (&p, &c) in lay.leaves.iter().zip(tris) {
                self.tight[p as usize] = triangle_box(c, pts);
            }
        } else {
            for (i, &p) in lay.leaves.iter().enumerate() {
                self.tight[p as usize] = leaf_box(leaf(i), pts);
            }
        }
        for &p in lay.inner.iter().rev() {
            let [l, r] = kids[p as usize].map(|k| k as usize);
            let ((tl, al), (tr, ar)) = (&self.tight[l], &self.tight[r]);
            let (mut b, mut v) = (*tl, *al);
            for e in 0..6 {
                let right = outer(e, tr[e], tl[e]);
                b[e] = if right { tr[e] } else { tl[e] };
                v[e] = if right { ar[e] } else { al[e] };
            }
            self.tight[p as usize] = (b, v);
        }
        let base = nodes.len();
        nodes.resize(base + n, TYPE_INNER << TYPE_SHIFT);
        let words = &mut nodes[base..];
        for &p in &lay.inner {
            if types[p as usize] == TYPE_TEMPLATE_LEAF {
                words[p as usize] = pack_node([0, 0, lay.ic_of[p as usize]], 0, TYPE_TEMPLATE_LEAF);
            }
        }
        match multi {
            None => {
                for (&p, &c) in lay.leaves.iter().zip(tris) {
                    words[p as usize] = pack_node(c, 0, TYPE_LEAF);
                }
            }
            Some((blocks, block_start)) => {
                // Blocks in node-word order, as the i-HCCMesh encoder
                // writes them; the tree's triangle limit keeps every
                // offset within the leaf word's field.
                let slot_bits = block::slot_bits(tris.len() as u32);
                let mut w = BitWriter::default();
                for (i, &p) in lay.leaves.iter().enumerate() {
                    let (slot, count) = spans[i];
                    let at = block::write(&mut w, slot, slot_bits, leaf(i));
                    debug_assert!(at < 1 << MULTI_OFFSET_BITS);
                    words[p as usize] =
                        at as u32 | (count - 1) << MULTI_COUNT_SHIFT | TYPE_LEAF << TYPE_SHIFT;
                }
                block_start.push(blocks.len() as u32);
                blocks.extend_from_slice(&w.finish());
            }
        }
        self.ic_vertex.clear();
        self.ic_vertex.resize(lay.ics.len(), 0);
        // Pairs top-down, each against its parent's decoded box.
        self.decoded[0] = self.tight[0].0;
        for &p in &lay.inner {
            let pair = kids[p as usize].map(|k| k as usize);
            let [l, r] = pair;
            let (ll, rl) = (types[l] == TYPE_LEAF, types[r] == TYPE_LEAF);
            let ((tl, al), (tr, ar)) = (&self.tight[l], &self.tight[r]);
            let pc = code_pair(&self.decoded[p as usize], (tl, al, ll), (tr, ar, rl));
            // Fields a pair does not use are zero: or-ing them in is a
            // no-op, and a template leaf's third field (its
            // inter-connection's vertex) is zero unless set.
            for (side, &pos) in pair.iter().enumerate() {
                let f = pc.fields[side];
                let mut w = f[0] | f[1] << INDEX_BITS | (pc.mask >> (3 * side) & 7) << MASK_SHIFT;
                if types[pos] == TYPE_TEMPLATE_LEAF {
                    self.ic_vertex[lay.ic_of[pos] as usize] = f[2];
                } else {
                    w |= f[2] << (2 * INDEX_BITS);
                }
                words[pos] |= w;
            }
            stats.inner_pairs += usize::from(!ll && !rl);
            stats.mixed_pairs += usize::from(ll != rl);
            stats.loose_extents += pc.loose;
            self.decoded[l] = pc.boxes[0];
            self.decoded[r] = pc.boxes[1];
        }
        if types[0] != TYPE_LEAF {
            words[0] |= u32::from(lay.root_template);
        }
        stats.templates[lay.root_template as usize] += 1;
        for (&(lt, rt, ls), &vertex) in lay.ics.iter().zip(&self.ic_vertex) {
            stats.templates[lt as usize] += 1;
            stats.templates[rt as usize] += 1;
            ics.push(
                Interconnection {
                    vertex,
                    left_template: lt,
                    right_template: rt,
                    left_start: ls,
                }
                .pack(),
            );
        }
        self.tight[0].0
    }
}
