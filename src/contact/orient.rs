//! Oriented contact normals for a triangle pair of two meshes, from the
//! triangles' facing and their active edges ([`super::edges`]).
//!
//! # The rule
//!
//! The normal of a pair points from triangle A to triangle B, out of A's
//! surface and into B's, never the other way. Each triangle *faces* one
//! side ([`Facing`]):
//!
//! - a closed mesh faces outward: the side of its winding's normal when its
//!   signed volume is positive, the other side when negative;
//! - an open mesh (a ground, a ramp, a bowl) is two-sided by default: each
//!   triangle faces the side on which the other shape's centre lies, so a
//!   body resting on a ground is pushed up whichever way the ground was
//!   wound, and a ball in a bowl is pushed toward the bowl's inside. It can
//!   be made one-sided instead.
//!
//! The normal is the separating axis of the pair (the two face normals,
//! the nine edge–edge cross products and the six in-plane edge normals, each
//! both ways round) with the largest signed separation *among the axes
//! both triangles accept*. Along an axis `n`, triangle A touches with its
//! support feature (the corners farthest along `n`) and B with its corners
//! farthest along `−n`; a feature accepts `n` when
//!
//! - it is the face and `n` is (within the cone angle) the face's outward
//!   normal;
//! - it is an *active* edge (seen from the side the triangle faces) and
//!   `n` leans out across it, or a corner with an active edge, near the
//!   other triangle, and `n` leans out over it, in both cases not more
//!   than about 96° from the face's outward normal (past 90° it points into
//!   the solid behind the face, the few degrees over keep a box tilting on
//!   the ground meeting it along its side faces' bottom edges; at a sharp
//!   edge the triangle on its other side, paired with the same body,
//!   covers the rest of the edge's wedge). A far corner of a large
//!   triangle, like a 2-triangle ramp's own corners, is not where the two
//!   meet: the contact lies on the inactive diagonal or face between;
//! - it is an *inactive* edge or corner (a flat or concave one, inside a
//!   smooth surface) and `n` is within the cone angle of the face's
//!   outward normal: a body sliding over a tessellated plane meets the plane, not
//!   the edges between its triangles (Jolt's active edges, Bullet's
//!   internal-edge adjustment and parry's `FIX_INTERNAL_EDGES` do the same
//!   for a convex shape against a mesh; here both sides are meshes).
//!
//! When neither side touches with its face and one side touches with an
//! inactive feature, the normal becomes that side's face normal (A's first),
//! and the separation is measured along it: the contact is with the smooth
//! surface the inactive feature lies in. Not where that face normal would
//! lean more than about 96° from the other side's face normal, into its
//! solid (the other side touching with an active edge, which takes normals
//! up to that angle): the accepted axis, within the cone of the face
//! normal anyway, stays. A pair no axis is accepted for
//! gives no contact: it would only push into a back face or catch on an
//! internal edge.
//!
//! An accepted axis may separate the pair less than the plain separating
//! axis does (a triangle behind a one-sided face is pushed out of the
//! front, deeper than the plain depth). That is a contact only where the
//! two triangles lie over each other along the normal: their shadows on
//! the plane across it overlap, within a quarter of the smaller triangle's
//! longest edge. Side by side, the separation along the normal is that of
//! two slabs: a sliver of a scan beside a CAD triangle's edge, straddling
//! its plane, would be reported as penetrating it however far beside it
//! lies, and a fast body (a large prediction) met such pairs centimetres
//! apart as millimetres deep. Such pairs give no contact; the triangles
//! that do lie over each other give the contact.
//!
//! # Neighbours
//!
//! The flags say which edges are sharp, not how far the surface turns
//! there. Given a lookup of the triangle sharing an edge ([`Neighbours`],
//! [`oriented_axis_near`]; the per-pair mode passes one, the patch mode
//! does not: on a statue resting on a CAD turbine most pairs asked for a
//! lookup at the turbine's sharp edges, and the patch narrow phase took
//! about three times as long), a normal
//! leaning over a sharp edge (active from this side only) leans no further
//! than that neighbour's face normal, where the edge's normal cone ends
//! (the lookup runs only for an edge a tested axis leans over):
//!
//! - an active edge accepts a lean only up to there, so a box coming over
//!   a ridge's flat half does not meet the down half's crease along its
//!   in-plane edge normal, 80° from the vertical (a kick up);
//! - a pair whose plain axis (the direction it separates along, or
//!   penetrates least) leans past the neighbour's face normal at a sharp
//!   edge gives no contact: the other triangle lies beyond the neighbour,
//!   whose own pair with it gives the contact (Jolt's internal-edge
//!   removal drops such contacts likewise);
//! - a pair whose best axis is the neighbour's face normal itself, the
//!   other triangle touching with an edge or a corner, gives none either:
//!   the neighbour's pair gives it along its own face.
//!
//! Edges within the flat angle keep the rule above (the face normal): a
//! bound there too (a lean up to the few degrees a convex crease turns)
//! made a block rocking on a tessellated dome and an icosphere rolling on
//! a tessellated ramp lose contacts (`physics::rock_low_holds`,
//! `physics::roll_15deg_64x64`).
//!
//! The cone angle is the flat angle of the edge flags: a corner of a finely
//! tessellated sphere is inactive, and the faces around it lie within that
//! angle of the plane it rests on, so the plane's normal is accepted.
//!
//! # Cost
//!
//! The kernel's batched test has already found the axis that separates
//! most over all 34 directions. When both sides accept it, it is the best
//! accepted axis as well, and [`oriented_axis_from`] takes it after two
//! feature tests instead of testing all 34: on a statue resting on a
//! turbine most pairs take that path, and the oriented kernel costs about
//! what the unoriented one did.
//!
//! Pairs end before any search when no direction can be accepted by both:
//! when the two sides' cones do not meet, and when one side is flat (it
//! accepts only its cone) and the other can accept nothing in that cone
//! (its face cone too far, its active edges leaning out of the flat plane
//! or below its third corner, its corners with active edges away from the
//! flat triangle or never on top along the flat side's normal). A scan's
//! flat triangles against a CAD part's large sharp ones are mostly such
//! pairs.

use std::cell::OnceCell;

use glam::Vec3A;

use super::edges::side_bits;
use crate::geom::{Aabb, Triangle};

/// Which side of its triangles a shape's contacts come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Facing {
    /// Every triangle faces the side of its winding's normal times the sign
    /// (`1.0` or `-1.0`): a closed mesh, or an open one made one-sided.
    OneSided(f32),
    /// Each triangle faces the side on which `toward` (the other shape's
    /// centre, in the pair's frame) lies.
    TwoSided {
        /// The point the triangles face.
        toward: Vec3A,
    },
}

/// The facing of both sides of a pair and the cone angle (as its cosine).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairFacing {
    /// Shape A's facing.
    pub a: Facing,
    /// Shape B's facing.
    pub b: Facing,
    /// Cosine of the cone angle within which an inactive feature accepts a
    /// normal.
    pub cone_cos: f32,
}

impl PairFacing {
    /// Both facings with the cone angle of the default flat angle.
    pub fn new(a: Facing, b: Facing) -> Self {
        Self {
            a,
            b,
            cone_cos: super::edges::EdgeFlags::DEFAULT_FLAT_DEG.to_radians().cos(),
        }
    }
}

/// The oriented axis of a pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientedAxis {
    /// Unit normal from A to B.
    pub normal: Vec3A,
    /// Signed separation along it (negative: penetration).
    pub sep: f32,
    /// The axis in the kernel's numbering (0 A's face, 1 B's face, 2–10
    /// edge–edge, 11–13 A's in-plane edge normals, 14–16 B's).
    pub axis: u8,
}

/// The least `n · out` an active edge or corner accepts (about 96°; see
/// the module docs).
const OUTWARD_MIN: f32 = -0.1;

/// Where the triangle sharing an edge is found, so that a normal leaning
/// over the edge leans no further than that triangle's face normal (the
/// edge's normal cone ends there). The flags say which edges are shared;
/// the neighbour is looked up only for an edge a normal leans over.
pub trait Neighbours: Send + Sync {
    /// The corner, off the edge, of the triangle sharing edge `k` (corner
    /// `k` to `k + 1`) of triangle `t` (id `id` of side B when `b`, else of
    /// side A; given in A's frame), in A's frame; `None` without one.
    fn apex(&self, b: bool, id: u32, t: &Triangle, k: usize) -> Option<Vec3A>;
}

/// The cosine and sine of the bend at edge `k` of `t` (unit normal `out`
/// of the side it faces, edge `k`'s unit in-plane outward normal `m`)
/// toward the neighbour's corner `w`: the neighbour's face normal on that
/// side is `out · c + m · s` (`s < 0`: concave from that side).
pub fn bend_toward(t: &Triangle, k: usize, out: Vec3A, m: Vec3A, w: Vec3A) -> Option<(f32, f32)> {
    let (a, b) = (t[k], t[(k + 1) % 3]);
    let e = b - a;
    let v = w - a;
    let v = (v - e * (v.dot(e) / e.length_squared())).try_normalize()?;
    Some((v.dot(m), -v.dot(out)))
}

/// How far past the neighbour's face normal a lean is still taken as
/// within it (rounding; about 0.006°).
const BEND_SLACK: f32 = 1e-4;

/// How a direction leans over a shared edge, against the neighbour's face
/// normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lean {
    /// Not over the edge.
    None,
    /// Over it, short of the neighbour's face normal.
    Within,
    /// Along the neighbour's face normal (within rounding).
    End,
    /// Past it: out of the edge's normal cone.
    Past,
}

/// How a triangle's support feature accepted an axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Support {
    Face,
    Active,
    Inactive,
    /// A shared edge, the axis exactly its neighbour's face normal (the
    /// end of the edge's normal cone): the neighbour, paired with the same
    /// triangle, gives that contact along its own face.
    ConeEnd,
}

/// One side of the pair, ready for the tests. What only some pairs need
/// (the near box, the in-plane edge normals) is made on first use, so a
/// side kept for the next pair with the same triangle ([`SideCache`])
/// makes it once.
#[derive(Clone, Debug)]
struct Side {
    t: Triangle,
    /// Unit normal of the winding.
    raw: Vec3A,
    /// Unit normal of the side it faces.
    out: Vec3A,
    /// Active edges (bits 0–2) from that side.
    active: u8,
    /// How far apart two corners' projections on a unit direction may lie
    /// from rounding alone and still be tied: a millionth of the farthest
    /// coordinate. (Rounding follows the coordinates' size, not the
    /// projections': a face through the origin projects near 0 along its
    /// own normal, with the coordinates' rounding.)
    rounding: f32,
    /// The slack of [`near`](Self::near).
    slack: f32,
    near: OnceCell<Aabb>,
    in_plane: OnceCell<[Option<Vec3A>; 3]>,
    /// The triangle's id, and whether it is side B (for [`Neighbours`]).
    id: u32,
    is_b: bool,
    /// Sharp edges: active from this side only (convex), shared with one
    /// neighbour that bounds a lean over them.
    shared: u8,
    /// The bend at each shared edge, looked up on first use.
    bends: [OnceCell<Option<(f32, f32)>>; 3],
}

impl Facing {
    /// The side triangle `t` (unit winding normal `raw`) faces: `1.0` for
    /// the side of `raw`, `-1.0` for the other.
    pub fn sign(&self, t: &Triangle, raw: Vec3A) -> f32 {
        match *self {
            Facing::OneSided(s) => s,
            Facing::TwoSided { toward } => {
                let centroid = (t[0] + t[1] + t[2]) * (1.0 / 3.0);
                if raw.dot(toward - centroid) < 0.0 {
                    -1.0
                } else {
                    1.0
                }
            }
        }
    }
}

impl Side {
    #[cfg(test)]
    fn new(t: &Triangle, flags: u8, facing: Facing, slack: f32) -> Option<Self> {
        Self::with_id(t, flags, facing, slack, 0, false)
    }

    fn with_id(
        t: &Triangle,
        flags: u8,
        facing: Facing,
        slack: f32,
        id: u32,
        is_b: bool,
    ) -> Option<Self> {
        let raw = (t[1] - t[0]).cross(t[2] - t[0]).try_normalize()?;
        let sign = facing.sign(t, raw);
        let active = side_bits(flags, sign > 0.0);
        let other = side_bits(flags, sign <= 0.0);
        Some(Self {
            t: *t,
            raw,
            out: raw * sign,
            active,
            id,
            is_b,
            shared: active & !other,
            bends: Default::default(),
            rounding: 1e-6 * t[0].abs().max(t[1].abs()).max(t[2].abs()).max_element(),
            slack,
            near: OnceCell::new(),
            in_plane: OnceCell::new(),
        })
    }

    /// The triangle's box grown by its own size and the slack: where the
    /// corners of the other triangle lie that can be where the two meet.
    /// Made only when a corner asks, which most pairs never do.
    fn near(&self) -> &Aabb {
        self.near.get_or_init(|| {
            let b = Aabb::of_triangle(&self.t);
            b.loosened(b.extent().length() + self.slack)
        })
    }

    /// The unit in-plane outward normals of the three edges (`None` for an
    /// edge of no length).
    fn in_plane_normals(&self) -> &[Option<Vec3A>; 3] {
        self.in_plane.get_or_init(|| {
            let t = &self.t;
            [t[1] - t[0], t[2] - t[1], t[0] - t[2]].map(|e| self.raw.cross(e).try_normalize())
        })
    }

    /// Whether [`support`](Self::support) can accept `n` at all, from `n`
    /// alone: every feature wants it at most about 96° from the outward
    /// normal, and without an active edge within the cone of it.
    #[inline]
    fn may_accept(&self, n: Vec3A, cone_cos: f32) -> bool {
        let facing = n.dot(self.out);
        if self.active == 0 {
            facing >= cone_cos
        } else {
            facing >= cone_cos.min(OUTWARD_MIN)
        }
    }

    /// The cosine and sine of the half-angle of the cone of directions
    /// [`may_accept`](Self::may_accept) lets through, around `out`.
    #[inline]
    fn half_angle(&self, cone_cos: f32) -> (f32, f32) {
        let c = if self.active == 0 {
            cone_cos
        } else {
            cone_cos.min(OUTWARD_MIN)
        };
        (c, (1.0 - c * c).max(0.0).sqrt())
    }

    /// Whether some direction `n` may be accepted by this side (as A) and
    /// `−n` by `other` (as B): each side lets through only a cone around
    /// its outward normal ([`may_accept`](Self::may_accept)), and two
    /// cones share a direction only when their axes (`out` and
    /// `−other.out`) lie at most the sum of their half-angles apart. A
    /// side without active edges facing nearly the same way as a sharp
    /// one (a scan's flat triangle under a CAD part's edge) has none.
    #[inline]
    fn cones_meet(&self, other: &Side, cone_cos: f32) -> bool {
        // Two sides with active edges: about 96° each, over 180° together.
        if self.active != 0 && other.active != 0 && OUTWARD_MIN <= 0.0 {
            return true;
        }
        let (ca, sa) = self.half_angle(cone_cos);
        let (cb, sb) = other.half_angle(cone_cos);
        // Half-angles summing to 180° or more: every axis pair meets.
        ca + cb <= 0.0 || self.out.dot(-other.out) >= ca * cb - sa * sb - 1e-5
    }

    /// For a side without active edges: whether it may accept (either sign
    /// of) any direction in `other`'s plane, such as `other`'s in-plane edge
    /// normals. It accepts only directions within the cone of its normal,
    /// and the plane holds one only when the two normals lean at least
    /// nearly the cone's complement apart (a small margin keeps rounding on
    /// the accepting side).
    #[inline]
    fn may_accept_in_plane_of(&self, other: &Side, cone_cos: f32) -> bool {
        let d = self.out.dot(other.raw);
        let c = (cone_cos - 1e-4).max(0.0);
        1.0 - d * d >= c * c
    }

    /// For a side with active edges and a `flat` side without: whether
    /// [`support`](Self::support) may accept any unit direction `m` within
    /// the flat side's cone around `−flat.out` (the only directions the
    /// flat side accepts, whichever of the pair it is). It accepts `m` with
    /// its face or an inactive feature only within its own cone, so only
    /// when the two cones' axes lie within twice the cone angle; with an
    /// active edge only when `m` ties the edge's two corners, so is nearly
    /// perpendicular to it, which no `m` in the flat cone is when the edge
    /// leans far enough out of the flat side's plane, and when the third
    /// corner does not lie above the edge along `m`; with a corner only
    /// when the corner lies above the other two along some `m` in the cone
    /// and in the flat side's near box. A scan's flat triangle under a CAD
    /// part's large triangle usually meets none of these (a corner of the
    /// CAD triangle under the scan's is most often its low corner, not the
    /// one on top along the flat side's normal), and the pair has no
    /// accepted axis without the search.
    fn may_accept_within_cone_of(&self, flat: &Side, cone_cos: f32) -> bool {
        let axis = -flat.out;
        let cos_2 = 2.0 * cone_cos * cone_cos - 1.0;
        if self.out.dot(axis) >= cos_2 - 1e-4 {
            return true;
        }
        let sin = (1.0 - cone_cos * cone_cos).max(0.0).sqrt();
        let t = &self.t;
        let e = [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
        let len = e.map(|x| x.length());
        // Two corners tie along a unit `m` when their projections differ
        // by at most 1e-4 of the triangle's extent along `m` (at most its
        // longest edge) plus the coordinates' rounding.
        let tie = 1e-4 * len[0].max(len[1]).max(len[2]) + self.rounding;
        let active = |k: usize| self.active & (1 << k) != 0;
        // Whether some `m` in the cone has `m · d >= −slop`: over the cone,
        // `m · d <= |d| cos(φ − θ)` with `φ` the angle of `d` from the
        // axis, which is at least `−slop` only when
        // `axis · d >= −sin θ |d| − slop` (and a margin for rounding).
        let may_lead = |d: Vec3A, len: f32, slop: f32| axis.dot(d) >= -(sin + 1e-3) * len - slop;
        (0..3).any(|k| {
            let prev = (k + 2) % 3;
            // Edge k (corners k and next) is the support only when `m`
            // ties its corners, so is nearly perpendicular to it (over the
            // cone, |m · e| >= cos θ |axis · e| − sin θ |e|), and the third
            // corner does not lie above it (it would be the support):
            // `m · (t[k] − t[prev]) > −2 tie` (the edge's corners tie
            // within `tie` of the largest).
            let edge = active(k)
                && cone_cos * e[k].dot(axis).abs() - sin * len[k] <= 2.0 * tie + 1e-3 * len[k]
                && may_lead(e[prev], len[prev], 2.0 * tie);
            // Corner k is the support only when it lies above both others
            // along `m` (`e[k]` runs from it to the next corner, `e[prev]`
            // from the previous corner to it), and it accepts only when it
            // lies in the flat side's near box.
            let corner = (active(k) || active(prev))
                && may_lead(-e[k], len[k], tie)
                && may_lead(e[prev], len[prev], tie)
                && flat.near().contains_point(t[k]);
            edge || corner
        })
    }

    /// The bend at shared edge `k` (see [`bend_toward`]), `None` when the
    /// edge is not shared, there is no lookup, or no neighbour.
    fn bend(&self, k: usize, nb: Option<&dyn Neighbours>) -> Option<(f32, f32)> {
        if self.shared & (1 << k) == 0 {
            return None;
        }
        let nb = nb?;
        *self.bends[k].get_or_init(|| {
            let w = nb.apex(self.is_b, self.id, &self.t, k)?;
            let m = (self.t[(k + 1) % 3] - self.t[k])
                .cross(self.raw)
                .try_normalize()?;
            bend_toward(&self.t, k, self.out, m, w)
        })
    }

    /// Whether the unit `n` leans over edge `k` no further than the
    /// neighbour's face normal (`(c, s)`, [`bend`](Self::bend)), and by
    /// more than rounding.
    fn leans_within(&self, k: usize, n: Vec3A, (c, s): (f32, f32)) -> Lean {
        let m = (self.t[(k + 1) % 3] - self.t[k])
            .cross(self.raw)
            .normalize_or_zero();
        let (d, x) = (n.dot(self.out), n.dot(m));
        let past = x * c - d * s;
        if x <= 1e-6 {
            Lean::None
        } else if past > BEND_SLACK {
            Lean::Past
        } else if past >= -BEND_SLACK {
            Lean::End
        } else {
            Lean::Within
        }
    }

    /// Whether the feature farthest along `n` (a unit direction out of this
    /// side) is a shared edge that `n` leans over past the neighbour's face
    /// normal: out of the edge's normal cone, on the neighbour's side.
    fn past_bend(&self, n: Vec3A, nb: Option<&dyn Neighbours>) -> bool {
        if nb.is_none() || self.shared == 0 {
            return false;
        }
        let p = self.t.map(|v| n.dot(v));
        let max = p[0].max(p[1]).max(p[2]);
        let min = p[0].min(p[1]).min(p[2]);
        let eps = 1e-4 * (max - min) + self.rounding;
        let tied = p.map(|x| x >= max - eps);
        if tied.iter().filter(|t| **t).count() != 2 {
            return false;
        }
        let k = (0..3)
            .find(|&k| tied[k] && tied[(k + 1) % 3])
            .expect("two of three corners tied share an edge");
        self.bend(k, nb)
            .is_some_and(|b| self.leans_within(k, n, b) == Lean::Past)
    }

    /// Whether the feature farthest along `n` (a unit direction out of this
    /// side) accepts `n`, and how.
    #[cfg(test)]
    fn support(&self, n: Vec3A, cone_cos: f32, other: &Side) -> Option<Support> {
        self.support_with(n, cone_cos, other, None)
    }

    /// [`support`](Self::support), with the neighbours that bound a lean
    /// over a sharp edge: it accepts a lean only up to the neighbour's face
    /// normal ([`Support::ConeEnd`] there).
    fn support_with(
        &self,
        n: Vec3A,
        cone_cos: f32,
        other: &Side,
        nb: Option<&dyn Neighbours>,
    ) -> Option<Support> {
        let p = self.t.map(|v| n.dot(v));
        let max = p[0].max(p[1]).max(p[2]);
        let min = p[0].min(p[1]).min(p[2]);
        let eps = 1e-4 * (max - min) + self.rounding;
        let tied = p.map(|x| x >= max - eps);
        let count = tied.iter().filter(|t| **t).count();
        let facing = n.dot(self.out);
        let within_cone = facing >= cone_cos;
        let active = |k: usize| self.active & (1 << k) != 0;
        // Not more than about 96 degrees from the outward normal: a normal
        // past 90 points into the solid behind this face (at a sharp edge
        // the neighbouring triangle, paired with the same body, covers the
        // rest of the edge's wedge). The few degrees over 90 keep a box's
        // side face, tilting a little on the ground it stands on, meeting
        // the ground along its bottom edge.
        let outward = facing >= OUTWARD_MIN;
        // Edge `k`'s in-plane outward normal (unnormalized).
        let m = |k: usize| (self.t[(k + 1) % 3] - self.t[k]).cross(self.raw);
        match count {
            3 => within_cone.then_some(Support::Face),
            2 => {
                let k = (0..3)
                    .find(|&k| tied[k] && tied[(k + 1) % 3])
                    .expect("two of three corners tied share an edge");
                if active(k) && outward && at_most_a_little_behind(n, m(k)) {
                    let lean = self.bend(k, nb).map(|b| self.leans_within(k, n, b));
                    match lean {
                        Some(Lean::Past) => within_cone.then_some(Support::Inactive),
                        Some(Lean::End) => Some(Support::ConeEnd),
                        _ => Some(Support::Active),
                    }
                } else {
                    within_cone.then_some(Support::Inactive)
                }
            }
            _ => {
                let k = tied.iter().position(|t| *t).expect("one corner is the max");
                // A corner away from the other triangle is not where the two
                // meet (a far corner of a large triangle, its own edges
                // active, while the contact lies on the inactive edge or
                // face between): only the face's normal is accepted there.
                let (e1, e2) = (k, (k + 2) % 3);
                let over = || {
                    let r = self.t[k] - (self.t[0] + self.t[1] + self.t[2]) * (1.0 / 3.0);
                    other.near().contains_point(self.t[k]) && at_most_a_little_behind(n, r)
                };
                if outward && (active(e1) || active(e2)) && over() {
                    Some(Support::Active)
                } else {
                    within_cone.then_some(Support::Inactive)
                }
            }
        }
    }
}

/// Whether the unit direction `n` makes an angle of at most about 93°
/// with `v` (`n · v̂ ≥ −0.05`; true for `v = 0`), without normalizing `v`.
#[inline]
fn at_most_a_little_behind(n: Vec3A, v: Vec3A) -> bool {
    let d = n.dot(v);
    d >= 0.0 || d * d <= 0.0025 * v.length_squared()
}

/// Side A of the last pair oriented, kept for the next: a traversal pairs
/// one triangle of A with many of B in a row (on a scan dropped on a CAD
/// part, 99 % of pairs have the previous pair's A triangle), and its
/// normals, near box and in-plane edge normals are then made once.
#[derive(Clone, Debug, Default)]
pub struct SideCache {
    last: Option<(u8, Facing, Option<Side>)>,
}

impl SideCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The side of `t` (flags `flags`, facing `facing`, near-box slack
    /// `slack`), made unless it is the last one asked for.
    #[cfg(test)]
    fn side(&mut self, t: &Triangle, flags: u8, facing: Facing, slack: f32) -> Option<&Side> {
        self.side_of(t, flags, facing, slack, 0)
    }

    /// [`side`](Self::side) of triangle `id` of side A.
    fn side_of(
        &mut self,
        t: &Triangle,
        flags: u8,
        facing: Facing,
        slack: f32,
        id: u32,
    ) -> Option<&Side> {
        let same = self.last.as_ref().is_some_and(|(f, fc, s)| {
            *f == flags
                && *fc == facing
                && s.as_ref()
                    .is_some_and(|s| s.t == *t && s.slack == slack && s.id == id)
        });
        if !same {
            let side = Side::with_id(t, flags, facing, slack, id, false);
            self.last = Some((flags, facing, side));
        }
        self.last.as_ref().and_then(|(_, _, s)| s.as_ref())
    }
}

/// Signed separation of `b` from `a` along the unit direction `n`.
#[inline]
fn separation(a: &Triangle, b: &Triangle, n: Vec3A) -> f32 {
    let max_a = n.dot(a[0]).max(n.dot(a[1])).max(n.dot(a[2]));
    let min_b = n.dot(b[0]).min(n.dot(b[1])).min(n.dot(b[2]));
    min_b - max_a
}

/// The oriented axis of the pair `a` (flags `fa`), `b` (flags `fb`), both
/// in A's frame; `None` when no axis is accepted by both sides (or a
/// triangle has no area), or when the accepted axis would report the pair
/// deeper than its plain separating-axis depth by more than `slack` plus a
/// quarter of the smaller triangle's longest edge, or by more than that
/// quarter with the triangles side by side along it. See the module docs.
pub fn oriented_axis(
    a: &Triangle,
    fa: u8,
    b: &Triangle,
    fb: u8,
    facing: &PairFacing,
    slack: f32,
) -> Option<OrientedAxis> {
    oriented_axis_from(a, fa, b, fb, facing, slack, None)
}

/// [`oriented_axis`] given the pair's plain separating axis (`hint`: the
/// unit normal from A to B with the largest separation over every axis,
/// and that separation), as the kernel's batched test has already found it.
/// When both sides accept it, it is the best accepted axis too and the
/// search over the other 33 directions is skipped; the result is the same
/// (up to ties between axes of equal separation).
pub fn oriented_axis_from(
    a: &Triangle,
    fa: u8,
    b: &Triangle,
    fb: u8,
    facing: &PairFacing,
    slack: f32,
    hint: Option<OrientedAxis>,
) -> Option<OrientedAxis> {
    oriented_axis_cached(a, fa, b, fb, facing, slack, hint, &mut SideCache::new())
}

/// [`oriented_axis_from`] taking side A from `cache` when it is the last
/// pair's (and leaving it there for the next). The result is the same.
#[allow(clippy::too_many_arguments)]
pub fn oriented_axis_cached(
    a: &Triangle,
    fa: u8,
    b: &Triangle,
    fb: u8,
    facing: &PairFacing,
    slack: f32,
    hint: Option<OrientedAxis>,
    cache: &mut SideCache,
) -> Option<OrientedAxis> {
    oriented_axis_near((a, 0, fa), (b, 0, fb), facing, slack, hint, cache, None)
}

/// [`oriented_axis_cached`] of triangles `a` (id `ia` of A) and `b` (id
/// `ib` of B) whose neighbours `nb` finds: a normal leaning over a shared
/// edge leans no further than the neighbour's face normal (see
/// [`Neighbours`]). Without `nb`, the same.
#[allow(clippy::too_many_arguments)]
pub fn oriented_axis_near(
    (a, ia, fa): (&Triangle, u32, u8),
    (b, ib, fb): (&Triangle, u32, u8),
    facing: &PairFacing,
    slack: f32,
    hint: Option<OrientedAxis>,
    cache: &mut SideCache,
    nb: Option<&dyn Neighbours>,
) -> Option<OrientedAxis> {
    let sa = cache.side_of(a, fa, facing.a, slack, ia)?;
    let sb = &Side::with_id(b, fb, facing.b, slack, ib, true)?;
    let cone = facing.cone_cos;
    // No direction both sides may accept: nothing to search.
    if !sa.cones_meet(sb, cone) {
        return None;
    }
    // One side flat, the other with active edges that cannot accept any
    // direction in the flat side's cone: nothing to search either.
    if cone > 0.0
        && ((sb.active == 0 && sa.active != 0 && !sa.may_accept_within_cone_of(sb, cone))
            || (sa.active == 0 && sb.active != 0 && !sb.may_accept_within_cone_of(sa, cone)))
    {
        return None;
    }
    let mut best: Option<(OrientedAxis, Support, Support)> = None;
    // The plain separating-axis result, whichever way round and whatever
    // the features: the pair's true separation or penetration depth.
    let mut plain = f32::NEG_INFINITY;
    // The direction of `plain`.
    let mut plain_axis: Option<Vec3A> = None;
    // An edge-edge axis of nearly parallel edges has a noisy direction: the
    // search below skips those, and so does the hint.
    let well_posed = |h: &OrientedAxis| match h.axis {
        2..=10 => {
            let (k, l) = ((h.axis - 2) / 3, (h.axis - 2) % 3);
            let x = a[(k as usize + 1) % 3] - a[k as usize];
            let y = b[(l as usize + 1) % 3] - b[l as usize];
            x.cross(y).length_squared() > 1e-10 * x.length_squared() * y.length_squared()
        }
        _ => true,
    };
    let hint = hint.filter(|h| h.sep.is_finite() && h.normal.is_finite());
    let accepted_hint = hint
        .filter(|h| sa.may_accept(h.normal, cone) && sb.may_accept(-h.normal, cone))
        .filter(well_posed)
        .and_then(|h| {
            let ka = sa.support_with(h.normal, cone, sb, nb)?;
            let kb = sb.support_with(-h.normal, cone, sa, nb)?;
            Some((h, ka, kb))
        });
    if let Some((h, ka, kb)) = accepted_hint {
        plain = h.sep;
        best = Some((h, ka, kb));
    }
    // With the hint, the plain result is known and a direction a side
    // rejects needs no separation.
    let known_plain = hint.map(|h| h.sep);
    if let Some(h) = hint {
        plain = h.sep;
        plain_axis = Some(h.normal);
    }
    // One side flat (no active edge) and its face normal accepted by both:
    // that normal is the answer, without a search, when the faces meet
    // and the two sides' cones do not. Every direction the flat side
    // accepts lies within its cone, so the other side accepts none with
    // its face or an inactive feature (those want its own cone); the
    // search's winner then has the flat side inactive or its face, and the
    // rule below turns an inactive flat side into its face normal. (A
    // winner on the flat side's face tied within rounding of that normal
    // keeps its own direction in the search: the two differ by that
    // rounding.)
    if best.is_none() && known_plain.is_some() && cone > 0.0 {
        let facing_cos = sa.out.dot(-sb.out);
        let cos_2 = 2.0 * cone * cone - 1.0;
        if facing_cos >= OUTWARD_MIN && facing_cos < cos_2 - 1e-4 {
            let flat_face = if sb.active == 0 {
                let n = -sb.out;
                (sa.may_accept(n, cone))
                    .then(|| sa.support_with(n, cone, sb, nb))
                    .flatten()
                    .map(|ka| (n, 1, ka, Support::Face))
            } else if sa.active == 0 {
                let n = sa.out;
                (sb.may_accept(-n, cone))
                    .then(|| sb.support_with(-n, cone, sa, nb))
                    .flatten()
                    .map(|kb| (n, 0, Support::Face, kb))
            } else {
                None
            };
            if let Some((normal, axis, ka, kb)) = flat_face {
                let sep = separation(a, b, normal);
                best = Some((OrientedAxis { normal, sep, axis }, ka, kb));
            }
        }
    }
    let search = best.is_none();
    let mut consider = |n: Vec3A, axis: u8| {
        if known_plain.is_some() && (!sa.may_accept(n, cone) || !sb.may_accept(-n, cone)) {
            return;
        }
        let sep = separation(a, b, n);
        if sep > plain {
            plain = sep;
            plain_axis = Some(n);
        }
        if best.is_some_and(|(o, _, _)| sep <= o.sep) || !sep.is_finite() {
            return;
        }
        let Some(ka) = sa.support_with(n, cone, sb, nb) else {
            return;
        };
        let Some(kb) = sb.support_with(-n, cone, sa, nb) else {
            return;
        };
        best = Some((
            OrientedAxis {
                normal: n,
                sep,
                axis,
            },
            ka,
            kb,
        ));
    };
    if search {
        // With the plain result known, whole families of directions are
        // skipped where a side without active edges cannot accept them: a
        // direction within the cone of a side's normal (half-angle θ) is
        // nearly perpendicular to that side's plane, so it is no in-plane
        // edge normal of that side, and no cross product with an edge
        // leaning more than θ out of that side's plane.
        let pruned = known_plain.is_some() && cone > 0.0;
        let flat_a = pruned && sa.active == 0;
        let flat_b = pruned && sb.active == 0;
        // (e · out)² ≤ sin²θ |e|², with a margin for rounding.
        let sin2_cone = (1.0 - cone * cone).max(0.0) * 1.0002;
        let in_plane = |flat: bool, out: Vec3A, e: &Vec3A| {
            let d = e.dot(out);
            !flat || d * d <= sin2_cone * e.length_squared()
        };
        consider(sa.out, 0);
        consider(-sb.out, 1);
        consider(-sa.out, 0);
        consider(sb.out, 1);
        let ea = [a[1] - a[0], a[2] - a[1], a[0] - a[2]];
        let eb = [b[1] - b[0], b[2] - b[1], b[0] - b[2]];
        let eb_in = eb.map(|y| in_plane(flat_a, sa.out, &y));
        for (k, x) in ea.iter().enumerate() {
            if !in_plane(flat_b, sb.out, x) {
                continue;
            }
            for (l, y) in eb.iter().enumerate() {
                if !eb_in[l] {
                    continue;
                }
                let len2 = x.length_squared() * y.length_squared();
                let c = x.cross(*y);
                if c.length_squared() > 1e-10 * len2 {
                    let n = c.normalize();
                    let axis = 2 + (k * 3 + l) as u8;
                    consider(n, axis);
                    consider(-n, axis);
                }
            }
        }
        if !flat_a && (!flat_b || sb.may_accept_in_plane_of(sa, cone)) {
            for (k, n) in sa.in_plane_normals().iter().enumerate() {
                if let Some(n) = *n {
                    consider(n, 11 + k as u8);
                    consider(-n, 11 + k as u8);
                }
            }
        }
        if !flat_b && (!flat_a || sa.may_accept_in_plane_of(sb, cone)) {
            for (k, n) in sb.in_plane_normals().iter().enumerate() {
                if let Some(n) = *n {
                    consider(n, 14 + k as u8);
                    consider(-n, 14 + k as u8);
                }
            }
        }
    }
    // The plain axis (the direction the pair separates along, or
    // penetrates least) leans over a shared edge past the neighbour's face
    // normal: the other triangle lies beyond the neighbour, whose own pair
    // with it gives the contact (a box whose back has passed a ridge's
    // crease is beside the flat half, not on it; a box reaching a ridge is
    // beside the down half). Jolt's internal-edge removal drops such a
    // contact likewise, whatever its depth.
    if plain_axis.is_some_and(|n| sa.past_bend(n, nb) || sb.past_bend(-n, nb)) {
        return None;
    }
    let (mut o, ka, kb) = best?;
    // The best axis is a neighbour's face normal at a shared edge: that
    // neighbour's pair with the same triangle gives the contact (a box
    // resting on a ridge's flat half meets the down side's crease along
    // the flat half's normal, which the flat half reports itself).
    if (ka == Support::ConeEnd && kb != Support::Face)
        || (kb == Support::ConeEnd && ka != Support::Face)
    {
        return None;
    }
    let longest2 = |t: &Triangle| {
        (t[1] - t[0])
            .length_squared()
            .max((t[2] - t[1]).length_squared())
            .max((t[0] - t[2]).length_squared())
    };
    let lateral = 0.25 * longest2(a).min(longest2(b)).sqrt();
    let limit = plain - slack - lateral;
    // The face normal replaces the accepted axis only where it does not
    // point into the other side's solid: an active edge of B meeting A's
    // inactive corner accepts an axis within the cone of A's normal, but
    // A's normal itself may lean more than the 96° B allows from B's face
    // normal; the accepted axis stays then. (A body rolling on a
    // tessellated ground meets it with faces a few degrees apart, and the
    // ground's normal is taken.)
    let faces_meet = sa.out.dot(-sb.out) >= OUTWARD_MIN;
    if ka != Support::Face && kb != Support::Face && faces_meet {
        if ka == Support::Inactive {
            o = OrientedAxis {
                normal: sa.out,
                sep: separation(a, b, sa.out),
                axis: 0,
            };
        } else if kb == Support::Inactive {
            o = OrientedAxis {
                normal: -sb.out,
                sep: separation(a, b, -sb.out),
                axis: 1,
            };
        }
    }
    // An accepted axis far deeper than the pair's true depth: the features
    // that accept it are not where the triangles meet (a far corner of a
    // large triangle, a facet of a curved body that faces away).
    if o.sep < limit {
        return None;
    }
    // Deeper than the plain depth by more than the lateral allowance: a
    // real contact along `o.normal` only where the triangles lie over each
    // other along it (a triangle behind a one-sided face is pushed out of
    // the front), not where they lie side by side: there the separation
    // along the normal is that of two slabs, and a triangle beside a
    // floor's edge, straddling the floor's plane, would be reported as
    // penetrating it however far beside it lies.
    if o.sep < plain - lateral && side_by_side(a, b, o.normal, lateral) {
        return None;
    }
    Some(o)
}

/// Whether the triangles' shadows on the plane across the unit direction
/// `n` lie more than `tol` apart: some direction across `n`, perpendicular
/// to an edge of either shadow or along one, separates them by more (a
/// lower bound of the shadows' distance, so a pair it passes may still lie
/// apart; a shadow seen edge-on is covered by the directions along edges).
fn side_by_side(a: &Triangle, b: &Triangle, n: Vec3A, tol: f32) -> bool {
    // Along `m` (not unit, from the edge `e`): the gap between the
    // projections, compared with `tol` scaled by |m| (no square root).
    let apart = |m: Vec3A, e: Vec3A| {
        let len2 = m.length_squared();
        if len2 <= 1e-10 * e.length_squared() {
            return false;
        }
        let (pa, pb) = (a.map(|v| m.dot(v)), b.map(|v| m.dot(v)));
        let (min_a, max_a) = (pa[0].min(pa[1]).min(pa[2]), pa[0].max(pa[1]).max(pa[2]));
        let (min_b, max_b) = (pb[0].min(pb[1]).min(pb[2]), pb[0].max(pb[1]).max(pb[2]));
        let gap = (min_b - max_a).max(min_a - max_b);
        gap > 0.0 && gap * gap > tol * tol * len2
    };
    let edges = [
        a[1] - a[0],
        a[2] - a[1],
        a[0] - a[2],
        b[1] - b[0],
        b[2] - b[1],
        b[0] - b[2],
    ];
    edges.iter().any(|&e| apart(n.cross(e), e)) || edges.iter().any(|&e| apart(e - n * n.dot(e), e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::edges::{ALL_ACTIVE, FRONT};

    fn tri(p: [[f32; 3]; 3]) -> Triangle {
        p.map(Vec3A::from)
    }

    fn two_sided_toward(p: [f32; 3]) -> Facing {
        Facing::TwoSided {
            toward: Vec3A::from(p),
        }
    }

    /// A floor triangle (normal up) and a triangle 1 cm below its plane,
    /// facing down: the normal is up, never down into the floor.
    #[test]
    fn a_face_just_below_a_floor_is_pushed_up() {
        let floor = tri([[-2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 0.0]]);
        let t = tri([[0.0, -0.01, 0.0], [0.5, -0.01, 0.0], [0.0, -0.01, 0.5]]);
        let f = PairFacing::new(two_sided_toward([0.0, 0.5, 0.0]), Facing::OneSided(1.0));
        let o = oriented_axis(&floor, 0, &t, ALL_ACTIVE, &f, 0.1).expect("a contact");
        assert!((o.normal - Vec3A::Y).length() < 1e-6, "{:?}", o);
        assert!((o.sep + 0.01).abs() < 1e-6, "{:?}", o);
    }

    /// A cube's side triangle standing on a flat floor triangle whose
    /// corner pokes just under the side face: the floor's internal corner
    /// is inactive, so the normal is the floor's, not the side face's.
    #[test]
    fn an_internal_corner_under_a_side_face_gives_the_floor_normal() {
        // Floor triangle, internal to a tessellated plane: no active edge.
        let floor = tri([[-1.0, 0.0, 0.0], [-1.0, 0.0, 1.0], [0.0005, 0.0, 0.5]]);
        // The side face of a body at x >= 0, facing -x, its bottom edge
        // (active) 1 mm into the floor.
        let side = tri([[0.0, -0.001, 0.0], [0.0, -0.001, 1.0], [0.0, 1.0, 0.0]]);
        let facing = PairFacing::new(two_sided_toward([0.5, 0.5, 0.5]), Facing::OneSided(1.0));
        let raw = (side[1] - side[0]).cross(side[2] - side[0]).normalize();
        assert!(raw.x < 0.0, "the side faces -x");
        // Bottom edge (corner 0 -> 1, edge 0) active from the front.
        let o = oriented_axis(&floor, 0, &side, 0b001, &facing, 0.1).expect("a contact");
        assert!((o.normal - Vec3A::Y).length() < 1e-5, "{:?}", o);
        // With the floor's edges all active (a boundary), the side face's
        // normal separates least and is taken.
        let edge = oriented_axis(&floor, FRONT | 0b111_000, &side, 0b001, &facing, 0.1).unwrap();
        assert!(edge.normal.x.abs() > 0.99, "{:?}", edge);
    }

    /// The search's shortcuts drop only directions the full test rejects:
    /// `may_accept` is false only where `support` gives nothing, and two
    /// sides accept a common direction only when their cones meet.
    #[test]
    fn shortcuts_never_drop_an_accepted_direction() {
        let mut rng = crate::scene::rng::Rng::new(0x853c_49e6_748f_ea9b, 0);
        let mut rnd = move || rng.range(-1.0, 1.0);
        let cone = PairFacing::new(Facing::OneSided(1.0), Facing::OneSided(1.0)).cone_cos;
        let (mut accepted, mut both, mut mixed, mut apart, mut skipped_in_plane) = (0, 0, 0, 0, 0);
        for round in 0..20_000 {
            // Flat triangles some of the time: normals near ±y, so that
            // two cones often meet.
            let squash = if round % 4 == 0 { 0.02 } else { 0.2 };
            let t = |r: &mut dyn FnMut() -> f32| -> Triangle {
                [0, 1, 2].map(|_| Vec3A::new(r(), r() * squash, r()))
            };
            let (a, b) = (t(&mut rnd), t(&mut rnd));
            // Flags: none active a third of the time.
            let flags = |x: f32| {
                if x < -0.3 {
                    0
                } else {
                    (x.to_bits() & 0x3f) as u8
                }
            };
            let (fa, fb) = (flags(rnd()), flags(rnd()));
            let sign = if round % 2 == 0 { 1.0 } else { -1.0 };
            let (Some(sa), Some(sb)) = (
                Side::new(&a, fa, Facing::OneSided(sign), 10.0),
                Side::new(&b, fb, Facing::OneSided(-1.0), 10.0),
            ) else {
                continue;
            };
            // Directions near the outward normals as well as anywhere.
            let mut n = Vec3A::new(rnd(), rnd(), rnd());
            if round % 3 == 0 {
                n = n * 0.1 + sa.out;
            } else if round % 3 == 1 {
                n = n * 0.1 - sb.out;
            }
            let Some(n) = n.try_normalize() else { continue };
            // Every corner counts as near (the box of A, grown by 10).
            let near = &sa;
            for (side, dir) in [(&sa, n), (&sb, -n)] {
                if side.support(dir, cone, near).is_some() {
                    accepted += 1;
                    assert!(side.may_accept(dir, cone), "round {round}: {dir} dropped");
                }
            }
            // A's in-plane edge normals, skipped when B has no active edge
            // and cannot accept any direction in A's plane.
            if sb.active == 0 && !sb.may_accept_in_plane_of(&sa, cone) {
                for x in [a[1] - a[0], a[2] - a[1], a[0] - a[2]] {
                    let Some(m) = sa.raw.cross(x).try_normalize() else {
                        continue;
                    };
                    for m in [m, -m] {
                        assert!(
                            sb.support(-m, cone, near).is_none(),
                            "round {round}: in-plane {m} dropped"
                        );
                        skipped_in_plane += 1;
                    }
                }
            }
            let ka = sa.support(n, cone, near);
            let kb = sb.support(-n, cone, near);
            if ka.is_some() && kb.is_some() {
                assert!(sa.cones_meet(&sb, cone), "round {round}: cones said apart");
                match (sa.active == 0, sb.active == 0) {
                    (true, true) => both += 1,
                    (true, false) | (false, true) => mixed += 1,
                    _ => {}
                }
            }
            if !sa.cones_meet(&sb, cone) {
                apart += 1;
            }
        }
        assert!(
            accepted > 5000
                && both > 100
                && mixed > 1000
                && apart > 1000
                && skipped_in_plane > 1000,
            "{accepted} accepted, {both} both inactive, {mixed} one inactive, \
             {apart} apart, {skipped_in_plane} in-plane skipped"
        );
    }

    /// A sharp side that `may_accept_within_cone_of` says cannot accept any
    /// direction in a flat side's cone rejects every one: the search's own
    /// candidates (faces, edge-edge crosses, in-plane edge normals) and
    /// random directions over the cone up to its rim. The pairs are a small
    /// flat triangle near a larger sharp one, tilted by a few cone angles
    /// and with edges nearly in the flat plane, so that all three
    /// conditions of the test are met often and missed often.
    #[test]
    fn a_sharp_side_kept_out_of_a_flat_cone_accepts_nothing_there() {
        let mut rng = crate::scene::rng::Rng::new(0x9e37_79b9_7f4a_7c15, 3);
        let mut rnd = move || rng.range(-1.0, 1.0);
        let cone = PairFacing::new(Facing::OneSided(1.0), Facing::OneSided(1.0)).cone_cos;
        let theta = cone.acos();
        let (mut fired, mut kept, mut tested, mut below) = (0, 0, 0, 0);
        for round in 0..20_000 {
            // The flat triangle: small, in the plane y = 0, facing +y (the
            // sharp one comes from above), as B or as A.
            let s = 0.05 + 0.3 * rnd().abs();
            let flat_t = [0, 1, 2].map(|_| Vec3A::new(rnd() * s, 0.0, rnd() * s));
            // The sharp one: larger, tilted about a random horizontal axis
            // by up to four cone angles, its plane near the flat one's.
            let size = 0.1 + 2.0 * rnd().abs();
            let tilt = 4.0 * theta * rnd().abs();
            let axis = Vec3A::new(rnd(), 0.0, rnd()).normalize_or(Vec3A::X);
            let rot = glam::Quat::from_axis_angle(axis.into(), tilt);
            let lift = Vec3A::new(rnd() * size, 0.02 * rnd(), rnd() * size);
            let sharp_t = [0, 1, 2].map(|_| {
                let p = Vec3A::new(rnd() * size, 0.01 * rnd(), rnd() * size);
                Vec3A::from(rot * glam::Vec3::from(p)) + lift
            });
            let flags = 1 + (rnd().to_bits() % 63) as u8;
            let flat_first = round % 2 == 0;
            let (a, fa, b, fb) = if flat_first {
                (flat_t, 0, sharp_t, flags)
            } else {
                (sharp_t, flags, flat_t, 0)
            };
            // Each faces the other: the flat one up, the sharp one down.
            let facing = |t: &Triangle, up: bool| {
                let raw = (t[1] - t[0]).cross(t[2] - t[0]);
                let s = if (raw.y > 0.0) == up { 1.0 } else { -1.0 };
                Facing::OneSided(s)
            };
            let slack = 0.02;
            let (Some(sa), Some(sb)) = (
                Side::new(&a, fa, facing(&a, flat_first), slack),
                Side::new(&b, fb, facing(&b, !flat_first), slack),
            ) else {
                continue;
            };
            let (flat, sharp) = if flat_first { (&sa, &sb) } else { (&sb, &sa) };
            if sharp.active == 0 {
                continue;
            }
            if sharp.may_accept_within_cone_of(flat, cone) {
                kept += 1;
                continue;
            }
            fired += 1;
            // Fired although a corner with an active edge lies in the near
            // box: no direction in the cone puts that corner on top.
            let sharp_active = |k: usize| sharp.active & (1 << k) != 0;
            if (0..3).any(|k| {
                (sharp_active(k) || sharp_active((k + 2) % 3))
                    && flat.near().contains_point(sharp.t[k])
            }) {
                below += 1;
            }
            // Directions m the sharp side is asked about (n for A, −n for
            // B), within the flat cone around −flat.out.
            let mut dirs: Vec<Vec3A> = vec![sa.out, -sa.out, sb.out, -sb.out];
            let ea = [a[1] - a[0], a[2] - a[1], a[0] - a[2]];
            let eb = [b[1] - b[0], b[2] - b[1], b[0] - b[2]];
            for x in ea {
                for y in eb {
                    if let Some(c) = x.cross(y).try_normalize() {
                        dirs.extend([c, -c]);
                    }
                }
            }
            for s in [&sa, &sb] {
                for m in s.in_plane_normals().iter().flatten() {
                    dirs.extend([*m, -*m]);
                }
            }
            let centre = -flat.out;
            let u = centre.any_orthonormal_vector();
            let v = centre.cross(u);
            for k in 0..64 {
                let phi = k as f32 * 0.1;
                let alpha = theta * if k % 4 == 0 { 1.0 } else { rnd().abs() };
                dirs.push(
                    (centre * alpha.cos() + (u * phi.cos() + v * phi.sin()) * alpha.sin())
                        .normalize(),
                );
            }
            for m in dirs {
                if m.dot(centre) < cone {
                    continue;
                }
                tested += 1;
                assert!(
                    sharp.support(m, cone, flat).is_none(),
                    "round {round}: the sharp side accepts {m}"
                );
            }
        }
        assert!(
            fired > 2000 && kept > 2000 && tested > 50_000 && below > 500,
            "{fired} pairs without an axis ({below} with a near corner below), \
             {kept} searched, {tested} directions"
        );
    }

    /// Side A kept from the last pair gives every pair the answer a fresh
    /// side gives, also when the same triangle comes back with other
    /// flags, another facing or another slack (which must not reuse it).
    #[test]
    fn a_kept_side_gives_the_same_answers() {
        let mut rng = crate::scene::rng::Rng::new(0x2545_f491_4f6c_dd1d, 7);
        let mut rnd = move || rng.range(-1.0, 1.0);
        let mut cache = SideCache::new();
        let mut a: Triangle = [Vec3A::ZERO; 3];
        let (mut fa, mut differs, mut contacts) = (0u8, 0, 0);
        for round in 0..20_000 {
            // A new A triangle every 16 pairs; in between, its flags change
            // now and then, keeping the triangle.
            if round % 16 == 0 {
                a = [0, 1, 2].map(|_| Vec3A::new(rnd(), rnd() * 0.1, rnd()) * 0.4);
            }
            if round % 5 == 0 {
                fa = (rnd().to_bits() & 0x3f) as u8;
            }
            // Some B triangles far enough that the near box's slack
            // decides whether their corners count as near.
            let shift = Vec3A::new(if round % 2 == 0 { 2.0 * rnd() } else { 0.0 }, 0.0, 0.0);
            let b: Triangle =
                [0, 1, 2].map(|_| Vec3A::new(rnd(), rnd() * 0.3 + 0.05, rnd()) + shift);
            let fb = (rnd().to_bits() & 0x3f) as u8;
            let facing = if round % 3 == 0 {
                PairFacing::new(two_sided_toward([0.0, -1.0, 0.0]), Facing::OneSided(1.0))
            } else {
                PairFacing::new(Facing::OneSided(1.0), Facing::OneSided(-1.0))
            };
            let slack = if round % 7 == 0 { 0.0 } else { 1.5 };
            let kept = oriented_axis_cached(&a, fa, &b, fb, &facing, slack, None, &mut cache);
            let fresh = oriented_axis(&a, fa, &b, fb, &facing, slack);
            assert_eq!(kept, fresh, "round {round}");
            contacts += usize::from(fresh.is_some());
            // The same pair with the other A flags: the cache must not
            // answer with the side it holds.
            let other =
                oriented_axis_cached(&a, fa ^ 0x3f, &b, fb, &facing, slack, None, &mut cache);
            assert_eq!(other, oriented_axis(&a, fa ^ 0x3f, &b, fb, &facing, slack));
            differs += usize::from(other != fresh);
        }
        assert!(
            contacts > 2000 && differs > 200,
            "{contacts} contacts, {differs} differ by flags"
        );
        // The near box follows the slack asked for, not the kept side's.
        let one = Facing::OneSided(1.0);
        let wide = *cache.side(&a, fa, one, 1.0).expect("a side").near();
        let tight = *cache.side(&a, fa, one, 0.0).expect("a side").near();
        assert!(
            (wide.extent() - tight.extent() - Vec3A::splat(2.0))
                .abs()
                .max_element()
                < 1e-5
        );
    }

    /// The plain separating axis of a pair (the kernel's hint): the
    /// direction of largest separation over the face normals, edge–edge
    /// cross products and in-plane edge normals, both ways round.
    fn plain_axis(a: &Triangle, b: &Triangle) -> OrientedAxis {
        let edges = |t: &Triangle| [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
        let normal = |t: &Triangle| (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        let mut dirs = vec![(normal(a), 0), (normal(b), 1)];
        for (k, x) in edges(a).iter().enumerate() {
            for (l, y) in edges(b).iter().enumerate() {
                let c = x.cross(*y);
                if c.length_squared() > 1e-10 * x.length_squared() * y.length_squared() {
                    dirs.push((c.normalize(), 2 + (k * 3 + l) as u8));
                }
            }
            dirs.push((normal(a).cross(*x).normalize(), 11 + k as u8));
        }
        for (l, y) in edges(b).iter().enumerate() {
            dirs.push((normal(b).cross(*y).normalize(), 14 + l as u8));
        }
        dirs.iter()
            .flat_map(|&(n, axis)| [(n, axis), (-n, axis)])
            .map(|(normal, axis)| OrientedAxis {
                normal,
                sep: separation(a, b, normal),
                axis,
            })
            .max_by(|x, y| x.sep.total_cmp(&y.sep))
            .expect("two faces at least")
    }

    /// Given the plain axis as a hint, the answer is the full search's,
    /// also where one side is flat (no active edge) and its face normal is
    /// taken without searching: the same pairs get a contact, at the same
    /// separation, along the same normal (up to rounding ties).
    #[test]
    fn a_flat_sides_face_normal_is_the_searchs_answer() {
        let mut rng = crate::scene::rng::Rng::new(0x9e37_79b9_7f4a_7c15, 3);
        let mut rnd = move || rng.range(-1.0, 1.0);
        let (mut contacts, mut flat_face) = (0, 0);
        for round in 0..20_000 {
            // A large sharp triangle under a small flat one, or the other
            // way round.
            let big: Triangle = [0, 1, 2].map(|_| Vec3A::new(rnd(), rnd() * 0.6, rnd()));
            let lift = Vec3A::new(rnd() * 0.3, rnd() * 0.1, rnd() * 0.3);
            // Any way round a third of the time, so that some faces lean
            // too far apart to meet.
            let tilt = if round % 3 == 0 { 1.0 } else { 0.8 };
            let small: Triangle =
                [0, 1, 2].map(|_| Vec3A::new(rnd(), rnd() * tilt, rnd()) * 0.2 + lift);
            let sharp = (rnd().to_bits() & 0x3f) as u8 | 0b001;
            let (a, fa, b, fb) = if round % 2 == 0 {
                (big, sharp, small, 0)
            } else {
                (small, 0, big, sharp)
            };
            // Each side faces the other's centre.
            let centre = |t: &Triangle| (t[0] + t[1] + t[2]) * (1.0 / 3.0);
            let facing = PairFacing::new(
                Facing::TwoSided { toward: centre(&b) },
                Facing::TwoSided { toward: centre(&a) },
            );
            let slack = 0.1;
            let full = oriented_axis(&a, fa, &b, fb, &facing, slack);
            let hinted =
                oriented_axis_from(&a, fa, &b, fb, &facing, slack, Some(plain_axis(&a, &b)));
            match (full, hinted) {
                (None, None) => {}
                (Some(f), Some(h)) => {
                    contacts += 1;
                    assert!(
                        (f.sep - h.sep).abs() < 1e-4,
                        "round {round}: {f:?} vs {h:?}"
                    );
                    assert!(
                        (f.normal - h.normal).length() < 1e-3,
                        "round {round}: {f:?} vs {h:?}"
                    );
                    // Where the flat side's face normal could be taken
                    // without a search: faces meeting, cones apart.
                    let (sa, sb) = (
                        Side::new(&a, fa, facing.a, slack).unwrap(),
                        Side::new(&b, fb, facing.b, slack).unwrap(),
                    );
                    let flat_out = if fb == 0 { -sb.out } else { sa.out };
                    let c = sa.out.dot(-sb.out);
                    let apart = c >= OUTWARD_MIN && c < 2.0 * facing.cone_cos.powi(2) - 1.0;
                    flat_face += usize::from(apart && h.normal == flat_out);
                }
                (f, h) => panic!("round {round}: full search {f:?}, hinted {h:?}"),
            }
        }
        assert!(
            contacts > 1500 && flat_face > 1000,
            "{contacts} contacts, {flat_face} on the flat face"
        );
    }

    /// A small upright triangle beside a floor triangle's edge, straddling
    /// the floor's plane, is no penetration of the floor however large the
    /// prediction: along the floor's normal the two lie side by side.
    #[test]
    fn a_triangle_beside_a_floor_is_not_in_it() {
        // Floor facing down (its winding's normal is -y).
        let floor = tri([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]);
        let f = PairFacing::new(Facing::OneSided(1.0), two_sided_toward([0.5, -1.0, 0.0]));
        let mut checked = 0;
        for gap in [0.0, 0.001, 0.003, 0.01, 0.03, 0.1] {
            for dy in [-0.004, -0.001, 0.0005, 0.002] {
                // 5 mm tall, 5 mm wide, in the plane z = 0, `gap` beyond
                // the floor's corner at x = 1.
                let x = 1.0 + gap;
                let b = tri([[x, dy, 0.0], [x + 0.005, dy, 0.0], [x, dy + 0.005, 0.0]]);
                for slack in [0.001, 0.05, 0.3, 1.5] {
                    let plain = plain_axis(&floor, &b).sep;
                    let o = oriented_axis(&floor, 0, &b, ALL_ACTIVE, &f, slack);
                    if let Some(o) = o {
                        checked += 1;
                        // Beside the floor by more than a quarter of the
                        // small triangle's edge: never deeper than the
                        // true depth by more than that quarter.
                        assert!(
                            gap <= 0.25 * 0.005 || o.sep >= plain - 0.25 * 0.005 - 1e-6,
                            "gap {gap}, dy {dy}, slack {slack}: {o:?}, plain {plain}"
                        );
                    }
                }
            }
        }
        // The triangle through the floor's corner touches it.
        assert!(checked >= 4, "{checked} contacts");
    }

    /// A triangle wholly behind a one-sided face, deeper than it is wide,
    /// with both triangles inactive everywhere: still pushed out the front.
    #[test]
    fn normals_never_point_into_a_one_sided_face() {
        let a = tri([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
        let b = tri([[0.2, -0.05, 0.2], [0.4, -0.05, 0.2], [0.2, -0.05, 0.4]]);
        let f = PairFacing::new(Facing::OneSided(1.0), Facing::OneSided(1.0));
        let o = oriented_axis(&a, 0, &b, 0, &f, 0.1).expect("a contact");
        assert!(o.normal.dot(Vec3A::Y) > 0.999, "{:?}", o);
        // Facing the other way, the same pair gives nothing pointing up.
        let g = PairFacing::new(Facing::OneSided(-1.0), Facing::OneSided(1.0));
        if let Some(o) = oriented_axis(&a, 0, &b, 0, &g, 0.1) {
            assert!(o.normal.dot(Vec3A::Y) < -0.999, "{:?}", o);
        }
    }
}
