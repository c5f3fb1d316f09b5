//! # cbvh — compressed bounding volume hierarchies for collision detection and ray tracing
//!
//! cbvh stores triangle meshes as compressed bounding volume hierarchies and
//! uses them directly: as parry3d / rapier3d collision shapes, and as the
//! acceleration structure of a CPU ray tracer.
//!
//! The default features are the library a rapier program needs: the codecs,
//! the queries, the contacts and the parry/rapier integration. The rest is
//! behind features (see `Cargo.toml`): `render` (the ray tracer),
//! `image-files` (its PNG and GIF output), `serde` (`Serialize` on the stats
//! and reports), `sims` (the mesh generators and the rapier harnesses, with
//! rapier3d and `serde`) and `app` (all of them, and the command-line front
//! end).
//!
//! The modules, from the mesh to its uses (each folder's module docs say
//! what it owns):
//!
//! - [`mesh`]: the [`Mesh`] type and its loaders/writers (OFF, PLY, OBJ, STL).
//! - `scene` (feature `sims`): deterministic procedural scenes standing in
//!   for the papers' models.
//! - [`build`]: the one builder, producing a [`CanonicalBvh`] in a chosen layout.
//! - [`cursor`]: [`NodeCursor`], the traversal trait every codec implements.
//! - [`codec`]: the storage forms, the [`Codec`](codec::Codec) contract they
//!   implement, and the registry ([`codec::any`]) that names every codec once.
//! - [`query`]: ray, overlap, closest-point and tree-vs-tree queries over any
//!   cursor, and [`RayCursor`](query::RayCursor), through which a codec may
//!   answer the ray queries with a traversal of its own.
//! - [`contact`]: cbvh's own contacts: the batched triangle-pair kernel,
//!   active edges, oriented normals, and contact patches.
//! - [`parry`]: the parry3d / rapier3d integration.
//! - `sim` (feature `sims`): the rapier harnesses: the drop test behind the
//!   sims, and scenes with analytic answers that check contacts in motion.
//! - `render` (feature `render`): a Whitted-style ray tracer over any cursor
//!   (and parry's `TriMesh`).
//! - `app` (feature `app`): the command-line front end of every binary
//!   (the `cbvh` command and the drop tests), with their plots.
//! - [`geom`]: the small geometry types (glam-based) shared by all of them.
//! - [`files`]: [`IoError`], the one I/O error (with the path), and atomic
//!   file saves, for every file the crate writes.
//! - `logger` (feature `sims`): a minimal stderr logger for the binaries
//!   and examples (the library logs warnings through the `log` crate; an
//!   application installs its own logger).
//!
//! parry3d is imported only in [`parry`] and in the harness `sim`, and
//! rapier3d only in `sim`, which drives rapier (the integration speaks
//! parry's traits, which rapier takes, so the library does not depend on
//! rapier3d); the rest of the crate speaks its own small geometry types (or
//! parry's glam re-exports), and [`codec`] knows neither.
#![warn(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]

#[cfg(feature = "app")]
pub mod app;
pub mod build;
pub mod codec;
pub mod contact;
pub mod cursor;
pub mod files;
pub mod geom;
mod hash;
#[cfg(feature = "sims")]
pub mod logger;
pub mod mesh;
pub mod parry;
pub mod query;
#[cfg(feature = "render")]
pub mod render;
// The library's own unit tests generate their meshes with `scene` and
// `sim`, so `cargo test --lib` compiles both without the feature.
#[cfg(any(test, feature = "sims"))]
pub mod scene;
#[cfg(any(test, feature = "sims"))]
pub mod sim;

pub use build::{BuildOptions, CanonicalBvh, Layout};
pub use cursor::{NodeCursor, TraversalStats};
pub use files::IoError;
pub use mesh::{Mesh, MeshError};
