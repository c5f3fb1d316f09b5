//! Rebuilding a low-level tree's i-HCCMesh words from its decoded
//! structure and vertices (§5.1: "we traverse the decompressed tree in a
//! bottom-up manner and re-construct the AABB information"): tight boxes
//! bottom-up, then each sibling pair coded top-down against the box its
//! parent decodes to, with the i-HCCMesh encoder's own pair coding
//! ([`code_pair`]), so that the words come out as that encoder writes them.
//! Linear in the tree's nodes, no recursion (children always sit at larger
//! positions than their parent, so one reverse and one forward sweep do).

use super::super::HccStats;
use super::super::block;
use super::super::node::{
    INDEX_BITS, Interconnection, MASK_SHIFT, MULTI_COUNT_SHIFT, MULTI_OFFSET_BITS, TYPE_LEAF,
    TYPE_SHIFT, TYPE_TEMPLATE_LEAF, pack_node,
};
use super::super::pair::{EMPTY, Extents, code_pair, outer};
use super::model::Layout;
use crate::codec::common::bits::BitWriter;

/// Buffers reused from tree to tree.
#[derive(Default)]
pub struct Rebuild {
    tight: Vec<Extents>,
    attained: Vec<[u32; 6]>,
    decoded: Vec<Extents>,
    ic_vertex: Vec<u32>,
}

impl Rebuild {
    /// Appends the node words and inter-connections of the tree laid out
    /// in `lay` to `nodes` and `ics` (and, for multi-triangle leaves, its
    /// triangle blocks to `blocks` and their start to `block_start`); the
    /// leaf at position `p` holds `tris[spans[p].0..][..spans[p].1]`, over
    /// vertices `pts`. Counts its pairs and templates in `stats`; returns
    /// the tree's tight box.
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
        let leaf = |p: usize| {
            let (first, count) = spans[p];
            &tris[first as usize..(first + count) as usize]
        };
        let n = lay.types.len();
        let types = &lay.types[..n];
        self.tight.resize(n, EMPTY);
        self.attained.resize(n, [0; 6]);
        self.decoded.resize(n, EMPTY);
        // Tight boxes and the vertices attaining them, bottom-up; ties go
        // to the first corner and to the left child, as the encoder's.
        for p in (0..n).rev() {
            let (mut b, mut v) = (EMPTY, [0u32; 6]);
            if types[p] == TYPE_LEAF {
                for &c in leaf(p).iter().flatten() {
                    let pt = pts[c as usize];
                    for e in 0..6 {
                        if outer(e, pt[e % 3], b[e]) {
                            b[e] = pt[e % 3];
                            v[e] = c;
                        }
                    }
                }
            } else {
                let [l, r] = lay.kids[p].map(|k| k as usize);
                let (tl, tr) = (&self.tight[l], &self.tight[r]);
                let (al, ar) = (&self.attained[l], &self.attained[r]);
                for e in 0..6 {
                    let right = outer(e, tr[e], tl[e]);
                    b[e] = if right { tr[e] } else { tl[e] };
                    v[e] = if right { ar[e] } else { al[e] };
                }
            }
            self.tight[p] = b;
            self.attained[p] = v;
        }
        let base = nodes.len();
        match multi {
            None => nodes.extend(types.iter().enumerate().map(|(p, &ty)| match ty {
                TYPE_LEAF => pack_node(leaf(p)[0], 0, TYPE_LEAF),
                TYPE_TEMPLATE_LEAF => pack_node([0, 0, lay.ic_of[p]], 0, TYPE_TEMPLATE_LEAF),
                _ => ty << TYPE_SHIFT,
            })),
            Some((blocks, block_start)) => {
                // Blocks in node-word order, as the i-HCCMesh encoder
                // writes them; the tree's triangle limit keeps every
                // offset within the leaf word's field.
                let slot_bits = block::slot_bits(tris.len() as u32);
                let mut w = BitWriter::default();
                for (p, &ty) in types.iter().enumerate() {
                    nodes.push(match ty {
                        TYPE_LEAF => {
                            let (slot, count) = spans[p];
                            let at = block::write(&mut w, slot, slot_bits, leaf(p));
                            debug_assert!(at < 1 << MULTI_OFFSET_BITS);
                            at as u32 | (count - 1) << MULTI_COUNT_SHIFT | ty << TYPE_SHIFT
                        }
                        TYPE_TEMPLATE_LEAF => {
                            pack_node([0, 0, lay.ic_of[p]], 0, TYPE_TEMPLATE_LEAF)
                        }
                        _ => ty << TYPE_SHIFT,
                    });
                }
                block_start.push(blocks.len() as u32);
                blocks.extend_from_slice(&w.finish());
            }
        }
        let words = &mut nodes[base..];
        self.ic_vertex.clear();
        self.ic_vertex.resize(lay.ics.len(), 0);
        // Pairs top-down, each against its parent's decoded box.
        self.decoded[0] = self.tight[0];
        for p in 0..n {
            if types[p] == TYPE_LEAF {
                continue;
            }
            let kids = lay.kids[p].map(|k| k as usize);
            let [l, r] = kids;
            let (ll, rl) = (types[l] == TYPE_LEAF, types[r] == TYPE_LEAF);
            let pc = code_pair(
                &self.decoded[p],
                (&self.tight[l], &self.attained[l], ll),
                (&self.tight[r], &self.attained[r], rl),
            );
            for (side, &pos) in kids.iter().enumerate() {
                for j in 0..pc.used[side] {
                    let v = pc.fields[side][j];
                    if j == 2 && types[pos] == TYPE_TEMPLATE_LEAF {
                        self.ic_vertex[lay.ic_of[pos] as usize] = v;
                    } else {
                        words[pos] |= v << (INDEX_BITS as usize * j);
                    }
                }
            }
            match (ll, rl) {
                (false, false) => stats.inner_pairs += 1,
                (true, true) => {}
                _ => stats.mixed_pairs += 1,
            }
            stats.loose_extents += pc.loose;
            words[l] |= (pc.mask & 7) << MASK_SHIFT;
            words[r] |= (pc.mask >> 3) << MASK_SHIFT;
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
        self.tight[0]
    }
}
