//! [`Timed`]: a dispatcher wrapper that measures the time spent computing
//! contact manifolds, i.e. the narrow phase's collision work, separately
//! from rapier's solver. Used by the drop-test sims for every shape alike.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use parry3d::math::{Pose as PPose, Real, Vector};
use parry3d::query::details::NormalConstraints;
use parry3d::query::{
    ClosestPoints, Contact, ContactManifold, ContactManifoldsWorkspace, NonlinearRigidMotion,
    PersistentQueryDispatcher, QueryDispatcher, ShapeCastHit, ShapeCastOptions, ShapeDistance,
    ShapeIntersection, Unsupported,
};
use parry3d::shape::Shape;

/// One `contact_manifolds` call as [`Timed`] records it: the relative
/// pose, the prediction distance and the address of the first shape's data
/// (to tell which collider came first).
#[derive(Clone, Copy, Debug)]
pub struct RecordedCall {
    /// The pose of the second shape relative to the first.
    pub pos12: PPose,
    /// The prediction distance.
    pub prediction: Real,
    /// The address of the first shape (`g1`), as a number.
    pub first: usize,
}

/// The calls recorded so far, shared with the caller.
pub type CallLog = Arc<Mutex<Vec<RecordedCall>>>;

/// Wraps a dispatcher and adds the wall time of every `contact_manifolds`
/// call to a shared nanosecond counter; optionally records every call
/// ([`Timed::recording`]), so that another shape can be timed on the same
/// poses later.
#[derive(Clone, Debug)]
pub struct Timed<D> {
    inner: D,
    nanos: Arc<AtomicU64>,
    calls: Option<CallLog>,
}

impl<D> Timed<D> {
    /// Wraps `inner`; read the time with [`Timed::counter`].
    pub fn new(inner: D) -> Self {
        Self {
            inner,
            nanos: Arc::new(AtomicU64::new(0)),
            calls: None,
        }
    }

    /// Also records every `contact_manifolds` call into the log
    /// [`Timed::calls`] returns (after the timed call, outside its time).
    pub fn recording(mut self) -> Self {
        self.calls = Some(CallLog::default());
        self
    }

    /// The shared counter of nanoseconds spent in contact manifolds.
    pub fn counter(&self) -> Arc<AtomicU64> {
        self.nanos.clone()
    }

    /// The shared log of recorded calls (`None` unless recording).
    pub fn calls(&self) -> Option<CallLog> {
        self.calls.clone()
    }
}

impl<D: QueryDispatcher> QueryDispatcher for Timed<D> {
    fn intersection_test(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeIntersection, Unsupported> {
        self.inner.intersection_test(pos12, g1, g2)
    }

    fn distance(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeDistance, Unsupported> {
        self.inner.distance(pos12, g1, g2)
    }

    fn contact(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
    ) -> Result<Option<Contact>, Unsupported> {
        self.inner.contact(pos12, g1, g2, prediction)
    }

    fn closest_points(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        max_dist: Real,
    ) -> Result<ClosestPoints, Unsupported> {
        self.inner.closest_points(pos12, g1, g2, max_dist)
    }

    fn cast_shapes(
        &self,
        pos12: &PPose,
        local_vel12: Vector,
        g1: &dyn Shape,
        g2: &dyn Shape,
        options: ShapeCastOptions,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        self.inner.cast_shapes(pos12, local_vel12, g1, g2, options)
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
        self.inner.cast_shapes_nonlinear(
            motion1,
            g1,
            motion2,
            g2,
            start_time,
            end_time,
            stop_at_penetration,
        )
    }
}

impl<M, C, D: PersistentQueryDispatcher<M, C>> PersistentQueryDispatcher<M, C> for Timed<D> {
    fn contact_manifolds(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
        manifolds: &mut Vec<ContactManifold<M, C>>,
        workspace: &mut Option<ContactManifoldsWorkspace>,
    ) -> Result<(), Unsupported> {
        let t0 = Instant::now();
        let r = self
            .inner
            .contact_manifolds(pos12, g1, g2, prediction, manifolds, workspace);
        self.nanos
            .fetch_add(t0.elapsed().as_nanos() as u64, Ordering::Relaxed);
        if let Some(log) = &self.calls {
            let call = RecordedCall {
                pos12: *pos12,
                prediction,
                first: shape_address(g1),
            };
            log.lock().unwrap_or_else(|e| e.into_inner()).push(call);
        }
        r
    }

    fn contact_manifold_convex_convex(
        &self,
        pos12: &PPose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        normal_constraints1: Option<&dyn NormalConstraints>,
        normal_constraints2: Option<&dyn NormalConstraints>,
        prediction: Real,
        manifold: &mut ContactManifold<M, C>,
    ) -> Result<(), Unsupported> {
        self.inner.contact_manifold_convex_convex(
            pos12,
            g1,
            g2,
            normal_constraints1,
            normal_constraints2,
            prediction,
            manifold,
        )
    }
}

/// The address of a shape's data, as a number: the same for every clone of
/// the `Arc` a collider holds.
pub fn shape_address(shape: &dyn Shape) -> usize {
    shape as *const dyn Shape as *const () as usize
}
