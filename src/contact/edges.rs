//! Active edges: which triangle edges of a mesh are real edges of its
//! surface, computed once from the mesh, so that contacts on a tessellated
//! surface do not catch on the edges between its triangles.
//!
//! # The flags
//!
//! Every triangle gets one byte ([`EdgeFlags::get`]): bits 0–2 say whether
//! its edges 0, 1, 2 (edge `k` runs from corner `k` to corner `k + 1`) are
//! *active seen from the front* (the side its winding's normal points to),
//! bits 3–5 the same *seen from the back*. An edge is
//!
//! - active from both sides when it lies on the mesh's boundary (one
//!   triangle), is shared by more than two triangles, or belongs to a
//!   triangle without area;
//! - inactive from both sides when its two triangles are within the flat
//!   angle of each other ([`EdgeFlags::DEFAULT_FLAT_DEG`], 5°, as Jolt's
//!   default): a tessellated plane or a smooth curve;
//! - otherwise active from the side on which it is convex (a ridge) and
//!   inactive from the side on which it is concave (a valley: a convex body
//!   cannot touch the edge without touching a face first).
//!
//! A neighbour wound the other way round (the shared edge runs the same way
//! in both triangles) is compared with its normal reversed. Vertices are
//! welded by position, so a mesh that repeats its vertices per triangle
//! gets the same flags as one that shares them.
//!
//! Jolt stores the front bits only (its meshes are one-sided); the back bits
//! let a two-sided open mesh (a ground, a ramp, a bowl) be touched from
//! either side with the right edges. See [`crate::contact::orient`] for how
//! contacts use them.
//!
//! # Cost
//!
//! One byte a triangle in memory. Computing takes two sorts of three
//! entries a triangle (welding the corners, then pairing the edges), in
//! parallel on rayon's threads: about 48 bytes a triangle while it runs,
//! and about a second per million triangles. Codecs therefore compute the
//! flags once, when they encode, and store them in their files
//! ([`crate::codec::common::edges`]); a shape opened from a file reads
//! them ([`from_flags`](EdgeFlags::from_flags)) instead of computing them.

use std::sync::Arc;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::geom::Triangle;

/// Bits of the edges active from the front.
pub const FRONT: u8 = 0b000_111;
/// Bits of the edges active from the back.
pub const BACK: u8 = 0b111_000;
/// Every edge active from both sides (a triangle with no neighbours).
pub const ALL_ACTIVE: u8 = FRONT | BACK;

/// The flags of a mesh's triangles, by triangle id. See the module docs.
///
/// Cloning is cheap: the flags are shared (a codec and the shapes made
/// from it hold the same bytes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EdgeFlags {
    flags: Arc<[u8]>,
    /// Edges with one triangle.
    pub boundary_edges: u64,
    /// Edges with more than two triangles.
    pub non_manifold_edges: u64,
    /// Edges whose two triangles are wound the same way round.
    pub misoriented_edges: u64,
    /// Edges inactive from both sides (flat).
    pub flat_edges: u64,
    /// The signed volume the triangles enclose (positive when wound
    /// counter-clockwise seen from outside).
    pub signed_volume: f64,
}

impl EdgeFlags {
    /// The default flat angle in degrees: neighbours closer than this are
    /// one smooth surface.
    pub const DEFAULT_FLAT_DEG: f32 = 5.0;

    /// The flags of `count` triangles, triangle `id` given by `triangle(id)`,
    /// with the default flat angle.
    pub fn compute(count: usize, triangle: impl Fn(u32) -> Triangle + Sync) -> Self {
        Self::compute_with(count, triangle, Self::DEFAULT_FLAT_DEG)
    }

    /// [`compute`](Self::compute) with the flat angle `flat_deg` (degrees).
    pub fn compute_with(
        count: usize,
        triangle: impl Fn(u32) -> Triangle + Sync,
        flat_deg: f32,
    ) -> Self {
        assert!(
            count <= (u32::MAX / 3) as usize,
            "edge flags index corners with u32"
        );
        let normals: Vec<Vec3A> = (0..count as u32)
            .into_par_iter()
            .map(|t| unit_normal(&triangle(t)))
            .collect();
        let corners: Vec<([u32; 3], u32)> = (0..count as u32)
            .into_par_iter()
            .flat_map_iter(|t| {
                let v = triangle(t);
                (0..3u32).map(move |k| (key(v[k as usize]), t * 3 + k))
            })
            .collect();
        Self::from_corners(normals, corners, flat_deg)
    }

    /// The flags of `count` triangles handed out by `visit`, which calls
    /// its argument once with every triangle id below `count` and the
    /// triangle, in any order (a traversal of a tree's leaves, which is
    /// cheaper than looking every id up); ids it skips get every edge
    /// active. Default flat angle.
    pub fn from_visit(count: usize, visit: impl FnOnce(&mut dyn FnMut(u32, &Triangle))) -> Self {
        let (normals, corners) = visited(count, visit);
        Self::from_corners(normals, corners, Self::DEFAULT_FLAT_DEG)
    }

    /// The flags from each triangle's unit normal and its corners' position
    /// bits (corner `t * 3 + k` of triangle `t`).
    fn from_corners(normals: Vec<Vec3A>, corners: Vec<([u32; 3], u32)>, flat_deg: f32) -> Self {
        Self::from_corners_open(normals, corners, flat_deg, None)
    }

    /// [`from_visit`](Self::from_visit), and also every *open* edge: one
    /// with a single triangle among these (not degenerate), which another
    /// part of a larger mesh may share. The out-of-core builder computes
    /// each part's flags so, then pairs the parts' open edges across parts
    /// with [`resolve_open`](Self::resolve_open).
    pub fn from_visit_open(
        count: usize,
        visit: impl FnOnce(&mut dyn FnMut(u32, &Triangle)),
    ) -> (Self, Vec<OpenEdge>) {
        let (normals, corners) = visited(count, visit);
        let mut open = Vec::new();
        let flags =
            Self::from_corners_open(normals, corners, Self::DEFAULT_FLAT_DEG, Some(&mut open));
        (flags, open)
    }

    fn from_corners_open(
        normals: Vec<Vec3A>,
        mut corners: Vec<([u32; 3], u32)>,
        flat_deg: f32,
        mut open: Option<&mut Vec<OpenEdge>>,
    ) -> Self {
        let count = normals.len();
        let cos_flat = flat_deg.to_radians().cos();
        corners.par_sort_unstable();
        // Welded vertex of every corner, and each vertex's position.
        let mut vertex_of = vec![0u32; corners.len()];
        let mut positions: Vec<Vec3A> = Vec::new();
        for (k, (bits, corner)) in corners.iter().enumerate() {
            if k == 0 || corners[k - 1].0 != *bits {
                positions.push(Vec3A::from(bits.map(f32::from_bits)));
            }
            vertex_of[*corner as usize] = (positions.len() - 1) as u32;
        }
        drop(corners);
        let volume = |t: usize| {
            if !normals[t].is_finite() {
                return 0.0;
            }
            let p = |k: usize| {
                let q = positions[vertex_of[t * 3 + k] as usize];
                DVec3::new(q.x as f64, q.y as f64, q.z as f64)
            };
            p(0).dot(p(1).cross(p(2))) / 6.0
        };
        // Summed in fixed chunks, then in order: the same bits whatever
        // the threads do (codecs store the volume; encoding twice gives
        // the same file).
        const CHUNK: usize = 1 << 14;
        let signed_volume = (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                (c * CHUNK..count.min(c * CHUNK + CHUNK))
                    .map(volume)
                    .sum::<f64>()
            })
            .collect::<Vec<f64>>()
            .into_iter()
            .sum();
        // Half-edges by their welded ends, the lower first; the low bit
        // of the value says whether the edge runs from the higher end.
        let mut half: Vec<(u64, u32)> = (0..count * 3)
            .into_par_iter()
            .map(|c| {
                let t = c / 3;
                let (a, b) = (vertex_of[c], vertex_of[t * 3 + (c % 3 + 1) % 3]);
                let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                (key, ((c as u32) << 1) | u32::from(a > b))
            })
            .collect();
        half.par_sort_unstable();
        let mut flags = vec![0u8; count];
        let mut out = EdgeFlags::default();
        let mut start = 0;
        while start < half.len() {
            let mut end = start + 1;
            while end < half.len() && half[end].0 == half[start].0 {
                end += 1;
            }
            let (key, group) = (half[start].0, &half[start..end]);
            let degenerate = (key >> 32) == (key & 0xffff_ffff);
            let corner = |h: u32| (h >> 1) as usize;
            let mut set = |h: u32, bits: u8| {
                let c = corner(h);
                flags[c / 3] |= bits << (c % 3);
            };
            if degenerate || group.len() != 2 {
                if group.len() == 1 {
                    out.boundary_edges += 1;
                    if let Some(open) = open.as_deref_mut()
                        && !degenerate
                    {
                        let c = corner(group[0].1);
                        let a = self::key(positions[vertex_of[c] as usize]);
                        let b =
                            self::key(positions[vertex_of[(c / 3) * 3 + (c % 3 + 1) % 3] as usize]);
                        open.push(OpenEdge {
                            ends: [a.min(b), a.max(b)],
                            corner: c as u64,
                            reversed: a > b,
                            normal: normals[c / 3].to_array(),
                        });
                    }
                } else if !degenerate {
                    out.non_manifold_edges += 1;
                }
                for &(_, h) in group {
                    set(h, 0b1001);
                }
            } else {
                let (h1, h2) = (group[0].1, group[1].1);
                let (t1, t2) = (corner(h1) / 3, corner(h2) / 3);
                let same_way = (h1 & 1) == (h2 & 1);
                out.misoriented_edges += u64::from(same_way);
                let c1 = corner(h1);
                let a = positions[vertex_of[c1] as usize];
                let b = positions[vertex_of[(c1 / 3) * 3 + (c1 % 3 + 1) % 3] as usize];
                let (b1, b2) = pair_bits(normals[t1], normals[t2], same_way, b - a, cos_flat);
                out.flat_edges += u64::from(b1 == 0 && b2 == 0);
                set(h1, b1);
                set(h2, b2);
            }
            start = end;
        }
        out.flags = flags.into();
        out.signed_volume = signed_volume;
        out
    }

    /// Flags as stored (a codec's file): `flags[id]` is triangle `id`'s
    /// byte. `None` if a byte has bits 6–7 set. The counters are zero (and
    /// the volume 0): set the public fields as stored.
    pub fn from_flags(flags: Vec<u8>) -> Option<Self> {
        if flags.iter().fold(0, |a, &f| a | f) & !ALL_ACTIVE != 0 {
            return None;
        }
        Some(Self {
            flags: flags.into(),
            ..Self::default()
        })
    }

    /// The flags of a model built in chunks (an out-of-core build): the
    /// chunks' bytes `flags` (a triangle each, as each chunk saw it), the
    /// counters summed over the chunks in `sum`, and the chunks' open edges
    /// paired across them ([`resolve_open`](Self::resolve_open)); with the
    /// number of edges that pairing joined. `None` if a byte has bits 6–7
    /// set.
    pub fn joined(flags: Vec<u8>, sum: &EdgeFlags, open: &mut [OpenEdge]) -> Option<(Self, u64)> {
        let mut e = Self::from_flags(flags)?;
        e.boundary_edges = sum.boundary_edges;
        e.non_manifold_edges = sum.non_manifold_edges;
        e.misoriented_edges = sum.misoriented_edges;
        e.flat_edges = sum.flat_edges;
        e.signed_volume = sum.signed_volume;
        e.resolve_open(open);
        let paired = (sum.boundary_edges - e.boundary_edges) / 2;
        Some((e, paired))
    }

    /// Every triangle's flags, by id.
    pub fn as_slice(&self) -> &[u8] {
        &self.flags
    }

    /// The flags of a triangle whose edges are all active from both sides,
    /// for `count` triangles: contacts then behave as without flags.
    pub fn all_active(count: usize) -> Self {
        Self {
            flags: vec![ALL_ACTIVE; count].into(),
            boundary_edges: 3 * count as u64,
            ..Self::default()
        }
    }

    /// The flags of triangle `id` (bits 0–2 front, 3–5 back), or all active
    /// for an id past the end.
    #[inline]
    pub fn get(&self, id: u32) -> u8 {
        self.flags.get(id as usize).copied().unwrap_or(ALL_ACTIVE)
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.flags.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.flags.is_empty()
    }

    /// Bytes held (shared by every clone).
    pub fn bytes(&self) -> usize {
        self.flags.len()
    }

    /// Whether the mesh is closed: every edge has exactly two triangles.
    pub fn is_closed(&self) -> bool {
        !self.flags.is_empty() && self.boundary_edges == 0 && self.non_manifold_edges == 0
    }

    /// The side of a closed mesh's triangles that faces outward: `1.0` when
    /// the winding's normals point out of the enclosed volume, `-1.0` when
    /// they point in.
    pub fn outward(&self) -> f32 {
        if self.signed_volume < 0.0 { -1.0 } else { 1.0 }
    }
}

/// The unit normals and the corners (position bits, corner index) of the
/// `count` triangles `visit` hands out, for
/// [`from_corners`](EdgeFlags::from_corners).
#[allow(clippy::type_complexity)]
fn visited(
    count: usize,
    visit: impl FnOnce(&mut dyn FnMut(u32, &Triangle)),
) -> (Vec<Vec3A>, Vec<([u32; 3], u32)>) {
    assert!(
        count <= (u32::MAX / 3) as usize,
        "edge flags index corners with u32"
    );
    let mut normals = vec![Vec3A::NAN; count];
    let mut corners = vec![([u32::MAX; 3], u32::MAX); 3 * count];
    visit(&mut |id, t| {
        if (id as usize) < count {
            normals[id as usize] = unit_normal(t);
            for k in 0..3 {
                corners[id as usize * 3 + k] = (key(t[k]), id * 3 + k as u32);
            }
        }
    });
    // An id never visited: its corners stand apart from every other.
    for (c, entry) in corners.iter_mut().enumerate() {
        if entry.1 == u32::MAX {
            *entry = ([u32::MAX, u32::MAX, c as u32], c as u32);
        }
    }
    (normals, corners)
}

/// The bits (edge 0's position: `0b1001` both sides, `0b0001` front,
/// `0b1000` back, 0 neither) of an edge shared by two triangles with unit
/// normals `n1`, `n2` (NaN without area), wound the same way round along
/// it when `same_way` (misoriented), `e` the edge as the first triangle
/// runs it: both active without area, neither within the flat angle,
/// else each active from the side it is convex from.
fn pair_bits(n1: Vec3A, n2: Vec3A, same_way: bool, e: Vec3A, cos_flat: f32) -> (u8, u8) {
    if !n1.is_finite() || !n2.is_finite() {
        return (0b1001, 0b1001);
    }
    // The neighbour's normal as if it were wound like this triangle.
    let n2 = if same_way { -n2 } else { n2 };
    if n1.dot(n2) >= cos_flat {
        return (0, 0);
    }
    // Convex seen from t1's front: the neighbour bends away, e · (n1 × n2)
    // > 0 along t1's edge e. t2 sees the same edge convex from its front
    // when wound consistently, from its back otherwise.
    let convex = e.dot(n1.cross(n2)) > 0.0;
    let front = |convex: bool| if convex { 0b0001 } else { 0b1000 };
    (front(convex), front(convex != same_way))
}

/// An edge with one triangle in a part of a mesh
/// ([`EdgeFlags::from_visit_open`]), which a triangle of another part may
/// share: what pairing it takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpenEdge {
    /// The ends' position bits (`-0.0` as `0.0`), the lower first.
    pub ends: [[u32; 3]; 2],
    /// The corner the edge starts at: `3 · triangle + k` for edge `k`
    /// (the caller moves it to the whole mesh's numbering).
    pub corner: u64,
    /// Whether the triangle runs the edge from the higher end.
    pub reversed: bool,
    /// The triangle's unit normal (NaN without area).
    pub normal: [f32; 3],
}

impl EdgeFlags {
    /// Pairs the open edges of a mesh's parts, each part's flags computed
    /// alone ([`from_visit_open`](Self::from_visit_open)) and put end to
    /// end in `self`, the counters summed: edges two parts share get the
    /// flags one computation over the whole mesh gives them, and the
    /// counters are corrected (a shared edge is no longer a boundary).
    /// `open` is sorted in place; corners index `self`'s triangles.
    ///
    /// An edge with one triangle in one part and two or more in another
    /// stays as each part saw it: the two are an ordinary pair, the third
    /// a boundary (the whole mesh would call all three non-manifold).
    pub fn resolve_open(&mut self, open: &mut [OpenEdge]) {
        let cos_flat = Self::DEFAULT_FLAT_DEG.to_radians().cos();
        open.sort_unstable_by_key(|x| (x.ends, x.corner));
        let mut flags = self.flags.to_vec();
        let mut start = 0;
        while start < open.len() {
            let mut end = start + 1;
            while end < open.len() && open[end].ends == open[start].ends {
                end += 1;
            }
            let group = &open[start..end];
            let mut set = |e: &OpenEdge, bits: u8| {
                let (t, k) = ((e.corner / 3) as usize, (e.corner % 3) as u32);
                if let Some(f) = flags.get_mut(t) {
                    *f = (*f & !(0b1001 << k)) | (bits << k);
                }
            };
            match group.len() {
                1 => {}
                2 => {
                    let (e1, e2) = (&group[0], &group[1]);
                    self.boundary_edges -= 2;
                    let same_way = e1.reversed == e2.reversed;
                    self.misoriented_edges += u64::from(same_way);
                    let [lo, hi] = e1.ends.map(|p| Vec3A::from(p.map(f32::from_bits)));
                    let e = if e1.reversed { lo - hi } else { hi - lo };
                    let (b1, b2) = pair_bits(
                        Vec3A::from(e1.normal),
                        Vec3A::from(e2.normal),
                        same_way,
                        e,
                        cos_flat,
                    );
                    self.flat_edges += u64::from(b1 == 0 && b2 == 0);
                    set(e1, b1);
                    set(e2, b2);
                }
                n => {
                    self.boundary_edges -= n as u64;
                    self.non_manifold_edges += 1;
                }
            }
            start = end;
        }
        self.flags = flags.into();
    }
}

/// The unit normal of a triangle's winding, NaN without area.
#[inline]
fn unit_normal(v: &Triangle) -> Vec3A {
    (v[1] - v[0]).cross(v[2] - v[0]).normalize_or(Vec3A::NAN)
}

/// The position bits of a point (`-0.0` as `0.0`, so that both weld).
#[inline]
fn key(p: Vec3A) -> [u32; 3] {
    p.to_array().map(|x| (x + 0.0).to_bits())
}

/// The active-edge bits (0–2) of one side of a triangle's flags: the front
/// when `front`, else the back.
#[inline]
pub fn side_bits(flags: u8, front: bool) -> u8 {
    if front {
        flags & FRONT
    } else {
        (flags & BACK) >> 3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags_of(v: &[[f32; 3]], t: &[[u32; 3]]) -> EdgeFlags {
        EdgeFlags::compute(t.len(), |i| {
            t[i as usize].map(|k| Vec3A::from(v[k as usize]))
        })
    }

    /// The flags of `t` computed in parts (`part[i]` names triangle `i`'s),
    /// each part's numbered after the previous ones', then resolved: in
    /// that numbering, what the whole computation gives.
    fn flags_in_parts(
        v: &[[f32; 3]],
        t: &[[u32; 3]],
        part: &[usize],
        parts: usize,
    ) -> (EdgeFlags, Vec<usize>) {
        let mut order = Vec::new();
        let mut all = Vec::new();
        let mut open_all = Vec::new();
        let mut sum = EdgeFlags::default();
        for p in 0..parts {
            let ids: Vec<usize> = (0..t.len()).filter(|&i| part[i] == p).collect();
            let (f, open) = EdgeFlags::from_visit_open(ids.len(), |visit| {
                for (local, &i) in ids.iter().enumerate() {
                    visit(local as u32, &t[i].map(|k| Vec3A::from(v[k as usize])));
                }
            });
            let base = all.len() as u64;
            open_all.extend(open.into_iter().map(|mut e| {
                e.corner += 3 * base;
                e
            }));
            all.extend_from_slice(f.as_slice());
            sum.boundary_edges += f.boundary_edges;
            sum.non_manifold_edges += f.non_manifold_edges;
            sum.misoriented_edges += f.misoriented_edges;
            sum.flat_edges += f.flat_edges;
            order.extend(ids);
        }
        let mut out = EdgeFlags::from_flags(all).unwrap();
        out.boundary_edges = sum.boundary_edges;
        out.non_manifold_edges = sum.non_manifold_edges;
        out.misoriented_edges = sum.misoriented_edges;
        out.flat_edges = sum.flat_edges;
        out.resolve_open(&mut open_all);
        (out, order)
    }

    #[test]
    fn flags_computed_in_parts_and_resolved_equal_the_whole() {
        let robot =
            crate::scene::generate(crate::scene::Kind::Robot, 4000, 3, &mut |_, _| {}).unwrap();
        let statue =
            crate::scene::generate(crate::scene::Kind::Statue, 3000, 1, &mut |_, _| {}).unwrap();
        for mesh in [robot, statue] {
            let (v, t) = (&mesh.vertices, &mesh.triangles);
            let whole = flags_of(v, t);
            // Parts by position (cuts through the surface), by id, and
            // every triangle its own part.
            let by_x: Vec<usize> = t
                .iter()
                .map(|tri| {
                    let x: f32 = tri.iter().map(|&k| v[k as usize][0]).sum();
                    usize::from(x > 0.0) + usize::from(x > 0.3)
                })
                .collect();
            let by_id: Vec<usize> = (0..t.len()).map(|i| i * 5 / t.len()).collect();
            let alone: Vec<usize> = (0..t.len()).collect();
            for (part, parts) in [(by_x, 3), (by_id, 5), (alone, t.len())] {
                let (got, order) = flags_in_parts(v, t, &part, parts);
                for (new, &old) in order.iter().enumerate() {
                    assert_eq!(got.get(new as u32), whole.get(old as u32), "triangle {old}");
                }
                assert_eq!(got.boundary_edges, whole.boundary_edges);
                assert_eq!(got.non_manifold_edges, whole.non_manifold_edges);
                assert_eq!(got.misoriented_edges, whole.misoriented_edges);
                assert_eq!(got.flat_edges, whole.flat_edges);
            }
        }
    }

    #[test]
    fn a_flat_square_has_one_inactive_diagonal() {
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
        ];
        // Both wound with their normal up (-y x ... ): consistent.
        let t = [[0, 2, 1], [0, 3, 2]];
        let f = flags_of(&v, &t);
        assert_eq!(f.boundary_edges, 4);
        assert_eq!(f.flat_edges, 1);
        assert!(!f.is_closed());
        // Triangle 0's edge 0 (0 -> 2) is the diagonal: inactive both ways.
        assert_eq!(f.get(0), 0b110_110);
        // Triangle 1's edge 2 (2 -> 0) is the diagonal.
        assert_eq!(f.get(1), 0b011_011);
    }

    #[test]
    fn a_cube_is_closed_and_its_face_diagonals_are_inactive() {
        let v: Vec<[f32; 3]> = (0..8)
            .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
            .collect();
        // Outward-wound quads (counter-clockwise seen from outside).
        let quads = [
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
        ];
        let t: Vec<[u32; 3]> = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        let f = flags_of(&v, &t);
        assert!(f.is_closed());
        assert_eq!(f.misoriented_edges, 0);
        assert!((f.signed_volume - 1.0).abs() < 1e-9, "{}", f.signed_volume);
        assert_eq!(f.outward(), 1.0);
        assert_eq!(f.flat_edges, 6);
        for i in 0..12 {
            // Two cube edges active from the front (convex), the diagonal
            // inactive; nothing active from the back.
            let bits = f.get(i);
            assert_eq!((bits & FRONT).count_ones(), 2, "triangle {i}: {bits:06b}");
            assert_eq!(bits & BACK, 0, "triangle {i}: {bits:06b}");
        }
        // Wound inward, the same edges are active from the back instead.
        let inward: Vec<[u32; 3]> = t.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let g = flags_of(&v, &inward);
        assert_eq!(g.outward(), -1.0);
        for i in 0..12 {
            assert_eq!((g.get(i) & BACK).count_ones(), 2);
            assert_eq!(g.get(i) & FRONT, 0);
        }
    }

    #[test]
    fn a_valley_is_active_from_below_only() {
        // Two faces meeting at a 90 degree valley along z, normals up-ish.
        let v = [
            [-1.0, 1.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let t = [[0, 2, 1], [0, 4, 2], [1, 5, 3], [1, 2, 5]];
        let f = flags_of(&v, &t);
        // Triangle 0's edge 1 (1 -> 2) is the valley: inactive from the
        // front (concave), active from the back.
        let n0 =
            (Vec3A::from(v[2]) - Vec3A::from(v[0])).cross(Vec3A::from(v[1]) - Vec3A::from(v[0]));
        assert!(n0.y > 0.0, "front faces up");
        assert_eq!(f.get(0) & 0b010, 0);
        assert_eq!(f.get(0) & 0b010_000, 0b010_000);
    }

    /// Codecs store the flags and the volume: encoding twice must give
    /// the same bytes, whatever rayon's threads do.
    #[test]
    fn computing_twice_gives_the_same_bits() {
        // A bumpy grid of 2 × 200 × 200 triangles: several chunks of the
        // volume's sum.
        let n = 201u32;
        let v: Vec<[f32; 3]> = (0..n * n)
            .map(|i| {
                let (x, y) = (i % n, i / n);
                [x as f32, ((x * 7 + y * 13) % 5) as f32 * 0.1, y as f32]
            })
            .collect();
        let t: Vec<[u32; 3]> = (0..n - 1)
            .flat_map(|y| {
                (0..n - 1).flat_map(move |x| {
                    let i = y * n + x;
                    [[i, i + n, i + 1], [i + 1, i + n, i + n + 1]]
                })
            })
            .collect();
        let a = flags_of(&v, &t);
        for _ in 0..4 {
            let b = flags_of(&v, &t);
            assert_eq!(a, b);
            assert_eq!(a.signed_volume.to_bits(), b.signed_volume.to_bits());
        }
        let back = EdgeFlags::from_flags(a.as_slice().to_vec()).unwrap();
        assert_eq!(back.as_slice(), a.as_slice());
    }

    #[test]
    fn duplicated_vertices_weld() {
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
        ];
        let t = [[0, 1, 2], [3, 4, 5]];
        let f = flags_of(&v, &t);
        assert_eq!(f.flat_edges, 1);
        assert_eq!(f.boundary_edges, 4);
    }
}
