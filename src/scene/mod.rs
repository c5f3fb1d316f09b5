//! Deterministic procedural scenes standing in for the papers' models.
//!
//! [`generate`] builds a [`Kind`] of mesh at a requested triangle count
//! (from [`MIN_TRIS`] to [`MAX_TRIS`]; the count produced is within 5 % of
//! the request) from a seed. The same seed gives a bit-identical mesh
//! whatever the number of threads; different seeds give different meshes.
//!
//! | kind | stands in for | closed? |
//! |------|---------------|---------|
//! | [`Kind::Statue`] | Lucy, St. Matthew (scans) | yes: one watertight, outward-oriented surface |
//! | [`Kind::Turbine`] | the CAD turbine | every part (blade, hub, …) is closed; parts overlap |
//! | [`Kind::Plant`] | the power plant | every part (pipe, tank, box, …) is closed; parts overlap |
//! | [`Kind::Robot`] | the Hubo robot | every part (limb, joint, …) is closed; parts overlap |
//! | [`Kind::Isosurface`] | the iso-surface model | yes: the domain is padded |
//!
//! "Closed" means no boundary edges ([`crate::mesh::boundary_edges`] is 0)
//! and triangles wound counter-clockwise seen from outside.
//!
//! Y is up everywhere, and every scene but the isosurface rests on `y = 0`.
//! Sizes: the statue is about 2 units tall and 0.75 wide; the turbine about
//! 4 units across (axis along y) and 1.6 high; the plant 8.4 × 6.4 units
//! and under 3 high; the robot about 1.4 tall; the isosurface lies in a
//! ball of diameter 1.9 centred in `[0, 2]³`.
//!
//! All kinds except the isosurface are assembled from tessellated box
//! grids (module `grid`) bent into shapes (module `shapes`): their counts
//! follow from a formula, `4(nx·ny + ny·nz + nz·nx)` per part, so they are
//! planned exactly before anything is generated ([`planned_triangles`]).
//! Output buffers are allocated at their final size and filled in
//! parallel, disjoint chunks, so generating takes little more memory than
//! the mesh itself. The isosurface is steered by counting passes and
//! built slab by slab (module `iso`).

use std::fmt;
use std::str::FromStr;

use crate::mesh::Mesh;

mod grid;
mod iso;
mod mc;
mod noise;
mod parts;
mod plant;
pub(crate) mod rng;
mod robot;
mod shapes;
mod statue;
mod turbine;

/// Smallest triangle count [`generate`] accepts.
pub const MIN_TRIS: usize = 1_000;
/// Largest triangle count [`generate`] accepts.
pub const MAX_TRIS: usize = 200_000_000;

/// The kinds of scene [`generate`] can build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// A closed, finely detailed statue-like figure (Lucy, St. Matthew).
    Statue,
    /// A CAD-like turbine rotor with twisted blades.
    Turbine,
    /// A power-plant-like scene of pipes, tanks and buildings on a slab.
    Plant,
    /// A small articulated humanoid robot (Hubo).
    Robot,
    /// The marching-cubes isosurface of a noise field.
    Isosurface,
}

impl Kind {
    /// Every kind, in a fixed order.
    pub const ALL: [Kind; 5] = [
        Kind::Statue,
        Kind::Turbine,
        Kind::Plant,
        Kind::Robot,
        Kind::Isosurface,
    ];

    /// The kind's name as accepted by [`FromStr`]: `statue`, `turbine`,
    /// `plant`, `robot`, `isosurface`.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Statue => "statue",
            Kind::Turbine => "turbine",
            Kind::Plant => "plant",
            Kind::Robot => "robot",
            Kind::Isosurface => "isosurface",
        }
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Kind {
    type Err = GenError;

    /// Parses a kind name, ignoring ASCII case.
    fn from_str(s: &str) -> Result<Self, GenError> {
        Kind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| GenError::UnknownKind(s.to_string()))
    }
}

/// What to generate: a triangle count and a seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GenOptions {
    /// Requested triangle count.
    pub tris: usize,
    /// Seed: the same seed gives the same mesh.
    pub seed: u64,
}

impl GenOptions {
    /// The default count for `kind` (see [`default_tris`]) and seed 0.
    pub fn for_kind(kind: Kind) -> Self {
        Self {
            tris: default_tris(kind),
            seed: 0,
        }
    }
}

impl Default for GenOptions {
    /// 100 000 triangles, seed 0.
    fn default() -> Self {
        Self {
            tris: 100_000,
            seed: 0,
        }
    }
}

/// Why a scene cannot be generated.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum GenError {
    /// The requested triangle count is outside `min..=max`.
    #[error(
        "cannot generate a {kind} scene with {requested} triangles: the count must be between {min} and {max}"
    )]
    TrisOutOfRange {
        /// The kind asked for.
        kind: Kind,
        /// The requested count.
        requested: usize,
        /// Smallest accepted count ([`MIN_TRIS`]).
        min: usize,
        /// Largest accepted count ([`MAX_TRIS`]).
        max: usize,
    },
    /// A kind name that is not one of [`Kind::ALL`].
    #[error("unknown scene kind {0:?}: expected one of statue, turbine, plant, robot, isosurface")]
    UnknownKind(String),
}

/// The default triangle count of each kind: robot 16 000, turbine 50 000,
/// statue, plant and isosurface 100 000.
pub fn default_tris(kind: Kind) -> usize {
    match kind {
        Kind::Robot => 16_000,
        Kind::Turbine => 50_000,
        Kind::Statue | Kind::Plant | Kind::Isosurface => 100_000,
    }
}

fn check(kind: Kind, tris: usize) -> Result<(), GenError> {
    if (MIN_TRIS..=MAX_TRIS).contains(&tris) {
        Ok(())
    } else {
        Err(GenError::TrisOutOfRange {
            kind,
            requested: tris,
            min: MIN_TRIS,
            max: MAX_TRIS,
        })
    }
}

fn plan_parts(kind: Kind, tris: usize, seed: u64) -> (Vec<parts::Part>, Vec<grid::BoxGrid>) {
    match kind {
        Kind::Statue => statue::plan(tris, seed),
        Kind::Turbine => turbine::plan(tris, seed),
        Kind::Plant => plant::plan(tris, seed),
        Kind::Robot => robot::plan(tris, seed),
        Kind::Isosurface => unreachable!("the isosurface has no parts"),
    }
}

/// The triangle count that [`generate`] produces for these arguments,
/// computed without generating: exact, from the tessellation formula, for
/// every kind but the isosurface; for the isosurface exact up to about
/// 400 000 triangles (it runs counting passes), and above that simply the
/// request, which the fitted plan then hits within about 1 %.
pub fn planned_triangles(kind: Kind, tris: usize, seed: u64) -> Result<usize, GenError> {
    check(kind, tris)?;
    Ok(match kind {
        Kind::Isosurface => iso::planned_triangles(tris, seed) as usize,
        _ => parts::plan_triangles(&plan_parts(kind, tris, seed).1) as usize,
    })
}

/// Generates a `kind` scene of about `tris` triangles (within 5 %) from
/// `seed`, calling `progress(done, total)` now and then (about every 1 %
/// of the work, and with `done == total` at the end).
///
/// # Errors
/// [`GenError::TrisOutOfRange`] unless `MIN_TRIS <= tris <= MAX_TRIS`.
pub fn generate(
    kind: Kind,
    tris: usize,
    seed: u64,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Mesh, GenError> {
    check(kind, tris)?;
    Ok(match kind {
        Kind::Isosurface => iso::generate(tris, seed, progress),
        _ => {
            let (parts, grids) = plan_parts(kind, tris, seed);
            parts::build(&parts, &grids, progress)
        }
    })
}
