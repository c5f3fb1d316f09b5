//! The triangle-pair contact kernel: separation or penetration of two
//! triangles by the separating axis theorem, exactly, and the contact points
//! of a pair within a prediction distance.
//!
//! # Axes
//!
//! Two triangles are convex polytopes; the faces of their Minkowski
//! difference have normals among the two face normals, the nine cross
//! products of an edge of each, and (when the triangles are coplanar and the
//! difference is flat) the six in-plane edge normals `n × e`. The kernel
//! tests all 17. Along an axis `L` the signed separation is
//! `max(min_B − max_A, min_A − max_B) / |L|`; the largest over the axes is
//!
//! - the penetration depth, negated, when every axis overlaps (the support
//!   function of the difference is smallest at one of its face normals, and
//!   extra axes can only overlap more), with that axis as the normal;
//! - a lower bound of the distance when some axis separates. Then the exact
//!   distance comes from the closest features (six vertex–triangle and nine
//!   edge–edge distances), but only for pairs whose bound is within the
//!   prediction distance: the rest are rejected on the bound alone.
//!
//! # Batches
//!
//! Pairs are queued in a [`PairKernel`] in structure-of-arrays form,
//! [`LANES`] at a time; the 17-axis test runs over a whole batch with every
//! arithmetic step a loop over the lanes, which the compiler vectorizes (with
//! AVX2 when the processor has it, detected at run time, and SSE2 or the
//! target's baseline otherwise). Only pairs within the prediction distance
//! go on to the scalar part: the exact distance of separated pairs and the
//! contact points. Nothing is allocated per pair.
//!
//! # Contact points
//!
//! The normal points from triangle A to triangle B, in A's frame. Every
//! contact carries its *witness*: the deepest (or closest) point pair, whose
//! distance is the pair's exact separation. When the normal is a face normal
//! (within 1°), the other triangle is clipped to that face's prism
//! (Sutherland–Hodgman) and each clipped corner within the prediction
//! distance is a further point, with its distance to the face's plane, so
//! that a face resting on a face yields its whole support polygon.

use glam::Vec3A;

use super::features::clip_to_prism;
pub use super::features::{closest_on_segments, closest_points};
use super::orient::{Neighbours, OrientedAxis, PairFacing, SideCache, oriented_axis_near};
use super::sat::{Batch, Corners, sat_dispatch};
pub use super::sat::{LANES, Simd};
use crate::geom::Triangle;

/// Number of candidate axes per pair (2 faces, 9 edge-edge, 6 in-plane).
pub const AXES: usize = 17;

/// The most points one pair contact holds: its witness and a clipped
/// hexagon.
pub const MAX_PAIR_POINTS: usize = 7;

/// One contact point of a triangle pair, in triangle A's frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairPoint {
    /// The point on triangle A (or on its plane, for clipped face contacts).
    pub p1: Vec3A,
    /// The point on triangle B.
    pub p2: Vec3A,
    /// Signed distance along the pair's normal: negative when penetrating.
    pub dist: f32,
    /// Which point of the pair this is: 0 for the witness, 1.. for clipped
    /// corners. Stable for a pair whose configuration does not change.
    pub feature: u8,
}

/// Which feature gives a pair's normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalFeature {
    /// Triangle A's face normal.
    FaceA,
    /// Triangle B's face normal.
    FaceB,
    /// An edge of each (or the closest features of a separated pair).
    Other,
}

/// The contact of one triangle pair within the prediction distance.
#[derive(Clone, Copy, Debug)]
pub struct PairContact {
    /// Triangle id in A.
    pub i: u32,
    /// Triangle id in B.
    pub j: u32,
    /// Unit normal from A to B, in A's frame.
    pub normal: Vec3A,
    /// Exact signed separation: the distance when apart, minus the
    /// penetration depth when overlapping.
    pub dist: f32,
    /// Where the normal comes from.
    pub feature: NormalFeature,
    points: [PairPoint; MAX_PAIR_POINTS],
    len: u8,
}

impl PairContact {
    /// The contact points: the witness first, then clipped corners.
    pub fn points(&self) -> &[PairPoint] {
        &self.points[..self.len as usize]
    }

    fn push(&mut self, p: PairPoint) {
        if (self.len as usize) < MAX_PAIR_POINTS {
            self.points[self.len as usize] = p;
            self.len += 1;
        }
    }
}

/// Where a [`PairKernel`] hands its contacts.
///
/// [`PairKernel::push`] and [`PairKernel::flush`] take a closure;
/// [`PairKernel::push_into`] and [`PairKernel::flush_into`] a sink. A sink
/// that keeps only a summary of
/// the contacts (a [`PatchSet`](super::PatchSet) keeps each patch's deepest
/// and extreme points) can also take a pair *without its points*, through
/// [`absorb`](Self::absorb), when the points could not change that summary:
/// the kernel then skips the witness and clipping work for the pair.
pub trait ContactSink {
    /// Offered before the points of an overlapping pair (or of a separated
    /// pair under [`PairKernel::exact_separation`]`(false)`) are computed,
    /// with the pair's unit normal (A to B, in A's frame), its signed
    /// separation (every contact point of the pair is at least this far
    /// along the normal) and triangle A (every point on shape 1 lies in its
    /// hull, up to rounding). Returns whether the sink took the pair into
    /// account; then [`contact`](Self::contact) is not called for it.
    fn absorb(&mut self, _i: u32, _j: u32, _normal: Vec3A, _sep: f32, _a: &Triangle) -> bool {
        false
    }

    /// A pair contact with its points.
    fn contact(&mut self, c: &PairContact);
}

/// A closure as a sink that takes every contact with its points.
struct FnSink<F>(F);

impl<F: FnMut(&PairContact)> ContactSink for FnSink<F> {
    #[inline]
    fn contact(&mut self, c: &PairContact) {
        (self.0)(c)
    }
}

/// Counters of a kernel's work.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct KernelStats {
    /// Pairs tested.
    pub pairs: u64,
    /// Pairs within the prediction distance (contacts produced).
    pub contacts: u64,
    /// Separated pairs whose exact distance was computed.
    pub exact_distances: u64,
    /// Contacts the sink took without their points ([`ContactSink::absorb`]).
    pub absorbed: u64,
}

impl KernelStats {
    /// Adds another set of counters to this one.
    pub fn add(&mut self, o: &KernelStats) {
        self.pairs += o.pairs;
        self.contacts += o.contacts;
        self.exact_distances += o.exact_distances;
        self.absorbed += o.absorbed;
    }
}

/// Queues triangle pairs and hands each pair within the prediction distance
/// to a sink as a [`PairContact`]. See the module docs.
#[derive(Clone)]
pub struct PairKernel {
    batch: Batch,
    /// The contact being finished, handed to the sink by reference (a
    /// `PairContact` is 350 bytes: returning one by value per pair showed
    /// up as `memmove` in the profile).
    out: PairContact,
    prediction: f32,
    simd: Simd,
    exact: bool,
    facing: Option<PairFacing>,
    /// Side A of the last oriented pair, for the next (see [`SideCache`]).
    sides: SideCache,
    /// Where oriented pairs find their triangles' neighbours.
    neighbours: Option<std::sync::Arc<dyn Neighbours>>,
    /// Work counters since creation.
    pub stats: KernelStats,
}

impl PairKernel {
    /// A kernel reporting pairs closer than `prediction` (0 reports touching
    /// and overlapping pairs only).
    pub fn new(prediction: f32) -> Self {
        Self::with_simd(prediction, Simd::Auto)
    }

    /// A kernel with the batched test's implementation chosen (for tests
    /// that compare the paths).
    pub fn with_simd(prediction: f32, simd: Simd) -> Self {
        Self {
            batch: Batch::default(),
            out: PairContact {
                i: 0,
                j: 0,
                normal: Vec3A::ZERO,
                dist: 0.0,
                feature: NormalFeature::Other,
                points: [PairPoint::default(); MAX_PAIR_POINTS],
                len: 0,
            },
            prediction: prediction.max(0.0),
            simd,
            exact: true,
            facing: None,
            sides: SideCache::new(),
            neighbours: None,
            stats: KernelStats::default(),
        }
    }

    /// Whether separated pairs get their exact distance (the default) or
    /// the separating-axis bound, which is never larger. The bound makes a
    /// speculative contact start at most that much earlier, along the axis
    /// that separates best, and saves the closest-feature search; contact
    /// patches use it. Overlapping pairs are exact either way.
    pub fn exact_separation(mut self, exact: bool) -> Self {
        self.exact = exact;
        self
    }

    /// Oriented contacts ([`super::orient`]): with `Some`, every pair's
    /// normal points out of A's surface into B's, on an axis both triangles
    /// accept given their facing and their edge flags (pushed with
    /// [`push_flagged`](Self::push_flagged); pairs pushed otherwise count as
    /// having every edge active), and separated pairs get the separation
    /// along that axis (a lower bound of the distance). `None` (the default)
    /// takes the axis that separates most, either way round.
    pub fn oriented(mut self, facing: Option<PairFacing>) -> Self {
        self.facing = facing;
        self
    }

    /// Where [`oriented`](Self::oriented) pairs find the triangles that
    /// share their edges: a normal leaning over a shared edge then leans
    /// no further than the neighbour's face normal
    /// ([`super::orient::oriented_axis_near`]). `None` (the default): as
    /// far as the flags allow.
    pub fn neighbours(mut self, neighbours: Option<std::sync::Arc<dyn Neighbours>>) -> Self {
        self.neighbours = neighbours;
        self
    }

    /// Sets the facing of [`oriented`](Self::oriented) on a kernel in use
    /// (a body pair's facing changes with its pose).
    pub fn set_facing(&mut self, facing: Option<PairFacing>) {
        self.facing = facing;
    }

    /// The prediction distance.
    pub fn prediction(&self) -> f32 {
        self.prediction
    }

    /// Queues the pair `(i, a)`, `(j, b)`, both in A's frame; runs the batch
    /// when it is full.
    #[inline]
    pub fn push(
        &mut self,
        i: u32,
        a: &Triangle,
        j: u32,
        b: &Triangle,
        sink: &mut impl FnMut(&PairContact),
    ) {
        self.push_into(i, a, j, b, &mut FnSink(sink));
    }

    /// [`push`](Self::push) into a [`ContactSink`], which may take pairs
    /// without their points.
    #[inline]
    pub fn push_into(
        &mut self,
        i: u32,
        a: &Triangle,
        j: u32,
        b: &Triangle,
        sink: &mut impl ContactSink,
    ) {
        self.push_within(i, a, j, b, self.prediction, sink);
    }

    /// [`push_into`](Self::push_into) with this pair's own prediction
    /// distance (at most the kernel's): a pair found where the shapes
    /// barely move needs a smaller margin (see
    /// [`MotionBound`](super::MotionBound)).
    #[inline]
    pub fn push_within(
        &mut self,
        i: u32,
        a: &Triangle,
        j: u32,
        b: &Triangle,
        prediction: f32,
        sink: &mut impl ContactSink,
    ) {
        let pred = prediction.min(self.prediction).max(0.0);
        if self.batch.put(a, b, (i, j), pred) {
            self.flush_into(sink);
        }
    }

    /// [`push_within`](Self::push_within) with each triangle's edge flags
    /// ([`EdgeFlags::get`](super::EdgeFlags::get)), which oriented contacts
    /// use.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn push_flagged(
        &mut self,
        (i, a, fa): (u32, &Triangle, u8),
        (j, b, fb): (u32, &Triangle, u8),
        prediction: f32,
        sink: &mut impl ContactSink,
    ) {
        let pred = prediction.min(self.prediction).max(0.0);
        let l = self.batch.len;
        let full = self.batch.put(a, b, (i, j), pred);
        self.batch.flags[l] = (fa, fb);
        if full {
            self.flush_into(sink);
        }
    }

    /// Runs the queued pairs.
    pub fn flush(&mut self, sink: &mut impl FnMut(&PairContact)) {
        self.flush_into(&mut FnSink(sink));
    }

    /// [`flush`](Self::flush) into a [`ContactSink`].
    pub fn flush_into(&mut self, sink: &mut impl ContactSink) {
        let n = self.batch.len;
        if n == 0 {
            return;
        }
        // Unused lanes repeat lane 0, so that they compute nothing odd.
        for l in n..LANES {
            for c in 0..3 {
                for k in 0..3 {
                    self.batch.a[c][k][l] = self.batch.a[c][k][0];
                    self.batch.b[c][k][l] = self.batch.b[c][k][0];
                }
            }
        }
        let out = sat_dispatch(&self.batch, self.simd);
        self.stats.pairs += n as u64;
        for l in 0..n {
            let pred = self.batch.pred[l];
            if out.sep[l] > pred || out.sep[l].is_nan() {
                continue;
            }
            let lane = |c: &Corners| -> Triangle {
                [0, 1, 2].map(|v| Vec3A::new(c[v][0][l], c[v][1][l], c[v][2][l]))
            };
            let (a, b) = (lane(&self.batch.a), lane(&self.batch.b));
            let (i, j) = self.batch.ids[l];
            let (mut sep, mut axis, up) = (out.sep[l], out.axis[l] as u8, out.up[l] != 0);
            let mut normal = None;
            if let Some(facing) = &self.facing {
                let (fa, fb) = self.batch.flags[l];
                let hint = OrientedAxis {
                    normal: axis_direction(&a, &b, axis, up),
                    sep,
                    axis,
                };
                let Some(o) = oriented_axis_near(
                    (&a, i, fa),
                    (&b, j, fb),
                    facing,
                    self.prediction,
                    Some(hint),
                    &mut self.sides,
                    self.neighbours.as_deref(),
                ) else {
                    continue;
                };
                if o.sep > pred {
                    continue;
                }
                (sep, axis, normal) = (o.sep, o.axis, Some(o.normal));
            }
            let exact = self.exact && normal.is_none();
            let n = normal.unwrap_or_else(|| axis_direction(&a, &b, axis, up));
            if (sep <= 0.0 || !exact)
                && n.is_finite()
                && n != Vec3A::ZERO
                && sink.absorb(i, j, n, sep, &a)
            {
                self.stats.contacts += 1;
                self.stats.absorbed += 1;
                continue;
            }
            if self.finish(i, &a, j, &b, (sep, axis, up), normal, pred) {
                self.stats.contacts += 1;
                sink.contact(&self.out);
            }
        }
        self.batch.len = 0;
    }

    /// The contact of one pair from its test result (scalar part), into
    /// `self.out`; whether the pair is a contact.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &mut self,
        i: u32,
        a: &Triangle,
        j: u32,
        b: &Triangle,
        (sep, axis, up): (f32, u8, bool),
        oriented: Option<Vec3A>,
        prediction: f32,
    ) -> bool {
        let c = &mut self.out;
        c.i = i;
        c.j = j;
        c.normal = Vec3A::ZERO;
        c.dist = sep;
        c.feature = NormalFeature::Other;
        c.len = 0;
        let na = face_normal(a);
        let nb = face_normal(b);
        if sep > 0.0 && self.exact && oriented.is_none() {
            // Separated: the exact distance from the closest features,
            // unless a face axis's witness corner lies over the face (then
            // the bound is the distance).
            let (p1, p2, d) = match face_witness(a, b, axis, up, sep) {
                Some(w) => w,
                None => {
                    self.stats.exact_distances += 1;
                    closest_points(a, b)
                }
            };
            if d > prediction {
                return false;
            }
            let n = if d > 0.0 {
                (p2 - p1) / d
            } else {
                axis_direction(a, b, axis, up)
            };
            c.normal = n;
            c.dist = d;
            c.push(PairPoint {
                p1,
                p2,
                dist: d,
                feature: 0,
            });
        } else {
            // Overlapping (the best axis gives the exact depth), or
            // separated with the bound asked for, or oriented: the best
            // axis and its witness.
            let n = oriented.unwrap_or_else(|| axis_direction(a, b, axis, up));
            c.normal = n;
            let (p1, p2) = witness(a, b, axis, n, sep);
            c.push(PairPoint {
                p1,
                p2,
                dist: sep,
                feature: 0,
            });
        }
        if !c.normal.is_finite() || c.normal == Vec3A::ZERO {
            return false;
        }
        // A face normal within 1°: clip the other triangle to the face.
        const COS_1_DEG: f32 = 0.999_847_7;
        if na.is_finite() && c.normal.dot(na).abs() >= COS_1_DEG {
            c.feature = NormalFeature::FaceA;
            let n = c.normal;
            let poly = clip_to_prism(b, a, na);
            for (k, v) in poly.iter().enumerate() {
                let d = n.dot(*v - a[0]);
                if d <= prediction {
                    c.push(PairPoint {
                        p1: *v - n * d,
                        p2: *v,
                        dist: d,
                        feature: k as u8 + 1,
                    });
                }
            }
        } else if nb.is_finite() && c.normal.dot(nb).abs() >= COS_1_DEG {
            c.feature = NormalFeature::FaceB;
            let n = c.normal;
            let poly = clip_to_prism(a, b, nb);
            for (k, v) in poly.iter().enumerate() {
                let d = n.dot(b[0] - *v);
                if d <= prediction {
                    c.push(PairPoint {
                        p1: *v,
                        p2: *v + n * d,
                        dist: d,
                        feature: k as u8 + 1,
                    });
                }
            }
        }
        true
    }
}

/// The contact of one pair, unbatched (tests, one-off queries).
pub fn pair_contact(a: &Triangle, b: &Triangle, prediction: f32) -> Option<PairContact> {
    let mut k = PairKernel::new(prediction);
    let mut out = None;
    k.push(0, a, 0, b, &mut |c| out = Some(*c));
    k.flush(&mut |c| out = Some(*c));
    out
}

/// Whether two triangles intersect or touch (the papers' interference test):
/// no separating axis among the 17.
pub fn triangles_intersect(a: &Triangle, b: &Triangle) -> bool {
    let mut batch = Batch::default();
    for c in 0..3 {
        for k in 0..3 {
            for l in 0..LANES {
                batch.a[c][k][l] = a[c][k];
                batch.b[c][k][l] = b[c][k];
            }
        }
    }
    batch.len = 1;
    sat_dispatch(&batch, Simd::Auto).sep[0] <= 0.0
}

/// Counts intersecting pairs in batches: queue pairs with
/// [`Interference::push`]; the count is in [`Interference::intersecting`].
#[derive(Clone, Default)]
pub struct Interference {
    batch: Batch,
    /// Pairs tested.
    pub tested: u64,
    /// Pairs that intersect or touch.
    pub intersecting: u64,
}

impl Interference {
    /// Queues one pair (both triangles in the same frame).
    #[inline]
    pub fn push(&mut self, a: &Triangle, b: &Triangle) {
        if self.batch.put(a, b, (0, 0), 0.0) {
            self.flush();
        }
    }

    /// Tests the queued pairs.
    pub fn flush(&mut self) {
        let n = self.batch.len;
        if n == 0 {
            return;
        }
        let out = sat_dispatch(&self.batch, Simd::Auto);
        self.tested += n as u64;
        self.intersecting += out.sep[..n].iter().filter(|s| **s <= 0.0).count() as u64;
        self.batch.len = 0;
    }
}

fn face_normal(t: &Triangle) -> Vec3A {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize_or(Vec3A::NAN)
}

fn edges(t: &Triangle) -> [Vec3A; 3] {
    [t[1] - t[0], t[2] - t[1], t[0] - t[2]]
}

/// The unnormalized axis `axis` of the pair (see [`sat_lanes`] for the order).
fn axis_vector(a: &Triangle, b: &Triangle, axis: u8) -> Vec3A {
    let ea = edges(a);
    let eb = edges(b);
    let na = ea[0].cross(-ea[2]);
    let nb = eb[0].cross(-eb[2]);
    match axis {
        0 => na,
        1 => nb,
        2..=10 => {
            let k = (axis - 2) as usize;
            ea[k / 3].cross(eb[k % 3])
        }
        11..=13 => na.cross(ea[(axis - 11) as usize]),
        _ => nb.cross(eb[(axis - 14) as usize]),
    }
}

/// The unit normal from A to B along `axis`.
fn axis_direction(a: &Triangle, b: &Triangle, axis: u8, up: bool) -> Vec3A {
    let l = axis_vector(a, b, axis).normalize_or_zero();
    if up { l } else { -l }
}

/// The witness point pair of a pair along its best axis's unit normal `n`
/// (from A to B) with separation `sep`.
fn witness(a: &Triangle, b: &Triangle, axis: u8, n: Vec3A, sep: f32) -> (Vec3A, Vec3A) {
    match axis {
        2..=10 => {
            // The closest points of the two edges, made to differ by exactly
            // `sep` along the normal (segment ends can make the segments'
            // own closest points differ sideways too, which a solver would
            // read as a tangential offset between the bodies).
            let k = (axis - 2) as usize;
            let (ia, ib) = (k / 3, k % 3);
            let (c1, c2) = closest_on_segments(a[ia], a[(ia + 1) % 3], b[ib], b[(ib + 1) % 3]);
            let m = (c1 + c2) * 0.5;
            (m - n * (0.5 * sep), m + n * (0.5 * sep))
        }
        1 | 14..=16 => {
            // B's feature: A's deepest corner along n.
            let u = *a
                .iter()
                .max_by(|x, y| n.dot(**x).total_cmp(&n.dot(**y)))
                .expect("three corners");
            (u, u + n * sep)
        }
        _ => {
            // A's feature: B's deepest corner against n.
            let v = *b
                .iter()
                .min_by(|x, y| n.dot(**x).total_cmp(&n.dot(**y)))
                .expect("three corners");
            (v - n * sep, v)
        }
    }
}

/// For a separated pair whose best axis is a face normal: the other
/// triangle's nearest corner and its projection, when the projection lies
/// inside the face. Then no feature is closer than that corner (the face
/// separates by exactly `sep` and the corner attains it), so the pair's
/// distance is `sep`.
fn face_witness(
    a: &Triangle,
    b: &Triangle,
    axis: u8,
    up: bool,
    sep: f32,
) -> Option<(Vec3A, Vec3A, f32)> {
    let (face, other, from_a) = match axis {
        0 => (a, b, true),
        1 => (b, a, false),
        _ => return None,
    };
    let n = axis_direction(a, b, axis, up);
    // The corner of `other` nearest the face along the axis.
    let toward = if from_a { -n } else { n };
    let v = *other
        .iter()
        .max_by(|x, y| toward.dot(**x).total_cmp(&toward.dot(**y)))
        .expect("three corners");
    let q = if from_a { v - n * sep } else { v + n * sep };
    let fnorm = (face[1] - face[0]).cross(face[2] - face[0]);
    let inside = (0..3).all(|k| {
        let e = face[(k + 1) % 3] - face[k];
        fnorm.dot(e.cross(q - face[k])) >= 0.0
    });
    if !inside {
        return None;
    }
    Some(if from_a { (q, v, sep) } else { (v, q, sep) })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(p: [[f32; 3]; 3]) -> Triangle {
        p.map(Vec3A::from)
    }

    #[test]
    fn face_on_face_gives_the_support_polygon() {
        let floor = tri([[-2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 0.0]]);
        // A small triangle 0.01 below the floor's plane: apart, but within
        // a prediction of 0.02.
        let t = tri([[0.0, -0.01, 0.0], [0.5, -0.01, 0.0], [0.0, -0.01, 0.5]]);
        assert!(pair_contact(&floor, &t, 0.0).is_none());
        let c = pair_contact(&floor, &t, 0.02).expect("within the prediction");
        assert!((c.dist - 0.01).abs() < 1e-6, "{}", c.dist);
        assert!((c.normal - Vec3A::NEG_Y).length() < 1e-6, "{}", c.normal);
        assert_eq!(c.feature, NormalFeature::FaceA);
        // Witness plus the three corners.
        assert_eq!(c.points().len(), 4);
        for p in c.points() {
            assert!((p.dist - 0.01).abs() < 1e-6);
            assert!((p.p1.y).abs() < 1e-6 && (p.p2.y + 0.01).abs() < 1e-6);
        }
    }

    #[test]
    fn separated_pairs_report_the_exact_distance() {
        let a = tri([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        // An edge-edge configuration: B crosses above A's hypotenuse.
        let b = tri([[1.0, 1.0, 0.5], [0.0, 0.0, 0.6], [1.0, 1.0, 2.0]]);
        let (_, _, d) = closest_points(&a, &b);
        let c = pair_contact(&a, &b, 1.0).expect("within prediction");
        assert!((c.dist - d).abs() < 1e-6);
        assert!(pair_contact(&a, &b, d * 0.99).is_none());
        assert!(!triangles_intersect(&a, &b));
    }

    #[test]
    fn crossing_triangles_intersect() {
        let a = tri([[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]]);
        let b = tri([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.5]]);
        assert!(triangles_intersect(&a, &b));
        let c = pair_contact(&a, &b, 0.0).expect("crossing");
        assert!(c.dist < 0.0);
    }

    /// The vectorized (AVX2 where detected) and portable paths agree bit
    /// for bit: no fused operations, the same lane-wise arithmetic.
    #[test]
    fn simd_and_scalar_paths_agree() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let mut batch = Batch::default();
            for l in 0..LANES {
                for c in 0..3 {
                    for k in 0..3 {
                        batch.a[c][k][l] = rnd();
                        batch.b[c][k][l] = rnd() * 0.5 + 0.3;
                    }
                }
            }
            batch.len = LANES;
            let x = sat_dispatch(&batch, Simd::Auto);
            let y = sat_dispatch(&batch, Simd::Scalar);
            assert_eq!(x.sep.map(f32::to_bits), y.sep.map(f32::to_bits));
            assert_eq!(x.axis, y.axis);
            assert_eq!(x.up, y.up);
        }
    }

    /// The oriented kernel, which starts from the batched test's best axis
    /// and searches every axis only when a side rejects it, gives the same
    /// normal and separation as the full search of
    /// [`oriented_axis`](super::super::orient::oriented_axis), on random
    /// close pairs with random edge flags and both facings.
    #[test]
    fn oriented_kernel_equals_the_full_search() {
        use crate::contact::orient::{Facing, oriented_axis};
        let mut rng = crate::scene::rng::Rng::new(0x2545_f491_4f6c_dd1d, 0);
        let mut rnd = move || rng.range(-1.0, 1.0);
        let (mut hinted, mut contacts) = (0, 0);
        for round in 0..8000 {
            let a: Triangle = [0, 1, 2].map(|_| Vec3A::new(rnd(), rnd() * 0.3, rnd()));
            let lift = rnd() * 0.3;
            let b: Triangle = [0, 1, 2].map(|_| Vec3A::new(rnd(), rnd() * 0.3 + lift, rnd()));
            // No active edge a third of the time (a smooth surface's
            // triangles), where the search skips the most.
            let mut flags = || {
                let x = rnd();
                if x < -0.3 {
                    0
                } else {
                    (x.to_bits() & 0x3f) as u8
                }
            };
            let (fa, fb) = (flags(), flags());
            let facing = if round % 2 == 0 {
                PairFacing::new(Facing::OneSided(1.0), Facing::OneSided(-1.0))
            } else {
                PairFacing::new(
                    Facing::TwoSided {
                        toward: Vec3A::new(0.0, 2.0, 0.0),
                    },
                    Facing::OneSided(1.0),
                )
            };
            let pred = 0.1;
            // The kernel drops a pair that some axis separates by more than
            // the prediction before orienting it (the oriented separation
            // is only a lower bound of the distance).
            let mut near = false;
            let mut plain = PairKernel::new(pred).exact_separation(false);
            plain.push(0, &a, 1, &b, &mut |_| near = true);
            plain.flush(&mut |_| near = true);
            let full =
                oriented_axis(&a, fa, &b, fb, &facing, pred).filter(|o| o.sep <= pred && near);
            let mut k = PairKernel::new(pred).oriented(Some(facing));
            let mut got = None;
            k.push_flagged(
                (0, &a, fa),
                (1, &b, fb),
                pred,
                &mut FnSink(&mut |c: &PairContact| got = Some((c.normal, c.dist))),
            );
            k.flush(&mut |c| got = Some((c.normal, c.dist)));
            match (full, got) {
                (None, None) => {}
                (Some(o), Some((n, d))) => {
                    contacts += 1;
                    // Axes of equal separation may be taken in either order.
                    assert!((o.sep - d).abs() < 1e-4, "round {round}: {o:?} vs {n} {d}");
                    if (o.normal - n).length() < 1e-4 {
                        hinted += 1;
                    }
                }
                (x, y) => panic!("round {round}: full search {x:?}, kernel {y:?}"),
            }
        }
        assert!(contacts > 500, "{contacts} contacts: too few to compare");
        assert!(
            hinted * 10 >= contacts * 9,
            "{hinted} of {contacts} normals equal"
        );
    }

    #[test]
    fn coplanar_disjoint_triangles_are_separated() {
        let a = tri([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
        let b = tri([[2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [2.0, 0.0, 1.0]]);
        assert!(!triangles_intersect(&a, &b));
        let c = pair_contact(&a, &b, 2.0).expect("within 2");
        assert!((c.dist - 1.0).abs() < 1e-6);
    }
}
