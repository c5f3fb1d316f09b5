//! Building a [`ClBvh`] (or a [`ClBvhCompact`]) from the canonical tree.
//!
//! # Leaf blocks
//! A leaf block holds the triangles of an isolated leaf, or of all lanes of
//! a multi-leaf node (lane by lane), in 4-byte arena words:
//!
//! | words | fast ([`LeafKind::Fast`]) | compact ([`LeafKind::Compact`]) |
//! |---|---|---|
//! | 1 | header: `n` (triangles) | header: `n \| U << 16` (`U` unique vertices) |
//! | next | `n` triangle ids (u32) | `U` vertex indices (u32), first use first |
//! | next | `9n` corners (f32, `[a, b, c]` each `[x, y, z]`) | `n` triangle ids (u32) |
//! | next | — | `⌈3n / 4⌉` words of local corner indices (u8 into the `U` list) |

use super::collapse::{Plan, triangles_below};
use super::node::{
    ChildRef, InnerNode, MAX_REF_INDEX, MultiLeafNode, TAG_INNER, TAG_LEAF, TAG_MULTI, child_ref,
};
use super::{ClBvh, ClBvhCompact, ClError, ClOptions, CompactOptions, LeafKind};
use crate::build::CanonicalBvh;
use crate::codec::common::MassProps;
use crate::codec::common::huge::huge;
use crate::codec::common::quant::Grid;
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;

/// The largest leaf size `M` (the N×M threshold is `8 · M`): a multi-leaf
/// node's up to `3 · 8 · M` distinct vertices must fit 8-bit local indices
/// in the compact variant, and its triangle counts 8-bit leaf ends.
pub const MAX_LEAF_SIZE: usize = 10;

struct Emitter<'a> {
    bvh: &'a CanonicalBvh,
    mesh: &'a Mesh,
    kind: LeafKind,
    inner: Vec<InnerNode>,
    arena: Vec<u32>,
    multi: usize,
    next_slot: u32,
    slot_of: Vec<u32>,
    blocks: Vec<[u32; 2]>,
    ids: Vec<u32>,
}

fn checked(what: &'static str, v: usize) -> Result<u32, ClError> {
    if v > MAX_REF_INDEX as usize {
        Err(ClError::TooLarge {
            what,
            value: v as u64,
            max: u64::from(MAX_REF_INDEX),
        })
    } else {
        Ok(v as u32)
    }
}

impl Emitter<'_> {
    /// Appends a leaf block for `ids` and returns its word offset.
    fn block(&mut self, ids: &[u32]) -> Result<u32, ClError> {
        let at = checked("arena words", self.arena.len())?;
        let n = ids.len() as u32;
        match self.kind {
            LeafKind::Fast => {
                self.arena.push(n);
                self.arena.extend_from_slice(ids);
                for &id in ids {
                    let corners = self.mesh.triangle_vertices(id as usize);
                    self.arena
                        .extend(corners.iter().flatten().map(|c| c.to_bits()));
                }
            }
            LeafKind::Compact => {
                let mut uniq: Vec<u32> = Vec::new();
                let mut local: Vec<u8> = Vec::with_capacity(3 * ids.len());
                for &id in ids {
                    for v in self.mesh.triangles[id as usize] {
                        let k = match uniq.iter().position(|&u| u == v) {
                            Some(k) => k,
                            None => {
                                uniq.push(v);
                                uniq.len() - 1
                            }
                        };
                        // At most 3 · 8 · MAX_LEAF_SIZE = 240 distinct.
                        local.push(k as u8);
                    }
                }
                debug_assert!(uniq.len() <= 256);
                self.arena.push(n | (uniq.len() as u32) << 16);
                self.arena.extend_from_slice(&uniq);
                self.arena.extend_from_slice(ids);
                local.resize(local.len().next_multiple_of(4), 0);
                self.arena.extend(
                    local
                        .chunks_exact(4)
                        .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])),
                );
                self.blocks.push([self.next_slot, at]);
                for &id in ids {
                    self.slot_of[id as usize] = self.next_slot;
                    self.next_slot += 1;
                }
            }
        }
        Ok(at)
    }

    fn isolated_leaf(&mut self, c: u32) -> Result<ChildRef, ClError> {
        let mut ids = std::mem::take(&mut self.ids);
        ids.clear();
        triangles_below(self.bvh, c, &mut ids);
        let at = self.block(&ids);
        self.ids = ids;
        Ok(child_ref(TAG_LEAF, at?))
    }

    fn multi_leaf(&mut self, plan: &Plan, c: u32) -> Result<ChildRef, ClError> {
        let kids = plan.children(self.bvh, c);
        let outer = self.bvh.nodes[c as usize].aabb();
        // The 8-bit conservative grid over the node's float box (min
        // rounds down, max up, checked with the decoder's arithmetic).
        let frame = Grid::new(&outer, 8);
        if !frame.step.is_finite() {
            return Err(ClError::Extent {
                min: outer.min.to_array(),
                max: outer.max.to_array(),
            });
        }
        let mut node = MultiLeafNode {
            start: frame.origin.to_array(),
            step: frame.step.to_array(),
            lo_x: [255; 8],
            hi_x: [0; 8],
            lo_y: [255; 8],
            hi_y: [0; 8],
            lo_z: [255; 8],
            hi_z: [0; 8],
        };
        let mut ends = [0u8; 8];
        let mut ids = std::mem::take(&mut self.ids);
        ids.clear();
        for (k, &kid) in kids.iter().enumerate() {
            let q = frame.quantize(&self.bvh.nodes[kid as usize].aabb());
            // At most 255 with 8 bits.
            let (lo, hi) = (
                q.min.to_array().map(|v| v as u8),
                q.max.to_array().map(|v| v as u8),
            );
            (node.lo_x[k], node.lo_y[k], node.lo_z[k]) = (lo[0], lo[1], lo[2]);
            (node.hi_x[k], node.hi_y[k], node.hi_z[k]) = (hi[0], hi[1], hi[2]);
            triangles_below(self.bvh, kid, &mut ids);
            ends[k] = ids.len() as u8;
        }
        ends[kids.len()..].fill(ids.len() as u8);
        let at = checked("arena words", self.arena.len())?;
        self.arena
            .extend_from_slice(bytemuck::cast_slice::<_, u32>(&[node]));
        self.arena
            .extend_from_slice(bytemuck::cast_slice::<_, u32>(&[ends]));
        self.multi += 1;
        let block = self.block(&ids);
        self.ids = ids;
        block?;
        Ok(child_ref(TAG_MULTI, at))
    }
}

impl ClBvh {
    /// Encodes `bvh` (built over `mesh`) with `options`.
    pub fn encode(bvh: &CanonicalBvh, mesh: &Mesh, options: &ClOptions) -> Result<Self, ClError> {
        let m = options.leaf_size;
        if !(1..=MAX_LEAF_SIZE).contains(&m) {
            return Err(ClError::LeafSize {
                got: m,
                max: MAX_LEAF_SIZE,
            });
        }
        if bvh.max_leaf_triangles > m {
            return Err(ClError::CanonicalLeaves {
                canonical: bvh.max_leaf_triangles,
                leaf_size: m,
            });
        }
        if bvh.triangle_count() != mesh.triangles.len() {
            return Err(ClError::MeshMismatch {
                tree: bvh.triangle_count(),
                mesh: mesh.triangles.len(),
            });
        }
        let threshold = if options.multi_leaf { 8 * m as u32 } else { 0 };
        let plan = Plan::new(bvh, m);
        let mut e = Emitter {
            bvh,
            mesh,
            kind: options.leaves,
            inner: Vec::new(),
            arena: Vec::new(),
            multi: 0,
            next_slot: 0,
            slot_of: match options.leaves {
                LeafKind::Fast => Vec::new(),
                LeafKind::Compact => vec![0; mesh.triangles.len()],
            },
            blocks: Vec::new(),
            ids: Vec::new(),
        };
        let mut work: Vec<(u32, usize)> = Vec::new();
        let node = |e: &mut Emitter, work: &mut Vec<(u32, usize)>, c: u32| {
            if plan.as_leaf[c as usize] {
                e.isolated_leaf(c)
            } else if plan.count[c as usize] <= threshold {
                e.multi_leaf(&plan, c)
            } else {
                let idx = checked("inner nodes", e.inner.len())?;
                e.inner.push(InnerNode::EMPTY);
                work.push((c, idx as usize));
                Ok(child_ref(TAG_INNER, idx))
            }
        };
        let root = node(&mut e, &mut work, 0)?;
        while let Some((c, idx)) = work.pop() {
            for (k, kid) in plan.children(bvh, c).into_iter().enumerate() {
                let r = node(&mut e, &mut work, kid)?;
                e.inner[idx].set(k, r, &bvh.nodes[kid as usize].aabb());
            }
        }
        let mut out = ClBvh {
            options: *options,
            inner: huge(e.inner),
            arena: huge(e.arena),
            multi_nodes: e.multi,
            root,
            root_box: bvh.root_aabb(),
            vertices: huge(mesh.vertices.iter().copied()),
            triangles: match options.leaves {
                LeafKind::Fast => huge(mesh.triangles.iter().copied()),
                LeafKind::Compact => Vec::new(),
            },
            slot_of: e.slot_of,
            blocks: e.blocks,
            mass: MassProps::of_mesh(mesh),
            edges: EdgeFlags::default(),
        };
        out.edges = crate::codec::common::edges::of_cursor(&out);
        Ok(out)
    }
}

impl ClBvhCompact {
    /// Encodes `bvh` (built over `mesh`) with compact leaves.
    pub fn encode(bvh: &CanonicalBvh, mesh: &Mesh, o: &CompactOptions) -> Result<Self, ClError> {
        let opts = ClOptions {
            leaf_size: o.leaf_size,
            leaves: LeafKind::Compact,
            multi_leaf: o.multi_leaf,
        };
        ClBvh::encode(bvh, mesh, &opts).map(ClBvhCompact)
    }
}
