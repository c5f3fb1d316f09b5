//! The rapier drop-test harness behind the sims (`sims/`): a dynamic mesh
//! dropped onto a fixed one, once per shape kind (parry's `TriMesh` and
//! every codec of the registry), with the narrow phase timed per step.
//!
//! This folder drives rapier, so it imports parry3d and rapier3d: with
//! [`crate::parry`] (the integration itself) it is one of the two places
//! in the crate that may. It uses the integration only through its public
//! API (the shape, the dispatcher, parry's `TriMesh` baseline).
//!
//! - [`droptest`]: the scene, the placement, one run per [`ShapeKind`]
//!   and its [`RunReport`].
//! - [`timed`]: [`Timed`], the dispatcher wrapper that times the narrow
//!   phase.

pub mod droptest;
pub mod timed;

pub use droptest::{DropScene, Placement, Replay, RunReport, RunSpec, ShapeKind, Trajectory};
pub use timed::Timed;
