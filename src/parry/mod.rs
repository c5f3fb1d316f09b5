//! The parry3d / rapier3d integration. This folder, and the drop-test
//! harness `crate::sim` (feature `sims`) that drives rapier with it, are
//! the only places in the crate that import parry3d. The integration needs
//! no rapier3d: rapier's narrow phase takes parry's query dispatcher
//! traits, which [`Dispatcher`] implements, and parry's shapes.
//!
//! - [`CbvhShape`]: one parry shape over any cbvh codec (`Shape`, `RayCast`,
//!   `PointQuery`, `CompositeShape`, `TypedCompositeShape`), with mass
//!   properties computed once at build time. It holds any codec of the
//!   registry ([`AnyCodec`](crate::codec::AnyCodec)), built by kind
//!   ([`CbvhShape::build`]) or opened from any codec's self-contained file
//!   ([`CbvhShape::open`], a shape that needs no mesh).
//! - [`Dispatcher`]: handles every pair with a cbvh shape on the cbvh trees
//!   (BVTT for cbvh vs cbvh, overlap queries for cbvh vs convex), chained to
//!   parry's default dispatcher for everything else. One file per query pair:
//!   [`cbvh_cbvh`], [`cbvh_convex`], [`cbvh_trimesh`]. Its [`ContactMode`]
//!   chooses between contact patches from cbvh's own triangle-pair kernel
//!   ([`crate::contact`], turned into manifolds by [`patches`]; the default)
//!   and one manifold per triangle pair through parry's convex-convex code.
//!   This departs from the design's first rule that triangle pairs always go
//!   through parry: at scan resolution a resting contact touches hundreds of
//!   thousands of pairs, and one manifold each floods the narrow phase and
//!   the solver.
//! - [`cones`]: cbvh's active edges and facing ([`crate::contact::edges`],
//!   [`crate::contact::orient`]) as parry normal constraints, where parry's
//!   convex-convex code computes the contact: a cbvh triangle against a
//!   convex shape, and the per-triangle-pair mode. A [`CbvhShape`] holds its
//!   edge flags (its codec's, stored in every codec file) and which sides it
//!   takes contacts on ([`Sides`]).
//! - [`trimesh`]: parry's own `TriMesh` built from a [`Mesh`](crate::Mesh),
//!   the baseline every comparison is made against, with its memory counted
//!   by part the same way cbvh's codecs count theirs.
//! - `raycast_target` (feature `render`): parry's `TriMesh` as a target of
//!   the ray tracer, to render through parry's own ray casting.

/// Runs `$body` with `$c` bound to a [`CbvhShape`]'s tree as a cursor,
/// scaled as the shape is ([`Scaled`](crate::cursor::Scaled): the codec's
/// own cursor behind a flag when the shape is unscaled). Every traversal of
/// a shape's tree in this folder goes through it, so that a scaled view
/// ([`CbvhShape::scaled`]) answers every query.
macro_rules! with_cursor {
    ($shape:expr, |$c:ident| $body:expr) => {{
        let shape: &$crate::parry::CbvhShape = $shape;
        let scale = shape.scale();
        $crate::with_codec!(shape.codec(), |raw| {
            let $c = &$crate::cursor::Scaled::new(raw, scale);
            $body
        })
    }};
}

pub mod cast;
pub mod cbvh_any;
pub mod cbvh_cbvh;
pub mod cbvh_convex;
pub mod cbvh_trimesh;
pub mod cones;
mod dispatcher;
pub mod patches;
#[cfg(feature = "render")]
pub mod raycast_target;
pub mod shape;
pub mod trimesh;
mod workspace;

pub use dispatcher::Dispatcher;
pub use patches::{ContactCounters, ContactMode};
pub use shape::{CbvhShape, ShapeBuildError, Sides, pose_from_parry};
pub use trimesh::{parry_trimesh, trimesh_bytes_by_part};
pub use workspace::CbvhWorkspace;
