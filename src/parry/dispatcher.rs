//! [`Dispatcher`]: parry's query dispatcher for pairs with a cbvh shape.

use parry3d::math::{Pose as PPose, Real, Vector};
use parry3d::query::details::NormalConstraints;
use parry3d::query::{
    ClosestPoints, Contact, ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher,
    NonlinearRigidMotion, PersistentQueryDispatcher, QueryDispatcher, QueryDispatcherChain,
    ShapeCastHit, ShapeCastOptions, ShapeDistance, ShapeIntersection, Unsupported,
};
use parry3d::shape::Shape;

use super::shape::CbvhShape;
use super::{cast, cbvh_cbvh, cbvh_convex};

/// Handles every query in which one side is a [`CbvhShape`] natively, on the
/// cbvh trees:
///
/// | pair | contact manifolds, intersection test, contact |
/// |---|---|
/// | cbvh vs cbvh | simultaneous traversal of both trees (BVTT) |
/// | cbvh vs convex (ball, cuboid, capsule, convex polyhedron, …) | overlap query with the convex shape's box |
///
/// Triangle pairs go through parry's own convex-convex code, so contacts are
/// parry's, and manifolds persist per triangle pair so that rapier
/// warm-starts. Every other query or pair answers `Unsupported`, so that the
/// next dispatcher of the chain (parry's default, whose composite-shape code
/// uses [`CbvhShape`]'s compatibility `Bvh`) handles it: no pair is dropped.
/// Nonlinear shape casts (rapier's CCD) run natively on the cbvh tree
/// ([`cast`](super::cast)); distance, closest points and linear shape casts
/// take the fallback path for now.
///
/// Install it in rapier with
/// `NarrowPhase::with_query_dispatcher(cbvh::parry::Dispatcher.chain(DefaultQueryDispatcher))`,
/// or [`Dispatcher::chained`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Dispatcher;

impl Dispatcher {
    /// This dispatcher followed by parry's default one: what rapier needs.
    pub fn chained() -> QueryDispatcherChain<Dispatcher, DefaultQueryDispatcher> {
        Dispatcher.chain(DefaultQueryDispatcher)
    }
}

enum Pair<'a> {
    Both(&'a CbvhShape, &'a CbvhShape),
    /// The cbvh shape, the convex shape, and whether the cbvh shape is second.
    Convex(&'a CbvhShape, &'a dyn Shape, bool),
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
        (Some(a), None) if is_convex(g2) => Pair::Convex(a, g2, false),
        (None, Some(b)) if is_convex(g1) => Pair::Convex(b, g1, true),
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
            Pair::Convex(m, c, flipped) => Ok(cbvh_convex::intersection_test(pos12, m, c, flipped)),
            Pair::Other => Err(Unsupported),
        }
    }

    fn distance(
        &self,
        _: &PPose,
        _: &dyn Shape,
        _: &dyn Shape,
    ) -> Result<ShapeDistance, Unsupported> {
        Err(Unsupported)
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
            Pair::Convex(m, c, flipped) => {
                Ok(cbvh_convex::contact(pos12, m, c, flipped, prediction))
            }
            Pair::Other => Err(Unsupported),
        }
    }

    fn closest_points(
        &self,
        _: &PPose,
        _: &dyn Shape,
        _: &dyn Shape,
        _: Real,
    ) -> Result<ClosestPoints, Unsupported> {
        Err(Unsupported)
    }

    fn cast_shapes(
        &self,
        _: &PPose,
        _: Vector,
        _: &dyn Shape,
        _: &dyn Shape,
        _: ShapeCastOptions,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        Err(Unsupported)
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
        // Leaves dispatch triangle-vs-other-shape back through `self`, which
        // hands convex pairs on to parry's default dispatcher.
        let chain = Dispatcher.chain(DefaultQueryDispatcher);
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
        match classify(g1, g2) {
            Pair::Both(a, b) => {
                cbvh_cbvh::contact_manifolds(pos12, a, b, prediction, manifolds, workspace);
                Ok(())
            }
            Pair::Convex(m, c, flipped) => {
                cbvh_convex::contact_manifolds(
                    pos12, m, c, flipped, prediction, manifolds, workspace,
                );
                Ok(())
            }
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
