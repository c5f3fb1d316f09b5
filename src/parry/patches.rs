//! Contact patches as parry manifolds: the [`ContactMode`] of the
//! dispatcher, and the conversion of a [`PatchSet`] into one parry
//! `ContactManifold` per patch, matched to last step's manifolds so that
//! rapier warm-starts.
//!
//! Patches are computed in the frame of one side, "A" (the cbvh shape, or
//! the first of two cbvh shapes); [`emit`] maps them to parry's order
//! (shape 1, shape 2) whichever side A is.
//!
//! # Step-to-step matching
//!
//! Each new patch takes the unused manifold of last step whose normal is
//! closest to its own (within the patch angle); it keeps that manifold's
//! data and transfers each point's solver data (impulses) from the old point
//! with the same feature ids. A point's ids are its triangle pair and which
//! point of the pair it is (`fid1` = face(triangle of shape 1), `fid2` =
//! vertex(triangle of shape 2 × 8 + point)), so a point that persists keeps
//! its warm-start impulse.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3A;
use parry3d::math::{Pose as PPose, Vector};
use parry3d::query::{
    ContactManifold, ContactManifoldsWorkspace, TrackedContact, TypedWorkspaceData, WorkspaceData,
};
use parry3d::shape::PackedFeatureId;

use crate::contact::{MotionBound, PatchOptions, PatchPoint, PatchSet, Region, opposed_losers};
use crate::geom::Aabb;

/// How the dispatcher turns triangle pairs into contact manifolds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ContactMode {
    /// cbvh's own triangle-pair kernel, reduced into contact patches: one
    /// manifold of at most four points per patch (the default).
    Patches(PatchOptions),
    /// One manifold per triangle pair through parry's convex-convex code:
    /// parry's exact contacts, for parity tests and users who want them.
    PerTrianglePair,
}

impl Default for ContactMode {
    fn default() -> Self {
        ContactMode::Patches(PatchOptions::default())
    }
}

impl ContactMode {
    /// The name used on command lines and in reports: `patches` or `pairs`.
    pub fn name(&self) -> &'static str {
        match self {
            ContactMode::Patches(_) => "patches",
            ContactMode::PerTrianglePair => "pairs",
        }
    }
}

/// Work counters a dispatcher adds to (shared by its clones), for reports:
/// read and reset them around a step.
#[derive(Debug, Default)]
pub struct ContactCounters {
    /// Triangle pairs whose boxes came within the prediction distance.
    pub candidate_pairs: AtomicU64,
    /// Triangle pairs within the prediction distance (contacts).
    pub contact_pairs: AtomicU64,
    /// Patches (manifolds) produced in patch mode.
    pub patches: AtomicU64,
}

impl ContactCounters {
    /// A new shared set of counters.
    pub fn shared() -> Arc<Self> {
        Arc::new(Self::default())
    }

    /// The three counters, reset to zero.
    pub fn take(&self) -> [u64; 3] {
        [
            self.candidate_pairs.swap(0, Ordering::Relaxed),
            self.contact_pairs.swap(0, Ordering::Relaxed),
            self.patches.swap(0, Ordering::Relaxed),
        ]
    }

    pub(crate) fn add(&self, candidates: u64, contacts: u64, patches: u64) {
        self.candidate_pairs
            .fetch_add(candidates, Ordering::Relaxed);
        self.contact_pairs.fetch_add(contacts, Ordering::Relaxed);
        self.patches.fetch_add(patches, Ordering::Relaxed);
    }
}

/// The workspace of a pair in patch mode. It holds nothing between steps
/// (the manifolds themselves carry what matching needs), but its presence
/// matters: rapier treats a pair with a workspace as composite, whose
/// manifold ordinals change from step to step, and rebuilds its solver
/// graph entries instead of trusting them (without it, rapier 0.36 panics
/// with "stale ContactRef manifold ordinal" when the patch count shrinks).
///
/// It also keeps the pair's last pose, for [`PatchOptions::motion_factor`].
#[derive(Clone, Copy, Debug, Default)]
pub struct PatchWorkspace {
    last_pos12: Option<PPose>,
}

impl WorkspaceData for PatchWorkspace {
    fn as_typed_workspace_data(&self) -> TypedWorkspaceData<'_> {
        TypedWorkspaceData::Custom
    }

    fn clone_dyn(&self) -> Box<dyn WorkspaceData> {
        Box::new(*self)
    }
}

/// Sets `workspace` to a [`PatchWorkspace`] (see there why it must exist)
/// and returns the prediction distance to use at `pos12`: `prediction`,
/// or less when the options bound it by the pair's motion since the last
/// step (`local_box1`, `local_box2`: each shape's box in its own frame).
///
/// The motion that matters is that of the points of shape 2 that can be in
/// contact: those inside shape 1's box (placed in shape 2's frame) grown by
/// the prediction. A statue tipping over an edge turns about the contact,
/// so its head moves far more than the region at the edge; bounding by the
/// whole box would take the head's move. The returned [`MotionBound`]'s
/// `prediction` is that pair-wide distance; a traversal can bound it
/// further region by region (see [`crate::contact::motion`]).
pub fn patch_workspace(
    workspace: &mut Option<ContactManifoldsWorkspace>,
    pos12: &PPose,
    local_box1: &crate::geom::Aabb,
    local_box2: &crate::geom::Aabb,
    prediction: f32,
    opts: &PatchOptions,
) -> MotionBound {
    let ok = workspace
        .as_ref()
        .is_some_and(|w| w.0.downcast_ref::<PatchWorkspace>().is_some());
    if !ok {
        *workspace = Some(ContactManifoldsWorkspace(Box::new(
            PatchWorkspace::default(),
        )));
    }
    let ws: &mut PatchWorkspace = workspace
        .as_mut()
        .and_then(|w| w.0.downcast_mut())
        .expect("workspace was just set to a PatchWorkspace");
    let last = ws.last_pos12.replace(*pos12);
    match (opts.motion_factor, last) {
        (Some(k), Some(last)) if !local_box2.is_empty() => {
            let floor = 0.1 * prediction;
            let box1_in_2 = local_box1
                .transformed(&super::pose_from_parry(&pos12.inverse()))
                .loosened(prediction);
            let region = crate::geom::Aabb::new(
                box1_in_2.min.max(local_box2.min),
                box1_in_2.max.min(local_box2.max),
            );
            if region.is_empty() {
                // Nothing of shape 2 can be in contact: no pair survives any
                // prediction, so the smallest does.
                return MotionBound::constant(floor);
            }
            // A rigid motion moves points affinely: the largest move over
            // the region is at one of its corners.
            let moved = region
                .corners()
                .iter()
                .map(|c| {
                    let c = Vector::new(c.x, c.y, c.z);
                    (*pos12 * c - last * c).length()
                })
                .fold(0.0f32, f32::max);
            let pair = (k * moved).max(floor).min(prediction);
            MotionBound::new(
                pair,
                &super::pose_from_parry(pos12),
                &super::pose_from_parry(&last),
                k,
                floor,
            )
        }
        _ => MotionBound::constant(prediction),
    }
}

/// One step of patch contacts for a pair whose patches are computed in the
/// frame of side A (the cbvh shape): sets up the pair's workspace, bounds
/// the prediction by the pair's motion (`b_in_a` places side B; `local_box_a`
/// and `local_box_b` are each side's own box), computes the patches with
/// `compute(bound)` (which may use `bound.prediction` everywhere or bound it
/// region by region)
/// and replaces `manifolds` with them (`flipped`: A is parry's shape 2).
#[allow(clippy::too_many_arguments)]
pub fn patch_manifolds<M: Default + Clone, C: Default + Copy>(
    opts: &PatchOptions,
    workspace: &mut Option<ContactManifoldsWorkspace>,
    b_in_a: &PPose,
    local_box_a: &crate::geom::Aabb,
    local_box_b: &crate::geom::Aabb,
    prediction: f32,
    flipped: bool,
    manifolds: &mut Vec<ContactManifold<M, C>>,
    compute: impl FnOnce(&MotionBound) -> PatchSet,
) {
    let bound = patch_workspace(
        workspace,
        b_in_a,
        local_box_a,
        local_box_b,
        prediction,
        opts,
    );
    let set = compute(&bound);
    emit(
        &set,
        &b_in_a.inverse(),
        flipped,
        opts.max_angle_deg.to_radians().cos(),
        manifolds,
    );
}

/// Contact manifolds in the dispatcher's `mode` for a pair whose side A is
/// a cbvh shape, as every pair with one ([`cbvh_cbvh`](super::cbvh_cbvh),
/// [`cbvh_convex`](super::cbvh_convex),
/// [`cbvh_trimesh`](super::cbvh_trimesh)) computes them. `local_box_a`
/// and `local_box_b` are each side's box in its own frame; `flipped` says
/// A is parry's shape 2. With [`ContactMode::Patches`],
/// [`patch_manifolds`] over the patches `patches(b_in_a, bound, opts)`
/// returns (`b_in_a`: side B's pose in A's frame); with
/// [`ContactMode::PerTrianglePair`], `per_pair(manifolds, workspace)`'s
/// manifolds, less those [`drop_opposed_manifolds`] drops (the centres:
/// the boxes'), counted by [`count_pair_manifolds`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn manifolds_in_mode<M: Default + Clone, C: Default + Copy>(
    mode: &ContactMode,
    counters: Option<&ContactCounters>,
    pos12: &PPose,
    local_box_a: &crate::geom::Aabb,
    local_box_b: &crate::geom::Aabb,
    flipped: bool,
    prediction: f32,
    manifolds: &mut Vec<ContactManifold<M, C>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
    patches: impl FnOnce(&PPose, &MotionBound, &PatchOptions) -> PatchSet,
    per_pair: impl FnOnce(&mut Vec<ContactManifold<M, C>>, &mut Option<ContactManifoldsWorkspace>),
) {
    match mode {
        ContactMode::Patches(opts) => {
            let b_in_a = if flipped { pos12.inverse() } else { *pos12 };
            patch_manifolds(
                opts,
                workspace,
                &b_in_a,
                local_box_a,
                local_box_b,
                prediction,
                flipped,
                manifolds,
                |bound| patches(&b_in_a, bound, opts),
            );
        }
        ContactMode::PerTrianglePair => {
            per_pair(manifolds, workspace);
            let centre = |b: &crate::geom::Aabb| Vector::from(b.center().to_array());
            let (ca, cb) = (centre(local_box_a), centre(local_box_b));
            let (c1, c2) = if flipped { (cb, ca) } else { (ca, cb) };
            drop_opposed_manifolds(pos12, c1, c2, manifolds);
            count_pair_manifolds(counters, manifolds);
        }
    }
}

/// Counts the per-pair mode's work: one contact pair per manifold with
/// points.
pub fn count_pair_manifolds<M, C>(
    counters: Option<&ContactCounters>,
    manifolds: &[ContactManifold<M, C>],
) {
    if let Some(c) = counters {
        let with_points = manifolds.iter().filter(|m| !m.points.is_empty()).count();
        c.add(0, with_points as u64, 0);
    }
}

/// The per-pair mode's guard against one region pushed both ways, the
/// rule the patch mode applies to its patches
/// ([`crate::contact::opposed_losers`]): of two manifolds
/// whose normals are within 25° of opposite and whose points' bounds (on
/// shape 1) meet, as two triangles sharing an edge can give when each
/// pair's own oriented axis leans over its own active edge, the one
/// leaning less from shape 1's centre `c1` toward shape 2's centre `c2`
/// (each in its shape's frame, shape 2 placed by `pos12`) loses its
/// points. Returns how many did.
pub fn drop_opposed_manifolds<M, C>(
    pos12: &PPose,
    c1: Vector,
    c2: Vector,
    manifolds: &mut [ContactManifold<M, C>],
) -> usize {
    let with_points: Vec<usize> = (0..manifolds.len())
        .filter(|&k| !manifolds[k].points.is_empty())
        .collect();
    if with_points.len() < 2 {
        return 0;
    }
    let regions: Vec<Region> = with_points
        .iter()
        .map(|&k| {
            let m = &manifolds[k];
            let mut bounds = Aabb::EMPTY;
            for p in &m.points {
                bounds.grow(Vec3A::from(p.local_p1));
            }
            Region {
                normal: Vec3A::from(m.local_n1),
                bounds,
                key: (u64::from(m.subshape1) << 32) | u64::from(m.subshape2),
            }
        })
        .collect();
    let toward = Vec3A::from(*pos12 * c2 - c1);
    let dropped = opposed_losers(&regions, toward);
    let mut count = 0;
    for (&k, _) in with_points.iter().zip(&dropped).filter(|(_, d)| **d) {
        manifolds[k].points.clear();
        count += 1;
    }
    count
}

const CODE_MASK: u32 = (1 << 30) - 1;

/// Up to this many old manifolds, [`emit`] finds a patch's old manifold by
/// scanning them rather than through hash maps built each step.
const LINEAR_SCAN_MANIFOLDS: usize = 64;

fn ids(i1: u32, i2: u32, feature: u8) -> (PackedFeatureId, PackedFeatureId) {
    (
        PackedFeatureId::face(i1 & CODE_MASK),
        PackedFeatureId::vertex(i2.wrapping_mul(8).wrapping_add(feature as u32) & CODE_MASK),
    )
}

fn v(p: Vec3A) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

/// Replaces `manifolds` with one manifold per patch of `set`. The patches
/// are in A's frame; `a_to_b` maps A's frame to the other side's; `flipped`
/// says A is parry's shape 2. `cos_angle` bounds the normal change for a
/// patch to inherit an old manifold.
pub fn emit<M: Default + Clone, C: Default + Copy>(
    set: &PatchSet,
    a_to_b: &PPose,
    flipped: bool,
    cos_angle: f32,
    manifolds: &mut Vec<ContactManifold<M, C>>,
) {
    let mut old = std::mem::take(manifolds);
    let mut used = vec![false; old.len()];
    // Old manifolds by the cell of their normal, as the patch set indexes
    // its patches: a normal within the angle lies in one of the 27 cells
    // around another's.
    let cell = (2.0 * (cos_angle.clamp(-1.0, 1.0).acos() * 0.5).sin()).max(1e-3);
    let key = |n: Vector| {
        let q = n / cell;
        (q.x.round() as i32, q.y.round() as i32, q.z.round() as i32)
    };
    // Few old manifolds (the usual case) are scanned faster than they are
    // hashed; both find the same one.
    let small = old.len() <= LINEAR_SCAN_MANIFOLDS;
    let mut by_cell: crate::hash::FastMap<(i32, i32, i32), Vec<u32>> = Default::default();
    let mut by_pair: crate::hash::FastMap<(u32, u32), u32> = Default::default();
    if !small {
        for (k, m) in old.iter().enumerate() {
            by_cell.entry(key(m.local_n1)).or_default().push(k as u32);
            by_pair.insert((m.subshape1, m.subshape2), k as u32);
        }
    }
    for patch in &set.patches {
        let (pts, n) = patch.reduced();
        if n == 0 {
            continue;
        }
        let n_a = v(patch.normal);
        let n_b = a_to_b.rotation * -n_a;
        let (local_n1, local_n2) = if flipped { (n_b, n_a) } else { (n_a, n_b) };
        // The old manifold with the closest normal, within the angle.
        let rep = patch.deepest;
        let (sub1, sub2) = if flipped {
            (rep.j, rep.i)
        } else {
            (rep.i, rep.j)
        };
        // Last step's manifold of the same representative pair (the last
        // one, if several), else the one with the closest normal.
        let same_pair = if small {
            old.iter()
                .rposition(|m| (m.subshape1, m.subshape2) == (sub1, sub2))
        } else {
            by_pair.get(&(sub1, sub2)).map(|&k| k as usize)
        };
        let mut best: Option<(usize, f32)> = same_pair
            .filter(|&k| !used[k] && old[k].local_n1.dot(local_n1) >= cos_angle)
            .map(|k| (k, 2.0));
        let mut consider = |k: usize| {
            let d = old[k].local_n1.dot(local_n1);
            if !used[k] && d >= cos_angle && best.is_none_or(|b| d > b.1 || (d == b.1 && k < b.0)) {
                best = Some((k, d));
            }
        };
        if small {
            (0..old.len()).for_each(&mut consider);
        } else {
            let (x, y, z) = key(local_n1);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &k in by_cell.get(&(x + dx, y + dy, z + dz)).into_iter().flatten() {
                            consider(k as usize);
                        }
                    }
                }
            }
        }
        let point = |p: &PatchPoint| {
            // The point on shape 2 sits exactly `dist` along the patch
            // normal from the point on shape 1: a pair's own normal may
            // differ from the patch's by up to the patch angle, and rapier
            // reads any sideways offset between the two points as relative
            // displacement (its friction anchors).
            let q1 = v(p.p1);
            let q2 = a_to_b * v(p.p1 + patch.normal * p.dist);
            if flipped {
                let (f2, f1) = ids(p.i, p.j, p.feature);
                TrackedContact::new(q2, q1, f1, f2, p.dist)
            } else {
                let (f1, f2) = ids(p.i, p.j, p.feature);
                TrackedContact::new(q1, q2, f1, f2, p.dist)
            }
        };
        let mut m = match best {
            Some((k, _)) => {
                used[k] = true;
                let mut m = old[k].take();
                let prev = std::mem::take(&mut m.points);
                m.points = pts[..n].iter().map(point).collect();
                m.match_contacts(&prev);
                m
            }
            None => {
                let mut m = ContactManifold::with_data(sub1, sub2, M::default());
                m.points = pts[..n].iter().map(point).collect();
                m
            }
        };
        m.subshape1 = sub1;
        m.subshape2 = sub2;
        m.local_n1 = local_n1;
        m.local_n2 = local_n2;
        manifolds.push(m);
    }
    old.clear();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Aabb;
    use crate::query::Prediction;
    use parry3d::math::Rotation;

    /// Shape 2, a pole 10 tall standing on shape 1's unit box, tipping by
    /// 0.01 rad about its foot: its head moves 0.1, the part that can touch
    /// shape 1 about 0.012. The bound follows the part that can touch.
    #[test]
    fn motion_bound_follows_the_region_that_can_touch() {
        let box1 = Aabb::new(Vec3A::ZERO, Vec3A::ONE);
        let box2 = Aabb::new(Vec3A::new(0.0, 1.0, 0.0), Vec3A::new(1.0, 11.0, 1.0));
        let opts = PatchOptions::default();
        let prediction = 1.0;
        let pivot = Vector::new(0.5, 1.0, 0.5);
        let tip = |angle: f32| {
            let r = PPose::from_parts(Vector::ZERO, Rotation::from_rotation_z(angle));
            PPose::from_translation(pivot) * r * PPose::from_translation(-pivot)
        };
        let mut ws = None;
        let first = patch_workspace(&mut ws, &tip(0.0), &box1, &box2, prediction, &opts).prediction;
        assert_eq!(first, prediction, "no previous pose: the full prediction");
        let tipped =
            patch_workspace(&mut ws, &tip(0.01), &box1, &box2, prediction, &opts).prediction;
        // 2 × 0.0122 is under the floor of a tenth of the prediction; the
        // whole pole's move would have given 2 × 0.1.
        assert_eq!(tipped, 0.1 * prediction);
        // A translation moves every point alike: 2 × 0.3.
        let moved = PPose::from_translation(Vector::new(0.3, 0.0, 0.0)) * tip(0.01);
        let slid = patch_workspace(&mut ws, &moved, &box1, &box2, prediction, &opts);
        assert!((slid.prediction - 0.6).abs() < 1e-3, "{slid:?}");
        // Region by region: the pole's foot (in shape 1's frame now) slid
        // by 0.3 as well, so it gets the same 0.6.
        let foot = Aabb::new(Vec3A::new(0.7, 0.9, 0.4), Vec3A::new(0.9, 1.1, 0.6));
        let at_foot = slid.within(&foot);
        assert!((at_foot - 0.6).abs() < 0.01, "{at_foot}");
        // Far apart: nothing can touch, the smallest prediction.
        let away = PPose::from_translation(Vector::new(50.0, 0.0, 0.0));
        let far = patch_workspace(&mut ws, &away, &box1, &box2, prediction, &opts);
        assert_eq!(far.prediction, 0.1 * prediction);
    }
}
