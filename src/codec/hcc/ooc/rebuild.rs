//! Rebuilding a low-level tree's i-HCCMesh words from its decoded
//! structure and vertices (§5.1: "we traverse the decompressed tree in a
//! bottom-up manner and re-construct the AABB information"): tight boxes
//! bottom-up, then each sibling pair coded top-down against the box its
//! parent decodes to, with the i-HCCMesh encoder's own pair coding
//! ([`code_pair`]), so that the words come out as that encoder writes them.
//! Linear in the tree's nodes, no recursion (children always sit at larger
//! positions than their parent, so one reverse and one forward sweep do).

use super::super::HccStats;
use super::super::node::{
    INDEX_BITS, Interconnection, MASK_SHIFT, TYPE_LEAF, TYPE_SHIFT, TYPE_TEMPLATE_LEAF, pack_node,
};
use super::super::pair::{EMPTY, Extents, code_pair, outer};
use super::model::Layout;

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
    /// in `lay`, with leaf corners `corners` (by position) over vertices
    /// `pts`, to `nodes` and `ics`; counts its pairs and templates in
    /// `stats`; returns the tree's tight box.
    pub fn tree(
        &mut self,
        lay: &Layout,
        corners: &[[u32; 3]],
        pts: &[[f32; 3]],
        nodes: &mut Vec<u32>,
        ics: &mut Vec<u32>,
        stats: &mut HccStats,
    ) -> Extents {
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
                for &c in &corners[p] {
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
        nodes.extend(types.iter().enumerate().map(|(p, &ty)| match ty {
            TYPE_LEAF => pack_node(corners[p], 0, TYPE_LEAF),
            TYPE_TEMPLATE_LEAF => pack_node([0, 0, lay.ic_of[p]], 0, TYPE_TEMPLATE_LEAF),
            _ => ty << TYPE_SHIFT,
        }));
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
