//! Building an [`HccBvh`] from the canonical tree.

use super::block;
use super::canonical::check_tree;
use super::decompose::decompose;
use super::error::HccError;
use super::ids::{IdMap, VertexIds};
use super::node::{
    HIGH_LEAF, HighNode, INDEX_BITS, Interconnection, MAX_TREE_INTERCONNECTIONS, MAX_TREE_NODES,
    MAX_TREES, MULTI_COUNT_SHIFT, MULTI_OFFSET_BITS, TYPE_INNER, TYPE_LEAF, TYPE_SHIFT,
    TYPE_TEMPLATE_LEAF, TreeHeader, pack_node,
};
use super::pair::{Extents, code_pair, outer, to_lanes};
use super::template::{MAX_HEIGHT, MAX_TEMPLATE_NODES, TEMPLATES, id_of_mask};
use super::vertices::{MAX_VERTEX_BITS, Quantized, Vertices};
use super::{HccBvh, HccOptions, HccStats, MAX_LEAF_TRIANGLES};
use crate::build::CanonicalBvh;
use crate::codec::common::MassProps;
use crate::codec::common::bits::BitWriter;
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;

/// Tight boxes of every canonical node and, per extent, a vertex (mesh id)
/// that attains it.
struct Tight {
    boxes: Vec<Extents>,
    verts: Vec<[u32; 6]>,
}

/// The tight boxes of `bvh`'s nodes over `triangles` with positions
/// `points` (world positions, or grid coordinates when quantizing).
fn tight(bvh: &CanonicalBvh, triangles: &[[u32; 3]], points: &[[f32; 3]]) -> Tight {
    let n = bvh.nodes.len();
    let mut boxes = vec![[0.0f32; 6]; n];
    let mut verts = vec![[0u32; 6]; n];
    // Post-order with an explicit stack: (node, children done).
    let mut stack = vec![(0u32, false)];
    while let Some((i, done)) = stack.pop() {
        let node = &bvh.nodes[i as usize];
        if node.is_leaf() {
            let mut b = super::pair::EMPTY;
            let mut v = [0u32; 6];
            for &t in &bvh.leaf_triangles[node.leaf_range()] {
                for c in triangles[t as usize] {
                    let p = points[c as usize];
                    for e in 0..6 {
                        if outer(e, p[e % 3], b[e]) {
                            b[e] = p[e % 3];
                            v[e] = c;
                        }
                    }
                }
            }
            boxes[i as usize] = b;
            verts[i as usize] = v;
        } else if !done {
            stack.push((i, true));
            stack.push((node.a, false));
            stack.push((node.b, false));
        } else {
            let (l, r) = (node.a as usize, node.b as usize);
            for e in 0..6 {
                let from = if outer(e, boxes[r][e], boxes[l][e]) {
                    r
                } else {
                    l
                };
                boxes[i as usize][e] = boxes[from][e];
                verts[i as usize][e] = verts[from][e];
            }
        }
    }
    Tight { boxes, verts }
}

/// What one encode reads and accumulates besides the structure itself.
struct Scratch<'a> {
    bvh: &'a CanonicalBvh,
    mesh: &'a Mesh,
    /// The tight boxes: in world coordinates, or with quantized vertices
    /// in the grid's integer coordinates (see `grid`).
    tight: Tight,
    /// The quantization grid, when `tight` is on it.
    grid: Option<Quantized>,
    /// Local position of each canonical node in its low-level tree.
    pos_of: Vec<u32>,
    /// Local vertex index of each mesh vertex, valid where `stamp` is the
    /// current tree.
    local_of: Vec<u32>,
    stamp: Vec<u32>,
    /// The mesh vertex of each stored vertex (all trees so far).
    stored: Vec<u32>,
    /// The input id of each stored triangle, in rank order.
    rank_ids: Vec<u32>,
}

impl Scratch<'_> {
    /// The local index of mesh vertex `v` in tree `tree`, whose array
    /// starts at stored vertex `base`, appending it on first use.
    fn local_vertex(&mut self, tree: u32, v: u32, base: u32) -> u32 {
        let v = v as usize;
        if self.stamp[v] != tree {
            self.stamp[v] = tree;
            self.local_of[v] = self.stored.len() as u32 - base;
            self.stored.push(v as u32);
        }
        self.local_of[v]
    }
}

/// One low-level tree under construction.
#[derive(Default)]
struct TreeBuild {
    /// Canonical node at each local position.
    canon_at: Vec<u32>,
    /// Node type at each local position.
    types: Vec<u32>,
    /// Inter-connection index of each template leaf (by local position).
    ic_at: Vec<u32>,
    ics: Vec<Interconnection>,
    words: Vec<u32>,
    /// Template leaves whose child templates are not yet allocated.
    pending: Vec<u32>,
}

impl TreeBuild {
    /// Lays out the template rooted at canonical node `root` at the end of
    /// the node array; returns its id and first local position.
    fn alloc_template(&mut self, bvh: &CanonicalBvh, pos_of: &mut [u32], root: u32) -> (u8, u32) {
        let mut list = [0u32; MAX_TEMPLATE_NODES];
        let mut depth = [0usize; MAX_TEMPLATE_NODES];
        list[0] = root;
        let (mut len, mut i, mut mask) = (1usize, 0usize, 0u16);
        while i < len {
            let n = &bvh.nodes[list[i] as usize];
            if !n.is_leaf() && depth[i] < MAX_HEIGHT - 1 {
                mask |= 1 << i;
                list[len] = n.a;
                list[len + 1] = n.b;
                depth[len] = depth[i] + 1;
                depth[len + 1] = depth[i] + 1;
                len += 2;
            }
            i += 1;
        }
        let id = id_of_mask(mask).expect("a breadth-first shape of height at most 4");
        let start = self.canon_at.len() as u32;
        for (k, &n) in list[..len].iter().enumerate() {
            pos_of[n as usize] = start + k as u32;
            self.canon_at.push(n);
            let ty = if bvh.nodes[n as usize].is_leaf() {
                TYPE_LEAF
            } else if mask >> k & 1 != 0 {
                TYPE_INNER
            } else {
                self.pending.push(n);
                TYPE_TEMPLATE_LEAF
            };
            self.types.push(ty);
            self.ic_at.push(u32::MAX);
        }
        (id, start)
    }

    /// Writes the 9-bit field `j` of the node at local position `p`; the
    /// third field of a template leaf goes to its inter-connection.
    fn set_field(&mut self, p: u32, j: usize, v: u32) {
        let p = p as usize;
        if j == 2 && self.types[p] == TYPE_TEMPLATE_LEAF {
            self.ics[self.ic_at[p] as usize].vertex = v;
        } else {
            self.words[p] |= v << (INDEX_BITS as usize * j);
        }
    }
}

impl HccBvh {
    /// Encodes `bvh` (built over `mesh`) with the default options
    /// (lossless `f32` vertices, input vertex ids kept). A tree with one
    /// triangle a leaf gives the paper's i-HCCMesh; one built with
    /// [`BuildOptions::max_leaf_triangles`](crate::build::BuildOptions)
    /// above 1 (at most [`MAX_LEAF_TRIANGLES`]) gives multi-triangle leaves.
    pub fn encode(bvh: &CanonicalBvh, mesh: &Mesh) -> Result<Self, HccError> {
        Self::encode_with(bvh, mesh, &HccOptions::default())
    }

    /// Encodes `bvh` (built over `mesh`) with `options`.
    pub fn encode_with(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &HccOptions,
    ) -> Result<Self, HccError> {
        Self::encode_part(bvh, mesh, options, None)
    }

    /// [`encode_with`](Self::encode_with), or with `part` one chunk of a
    /// larger model (the out-of-core builder's): quantized on the grid of
    /// the whole model's bounds `part` gives, with neither mass nor edge
    /// flags (the builder sums those over the chunks).
    pub(super) fn encode_part(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &HccOptions,
        part: Option<([f32; 3], [f32; 3])>,
    ) -> Result<Self, HccError> {
        let multi = bvh.max_leaf_triangles > 1;
        if bvh.max_leaf_triangles > MAX_LEAF_TRIANGLES {
            return Err(HccError::LeafSize {
                got: bvh.max_leaf_triangles,
                limit: MAX_LEAF_TRIANGLES,
            });
        }
        if bvh.triangle_count() != mesh.triangles.len() {
            return Err(HccError::MeshMismatch {
                tree: bvh.triangle_count(),
                mesh: mesh.triangles.len(),
            });
        }
        if !mesh.triangles.is_empty() {
            let leaf_limit = if multi { MAX_LEAF_TRIANGLES } else { 1 };
            check_tree(bvh, mesh.triangles.len(), leaf_limit)?;
        }
        if let Some(bits) = options.vertex_bits
            && !(1..=MAX_VERTEX_BITS).contains(&bits)
        {
            return Err(HccError::VertexBits {
                got: bits,
                limit: MAX_VERTEX_BITS,
            });
        }
        let (quant, qcoords, points) = quantize(mesh, options.vertex_bits, part)?;
        let points: &[[f32; 3]] = points.as_deref().unwrap_or(&mesh.vertices);
        let mut out = HccBvh {
            high: Vec::new(),
            headers: Vec::new(),
            nodes: Vec::new(),
            ics: Vec::new(),
            vertices: Vertices::default(),
            blocks: Vec::new(),
            block_start: Vec::new(),
            leaf_bits: Vec::new(),
            leaf_rank: Vec::new(),
            ids: None,
            vertex_ids: None,
            multi,
            triangle_count: mesh.triangles.len() as u32,
            mesh_vertices: mesh.vertices.len() as u32,
            mass: match part {
                Some(_) => MassProps::ZERO,
                None => MassProps::of_mesh(mesh),
            },
            edges: EdgeFlags::default(),
            stats: HccStats::default(),
        };
        let mut s = Scratch {
            bvh,
            mesh,
            tight: Tight {
                boxes: Vec::new(),
                verts: Vec::new(),
            },
            grid: quant.clone(),
            pos_of: vec![0; bvh.nodes.len()],
            local_of: vec![0; mesh.vertices.len()],
            stamp: vec![u32::MAX; mesh.vertices.len()],
            stored: Vec::new(),
            rank_ids: Vec::with_capacity(mesh.triangles.len()),
        };
        if !mesh.triangles.is_empty() {
            // With quantized vertices, the boxes and the pair coding work
            // on the grid's integer coordinates (exact in `f32`: at most
            // 24 bits), which the o-HCCMesh decoder has without computing
            // a value: a pair is coded by comparing integers, whatever
            // the grid's values round to.
            let on_grid: Option<Vec<[f32; 3]>> = qcoords
                .as_ref()
                .map(|qc| qc.iter().map(|g| g.map(|c| c as f32)).collect());
            s.tight = tight(bvh, &mesh.triangles, on_grid.as_deref().unwrap_or(points));
            out.encode_trees(&mut s)?;
        }
        out.build_leaf_ranks();
        out.ids = options.triangle_ids.then(|| IdMap::new(&s.rank_ids));
        let mut used = vec![false; mesh.vertices.len()];
        for t in &mesh.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        if options.vertex_ids {
            let unused = (0..mesh.vertices.len())
                .filter(|&v| !used[v])
                .map(|v| (v as u32, points[v]))
                .collect();
            out.vertex_ids = Some(VertexIds::new(&s.stored, unused));
        }
        out.vertices = match (quant, qcoords) {
            (Some(mut q), Some(qc)) => {
                let mut grid = Vec::new();
                for (k, h) in out.headers.iter().enumerate() {
                    let end = out
                        .headers
                        .get(k + 1)
                        .map_or(s.stored.len(), |n| n.vertex_start as usize);
                    grid.clear();
                    grid.extend(
                        s.stored[h.vertex_start as usize..end]
                            .iter()
                            .map(|&v| qc[v as usize]),
                    );
                    q.push_tree(&grid);
                }
                Vertices::Packed(q)
            }
            _ => Vertices::F32(s.stored.iter().map(|&v| points[v as usize]).collect()),
        };
        out.stats.trees = out.headers.len();
        out.stats.tree_vertices = s.stored.len();
        out.stats.mesh_vertices = used.iter().filter(|&&u| u).count();
        out.stats.high_nodes = out.high.len();
        if part.is_none() {
            out.edges = crate::codec::common::edges::of_cursor(&out);
        }
        Ok(out)
    }

    /// The high-level tree, depth-first, left first; its leaves number the
    /// low-level trees in the same order.
    fn encode_trees(&mut self, s: &mut Scratch<'_>) -> Result<(), HccError> {
        let dec = decompose(s.bvh, s.mesh).map_err(|e| HccError::LeafTooBig {
            node: e.node,
            vertices: e.vertices,
        })?;
        if dec.roots.len() > MAX_TREES {
            return Err(HccError::TooManyTrees {
                trees: dec.roots.len(),
                limit: MAX_TREES,
            });
        }
        let mut is_root = vec![false; s.bvh.nodes.len()];
        for &r in &dec.roots {
            is_root[r as usize] = true;
        }
        self.high.push(HighNode::zeroed_node());
        let mut stack = vec![(0u32, 0u32)];
        while let Some((c, h)) = stack.pop() {
            let b = s.tight.boxes[c as usize];
            let b = match &s.grid {
                // Monotone: the grid value of the least grid coordinate is
                // the least value.
                Some(q) => std::array::from_fn(|e| q.value(e % 3, b[e] as u32)),
                None => b,
            };
            let mut node = HighNode {
                min: [b[0], b[1], b[2]],
                max: [b[3], b[4], b[5]],
                a: self.high.len() as u32,
                b: self.high.len() as u32 + 1,
            };
            if is_root[c as usize] {
                node.a = self.headers.len() as u32;
                node.b = HIGH_LEAF;
                self.high[h as usize] = node;
                self.encode_tree(s, c)?;
            } else {
                let first = node.a;
                self.high[h as usize] = node;
                self.high.push(HighNode::zeroed_node());
                self.high.push(HighNode::zeroed_node());
                let cn = &s.bvh.nodes[c as usize];
                stack.push((cn.b, first + 1));
                stack.push((cn.a, first));
            }
        }
        Ok(())
    }

    /// Encodes the low-level tree rooted at canonical node `root`.
    fn encode_tree(&mut self, s: &mut Scratch<'_>, root: u32) -> Result<(), HccError> {
        let bvh = s.bvh;
        let tree = self.headers.len() as u32;
        let header = TreeHeader {
            node_start: self.nodes.len() as u32,
            ic_start: self.ics.len() as u32,
            vertex_start: s.stored.len() as u32,
            first_triangle: s.rank_ids.len() as u32,
        };
        self.headers.push(header);
        let mut t = TreeBuild::default();
        // Structure: templates top-down, the two child templates of a
        // template leaf next to each other, template leaves taken
        // depth-first so a subtree's templates stay close in memory.
        let (root_template, _) = t.alloc_template(bvh, &mut s.pos_of, root);
        while let Some(n) = t.pending.pop() {
            let node = &bvh.nodes[n as usize];
            let (lt, ls) = t.alloc_template(bvh, &mut s.pos_of, node.a);
            let (rt, rs) = t.alloc_template(bvh, &mut s.pos_of, node.b);
            debug_assert_eq!(rs, ls + TEMPLATES[lt as usize].nodes as u32);
            t.ic_at[s.pos_of[n as usize] as usize] = t.ics.len() as u32;
            t.ics.push(Interconnection {
                vertex: 0,
                left_template: lt,
                right_template: rt,
                left_start: ls,
            });
        }
        if t.canon_at.len() > MAX_TREE_NODES || t.ics.len() > MAX_TREE_INTERCONNECTIONS {
            return Err(HccError::TreeLimits {
                tree,
                nodes: t.canon_at.len(),
                interconnections: t.ics.len(),
            });
        }
        t.words = t
            .types
            .iter()
            .zip(&t.ic_at)
            .map(|(&ty, &ic)| {
                if ty == TYPE_TEMPLATE_LEAF {
                    pack_node([0, 0, ic], 0, ty)
                } else {
                    ty << TYPE_SHIFT
                }
            })
            .collect();
        self.encode_leaves(s, &mut t, tree, &header)?;
        if t.types[0] != TYPE_LEAF {
            t.words[0] |= root_template as u32;
        }
        self.encode_boxes(s, &mut t, root);
        self.nodes.extend_from_slice(&t.words);
        self.ics.extend(t.ics.iter().map(Interconnection::pack));
        // Template statistics: every template root (the tree root and the
        // children of template leaves).
        self.stats.templates[root_template as usize] += 1;
        for ic in &t.ics {
            self.stats.templates[ic.left_template as usize] += 1;
            self.stats.templates[ic.right_template as usize] += 1;
        }
        Ok(())
    }

    /// The leaves in node-word order: their triangles' ranks (input ids in
    /// `rank_ids`), the tree's vertices by first use, and the leaf words
    /// (one triangle's corners, or a multi-triangle leaf's block).
    fn encode_leaves(
        &mut self,
        s: &mut Scratch<'_>,
        t: &mut TreeBuild,
        tree: u32,
        header: &TreeHeader,
    ) -> Result<(), HccError> {
        let (bvh, mesh) = (s.bvh, s.mesh);
        let tree_triangles: u32 = t
            .canon_at
            .iter()
            .zip(&t.types)
            .filter(|p| *p.1 == TYPE_LEAF)
            .map(|p| bvh.nodes[*p.0 as usize].leaf_range().len() as u32)
            .sum();
        let slot_bits = block::slot_bits(tree_triangles);
        let mut stream = BitWriter::default();
        let mut corners = Vec::new();
        for p in 0..t.canon_at.len() {
            if t.types[p] != TYPE_LEAF {
                continue;
            }
            let node = &bvh.nodes[t.canon_at[p] as usize];
            let ids = &bvh.leaf_triangles[node.leaf_range()];
            let slot = s.rank_ids.len() as u32 - header.first_triangle;
            s.rank_ids.extend_from_slice(ids);
            corners.clear();
            for &id in ids {
                let c = mesh.triangles[id as usize]
                    .map(|v| s.local_vertex(tree, v, header.vertex_start));
                corners.push(c);
            }
            if self.multi {
                let at = block::write(&mut stream, slot, slot_bits, &corners);
                if at >= 1 << MULTI_OFFSET_BITS {
                    return Err(HccError::BlockLimits { tree, bits: at });
                }
                t.words[p] |= at as u32 | (ids.len() as u32 - 1) << MULTI_COUNT_SHIFT;
            } else {
                t.words[p] = pack_node(corners[0], 0, TYPE_LEAF);
            }
        }
        if self.multi {
            self.block_start.push(self.blocks.len() as u32);
            self.blocks.extend_from_slice(&stream.finish());
            if u32::try_from(self.blocks.len()).is_err() {
                return Err(HccError::BlockLimits {
                    tree,
                    bits: self.blocks.len() as u64 * 8,
                });
            }
        }
        Ok(())
    }

    /// The boxes, top-down: each pair of children coded against the box
    /// their parent decodes to.
    fn encode_boxes(&mut self, s: &Scratch<'_>, t: &mut TreeBuild, root: u32) {
        let (bvh, tight) = (s.bvh, &s.tight);
        let local = |v: u32| s.local_of[v as usize];
        let lanes = |i: u32| {
            let v = tight.verts[i as usize];
            (
                to_lanes(&tight.boxes[i as usize]),
                [v[0], v[1], v[2], v[3], v[4], v[5], 0, 0],
            )
        };
        let mut stack = vec![(root, lanes(root).0)];
        while let Some((p, d)) = stack.pop() {
            let node = &bvh.nodes[p as usize];
            if node.is_leaf() {
                continue;
            }
            let (l, r) = (node.a, node.b);
            let (pl, pr) = (s.pos_of[l as usize], s.pos_of[r as usize]);
            let (ll, rl) = (
                t.types[pl as usize] == TYPE_LEAF,
                t.types[pr as usize] == TYPE_LEAF,
            );
            let ((bl, vl), (br, vr)) = (lanes(l), lanes(r));
            let pc = code_pair(&d, (&bl, &vl, ll), (&br, &vr, rl));
            for (side, pos) in [pl, pr].into_iter().enumerate() {
                for j in 0..pc.used[side] {
                    t.set_field(pos, j, local(pc.fields[side][j]));
                }
            }
            match (ll, rl) {
                (false, false) => self.stats.inner_pairs += 1,
                (true, true) => {}
                _ => self.stats.mixed_pairs += 1,
            }
            self.stats.loose_extents += pc.loose;
            let mask = pc.mask;
            let [dl, dr] = pc.boxes;
            t.words[pl as usize] |= (mask & 7) << super::node::MASK_SHIFT;
            t.words[pr as usize] |= (mask >> 3) << super::node::MASK_SHIFT;
            stack.push((l, dl));
            stack.push((r, dr));
        }
    }

    /// Rebuilds the leaf rank/select bits from the node words.
    pub(super) fn build_leaf_ranks(&mut self) {
        self.leaf_bits = vec![0; self.nodes.len().div_ceil(64)];
        for (bits, words) in self.leaf_bits.iter_mut().zip(self.nodes.chunks(64)) {
            for (i, &w) in words.iter().enumerate() {
                *bits |= u64::from(w >> TYPE_SHIFT == TYPE_LEAF) << i;
            }
        }
        self.rank_leaf_bits();
    }

    /// Rebuilds the leaf ranks from the leaf bits (which a decoder that
    /// knows where the leaves are may set without reading the words).
    pub(super) fn rank_leaf_bits(&mut self) {
        let mut before = 0;
        self.leaf_rank = self
            .leaf_bits
            .iter()
            .map(|w| {
                let r = before;
                before += w.count_ones();
                r
            })
            .collect();
    }
}

/// Quantized copies of `mesh`'s vertices when `bits` is set: the grid, each
/// vertex's grid coordinates, and its decoded position.
#[allow(clippy::type_complexity)]
fn quantize(
    mesh: &Mesh,
    bits: Option<u32>,
    bounds: Option<([f32; 3], [f32; 3])>,
) -> Result<
    (
        Option<Quantized>,
        Option<Vec<[u32; 3]>>,
        Option<Vec<[f32; 3]>>,
    ),
    HccError,
> {
    let Some(bits) = bits else {
        return Ok((None, None, None));
    };
    let (lo, hi) = bounds
        .or_else(|| mesh.bounds())
        .unwrap_or(([0.0; 3], [0.0; 3]));
    for a in 0..3 {
        let extent = hi[a] - lo[a];
        if !extent.is_finite() {
            return Err(HccError::Extent { extent });
        }
    }
    let mut q = Quantized::grid(bits, lo, hi);
    let mut error = [0f32; 3];
    let mut grid = Vec::with_capacity(mesh.vertices.len());
    let mut points = Vec::with_capacity(mesh.vertices.len());
    for v in &mesh.vertices {
        let g: [u32; 3] = std::array::from_fn(|a| q.nearest(a, v[a]));
        let p: [f32; 3] = std::array::from_fn(|a| q.value(a, g[a]));
        for a in 0..3 {
            error[a] = error[a].max((p[a] - v[a]).abs());
        }
        grid.push(g);
        points.push(p);
    }
    q.error = error;
    Ok((Some(q), Some(grid), Some(points)))
}

impl HighNode {
    fn zeroed_node() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}
