//! [`ChildBoxes`]: the boxes of a node's children as a batch, and the box
//! tests traversals run over all of them at once.
//!
//! # Lanes and padding
//! A batch holds up to [`MAX_CHILDREN`] boxes, lane `i` being the node's
//! `i`-th child. Lanes at and past [`len`](ChildBoxes::len) are *padding*:
//! they hold [`Aabb::EMPTY`] and every test masks them out, so they never
//! hit whatever the query (an empty box alone is not enough: an empty box
//! overlaps a query that spans all of space, and a ray whose direction is
//! NaN on every axis meets any box).
//!
//! # Two forms
//! More than two boxes are kept in structure-of-arrays form, per axis the
//! lanes' minima and maxima in chunks of four, and tested a chunk at a
//! time. One or two boxes (a binary node's) are kept as boxes and tested
//! box by box with the single-box functions: that takes fewer instructions
//! than a transposed chunk (an overlap test a quarter as many), and since a
//! binary codec's batch always has two lanes, the choice is made when the
//! traversal is compiled. Measured on the plain and RACBVH codecs, every
//! traversal built on chunks for two lanes lost 5–30 % against the
//! box-by-box traversal it replaced; built this way it loses nothing.
//!
//! # Exactness
//! Every test makes, lane by lane, the decision its single-box counterpart
//! on [`Aabb`] / [`Ray`] makes, from the same floating-point operations in
//! the same order (see [`ChildBoxes::slab`] for the one fold that is
//! written differently to the same result), so that a traversal over
//! batches is bit for bit the traversal box by box. The unit tests check
//! both forms against the single-box functions, NaN-producing rays
//! included.
//!
//! # SIMD
//! A chunk is four glam `Vec4`s, the type the single-box code already uses
//! (`Vec3A`) in four lanes: on x86-64 its operations are single SSE2
//! instructions (the baseline, so no feature detection), with the same
//! `minps`/`maxps` NaN rules as the single-box test; elsewhere glam's
//! scalar code, again with the single-box test's rules. Loops over
//! `[f32; 4]` arrays were tried first: LLVM vectorized the arithmetic but
//! turned the `minps`-style selects into branches and stored transposed
//! boxes lane by lane. AVX2 (eight lanes at once, behind runtime
//! detection) would pay only for 8-wide nodes and is left to the codec that
//! has them.

use glam::{BVec4A, Mat4, Vec3A, Vec4};

use super::MAX_CHILDREN;
use crate::geom::{Aabb, Pose, Ray, SLAB_EXIT_SCALE};

/// Lanes per chunk: one SSE register of `f32`.
const W: usize = 4;
/// Chunks in a full batch.
const CHUNKS: usize = MAX_CHILDREN / W;
/// Batches of at most this many lanes are kept as boxes (see the module
/// docs).
const NARROW: usize = 2;

/// `[f(0), f(1), f(2)]`, one per axis (always inlined, unlike
/// `std::array::from_fn` with a large closure).
#[inline(always)]
fn axes<T>(mut f: impl FnMut(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

/// Four points as three rows of coordinates `[xs, ys, zs]` (a 4 × 4
/// transpose in registers).
#[inline(always)]
fn transpose(p: [Vec3A; W]) -> [Vec4; 3] {
    let t = Mat4::from_cols(
        p[0].extend(0.0),
        p[1].extend(0.0),
        p[2].extend(0.0),
        p[3].extend(0.0),
    )
    .transpose();
    [t.x_axis, t.y_axis, t.z_axis]
}

/// glam's `Vec3A::max_element` (`max(max(x, z), max(y, z))`) of four
/// points given as rows.
#[inline(always)]
fn max_element(x: Vec4, y: Vec4, z: Vec4) -> Vec4 {
    x.max(z).max(y.max(z))
}

/// Eight lanes of entry distances from two chunks.
#[inline(always)]
fn lanes8([a, b]: [Vec4; CHUNKS]) -> [f32; MAX_CHILDREN] {
    [a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w]
}

/// Boxes in structure-of-arrays form: `min[axis][chunk]` holds lanes
/// `4 * chunk ..` of that axis. Lanes not in use are [`Aabb::EMPTY`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rows {
    min: [[Vec4; CHUNKS]; 3],
    max: [[Vec4; CHUNKS]; 3],
}

impl Rows {
    const EMPTY: Rows = Rows {
        min: [[Vec4::INFINITY; CHUNKS]; 3],
        max: [[Vec4::NEG_INFINITY; CHUNKS]; 3],
    };

    /// Rows of `n` boxes, lane `i` being `get(i)`, written a chunk at a time
    /// (so that reading a chunk back is one forwarded load, not four
    /// stores waiting to reach the cache).
    #[inline(always)]
    fn from_lanes(n: usize, mut get: impl FnMut(usize) -> Aabb) -> Rows {
        let mut r = Rows::EMPTY;
        for k in 0..chunks(n) {
            let mut b = [Aabb::EMPTY; W];
            for (l, b) in b.iter_mut().enumerate() {
                if k * W + l < n {
                    *b = get(k * W + l);
                }
            }
            let (mn, mx) = (transpose(b.map(|b| b.min)), transpose(b.map(|b| b.max)));
            for a in 0..3 {
                r.min[a][k] = mn[a];
                r.max[a][k] = mx[a];
            }
        }
        r
    }

    /// Writes one lane.
    #[inline(always)]
    fn set(&mut self, i: usize, b: &Aabb) {
        let (k, j) = (i / W, i % W);
        for a in 0..3 {
            self.min[a][k][j] = b.min[a];
            self.max[a][k][j] = b.max[a];
        }
    }

    /// Lane `i`.
    #[inline(always)]
    fn get(&self, i: usize) -> Aabb {
        let (k, j) = (i / W, i % W);
        Aabb::from_arrays(axes(|a| self.min[a][k][j]), axes(|a| self.max[a][k][j]))
    }
}

/// Chunks that hold `n` lanes (at least one, so that no test needs a
/// branch for an empty batch).
#[inline(always)]
fn chunks(n: usize) -> usize {
    if n > W { CHUNKS } else { 1 }
}

/// The lanes of chunk `k` below `n`, as a vector mask.
#[inline(always)]
fn live(n: usize, k: usize) -> BVec4A {
    let left = n.saturating_sub(k * W) as f32;
    Vec4::new(0.0, 1.0, 2.0, 3.0).cmplt(Vec4::splat(left))
}

/// [`ChildBoxes::slab`] on rows of `n` lanes.
///
/// The single-box test folds the axes with `f32::max`/`min`, which skip
/// NaN (a zero direction component on a slab's plane): the result is the
/// largest (smallest) of the values that are not NaN, with `0` (`t_max`).
/// Here the same fold starts from `0` (`t_max`) and takes each axis with
/// `maxps`/`minps`, which keep the running value when the axis is NaN: one
/// instruction per axis instead of four. A NaN `t_max`, which the exit fold
/// cannot start from, starts it from `+∞` and gives NaN (a miss) where
/// every axis was NaN, as the single-box test does. An entry distance of
/// zero may differ in sign from the single-box test's, which no comparison
/// sees.
#[inline(always)]
fn slab_rows(r: &Rows, n: usize, ray: &Ray, t_max: f32) -> (u32, [f32; MAX_CHILDREN]) {
    let o = ray.origin.to_array().map(Vec4::splat);
    let inv = ray.inv_dir.to_array().map(Vec4::splat);
    // Per axis, the rows of the planes the ray enters and leaves by.
    let by_max = ray.enters_by_max();
    let near = axes(|a| if by_max[a] { &r.max[a] } else { &r.min[a] });
    let far = axes(|a| if by_max[a] { &r.min[a] } else { &r.max[a] });
    let nan_limit = t_max.is_nan();
    let limit = Vec4::splat(if nan_limit { f32::INFINITY } else { t_max });
    let mut t = [Vec4::INFINITY; CHUNKS];
    let mut m = 0;
    for (k, tk) in t.iter_mut().enumerate().take(chunks(n)) {
        let mut enter = Vec4::ZERO;
        let mut exit = limit;
        let mut bounded = BVec4A::splat(false);
        for a in 0..3 {
            // `maxps`/`minps` return the second operand when either is
            // NaN: a NaN plane distance (a ray in the plane) is skipped.
            let tf = (far[a][k] - o[a]) * inv[a];
            enter = ((near[a][k] - o[a]) * inv[a]).max(enter);
            exit = tf.min(exit);
            if nan_limit {
                bounded |= tf.cmpeq(tf);
            }
        }
        let mut exit = exit * SLAB_EXIT_SCALE;
        if nan_limit {
            exit = Vec4::select(bounded, exit, Vec4::NAN);
        }
        *tk = enter;
        m |= enter.cmple(exit).bitmask() << (k * W);
    }
    (m & lane_mask(n), lanes8(t))
}

/// [`ChildBoxes::overlaps_grown`] on rows of `n` lanes (no margin when
/// `None`).
#[inline(always)]
fn overlaps_rows(r: &Rows, n: usize, margin: Option<f32>, q: &Aabb) -> u32 {
    let (qmin, qmax) = (q.min.to_array(), q.max.to_array());
    let g = Vec4::splat(margin.unwrap_or(0.0));
    let mut m = 0;
    for k in 0..chunks(n) {
        let mut ok = BVec4A::splat(true);
        for a in 0..3 {
            let (mut mn, mut mx) = (r.min[a][k], r.max[a][k]);
            if margin.is_some() {
                mn -= g;
                mx += g;
            }
            ok &= mn.cmple(Vec4::splat(qmax[a])) & Vec4::splat(qmin[a]).cmple(mx);
        }
        m |= ok.bitmask() << (k * W);
    }
    m & lane_mask(n)
}

/// [`ChildBoxes::distance_squared`] on rows of `n` lanes.
#[inline(always)]
fn distance_squared_rows(r: &Rows, n: usize, p: Vec3A) -> [f32; MAX_CHILDREN] {
    let p = p.to_array().map(Vec4::splat);
    let mut out = [Vec4::INFINITY; CHUNKS];
    for (k, out) in out.iter_mut().enumerate().take(chunks(n)) {
        let d = axes(|a| (r.min[a][k] - p[a]).max(p[a] - r.max[a][k]).max(Vec4::ZERO));
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        *out = Vec4::select(live(n, k), d2, Vec4::INFINITY);
    }
    lanes8(out)
}

/// [`ChildBoxes::box_distances`] on rows of `n` lanes.
#[inline(always)]
fn box_distances_rows(r: &Rows, n: usize, q: &Aabb, lane_first: bool) -> [f32; MAX_CHILDREN] {
    let (qmin, qmax) = (q.min.to_array(), q.max.to_array());
    let mut out = [Vec4::INFINITY; CHUNKS];
    for (k, out) in out.iter_mut().enumerate().take(chunks(n)) {
        let d = axes(|a| {
            let lane_gap = r.min[a][k] - Vec4::splat(qmax[a]);
            let q_gap = Vec4::splat(qmin[a]) - r.max[a][k];
            let v = if lane_first {
                lane_gap.max(q_gap)
            } else {
                q_gap.max(lane_gap)
            };
            v.max(Vec4::ZERO)
        });
        let dist = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        *out = Vec4::select(live(n, k), dist, Vec4::INFINITY);
    }
    lanes8(out)
}

/// [`ChildBoxes::transformed`] on rows of `n` lanes.
#[inline(always)]
fn transformed_rows(r: &Rows, n: usize, pose: &Pose) -> Rows {
    let cols = [
        pose.rotation.x_axis.to_array(),
        pose.rotation.y_axis.to_array(),
        pose.rotation.z_axis.to_array(),
    ];
    // rot[c][a]: element `a` of column `c`, in every lane.
    let rot = cols.map(|c| c.map(Vec4::splat));
    let rot_abs = cols.map(|c| c.map(|x| Vec4::splat(x.abs())));
    let t = pose.translation.to_array().map(Vec4::splat);
    let ta = pose.translation.to_array().map(|x| Vec4::splat(x.abs()));
    let t_mag = max_element(ta[0], ta[1], ta[2]);
    let mut out = Rows::EMPTY;
    for k in 0..chunks(n) {
        let (mn, mx) = (axes(|a| r.min[a][k]), axes(|a| r.max[a][k]));
        let ctr = axes(|a| (mn[a] + mx[a]) * 0.5);
        let half = axes(|a| (mx[a] - mn[a]) * 0.5);
        // Mat3A * Vec3A: x_axis * v.x + y_axis * v.y + z_axis * v.z.
        let c = axes(|a| rot[0][a] * ctr[0] + rot[1][a] * ctr[1] + rot[2][a] * ctr[2] + t[a]);
        let e =
            axes(|a| rot_abs[0][a] * half[0] + rot_abs[1][a] * half[1] + rot_abs[2][a] * half[2]);
        let corner = axes(|a| mn[a].abs().max(mx[a].abs()));
        let mag = max_element(c[0].abs(), c[1].abs(), c[2].abs())
            + max_element(e[0], e[1], e[2])
            + t_mag
            + max_element(corner[0], corner[1], corner[2]);
        let pad = mag * 8.0 * f32::EPSILON;
        let live = live(n, k);
        for a in 0..3 {
            let ea = e[a] + pad;
            out.min[a][k] = Vec4::select(live, c[a] - ea, Vec4::INFINITY);
            out.max[a][k] = Vec4::select(live, c[a] + ea, Vec4::NEG_INFINITY);
        }
    }
    out
}

/// [`ChildBoxes::scaled`] on rows of `n` lanes.
#[inline(always)]
fn scaled_rows(r: &Rows, n: usize, s: Vec3A) -> Rows {
    let s = s.to_array().map(Vec4::splat);
    let mut out = Rows::EMPTY;
    for k in 0..chunks(n) {
        let live = live(n, k);
        for (a, &sa) in s.iter().enumerate() {
            let (p, q) = (r.min[a][k] * sa, r.max[a][k] * sa);
            out.min[a][k] = Vec4::select(live, p.min(q), Vec4::INFINITY);
            out.max[a][k] = Vec4::select(live, p.max(q), Vec4::NEG_INFINITY);
        }
    }
    out
}

/// The mask of lanes `0..n`.
#[inline(always)]
fn lane_mask(n: usize) -> u32 {
    (1u32 << n) - 1
}

/// How a batch holds its boxes (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Repr {
    /// At most [`NARROW`] lanes, as boxes (slots past the length are
    /// not read: a cleared batch keeps its old boxes there).
    Narrow([Aabb; NARROW]),
    /// More lanes, as rows.
    Wide(Rows),
}

/// Up to [`MAX_CHILDREN`] boxes, lane `i` for child `i`, and the box tests
/// over all of them at once (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChildBoxes {
    len: usize,
    repr: Repr,
}

impl Default for ChildBoxes {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl ChildBoxes {
    /// A batch without lanes (every lane padding).
    pub const EMPTY: ChildBoxes = ChildBoxes {
        len: 0,
        repr: Repr::Narrow([Aabb::EMPTY; NARROW]),
    };

    /// A batch of the given boxes.
    ///
    /// # Panics
    /// With more than [`MAX_CHILDREN`] boxes.
    #[inline(always)]
    pub fn from_boxes(boxes: &[Aabb]) -> Self {
        Self::from_lanes(boxes.len(), |i| boxes[i])
    }

    /// A batch of `n` boxes, lane `i` being `get(i)` (called once per
    /// lane, in lane order).
    ///
    /// A value meant to be built and tested in the same loop iteration of
    /// a traversal into which both are inlined, so that the compiler keeps
    /// it in registers.
    ///
    /// # Panics
    /// If `n > MAX_CHILDREN`.
    #[inline(always)]
    pub fn from_lanes(n: usize, mut get: impl FnMut(usize) -> Aabb) -> Self {
        assert!(
            n <= MAX_CHILDREN,
            "a batch holds at most {MAX_CHILDREN} boxes"
        );
        let repr = if n <= NARROW {
            let mut pair = [Aabb::EMPTY; NARROW];
            for (i, b) in pair.iter_mut().enumerate().take(n) {
                *b = get(i);
            }
            Repr::Narrow(pair)
        } else {
            Repr::Wide(Rows::from_lanes(n, get))
        };
        Self { len: n, repr }
    }

    /// A batch of `n` lanes given as rows, `min[axis][lane]` and
    /// `max[axis][lane]` (for codecs that store or decode a node's child
    /// boxes axis by axis, as an 8-wide node does): past two lanes the rows
    /// are loaded as they are, four lanes to a load, without a transpose.
    /// Lanes at and past `n` are not read as boxes: they become padding.
    ///
    /// # Panics
    /// If `n > MAX_CHILDREN`.
    #[inline(always)]
    pub fn from_rows(
        n: usize,
        min: [&[f32; MAX_CHILDREN]; 3],
        max: [&[f32; MAX_CHILDREN]; 3],
    ) -> Self {
        if n <= NARROW {
            return Self::from_lanes(n, |i| {
                Aabb::from_arrays(axes(|a| min[a][i]), axes(|a| max[a][i]))
            });
        }
        assert!(
            n <= MAX_CHILDREN,
            "a batch holds at most {MAX_CHILDREN} boxes"
        );
        let mut r = Rows::EMPTY;
        for k in 0..chunks(n) {
            let live = live(n, k);
            let lanes = k * W..k * W + W;
            for a in 0..3 {
                let (mn, mx) = (&min[a][lanes.clone()], &max[a][lanes.clone()]);
                r.min[a][k] = Vec4::select(live, Vec4::from_slice(mn), Vec4::INFINITY);
                r.max[a][k] = Vec4::select(live, Vec4::from_slice(mx), Vec4::NEG_INFINITY);
            }
        }
        Self {
            len: n,
            repr: Repr::Wide(r),
        }
    }

    /// Makes the batch empty (keeping the two-box form's storage, so that
    /// refilling a binary node's batch writes two boxes and a length).
    #[inline(always)]
    pub fn clear(&mut self) {
        if let Repr::Wide(_) = self.repr {
            self.repr = Repr::Narrow([Aabb::EMPTY; NARROW]);
        }
        self.len = 0;
    }

    /// Appends a box (for cursors that produce children one at a time;
    /// past two lanes this writes the rows lane by lane, which reads back
    /// slower than a batch built by [`from_lanes`](Self::from_lanes)).
    ///
    /// # Panics
    /// If the batch is full.
    #[inline(always)]
    pub fn push(&mut self, b: Aabb) {
        let i = self.len;
        assert!(
            i < MAX_CHILDREN,
            "a batch holds at most {MAX_CHILDREN} boxes"
        );
        match &mut self.repr {
            Repr::Narrow(pair) if i < NARROW => pair[i] = b,
            Repr::Narrow(pair) => {
                let mut rows = Rows::EMPTY;
                for (j, p) in pair.iter().enumerate() {
                    rows.set(j, p);
                }
                rows.set(i, &b);
                self.repr = Repr::Wide(rows);
            }
            Repr::Wide(rows) => rows.set(i, &b),
        }
        self.len = i + 1;
    }

    /// Number of lanes in use.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no lane is in use.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The mask of the lanes in use (bit `i` for lane `i`).
    #[inline]
    pub fn lanes(&self) -> u32 {
        lane_mask(self.len)
    }

    /// Calls `f` with each lane of `mask` that is in use, lowest first.
    /// For a binary node's two lanes this is two bit tests, as the
    /// box-by-box traversal had.
    #[inline(always)]
    pub fn for_each_in(&self, mask: u32, mut f: impl FnMut(usize)) {
        let mut m = mask & self.lanes();
        if let Repr::Narrow(_) = self.repr {
            for i in 0..NARROW {
                if m >> i & 1 != 0 {
                    f(i);
                }
            }
            return;
        }
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            f(i);
        }
    }

    /// The box of lane `i` ([`Aabb::EMPTY`] for padding).
    ///
    /// # Panics
    /// If `i >= MAX_CHILDREN`.
    #[inline]
    pub fn get(&self, i: usize) -> Aabb {
        assert!(i < MAX_CHILDREN, "lane {i} of at most {MAX_CHILDREN}");
        match &self.repr {
            // No indexing by `i`, so that the compiler can keep the boxes
            // in registers.
            Repr::Narrow(pair) => match i {
                0 if self.len > 0 => pair[0],
                1 if self.len > 1 => pair[1],
                _ => Aabb::EMPTY,
            },
            Repr::Wide(rows) => rows.get(i),
        }
    }

    /// The slab test of [`Ray::intersect_aabb`] on every lane: the mask of
    /// the lanes the ray meets within `[0, t_max]` and each lane's entry
    /// distance (meaningful for lanes in the mask). The same decisions and
    /// the same entry distances as the single-box test, conservative exit
    /// scale ([`SLAB_EXIT_SCALE`]) included.
    #[inline(always)]
    pub fn slab(&self, ray: &Ray, t_max: f32) -> (u32, [f32; MAX_CHILDREN]) {
        match &self.repr {
            Repr::Narrow(pair) => {
                let mut t = [f32::INFINITY; MAX_CHILDREN];
                let mut m = 0;
                for (i, b) in pair.iter().enumerate().take(self.len) {
                    if let Some(enter) = ray.intersect_aabb(b, t_max) {
                        t[i] = enter;
                        m |= 1 << i;
                    }
                }
                (m, t)
            }
            Repr::Wide(rows) => slab_rows(rows, self.len, ray, t_max),
        }
    }

    /// The lanes whose box shares a point with `q` (touching counts), as
    /// [`Aabb::intersects`].
    #[inline(always)]
    pub fn overlaps(&self, q: &Aabb) -> u32 {
        self.overlaps_loosened(None, q)
    }

    /// The lanes whose box, grown by `margin` on every side, shares a point
    /// with `q`: `lane.loosened(margin).intersects(q)` ([`Aabb::loosened`],
    /// [`Aabb::intersects`]) lane by lane.
    #[inline(always)]
    pub fn overlaps_grown(&self, margin: f32, q: &Aabb) -> u32 {
        self.overlaps_loosened(Some(margin), q)
    }

    #[inline(always)]
    fn overlaps_loosened(&self, margin: Option<f32>, q: &Aabb) -> u32 {
        match &self.repr {
            Repr::Narrow(pair) => {
                let mut m = 0;
                for (i, b) in pair.iter().enumerate().take(self.len) {
                    let b = margin.map_or(*b, |g| b.loosened(g));
                    m |= u32::from(b.intersects(q)) << i;
                }
                m
            }
            Repr::Wide(rows) => overlaps_rows(rows, self.len, margin, q),
        }
    }

    /// Each lane's squared distance to `p` (0 inside), as
    /// [`Aabb::distance_squared`]; `+∞` for padding.
    #[inline(always)]
    pub fn distance_squared(&self, p: Vec3A) -> [f32; MAX_CHILDREN] {
        match &self.repr {
            Repr::Narrow(pair) => {
                let mut out = [f32::INFINITY; MAX_CHILDREN];
                for (o, b) in out.iter_mut().zip(pair).take(self.len) {
                    *o = b.distance_squared(p);
                }
                out
            }
            Repr::Wide(rows) => distance_squared_rows(rows, self.len, p),
        }
    }

    /// Each lane's distance to the box `q`: the length of the gap between
    /// them per axis (0 when they overlap); `+∞` for padding. With
    /// `lane_first`, computed as `dist(lane, q)`, else as `dist(q, lane)`,
    /// where `dist(x, y) = |max(x.min − y.max, y.min − x.max, 0)|` with
    /// `Vec3A` operations (the two differ only on NaN).
    #[inline(always)]
    pub fn box_distances(&self, q: &Aabb, lane_first: bool) -> [f32; MAX_CHILDREN] {
        match &self.repr {
            Repr::Narrow(pair) => {
                let dist = |x: &Aabb, y: &Aabb| {
                    (x.min - y.max).max(y.min - x.max).max(Vec3A::ZERO).length()
                };
                let mut out = [f32::INFINITY; MAX_CHILDREN];
                for (o, b) in out.iter_mut().zip(pair).take(self.len) {
                    *o = if lane_first { dist(b, q) } else { dist(q, b) };
                }
                out
            }
            Repr::Wide(rows) => box_distances_rows(rows, self.len, q, lane_first),
        }
    }

    /// Every box after the rigid transform `pose`, as [`Aabb::transformed`]
    /// lane by lane (conservative; padding stays empty): one call moves a
    /// node's children into another frame.
    #[inline(always)]
    pub fn transformed(&self, pose: &Pose) -> ChildBoxes {
        let repr = match &self.repr {
            Repr::Narrow(pair) => {
                let mut out = [Aabb::EMPTY; NARROW];
                for (o, b) in out.iter_mut().zip(pair).take(self.len) {
                    *o = b.transformed(pose);
                }
                Repr::Narrow(out)
            }
            Repr::Wide(rows) => Repr::Wide(transformed_rows(rows, self.len, pose)),
        };
        ChildBoxes {
            len: self.len,
            repr,
        }
    }

    /// Every box scaled axis by axis by `s` (no component zero; a negative
    /// one mirrors, swapping that axis's bounds), as [`Aabb::scaled`] lane
    /// by lane; padding stays empty. Exact: a product rounds the same way
    /// for a box's bound as for a point's coordinate, so a scaled box
    /// contains the scaled points of the box.
    #[inline(always)]
    pub fn scaled(&self, s: Vec3A) -> ChildBoxes {
        let repr = match &self.repr {
            Repr::Narrow(pair) => {
                let mut out = [Aabb::EMPTY; NARROW];
                for (o, b) in out.iter_mut().zip(pair).take(self.len) {
                    *o = b.scaled(s);
                }
                Repr::Narrow(out)
            }
            Repr::Wide(rows) => Repr::Wide(scaled_rows(rows, self.len, s)),
        };
        ChildBoxes {
            len: self.len,
            repr,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64's output function.
    fn mix64(mut z: u64) -> u64 {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Deterministic numbers for the tests, with the special values the
    /// slab test must treat as the single-box test does: zeros of both
    /// signs, repeats (flat boxes, origins on a face), huge magnitudes.
    struct Gen(u64);

    impl Gen {
        fn bits(&mut self) -> u64 {
            self.0 += 1;
            mix64(self.0)
        }

        fn coord(&mut self) -> f32 {
            let r = self.bits();
            match r % 16 {
                0 => 0.0,
                1 => -0.0,
                2 => 1.0,
                3 => ((r >> 8) % 5) as f32 - 2.0,
                4 => 1e30 * if r & 256 != 0 { 1.0 } else { -1.0 },
                _ => ((r >> 11) as f64 / (1u64 << 53) as f64 * 8.0 - 4.0) as f32,
            }
        }

        fn vec(&mut self) -> Vec3A {
            Vec3A::new(self.coord(), self.coord(), self.coord())
        }

        fn aabb(&mut self) -> Aabb {
            let (p, q) = (self.vec(), self.vec());
            match self.bits() % 8 {
                // Flat on one axis, a point, empty, or as drawn.
                0 => Aabb::new(p.min(q), p.max(q) * Vec3A::new(1.0, 1.0, 0.0)),
                1 => Aabb::new(p, p),
                2 => Aabb::EMPTY,
                _ => Aabb::new(p.min(q), p.max(q)),
            }
        }

        fn dir(&mut self) -> Vec3A {
            let mut d = self.vec();
            // Components exactly zero (of either sign) in some rays, and in
            // others infinite or NaN (an inverse of zero or NaN: slabs
            // whose distances are NaN, which both tests must skip alike).
            let axis = (self.bits() % 3) as usize;
            match self.bits() % 8 {
                0 | 1 => d[axis] = if self.bits() & 1 != 0 { 0.0 } else { -0.0 },
                2 => d[axis] = f32::INFINITY,
                3 => d[axis] = f32::NEG_INFINITY,
                4 => d[axis] = f32::NAN,
                5 => d = Vec3A::ZERO,
                _ => {}
            }
            d
        }

        /// A batch of 0 to 8 boxes, the same boxes as rows, and the boxes.
        fn batch(&mut self) -> (ChildBoxes, Rows, Vec<Aabb>) {
            let n = (self.bits() % (MAX_CHILDREN as u64 + 1)) as usize;
            let boxes: Vec<Aabb> = (0..n).map(|_| self.aabb()).collect();
            let rows = Rows::from_lanes(n, |i| boxes[i]);
            (ChildBoxes::from_boxes(&boxes), rows, boxes)
        }
    }

    fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    fn same_box(a: &Aabb, b: &Aabb) -> bool {
        (0..3).all(|k| same(a.min[k], b.min[k]) && same(a.max[k], b.max[k]))
    }

    /// Both forms (the batch as built, box by box up to two lanes, and the
    /// rows for any number of lanes) against the single-box slab test.
    #[test]
    fn slab_agrees_with_single_box_test() {
        let mut g = Gen(1);
        for _ in 0..20_000 {
            let (batch, rows, boxes) = g.batch();
            let n = boxes.len();
            let mut origin = g.vec();
            if g.bits().is_multiple_of(4) && n > 0 {
                // An origin on a face of the first box.
                origin.x = boxes[0].min.x;
            }
            let ray = Ray::new(origin, g.dir());
            let t_max = match g.bits() % 4 {
                0 => f32::INFINITY,
                1 => f32::NAN,
                _ => g.coord().abs(),
            };
            for (mask, t) in [batch.slab(&ray, t_max), slab_rows(&rows, n, &ray, t_max)] {
                assert_eq!(mask & !lane_mask(n), 0, "padding lanes hit");
                for (i, b) in boxes.iter().enumerate() {
                    let want = ray.intersect_aabb(b, t_max);
                    assert_eq!(
                        mask >> i & 1 != 0,
                        want.is_some(),
                        "lane {i}: {b:?} {ray:?}"
                    );
                    if let Some(w) = want {
                        // Bit for bit, except that a zero may differ in sign.
                        assert!(
                            same(w, t[i]) || w == t[i],
                            "lane {i}: entry {} vs {w}",
                            t[i]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn overlap_and_distances_agree_with_single_box_tests() {
        let mut g = Gen(2);
        let dist =
            |x: &Aabb, y: &Aabb| (x.min - y.max).max(y.min - x.max).max(Vec3A::ZERO).length();
        for _ in 0..20_000 {
            let (batch, rows, boxes) = g.batch();
            let n = boxes.len();
            let q = g.aabb();
            let p = g.vec();
            let margin = g.coord().abs();
            let forms = [
                (
                    batch.overlaps(&q),
                    batch.overlaps_grown(margin, &q),
                    batch.distance_squared(p),
                    batch.box_distances(&q, true),
                    batch.box_distances(&q, false),
                ),
                (
                    overlaps_rows(&rows, n, None, &q),
                    overlaps_rows(&rows, n, Some(margin), &q),
                    distance_squared_rows(&rows, n, p),
                    box_distances_rows(&rows, n, &q, true),
                    box_distances_rows(&rows, n, &q, false),
                ),
            ];
            for (m, ml, d2, dl, dq) in forms {
                assert_eq!((m | ml) & !lane_mask(n), 0, "padding lanes hit");
                for (i, b) in boxes.iter().enumerate() {
                    assert_eq!(m >> i & 1 != 0, b.intersects(&q), "lane {i}");
                    assert_eq!(ml >> i & 1 != 0, b.loosened(margin).intersects(&q));
                    assert!(same(d2[i], b.distance_squared(p)), "lane {i}");
                    assert!(same(dl[i], dist(b, &q)) && same(dq[i], dist(&q, b)));
                }
                for i in n..MAX_CHILDREN {
                    assert_eq!(d2[i], f32::INFINITY);
                    assert_eq!(dl[i], f32::INFINITY);
                }
            }
        }
    }

    #[test]
    fn transform_agrees_with_single_box_transform() {
        let mut g = Gen(3);
        for _ in 0..5_000 {
            let (batch, rows, boxes) = g.batch();
            let n = boxes.len();
            let r = (g.bits() % 628) as f32 / 100.0;
            let axis = (g.vec() + Vec3A::splat(0.1)).normalize_or(Vec3A::Z);
            let pose = Pose::from_rotation_translation(
                glam::Quat::from_axis_angle(axis.into(), r),
                g.vec().into(),
            );
            let moved = batch.transformed(&pose);
            let moved_rows = transformed_rows(&rows, n, &pose);
            assert_eq!(moved.len(), n);
            for (i, b) in boxes.iter().enumerate() {
                let want = b.transformed(&pose);
                assert!(same_box(&moved.get(i), &want), "lane {i}: {want:?}");
                assert!(same_box(&moved_rows.get(i), &want), "rows, lane {i}");
            }
            for i in n..MAX_CHILDREN {
                assert_eq!(moved.get(i), Aabb::EMPTY, "padding stays empty");
                assert_eq!(moved_rows.get(i), Aabb::EMPTY, "padding stays empty");
            }
        }
    }

    /// Batches built at once, lane by lane, or from rows hold the same
    /// boxes, and visit the same lanes of a mask.
    #[test]
    fn constructors_agree() {
        let mut g = Gen(4);
        for _ in 0..2_000 {
            let (batch, _, boxes) = g.batch();
            let mut pushed = ChildBoxes::EMPTY;
            // Rows with garbage past the batch's lanes, which must not
            // show.
            let junk = g.coord();
            let (mut min, mut max) = ([[junk; MAX_CHILDREN]; 3], [[-junk; MAX_CHILDREN]; 3]);
            for (i, b) in boxes.iter().enumerate() {
                pushed.push(*b);
                for a in 0..3 {
                    min[a][i] = b.min[a];
                    max[a][i] = b.max[a];
                }
            }
            let [a, b, c] = &min;
            let [d, e, f] = &max;
            let from_rows = ChildBoxes::from_rows(boxes.len(), [a, b, c], [d, e, f]);
            for i in 0..MAX_CHILDREN {
                let want = boxes.get(i).copied().unwrap_or(Aabb::EMPTY);
                for c in [&batch, &pushed, &from_rows] {
                    assert!(same_box(&c.get(i), &want), "lane {i}");
                }
            }
            let all = Aabb::from_arrays([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]);
            assert_eq!(from_rows.overlaps(&all), batch.lanes(), "padding of rows");
            assert_eq!(from_rows.len(), batch.len());
            let mask = g.bits() as u32;
            let mut seen = Vec::new();
            pushed.for_each_in(mask, |i| seen.push(i));
            let want: Vec<usize> = (0..boxes.len()).filter(|&i| mask >> i & 1 != 0).collect();
            assert_eq!(seen, want);
            seen.clear();
            batch.for_each_in(mask, |i| seen.push(i));
            assert_eq!(seen, want);
        }
    }

    #[test]
    fn transpose_gives_coordinate_rows() {
        let mut g = Gen(5);
        for _ in 0..1000 {
            let p = [g.vec(), g.vec(), g.vec(), g.vec()];
            let rows = transpose(p);
            for a in 0..3 {
                for l in 0..W {
                    assert!(same(rows[a][l], p[l][a]));
                }
            }
        }
    }

    /// Padding lanes stay out of every mask even for queries that contain
    /// all of space (an empty box alone would overlap those).
    #[test]
    fn padding_lanes_never_hit() {
        let all = Aabb::from_arrays([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]);
        let ray = Ray::new(Vec3A::ZERO, Vec3A::new(1.0, 0.5, 0.0));
        for n in 0..=MAX_CHILDREN {
            for b in [all, Aabb::EMPTY] {
                let boxes = vec![b; n];
                let batch = ChildBoxes::from_boxes(&boxes);
                let rows = Rows::from_lanes(n, |i| boxes[i]);
                assert_eq!(batch.lanes().count_ones() as usize, n);
                assert_eq!(batch.overlaps(&all), batch.lanes());
                assert_eq!(batch.overlaps_grown(1.0, &all), batch.lanes());
                assert_eq!(overlaps_rows(&rows, n, Some(1.0), &all), batch.lanes());
                if b == all {
                    assert_eq!(batch.slab(&ray, f32::INFINITY).0, batch.lanes());
                    assert_eq!(slab_rows(&rows, n, &ray, f32::INFINITY).0, batch.lanes());
                }
            }
        }
        let none = ChildBoxes::from_boxes(&[]);
        assert_eq!(none, ChildBoxes::EMPTY);
        assert_eq!(none.overlaps(&all), 0);
        assert_eq!(none.slab(&ray, f32::INFINITY).0, 0);
    }
}
