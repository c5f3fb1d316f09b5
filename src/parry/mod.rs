//! The parry3d / rapier3d integration. This folder is the only place in
//! the crate that imports parry3d or rapier3d.
//!
//! - [`trimesh`]: parry's own `TriMesh` built from a [`Mesh`](crate::Mesh),
//!   the baseline every comparison is made against, with its memory counted
//!   by part the same way cbvh's codecs count theirs.

pub mod trimesh;

pub use trimesh::{parry_trimesh, trimesh_bytes_by_part};
