//! The parry3d / rapier3d integration. This folder is the only place in
//! the crate that imports parry3d or rapier3d.
//!
//! - [`CbvhShape`]: one parry shape over any cbvh codec (`Shape`, `RayCast`,
//!   `PointQuery`, `CompositeShape`, `TypedCompositeShape`), with mass
//!   properties computed once at build time.
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
//! - [`open_codec`]: any codec's self-contained file, chosen by its magic,
//!   opened (and verified) into a [`Codec`] or, through [`CbvhShape::open`],
//!   a shape that needs no mesh.
//! - [`droptest`]: the rapier drop test behind the sims, timing the narrow
//!   phase per step through [`timed::Timed`].
//! - [`trimesh`]: parry's own `TriMesh` built from a [`Mesh`](crate::Mesh),
//!   the baseline every comparison is made against, with its memory counted
//!   by part the same way cbvh's codecs count theirs.

pub mod cast;
pub mod cbvh_any;
pub mod cbvh_cbvh;
pub mod cbvh_convex;
pub mod cbvh_trimesh;
mod dispatcher;
pub mod droptest;
mod open;
pub mod patches;
pub mod raycast_target;
pub mod shape;
pub mod timed;
pub mod trimesh;
mod workspace;

pub use dispatcher::Dispatcher;
pub use open::{CodecError, CodecFileError, OpenOptions, codec_file_kind, open_codec};
pub use patches::{ContactCounters, ContactMode};
pub use shape::{CbvhShape, Codec, pose_from_parry};
pub use trimesh::{parry_trimesh, trimesh_bytes_by_part};
pub use workspace::CbvhWorkspace;
