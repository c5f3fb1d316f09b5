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
//! Every vertex and triangle is computed from its index alone, so output
//! buffers are allocated at their final size and filled in parallel,
//! disjoint chunks: generating takes little more memory than the mesh
//! itself. The isosurface is steered by counting passes and built slab by
//! slab (module `iso`).
//!
//! [`generate_to_ply`] writes a scene straight to a binary PLY file
//! ([`crate::mesh::PlyWriter`]), the same bytes as [`crate::mesh::save`] of
//! [`generate`]. The part-based kinds *stream* ([`Kind::streams`]): their
//! vertices, then their triangles, are computed and written batch by batch,
//! in a few MiB whatever the size, up to [`MAX_STREAMED_TRIS`] triangles.
//! The isosurface is generated in memory and then written, up to
//! [`MAX_TRIS`] like [`generate`].

use std::fmt;
use std::io::{self, Write};
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
/// Largest triangle count [`generate`] accepts (the mesh is held in
/// memory: about 3.6 GB at this size).
pub const MAX_TRIS: usize = 200_000_000;
/// Largest triangle count [`generate_to_ply`] accepts for the kinds that
/// stream ([`Kind::streams`]): about 19 GB of PLY, written in a few MiB of
/// memory (the limit keeps the vertices far within `u32` indices).
pub const MAX_STREAMED_TRIS: usize = 1_000_000_000;

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

    /// Whether [`generate_to_ply`] streams this kind (computes and writes
    /// it batch by batch in bounded memory): every kind but the isosurface,
    /// which is generated in memory and then written.
    pub fn streams(self) -> bool {
        self != Kind::Isosurface
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
    check_max(kind, tris, MAX_TRIS)
}

fn check_max(kind: Kind, tris: usize, max: usize) -> Result<(), GenError> {
    if (MIN_TRIS..=max).contains(&tris) {
        Ok(())
    } else {
        Err(GenError::TrisOutOfRange {
            kind,
            requested: tris,
            min: MIN_TRIS,
            max,
        })
    }
}

/// The parts and grids of a part-based kind (not the isosurface).
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
        _ => assembly(kind, tris, seed).build(progress),
    })
}

fn assembly(kind: Kind, tris: usize, seed: u64) -> parts::Assembly {
    let (parts, grids) = plan_parts(kind, tris, seed);
    parts::Assembly::new(parts, grids)
}

/// The counts of a mesh written by [`generate_to_ply`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Written {
    /// Vertices written.
    pub vertices: u64,
    /// Triangles written.
    pub triangles: u64,
}

/// Why [`generate_to_ply`] failed.
#[derive(Debug, thiserror::Error)]
pub enum GenWriteError {
    /// The arguments name no scene that can be generated.
    #[error(transparent)]
    Gen(#[from] GenError),
    /// Writing failed.
    #[error(transparent)]
    Io(#[from] io::Error),
}

/// Generates a `kind` scene like [`generate`] and writes it to `out` as
/// binary little-endian PLY: the same bytes as [`crate::mesh::save`] of
/// the mesh [`generate`] returns for these arguments. The kinds that
/// stream ([`Kind::streams`]) are computed and written batch by batch in
/// a few MiB of memory, and accept up to [`MAX_STREAMED_TRIS`] triangles;
/// the isosurface is generated in memory, then written, and accepts up to
/// [`MAX_TRIS`]. `progress(done, total)` is called about every 1 % of the
/// work (and at least every 262 144 vertices or triangles when streaming),
/// with `done == total` at the end; for a streamed kind the work includes
/// the writing.
///
/// `out` gets the bytes in writes of about 64 KiB; give it a file through
/// a [`std::io::BufWriter`] or [`crate::files::AtomicFile`], which `cbvh
/// gen` uses so that a run that fails or is killed leaves nothing under
/// the file's name.
///
/// # Errors
/// [`GenWriteError::Gen`] for a triangle count out of range,
/// [`GenWriteError::Io`] when `out` fails.
pub fn generate_to_ply<W: Write + Send>(
    kind: Kind,
    tris: usize,
    seed: u64,
    out: W,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Written, GenWriteError> {
    let ply = if kind.streams() {
        check_max(kind, tris, MAX_STREAMED_TRIS)?;
        let scene = assembly(kind, tris, seed);
        let mut ply = crate::mesh::PlyWriter::new(out, scene.vertices(), scene.triangles())?;
        scene.write_ply(&mut ply, progress)?;
        ply
    } else {
        let mesh = generate(kind, tris, seed, progress)?;
        let mut ply = crate::mesh::PlyWriter::new(
            out,
            mesh.vertices.len() as u64,
            mesh.triangles.len() as u64,
        )?;
        ply.write_vertices(&mesh.vertices)?;
        ply.write_triangles(&mesh.triangles)?;
        ply
    };
    let (vertices, triangles) = ply.counts();
    ply.finish()?;
    Ok(Written {
        vertices,
        triangles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streamed_counts_hold_up_to_the_streaming_maximum() {
        // Above MAX_TRIS only generate_to_ply plans; sweep that range in
        // 1 % steps, exactly as the formula promises.
        for kind in Kind::ALL.into_iter().filter(|k| k.streams()) {
            let mut t = MAX_TRIS as f64;
            while t <= MAX_STREAMED_TRIS as f64 {
                let tris = t as usize;
                let scene = assembly(kind, tris, 1);
                let got = scene.triangles() as f64;
                assert!((got / t - 1.0).abs() < 0.01, "{kind} {tris}: plans {got}");
                assert!(scene.vertices() < u64::from(u32::MAX) / 2);
                t *= 1.01;
            }
        }
    }

    #[test]
    fn streaming_limits() {
        let mut sink = Vec::new();
        for kind in Kind::ALL {
            let max = if kind.streams() {
                MAX_STREAMED_TRIS
            } else {
                MAX_TRIS
            };
            let err = generate_to_ply(kind, max + 1, 0, &mut sink, &mut |_, _| {}).unwrap_err();
            assert!(
                matches!(err, GenWriteError::Gen(GenError::TrisOutOfRange { max: m, .. }) if m == max),
                "{kind}: {err}"
            );
        }
        assert!(sink.is_empty());
    }
}
