//! The rapier harnesses: the drop test behind the sims (`sims/`), a
//! dynamic mesh dropped onto a fixed one, once per shape kind (parry's
//! `TriMesh` and every codec of the registry), with the narrow phase timed
//! per step; and the analytic scenes that check contacts in motion.
//!
//! This folder drives rapier, so it imports parry3d and rapier3d: with
//! [`crate::parry`] (the integration itself) it is one of the two places
//! in the crate that may import parry3d, and the only one that imports
//! rapier3d (which only the `sims` feature brings). It uses the
//! integration only through its public API (the shape, the dispatcher,
//! parry's `TriMesh` baseline).
//!
//! - [`droptest`]: the scene, the placement, one run per [`ShapeKind`]
//!   and its [`RunReport`].
//! - [`slide`]: scenes with analytic answers (a cube sliding or staying
//!   on a ramp, a sphere rolling, a ball settling in a bowl, cubes resting,
//!   stacked, at a table's edge), run for every representation of the
//!   ground and the body, each [`slide::Report`] measured against expected.
//! - [`ccd`]: continuous collision in rapier: fast bodies shot at
//!   zero-thickness walls and a spinning bar swept into a strip, each
//!   [`ccd::CcdReport`] against the analytic first contact.
//! - [`character`]: rapier's kinematic character controller walking a
//!   capsule over terrain, ramps, stairs, a wall and a slope it snaps
//!   down, each [`character::WalkReport`] against the geometry's answer.
//! - [`timed`]: [`Timed`], the dispatcher wrapper that times the narrow
//!   phase.

pub mod ccd;
pub mod character;
pub mod droptest;
pub mod slide;
pub mod timed;
pub mod trace;

pub use droptest::{
    DropScene, Placement, Replay, RunReport, RunSpec, ShapeKind, SimError, Trajectory,
};
pub use timed::Timed;
