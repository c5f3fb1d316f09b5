//! [`Dispatcher`]: parry's query dispatcher for pairs with a cbvh shape.

use parry3d::math::{Pose as PPose, Real, Vector};
use parry3d::query::details::NormalConstraints;
use parry3d::query::{
    ClosestPoints, Contact, ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher,
    NonlinearRigidMotion, PersistentQueryDispatcher, QueryDispatcher, QueryDispatcherChain,
    ShapeCastHit, ShapeCastOptions, ShapeDistance, ShapeIntersection, Unsupported,
};
use parry3d::shape::{Shape, TriMesh};

use std::sync::Arc;

use super::patches::{ContactCounters, ContactMode};
use super::shape::CbvhShape;
use super::{cast, cbvh_any, cbvh_cbvh, cbvh_convex, cbvh_trimesh};

/// Handles every query in which one side is a [`CbvhShape`] natively, on the
/// cbvh trees:
///
/// | pair | contact manifolds, intersection test, contact |
/// |---|---|
/// | cbvh vs cbvh | simultaneous traversal of both trees (BVTT) |
/// | cbvh vs convex (ball, cuboid, capsule, convex polyhedron, …) | overlap query with the convex shape's box |
/// | cbvh vs parry `TriMesh` | overlap query on the cbvh tree, then the `TriMesh`'s own `Bvh` per triangle ([`cbvh_trimesh`](super::cbvh_trimesh)) |
///
/// Contacts follow the dispatcher's [`ContactMode`]: by default
/// ([`ContactMode::Patches`]) cbvh's own triangle-pair kernel runs on the
/// candidate pairs and the contacts are reduced into contact patches, one
/// manifold of at most four points per patch, matched from step to step
/// ([`patches`](super::patches)); with [`ContactMode::PerTrianglePair`]
/// triangle pairs go through parry's own convex-convex code, so contacts
/// are parry's, and manifolds persist per triangle pair. Against convex
/// shapes the patch mode reduces parry's per-triangle manifolds the same
/// way. Contact manifolds with other composite shapes (compounds,
/// heightfields, voxels) answer `Unsupported`, so that the next dispatcher
/// of the chain (parry's default, whose composite-shape code uses
/// [`CbvhShape`]'s compatibility `Bvh`) handles them: no pair is dropped.
/// Distance and closest points run natively too: branch and bound over both
/// trees for two cbvh shapes ([`cbvh_cbvh`](super::cbvh_cbvh)), or a
/// best-first search of the cbvh tree against any other shape
/// ([`cbvh_any`](super::cbvh_any)), as do linear and nonlinear shape casts
/// ([`cbvh_any`](super::cbvh_any), [`cast`](super::cast)).
///
/// Install it in rapier with
/// `NarrowPhase::with_query_dispatcher(cbvh::parry::Dispatcher::default().chain(DefaultQueryDispatcher))`,
/// or [`Dispatcher::chained`].
#[derive(Clone, Debug, Default)]
pub struct Dispatcher {
    /// How triangle pairs become contact manifolds.
    pub mode: ContactMode,
    /// Work counters to add to, if any (the sims read them per step).
    pub counters: Option<Arc<ContactCounters>>,
}

impl Dispatcher {
    /// A dispatcher with the given contact mode.
    pub fn new(mode: ContactMode) -> Self {
        Self {
            mode,
            counters: None,
        }
    }

    /// This dispatcher adding its work to `counters`.
    pub fn with_counters(mut self, counters: Arc<ContactCounters>) -> Self {
        self.counters = Some(counters);
        self
    }

    /// The default dispatcher (contact patches) followed by parry's default
    /// one: what rapier needs.
    pub fn chained() -> QueryDispatcherChain<Dispatcher, DefaultQueryDispatcher> {
        Dispatcher::default().chain(DefaultQueryDispatcher)
    }

    /// This dispatcher followed by parry's default one.
    pub fn then_default(self) -> QueryDispatcherChain<Dispatcher, DefaultQueryDispatcher> {
        self.chain(DefaultQueryDispatcher)
    }
}

enum Pair<'a> {
    Both(&'a CbvhShape, &'a CbvhShape),
    /// The cbvh shape, the other shape (any non-cbvh shape), and whether the
    /// cbvh shape is second.
    One(&'a CbvhShape, &'a dyn Shape, bool),
    Other,
}

fn is_convex(s: &dyn Shape) -> bool {
    s.is_convex() && s.as_composite_shape().is_none()
}

fn classify<'a>(g1: &'a dyn Shape, g2: &'a dyn Shape) -> Pair<'a> {
    let c1 = g1.as_shape::<CbvhShape>();
    let c2 = g2.as_shape::<CbvhShape>();
    match (c1, c2) {
        (Some(a), Some(b)) => Pair::Both(a, b),
        (Some(a), None) => Pair::One(a, g2, false),
        (None, Some(b)) => Pair::One(b, g1, true),
        _ => Pair::Other,
    }
}

impl QueryDispatcher for Dispatcher {
    fn intersection_test(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeIntersection, Unsupported> {
        match classify(g1, g2) {
            Pair::Both(a, b) => Ok(cbvh_cbvh::intersection_test(pos12, a, b)),
            Pair::One(m, c, flipped) => Ok(cbvh_convex::intersection_test(pos12, m, c, flipped)),
            Pair::Other => Err(Unsupported),
        }
    }

    fn distance(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeDistance, Unsupported> {
        let chain = self.clone().then_default();
        match (g1.as_shape::<CbvhShape>(), g2.as_shape::<CbvhShape>()) {
            (Some(a), Some(b)) => Ok(cbvh_cbvh::distance(pos12, a, b)),
            (Some(a), None) => Ok(cbvh_any::distance(&chain, pos12, a, g2, true)),
            (None, Some(b)) => Ok(cbvh_any::distance(&chain, pos12, b, g1, false)),
            (None, None) => Err(Unsupported),
        }
    }

    fn contact(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
    ) -> Result<Option<Contact>, Unsupported> {
        match classify(g1, g2) {
            Pair::Both(a, b) => Ok(cbvh_cbvh::contact(pos12, a, b, prediction)),
            Pair::One(m, c, flipped) => Ok(cbvh_convex::contact(pos12, m, c, flipped, prediction)),
            Pair::Other => Err(Unsupported),
        }
    }

    fn closest_points(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        max_dist: Real,
    ) -> Result<ClosestPoints, Unsupported> {
        let chain = self.clone().then_default();
        match (g1.as_shape::<CbvhShape>(), g2.as_shape::<CbvhShape>()) {
            (Some(a), Some(b)) => Ok(cbvh_cbvh::closest_points(pos12, a, b, max_dist)),
            (Some(a), None) => Ok(cbvh_any::closest_points(
                &chain, pos12, a, g2, true, max_dist,
            )),
            (None, Some(b)) => Ok(cbvh_any::closest_points(
                &chain, pos12, b, g1, false, max_dist,
            )),
            (None, None) => Err(Unsupported),
        }
    }

    fn cast_shapes(
        &self,
        pos12: &PPose,
        local_vel12: Vector,
        g1: &dyn Shape,
        g2: &dyn Shape,
        options: ShapeCastOptions,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        // With two cbvh shapes, each triangle of the first is cast against
        // the second through the chain, which searches the second's tree.
        let chain = self.clone().then_default();
        if let Some(a) = g1.as_shape::<CbvhShape>() {
            Ok(cbvh_any::cast_shapes(
                &chain,
                pos12,
                local_vel12,
                a,
                g2,
                true,
                options,
            ))
        } else if let Some(b) = g2.as_shape::<CbvhShape>() {
            Ok(cbvh_any::cast_shapes(
                &chain,
                pos12,
                local_vel12,
                b,
                g1,
                false,
                options,
            ))
        } else {
            Err(Unsupported)
        }
    }

    fn cast_shapes_nonlinear(
        &self,
        motion1: &NonlinearRigidMotion,
        g1: &dyn Shape,
        motion2: &NonlinearRigidMotion,
        g2: &dyn Shape,
        start_time: Real,
        end_time: Real,
        stop_at_penetration: bool,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        // Two cbvh shapes: one search over pairs of nodes of both trees.
        // One: the tree searched against the other shape, whose leaves
        // dispatch triangle-vs-other-shape back through `self`, which
        // hands convex pairs on to parry's default dispatcher.
        let chain = self.clone().then_default();
        if let (Some(a), Some(b)) = (g1.as_shape::<CbvhShape>(), g2.as_shape::<CbvhShape>()) {
            return Ok(cast::cast_nonlinear_pair(
                &chain,
                a,
                motion1,
                b,
                motion2,
                start_time,
                end_time,
                stop_at_penetration,
            ));
        }
        if let Some(m) = g1.as_shape::<CbvhShape>() {
            Ok(cast::cast_nonlinear(
                &chain,
                m,
                motion1,
                g2,
                motion2,
                true,
                start_time,
                end_time,
                stop_at_penetration,
            ))
        } else if let Some(m) = g2.as_shape::<CbvhShape>() {
            Ok(cast::cast_nonlinear(
                &chain,
                m,
                motion2,
                g1,
                motion1,
                false,
                start_time,
                end_time,
                stop_at_penetration,
            ))
        } else {
            Err(Unsupported)
        }
    }
}

impl<M: Default + Clone + Send + Sync, C: Default + Copy + Send + Sync>
    PersistentQueryDispatcher<M, C> for Dispatcher
{
    fn contact_manifolds(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
        manifolds: &mut Vec<ContactManifold<M, C>>,
        workspace: &mut Option<ContactManifoldsWorkspace>,
    ) -> Result<(), Unsupported> {
        let mode = &self.mode;
        let counters = self.counters.as_deref();
        match classify(g1, g2) {
            Pair::Both(a, b) => {
                cbvh_cbvh::contact_manifolds_in(
                    mode, counters, pos12, a, b, prediction, manifolds, workspace,
                );
                Ok(())
            }
            Pair::One(m, c, flipped) if is_convex(c) => {
                cbvh_convex::contact_manifolds_in(
                    mode, counters, pos12, m, c, flipped, prediction, manifolds, workspace,
                );
                Ok(())
            }
            Pair::One(m, other, flipped) => match other.as_shape::<TriMesh>() {
                Some(tm) => {
                    cbvh_trimesh::contact_manifolds_in(
                        mode, counters, pos12, m, tm, flipped, prediction, manifolds, workspace,
                    );
                    Ok(())
                }
                // Other composite shapes (compounds, heightfields, voxels):
                // parry's composite-shape code, through the fallback `Bvh`.
                None => Err(Unsupported),
            },
            Pair::Other => Err(Unsupported),
        }
    }

    fn contact_manifold_convex_convex(
        &self,
        _: &PPose,
        _: &dyn Shape,
        _: &dyn Shape,
        _: Option<&dyn NormalConstraints>,
        _: Option<&dyn NormalConstraints>,
        _: Real,
        _: &mut ContactManifold<M, C>,
    ) -> Result<(), Unsupported> {
        Err(Unsupported)
    }
}
