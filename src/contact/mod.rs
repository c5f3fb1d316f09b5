//! cbvh's own contact generation for triangle meshes, independent of parry:
//!
//! - [`kernel`]: the triangle-pair contact kernel (separating axes over a
//!   batch of pairs in structure-of-arrays form, the exact distance of
//!   separated pairs, clipped contact points) and the papers' interference
//!   test (does a triangle pair intersect);
//! - [`patch`]: the reduction of many pair contacts into contact patches
//!   (normals within a few degrees, near each other), each at most four
//!   points that keep the patch's support area;
//! - [`edges`]: active edges, one byte a triangle computed once from the
//!   mesh (when a codec encodes it; codec files store them): which edges
//!   are real (convex or boundary) seen from each side;
//! - [`orient`]: oriented normals: out of A's surface into B's, on an axis
//!   both triangles accept given the side they face and their edge flags;
//! - [`motion`]: the prediction distance bounded by how far each region of
//!   a body moved since the last step.
//!
//! The parry integration ([`crate::parry`]) turns patches into parry
//! `ContactManifold`s, one per patch, matched from step to step. This
//! replaces the design's earlier rule that every triangle pair goes through
//! parry's convex-convex code: that path stays available as the
//! per-triangle-pair contact mode.

pub mod edges;
mod features;
pub mod kernel;
pub mod motion;
pub mod orient;
pub mod patch;
mod sat;

pub use edges::EdgeFlags;
pub use features::closest_points as triangle_closest_points;
pub use kernel::{
    ContactSink, Interference, KernelStats, PairContact, PairKernel, PairPoint, pair_contact,
    triangles_intersect,
};
pub use motion::MotionBound;
pub use orient::{Facing, Neighbours, PairFacing};
pub use patch::{Patch, PatchOptions, PatchPoint, PatchSet, Region, opposed_losers};
