//! Rebuilding a low-level tree's i-HCCMesh words from its decoded
//! structure and vertices (§5.1: "we traverse the decompressed tree in a
//! bottom-up manner and re-construct the AABB information"): tight boxes
//! bottom-up, then each sibling pair coded top-down against the box its
//! parent decodes to, with the i-HCCMesh encoder's own pair coding
//! ([`code_pair`](super::super::pair::code_pair)), so that the words come
//! out as that encoder writes them.
//! Linear in the tree's nodes, no recursion (children always sit at larger
//! positions than their parent, so one reverse and one forward sweep over
//! the nodes with children do, after one sweep over the leaves; the
//! layout lists both kinds, so no sweep branches on node types). Boxes are
//! kept as the pair coding's eight lanes (minima and negated maxima), so
//! that a union or a pair is a few vector operations: on the quantization
//! grid (as the encoder codes quantized boxes), in 16-bit lanes
//! ([`grid16`](super::super::grid16), one SSE2 register a box) when the
//! grid has at most 16 bits, else in `f32` lanes of grid coordinates.

use super::super::HccStats;
use super::super::block;
use super::super::node::{
    INDEX_BITS, INDEX_MASK, Interconnection, MASK_SHIFT, MULTI_COUNT_SHIFT, MULTI_OFFSET_BITS,
    TYPE_INNER, TYPE_LEAF, TYPE_SHIFT, TYPE_TEMPLATE_LEAF, pack_node,
};
use super::super::pair::{BoxLanes, Extents};
use super::model::Layout;
use crate::codec::common::bits::BitWriter;

/// Buffers reused from tree to tree, for boxes as `L`.
#[derive(Default)]
pub struct Rebuild<L: BoxLanes> {
    /// Per vertex, its box.
    pts: Vec<L>,
    /// Per position, the tight box and the vertex attaining each lane.
    tight: Vec<(L, L::Vertices)>,
    decoded: Vec<L>,
    /// Per inter-connection, the vertex its template leaf gave up, and
    /// one more entry that takes the writes of other nodes.
    ic_vertex: Vec<u32>,
}

/// The tight box of `tris` over vertices `pts` and the vertex attaining
/// each lane (ties go to the first corner).
#[inline(always)]
fn leaf_box<L: BoxLanes>(tris: &[[u32; 3]], pts: &[L]) -> (L, L::Vertices) {
    let mut corners = tris.iter().flatten();
    let first = corners.next().map_or(0, |&c| c);
    let mut b = (pts[first as usize], L::vertex(first));
    for &c in corners {
        b = L::union((&b.0, &b.1), (&pts[c as usize], &L::vertex(c)));
    }
    b
}

/// [`leaf_box`] of one triangle `c`, unrolled.
#[inline(always)]
fn triangle_box<L: BoxLanes>(c: [u32; 3], pts: &[L]) -> (L, L::Vertices) {
    let b = (pts[c[0] as usize], L::vertex(c[0]));
    let b = L::union((&b.0, &b.1), (&pts[c[1] as usize], &L::vertex(c[1])));
    L::union((&b.0, &b.1), (&pts[c[2] as usize], &L::vertex(c[2])))
}

impl<L: BoxLanes> Rebuild<L> {
    /// Appends the node words and inter-connections of the tree laid out
    /// in `lay` to `nodes` and `ics` (and, for multi-triangle leaves, its
    /// triangle blocks to `blocks` and their start to `block_start`); the
    /// `i`-th leaf (in `lay.leaves()`) holds `tris[spans[i].0..][..spans[i].1]`
    /// (`tris[i]` alone when `spans` is empty, which it must be exactly
    /// when `multi` is `None`), over vertices at grid coordinates `grid`
    /// (as the i-HCCMesh encoder codes quantized boxes). Counts its pairs
    /// and templates in `stats`; returns the tree's tight box, on the
    /// grid. Inlined into the decoder, its one caller.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    pub fn tree(
        &mut self,
        lay: &Layout,
        (spans, tris): (&[(u32, u32)], &[[u32; 3]]),
        grid: &[[u32; 3]],
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
        self.pts.clear();
        self.pts.extend(grid.iter().map(|&g| L::point(g)));
        let pts = &self.pts[..];
        let n = lay.positions();
        let types = lay.types();
        let kids = lay.kids();
        let ic_of = lay.ic_of();
        self.tight.resize(n, Default::default());
        self.decoded.resize(n, L::default());
        // Tight boxes and the vertices attaining them: the leaves, then the
        // other nodes bottom-up (children sit at larger positions than
        // their parent); ties go to the first corner and to the left
        // child, as the encoder's.
        if spans.is_empty() {
            for (&p, &c) in lay.leaves().iter().zip(tris) {
                self.tight[p as usize] = triangle_box(c, pts);
            }
        } else {
            for (i, &p) in lay.leaves().iter().enumerate() {
                self.tight[p as usize] = leaf_box(leaf(i), pts);
            }
        }
        for &p in lay.inner().iter().rev() {
            let [l, r] = kids[p as usize].map(|k| k as usize);
            let ((tl, al), (tr, ar)) = (&self.tight[l], &self.tight[r]);
            self.tight[p as usize] = L::union((tl, al), (tr, ar));
        }
        let base = nodes.len();
        nodes.resize(base + n, TYPE_INNER << TYPE_SHIFT);
        let words = &mut nodes[base..];
        for &p in lay.inner() {
            // A select, not a branch: template leaves come unpredictably.
            // (Other nodes have no inter-connection: their masked field
            // is computed and dropped.)
            let ic = ic_of[p as usize] & INDEX_MASK;
            let tl = pack_node([0, 0, ic], 0, TYPE_TEMPLATE_LEAF);
            let w = &mut words[p as usize];
            *w = if types[p as usize] == TYPE_TEMPLATE_LEAF {
                tl
            } else {
                *w
            };
        }
        match multi {
            None => {
                for (&p, &c) in lay.leaves().iter().zip(tris) {
                    words[p as usize] = pack_node(c, 0, TYPE_LEAF);
                }
            }
            Some((blocks, block_start)) => {
                // Blocks in node-word order, as the i-HCCMesh encoder
                // writes them; the tree's triangle limit keeps every
                // offset within the leaf word's field.
                let slot_bits = block::slot_bits(tris.len() as u32);
                let mut w = BitWriter::default();
                for (i, &p) in lay.leaves().iter().enumerate() {
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
        self.ic_vertex.resize(lay.ics.len() + 1, 0);
        let spare = lay.ics.len();
        // Pairs top-down, each against its parent's decoded box; the
        // counts kept in locals (registers), added to `stats` after.
        let (mut inner_pairs, mut mixed_pairs, mut loose) = (0, 0, 0);
        self.decoded[0] = self.tight[0].0;
        for &p in lay.inner() {
            let pair = kids[p as usize].map(|k| k as usize);
            let [l, r] = pair;
            let (ll, rl) = (types[l] == TYPE_LEAF, types[r] == TYPE_LEAF);
            let ((tl, al), (tr, ar)) = (&self.tight[l], &self.tight[r]);
            let pc = L::code(&self.decoded[p as usize], (tl, al, ll), (tr, ar, rl));
            // Fields a pair does not use are zero: or-ing them in is a
            // no-op. A template leaf's third field goes to its
            // inter-connection (other nodes write the spare entry).
            for (side, &pos) in pair.iter().enumerate() {
                let f = pc.fields[side];
                let tl = types[pos] == TYPE_TEMPLATE_LEAF;
                let ic = if tl { ic_of[pos] as usize } else { spare };
                self.ic_vertex[ic] = f[2];
                let third = if tl { 0 } else { f[2] << (2 * INDEX_BITS) };
                words[pos] |=
                    f[0] | f[1] << INDEX_BITS | third | (pc.mask >> (3 * side) & 7) << MASK_SHIFT;
            }
            inner_pairs += usize::from(!ll && !rl);
            mixed_pairs += usize::from(ll != rl);
            loose += pc.loose;
            self.decoded[l] = pc.boxes[0];
            self.decoded[r] = pc.boxes[1];
        }
        stats.inner_pairs += inner_pairs;
        stats.mixed_pairs += mixed_pairs;
        stats.loose_extents += loose;
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
        self.tight[0].0.extents()
    }
}
