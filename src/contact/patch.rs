//! Patch reduction: the contacts of many triangle pairs grouped into a few
//! contact patches, each reduced to at most four points.
//!
//! A pair contact joins the first patch whose normal is within
//! [`PatchOptions::max_angle_deg`] of its own and whose points come within
//! the patch gap of its witness point; otherwise it starts a patch. The
//! patch keeps, streaming and without storing points:
//!
//! - its seed normal (the first pair's), so every member's normal is within
//!   the angle of the patch normal;
//! - the deepest point (smallest signed distance) and the representative
//!   triangle pair it came from;
//! - the extreme points along eight directions of the contact plane (an
//!   octagon around the support area) and the bounds of all points.
//!
//! [`Patch::reduced`] then picks at most four of those candidates as Jolt
//! and PhysX do: the deepest point, the point farthest from it, and the two
//! points spanning the largest triangle areas on either side of that
//! segment. The last pair consulted is tried first, since a traversal meets
//! neighbouring pairs one after another: finding a patch is O(1) in the
//! usual case.
//!
//! Sets built separately (one per traversal task, in a fixed task order)
//! are merged with [`PatchSet::merge`]; the result depends on the order of
//! the tasks, never on the number of threads.

use glam::Vec3A;

use super::kernel::{ContactSink, PairContact};
use crate::geom::{Aabb, Triangle};
use crate::hash::FastMap;

/// A cell of the normal index: the normal's coordinates divided by the
/// cell size and rounded.
type NormalKey = (i32, i32, i32);

/// How contacts are grouped into patches.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct PatchOptions {
    /// Largest angle between a pair's normal and its patch's, in degrees.
    pub max_angle_deg: f32,
    /// Largest gap between a pair's witness point and the points already in
    /// a patch for the pair to join it, as a fraction of the smaller shape's
    /// bounding-box diagonal.
    pub gap_fraction: f32,
    /// Bound the prediction distance by the pair's motion: when a pair was
    /// also queried at the previous step, only triangle pairs within this
    /// factor times the largest distance the nearby points of shape 2
    /// moved relative to shape 1 since then (and at least a tenth of the
    /// prediction) are considered, never more than the prediction. For two
    /// cbvh shapes "nearby" is the box of shape 2's node in each node pair
    /// of the two-tree traversal ([`MotionBound`](super::MotionBound)), so
    /// a statue rocking on its base pays for the slow region at the
    /// contact, not for its swinging head; against other shapes it is the
    /// part of shape 2 that can touch shape 1. A resting body then skips
    /// the pairs that are merely within the speculative margin. `None`
    /// always uses the full prediction.
    pub motion_factor: Option<f32>,
}

impl Default for PatchOptions {
    fn default() -> Self {
        Self {
            max_angle_deg: 5.0,
            gap_fraction: 0.1,
            motion_factor: Some(2.0),
        }
    }
}

/// A contact point with the triangle pair and point it came from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PatchPoint {
    /// The point on shape 1, in shape 1's frame.
    pub p1: Vec3A,
    /// The point on shape 2, in shape 1's frame.
    pub p2: Vec3A,
    /// Signed distance along the patch normal's pair normal (negative:
    /// penetration).
    pub dist: f32,
    /// Triangle of shape 1.
    pub i: u32,
    /// Triangle of shape 2.
    pub j: u32,
    /// Which point of the pair (see [`PairPoint::feature`](super::kernel::PairPoint::feature)).
    pub feature: u8,
}

const DIRS: usize = 8;

/// Two patches whose normals are within this angle of opposite, with
/// meeting bounds, push one region both ways ([`PatchSet::drop_opposed`]).
pub const OPPOSED_DEG: f32 = 25.0;

/// Up to this many patches, a contact's patch is found by scanning them all
/// rather than through the normal-cell index: a traversal task usually
/// holds a few dozen patches, and hashing 27 cells costs more than scanning
/// them (2 M statue, narrow-phase median of two runs each: scan only 2.41
/// and 2.50 ms, index only 3.12 and 2.38 ms, both 2.62 and 2.35 ms; noisy).
const LINEAR_SCAN_PATCHES: usize = 64;

/// One contact patch. See the module docs.
#[derive(Clone, Debug)]
pub struct Patch {
    /// Unit normal from shape 1 to shape 2, in shape 1's frame.
    pub normal: Vec3A,
    basis: [Vec3A; 2],
    /// Bounds of the patch's points on shape 1.
    pub bounds: Aabb,
    /// The deepest point.
    pub deepest: PatchPoint,
    extremes: [(f32, PatchPoint); DIRS],
    /// The smallest cosine between a member pair's normal and the patch
    /// normal (the cone the members' normals lie in).
    pub min_cos: f32,
    /// Triangle pairs in the patch.
    pub pairs: u32,
    /// Contact points offered to the patch.
    pub points: u32,
    /// The member pairs, when the set records them.
    pub members: Vec<(u32, u32)>,
}

fn basis(n: Vec3A) -> [Vec3A; 2] {
    let t = if n.x.abs() > 0.57 {
        Vec3A::new(n.y, -n.x, 0.0)
    } else {
        Vec3A::new(0.0, n.z, -n.y)
    }
    .normalize_or(Vec3A::X);
    [t, n.cross(t)]
}

fn directions(b: &[Vec3A; 2]) -> [Vec3A; DIRS] {
    std::array::from_fn(|k| {
        let a = k as f32 * std::f32::consts::FRAC_PI_4;
        b[0] * a.cos() + b[1] * a.sin()
    })
}

impl Patch {
    fn new(normal: Vec3A, first: PatchPoint) -> Self {
        let basis = basis(normal);
        let dirs = directions(&basis);
        Self {
            normal,
            basis,
            bounds: Aabb::new(first.p1, first.p1),
            deepest: first,
            extremes: std::array::from_fn(|k| (dirs[k].dot(first.p1), first)),
            min_cos: 1.0,
            pairs: 0,
            points: 0,
            members: Vec::new(),
        }
    }

    /// The point's coordinates along the eight directions of the octagon.
    #[inline]
    fn projections(&self, p: Vec3A) -> [f32; DIRS] {
        let b = &self.basis;
        let (u, v) = (b[0].dot(p), b[1].dot(p));
        const H: f32 = std::f32::consts::FRAC_1_SQRT_2;
        [
            u,
            H * (u + v),
            v,
            H * (v - u),
            -u,
            -H * (u + v),
            -v,
            H * (u - v),
        ]
    }

    #[inline]
    fn offer(&mut self, p: PatchPoint) {
        self.points += 1;
        if p.dist < self.deepest.dist {
            self.deepest = p;
        }
        self.bounds.grow(p.p1);
        let proj = self.projections(p.p1);
        for (e, s) in self.extremes.iter_mut().zip(proj) {
            if s > e.0 {
                *e = (s, p);
            }
        }
    }

    /// The candidates the reduction chooses from: the deepest point and the
    /// extremes.
    pub fn candidates(&self) -> impl Iterator<Item = PatchPoint> + '_ {
        std::iter::once(self.deepest).chain(self.extremes.iter().map(|e| e.1))
    }

    /// At most four points that keep the patch's support area: the deepest,
    /// the farthest from it, and the two spanning the largest areas on each
    /// side of that segment. Deterministic.
    pub fn reduced(&self) -> ([PatchPoint; 4], usize) {
        let mut out = [self.deepest; 4];
        let mut n = 1;
        let a = self.deepest.p1;
        let far = self
            .candidates()
            .max_by(|x, y| {
                (x.p1 - a)
                    .length_squared()
                    .total_cmp(&(y.p1 - a).length_squared())
            })
            .expect("candidates are never empty");
        let span = (far.p1 - a).length_squared();
        let tiny = 1e-12 * (1.0 + a.length_squared());
        if span <= tiny {
            return (out, n);
        }
        out[n] = far;
        n += 1;
        let tangent = (far.p1 - a).cross(self.normal);
        let side = |p: &PatchPoint| tangent.dot(p.p1 - a);
        let plus = self
            .candidates()
            .max_by(|x, y| side(x).total_cmp(&side(y)))
            .expect("non-empty");
        let minus = self
            .candidates()
            .min_by(|x, y| side(x).total_cmp(&side(y)))
            .expect("non-empty");
        let eps = tiny.sqrt() * tangent.length();
        if side(&plus) > eps {
            out[n] = plus;
            n += 1;
        }
        if side(&minus) < -eps {
            out[n] = minus;
            n += 1;
        }
        (out, n)
    }
}

/// A patch set is a kernel sink that takes a pair without its points when
/// they could not change the patch the pair joins: triangle A (which holds
/// every point on shape 1) lies inside the patch's bounds and octagon, and
/// the pair is no deeper than the patch's deepest point, each by a margin
/// above rounding. The pair then counts as a member (and one point) of that
/// patch, found by triangle A's centroid instead of the witness point. At
/// the contact of two fine meshes most pairs are interior to their patch,
/// and their witness and clipped points are never computed.
impl ContactSink for PatchSet {
    fn absorb(&mut self, i: u32, j: u32, normal: Vec3A, sep: f32, a: &Triangle) -> bool {
        let centroid = (a[0] + a[1] + a[2]) * (1.0 / 3.0);
        let Some(k) = self.find(normal, centroid) else {
            return false;
        };
        let margin = self.margin;
        let p = &self.patches[k];
        if sep < p.deepest.dist + margin {
            return false;
        }
        let inner = Aabb::new(p.bounds.min + margin, p.bounds.max - margin);
        for v in a {
            if !inner.contains_point(*v) {
                return false;
            }
            let proj = p.projections(*v);
            if p.extremes.iter().zip(proj).any(|(e, s)| s > e.0 - margin) {
                return false;
            }
        }
        self.last = k;
        let record = self.record;
        let p = &mut self.patches[k];
        p.pairs += 1;
        p.points += 1;
        p.min_cos = p.min_cos.min(p.normal.dot(normal));
        if record {
            p.members.push((i, j));
        }
        true
    }

    fn contact(&mut self, c: &PairContact) {
        self.add(c);
    }
}

/// The patches of one body pair (or of one traversal task). See the module
/// docs.
#[derive(Clone, Debug)]
pub struct PatchSet {
    cos_angle: f32,
    max_angle: f32,
    gap: f32,
    /// Rounding margin of [`ContactSink::absorb`]'s tests (a length).
    margin: f32,
    record: bool,
    last: usize,
    /// Cell size of the normal index: the chord of the patch angle, so that
    /// normals within the angle fall in neighbouring cells.
    cell: f32,
    /// Patch indices by the cell of their normal, in creation order.
    index: FastMap<NormalKey, Vec<u32>>,
    /// The patches, in order of creation.
    pub patches: Vec<Patch>,
    /// The patches [`drop_opposed`](Self::drop_opposed) dropped, when the
    /// set records its members (tests and analysis).
    pub dropped: Vec<Patch>,
}

impl PatchSet {
    /// An empty set; `size` is the smaller shape's bounding-box diagonal
    /// (the gap is `options.gap_fraction × size`); with `record` every
    /// patch lists its member pairs (tests and analysis).
    pub fn new(options: &PatchOptions, size: f32, record: bool) -> Self {
        Self {
            cos_angle: options.max_angle_deg.to_radians().cos(),
            max_angle: options.max_angle_deg.to_radians(),
            gap: (options.gap_fraction * size).max(0.0),
            margin: 1e-5 * size.max(0.0),
            record,
            last: 0,
            cell: (2.0 * (options.max_angle_deg.to_radians() * 0.5).sin()).max(1e-3),
            index: FastMap::default(),
            patches: Vec::new(),
            dropped: Vec::new(),
        }
    }

    fn key(&self, n: Vec3A) -> NormalKey {
        let q = n / self.cell;
        (q.x.round() as i32, q.y.round() as i32, q.z.round() as i32)
    }

    /// The first patch (in creation order) that accepts a contact with
    /// `normal` at `at`: the last one used, else the candidates of the 27
    /// normal cells around the normal's (every normal within the angle lies
    /// in one of them), so finding a patch does not grow with the number of
    /// patches.
    fn find(&self, normal: Vec3A, at: Vec3A) -> Option<usize> {
        if self.last < self.patches.len() && self.accepts(self.last, normal, at) {
            // The last patch may not be the first accepting one; the result
            // still depends only on the order of the contacts.
            return Some(self.last);
        }
        // A few patches are scanned faster than 27 cells are hashed; both
        // give the first accepting patch in creation order.
        if self.patches.len() <= LINEAR_SCAN_PATCHES {
            return (0..self.patches.len()).find(|&k| self.accepts(k, normal, at));
        }
        self.first_near(normal, |p| {
            p.normal.dot(normal) >= self.cos_angle && p.bounds.loosened(self.gap).contains_point(at)
        })
    }

    /// The first patch (in creation order) with a normal in the 27 cells
    /// around `normal`'s that satisfies `pred`.
    fn first_near(&self, normal: Vec3A, pred: impl Fn(&Patch) -> bool) -> Option<usize> {
        let (x, y, z) = self.key(normal);
        let mut best: Option<usize> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = self.index.get(&(x + dx, y + dy, z + dz)) else {
                        continue;
                    };
                    for &k in list {
                        let k = k as usize;
                        if best.is_some_and(|b| b < k) {
                            break;
                        }
                        if pred(&self.patches[k]) {
                            best = Some(k);
                            break;
                        }
                    }
                }
            }
        }
        best
    }

    /// The patch a contact with `normal` whose first point is `first`
    /// joins, created if none accepts it; it becomes the last one used.
    fn patch_for(&mut self, normal: Vec3A, first: PatchPoint) -> &mut Patch {
        let k = match self.find(normal, first.p1) {
            Some(k) => k,
            None => self.create(normal, first),
        };
        self.last = k;
        &mut self.patches[k]
    }

    fn create(&mut self, normal: Vec3A, first: PatchPoint) -> usize {
        self.register(Patch::new(normal, first))
    }

    /// Appends `patch` and indexes it by its normal.
    fn register(&mut self, patch: Patch) -> usize {
        let k = self.patches.len();
        let key = self.key(patch.normal);
        self.index.entry(key).or_default().push(k as u32);
        self.patches.push(patch);
        k
    }

    /// Empties the set, keeping its allocation.
    pub fn clear(&mut self) {
        self.patches.clear();
        self.dropped.clear();
        self.index.clear();
        self.last = 0;
    }

    fn accepts(&self, k: usize, normal: Vec3A, at: Vec3A) -> bool {
        let p = &self.patches[k];
        p.normal.dot(normal) >= self.cos_angle && p.bounds.loosened(self.gap).contains_point(at)
    }

    /// Adds one pair contact (its points and its pair) to the patch it
    /// belongs to.
    pub fn add(&mut self, c: &PairContact) {
        let pts = c.points();
        let Some(w) = pts.first() else {
            return;
        };
        let point = |p: &super::kernel::PairPoint| PatchPoint {
            p1: p.p1,
            p2: p.p2,
            dist: p.dist,
            i: c.i,
            j: c.j,
            feature: p.feature,
        };
        let record = self.record;
        let patch = self.patch_for(c.normal, point(w));
        patch.pairs += 1;
        patch.min_cos = patch.min_cos.min(patch.normal.dot(c.normal));
        if record {
            patch.members.push((c.i, c.j));
        }
        for p in pts {
            patch.offer(point(p));
        }
    }

    /// Adds a contact point that did not come from the triangle kernel (a
    /// convex shape against a triangle), with its pair's normal.
    pub fn add_point(&mut self, normal: Vec3A, p: PatchPoint, new_pair: bool) {
        let record = self.record;
        let patch = self.patch_for(normal, p);
        if new_pair {
            patch.pairs += 1;
            patch.min_cos = patch.min_cos.min(patch.normal.dot(normal));
            if record {
                patch.members.push((p.i, p.j));
            }
        }
        patch.offer(p);
    }

    /// Merges another set's patches into this one, in order. A patch joins
    /// one of this set's only if all its members' normals stay within the
    /// angle of the joined patch's normal (the angle between the two
    /// normals plus the joining patch's own cone).
    pub fn merge(&mut self, other: PatchSet) {
        for p in other.patches {
            // The joined normal `q` must satisfy angle(q, p) + cone <=
            // max_angle, i.e. q·p >= cos(max_angle - cone): one cosine per
            // merged patch instead of an arc cosine per candidate.
            let cone = p.min_cos.clamp(-1.0, 1.0).acos();
            let slack = self.max_angle - cone;
            let k = if slack < 0.0 {
                None
            } else {
                let min_dot = slack.cos().max(self.cos_angle);
                let fits = |q: &Patch| {
                    q.normal.dot(p.normal) >= min_dot
                        && q.bounds.loosened(self.gap).intersects(&p.bounds)
                };
                // As in `find`: a few patches are scanned faster than 27
                // cells are hashed; both give the first fitting patch.
                if self.patches.len() <= LINEAR_SCAN_PATCHES {
                    self.patches.iter().position(fits)
                } else {
                    self.first_near(p.normal, fits)
                }
            };
            match k {
                Some(k) => {
                    let q = &mut self.patches[k];
                    let before = q.points;
                    for c in p.candidates() {
                        q.offer(c);
                    }
                    q.points = before + p.points;
                    q.bounds = q.bounds.union(&p.bounds);
                    q.pairs += p.pairs;
                    // cos(angle(q, p) + cone), by the sum formula.
                    let d = q.normal.dot(p.normal).clamp(-1.0, 1.0);
                    let joined = d * p.min_cos
                        - (1.0 - d * d).max(0.0).sqrt()
                            * (1.0 - p.min_cos * p.min_cos).max(0.0).sqrt();
                    q.min_cos = q.min_cos.min(joined);
                    q.members.extend(p.members);
                }
                None => {
                    self.register(p);
                }
            }
        }
        self.last = 0;
    }

    /// One direction per contact region: of two patches whose normals are
    /// within [`OPPOSED_DEG`] of opposite and whose points' bounds meet,
    /// one is dropped by [`opposed_losers`] (the rule and its reasons are
    /// there). Returns how many patches were dropped.
    pub fn drop_opposed(&mut self, toward: Vec3A) -> usize {
        if self.patches.len() < 2 {
            return 0;
        }
        let regions: Vec<Region> = self
            .patches
            .iter()
            .enumerate()
            .map(|(k, p)| Region {
                normal: p.normal,
                bounds: p.bounds,
                key: k as u64,
            })
            .collect();
        let dropped = opposed_losers(&regions, toward);
        let count = dropped.iter().filter(|d| **d).count();
        if count > 0 {
            if self.record {
                self.dropped.extend(
                    (0..dropped.len())
                        .filter(|&k| dropped[k])
                        .map(|k| self.patches[k].clone()),
                );
            }
            let mut k = 0;
            self.patches.retain(|_| {
                k += 1;
                !dropped[k - 1]
            });
            self.index.clear();
            for (k, p) in self.patches.iter().enumerate() {
                let key = self.key(p.normal);
                self.index.entry(key).or_default().push(k as u32);
            }
            self.last = 0;
        }
        count
    }

    /// Triangle pairs in all patches.
    pub fn pair_count(&self) -> usize {
        self.patches.iter().map(|p| p.pairs as usize).sum()
    }
}

/// One contact region as [`opposed_losers`] sees it.
#[derive(Clone, Copy, Debug)]
pub struct Region {
    /// Unit normal from shape 1 to shape 2, in shape 1's frame.
    pub normal: Vec3A,
    /// Bounds of the region's points on shape 1.
    pub bounds: Aabb,
    /// Orders regions of equal standing: of two that lean equally, the
    /// smaller key stays. Distinct keys make the answer independent of the
    /// order the regions come in.
    pub key: u64,
}

/// Which regions to drop so that no contact region is pushed both ways:
/// of two regions whose normals are within [`OPPOSED_DEG`] of opposite and
/// whose bounds meet (as two features of a deeply overlapping pair, or two
/// triangles sharing an edge, can give), the one whose normal leans less
/// along `toward` (from shape 1's centre toward shape 2's, in shape 1's
/// frame: the direction that separates the bodies) is dropped. Regions on
/// the two sides of a thin plate, or on two walls, have disjoint bounds
/// and both stay (so does a triangle of one shape straddling a thin part
/// of the other, pushed from both of its sides). Bounds meet when they do
/// grown by 10⁻⁵ of their size and distance from the origin (a corner two
/// pairs report a few float steps apart). The pairs of meeting bounds are
/// found by sweeping the regions along x, in the order of their lower x
/// bound and key. The patch mode applies it to patches
/// ([`PatchSet::drop_opposed`]), the per-pair mode to its manifolds.
pub fn opposed_losers(regions: &[Region], toward: Vec3A) -> Vec<bool> {
    let n = regions.len();
    let mut dropped = vec![false; n];
    if n < 2 {
        return dropped;
    }
    let opposed_cos = OPPOSED_DEG.to_radians().cos();
    // Bounds grown by a few float steps of their coordinates: one corner
    // reported by the pairs of two triangles around it comes out a few
    // ulps apart, and such bounds meet.
    let bounds: Vec<Aabb> = regions
        .iter()
        .map(|r| {
            let b = r.bounds;
            let scale = b.min.abs().max(b.max.abs()).max_element() + b.extent().length();
            b.loosened(1e-5 * scale)
        })
        .collect();
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|&a, &b| {
        let (ka, kb) = (regions[a as usize].key, regions[b as usize].key);
        let (a, b) = (&bounds[a as usize], &bounds[b as usize]);
        a.min.x.total_cmp(&b.min.x).then(ka.cmp(&kb))
    });
    let opposed = |p: &Region, q: &Region| -p.normal.dot(q.normal) >= opposed_cos;
    // The one leaning less toward shape 2 goes (ties: the larger key).
    let loser = |i: usize, j: usize| {
        let (p, q) = (&regions[i], &regions[j]);
        let (lp, lq) = (p.normal.dot(toward), q.normal.dot(toward));
        if lq > lp || (lq == lp && q.key < p.key) {
            i
        } else {
            j
        }
    };
    for (k, &i) in order.iter().enumerate() {
        let i = i as usize;
        for &j in &order[k + 1..] {
            let j = j as usize;
            if bounds[j].min.x > bounds[i].max.x {
                break;
            }
            if dropped[i] || dropped[j] {
                continue;
            }
            if !opposed(&regions[i], &regions[j]) || !bounds[i].intersects(&bounds[j]) {
                continue;
            }
            dropped[loser(i, j)] = true;
        }
    }
    dropped
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(p: [f32; 3], i: u32) -> PatchPoint {
        PatchPoint {
            p1: Vec3A::from(p),
            p2: Vec3A::from(p),
            dist: -0.01,
            i,
            j: i,
            feature: 0,
        }
    }

    /// Two patches pushing one region both ways keep the one along the
    /// bodies' separation; opposed patches in separate places (two walls,
    /// the two faces of a plate) both stay; small and indexed sets agree.
    #[test]
    fn opposed_patches_in_one_region_keep_one_direction() {
        for filler in [0, 100] {
            let mut set = PatchSet::new(&PatchOptions::default(), 1.0, false);
            // Patches elsewhere, with other normals, to force the index.
            for k in 0..filler {
                let a = k as f32 * 0.06;
                let n = Vec3A::new(a.cos(), 0.0, a.sin());
                set.add_point(n, point([10.0 + k as f32, 5.0, 0.0], 1000 + k), true);
            }
            let before = set.patches.len();
            // One region, pushed up and down.
            set.add_point(Vec3A::Y, point([0.0, 0.0, 0.0], 1), true);
            set.add_point(Vec3A::Y, point([0.05, 0.0, 0.05], 2), true);
            set.add_point(Vec3A::NEG_Y, point([0.02, 0.0, 0.02], 3), true);
            // A plate's two faces 1 cm apart, and two walls 3 apart.
            set.add_point(Vec3A::Y, point([5.0, 0.01, 0.0], 4), true);
            set.add_point(Vec3A::NEG_Y, point([5.0, 0.0, 0.0], 5), true);
            set.add_point(Vec3A::X, point([-3.0, 1.0, 0.0], 6), true);
            set.add_point(Vec3A::NEG_X, point([0.0, 1.0, 0.0], 7), true);
            assert_eq!(set.patches.len(), before + 6);
            assert_eq!(set.drop_opposed(Vec3A::Y), 1, "filler {filler}");
            let kept: Vec<Vec3A> = set.patches[before..].iter().map(|p| p.normal).collect();
            assert_eq!(
                kept,
                vec![Vec3A::Y, Vec3A::Y, Vec3A::NEG_Y, Vec3A::X, Vec3A::NEG_X],
                "filler {filler}"
            );
            // The index still finds the patches that stayed.
            set.add_point(Vec3A::Y, point([0.03, 0.0, 0.04], 8), true);
            assert_eq!(set.patches.len(), before + 5, "filler {filler}");
            // Toward -y the region keeps its downward patch instead.
            let mut set = PatchSet::new(&PatchOptions::default(), 1.0, false);
            set.add_point(Vec3A::Y, point([0.0, 0.0, 0.0], 1), true);
            set.add_point(Vec3A::NEG_Y, point([0.0, 0.0, 0.0], 3), true);
            assert_eq!(set.drop_opposed(Vec3A::NEG_Y), 1);
            assert_eq!(set.patches[0].normal, Vec3A::NEG_Y);
        }
    }
}
