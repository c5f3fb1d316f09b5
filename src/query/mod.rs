//! Queries written once over [`NodeCursor`](crate::cursor::NodeCursor) and
//! monomorphized per codec:
//!
//! - [`ray`]: closest hit (distance, triangle id, barycentrics) and any hit
//!   within a distance (shadow rays);
//! - [`overlap`]: triangles whose boxes overlap a box, and a generic
//!   box-pruned visit;
//! - [`point`]: the closest point of the mesh to a point;
//! - [`best`]: best-first branch-and-bound search for the cheapest triangle;
//! - [`bvtt`]: simultaneous traversal of two hierarchies under a relative
//!   rigid pose (the bounding volume test tree), enumerating the triangle
//!   pairs whose boxes come within a prediction distance.
//!
//! Every query counts [`TraversalStats`](crate::cursor::TraversalStats).

pub mod best;
pub mod bvtt;
pub mod overlap;
pub mod point;
pub mod ray;

pub use best::find_best;
pub use bvtt::{bvtt, bvtt_pairs};
pub use overlap::{overlap, visit};
pub use point::{PointHit, closest_point};
pub use ray::{RayHit, any_hit, any_hit_with, closest_hit, closest_hit_with};
