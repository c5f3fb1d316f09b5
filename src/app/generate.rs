//! `cbvh gen KIND --tris N [--seed S] -o FILE`

use std::path::PathBuf;
use std::time::Instant;

use crate::files::{AtomicFile, IoError};
use crate::scene::{GenWriteError, Kind};

use super::CliResult;
use super::values::whole;

/// Arguments of `cbvh gen`.
#[derive(clap::Args, Debug)]
pub struct GenArgs {
    /// What to generate: statue, turbine, plant, robot or isosurface.
    pub kind: Kind,
    /// Requested triangle count (the result is within 5 %; default: the
    /// kind's default), from 1 000 to the limit of the output's form (see
    /// `--output`).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub tris: Option<usize>,
    /// Seed: the same seed gives the same mesh.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true,
          value_parser = whole::<u64>(0, u64::MAX))]
    pub seed: u64,
    /// Output file, .ply (binary) or .obj. PLY is written as it is
    /// generated, in bounded memory, for every kind but the isosurface (up
    /// to 1 000 000 000 triangles; the isosurface and .obj files: 200 000 000).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `cbvh gen`. A .ply file is written by [`crate::scene::generate_to_ply`]
/// (streamed, in bounded memory, for every kind but the isosurface), an
/// .obj file from the mesh in memory; either atomically, through a
/// temporary file beside the output, so that a failed or killed run leaves
/// nothing under the output's name.
pub fn run(a: GenArgs) -> CliResult {
    // Every flag before spending time generating: the output's place and
    // extension, and the count against what the generator makes (to a
    // PLY file, the kinds that stream go further than a mesh in memory).
    super::check_output("--output", &a.output, &["ply", "obj"])?;
    let format = crate::mesh::Format::from_path(&a.output)?;
    let tris = a.tris.unwrap_or_else(|| crate::scene::default_tris(a.kind));
    let max = if format == crate::mesh::Format::Ply && a.kind.streams() {
        crate::scene::MAX_STREAMED_TRIS
    } else {
        crate::scene::MAX_TRIS
    };
    super::check_tris("--tris", a.kind, tris, max)?;
    super::clear_stale(&a.output);
    if format == crate::mesh::Format::Ply {
        return write_ply(&a, tris);
    }
    let t0 = Instant::now();
    let mesh = super::generate(a.kind, tris, a.seed, "generating")?;
    let gen_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    crate::mesh::save(&mesh, &a.output)?;
    eprintln!(
        "{}: {} triangles, {} vertices ({} requested, seed {}); generated in {:.2} s ({:.2} M triangles/s), written in {:.2} s",
        a.output.display(),
        mesh.triangle_count(),
        mesh.vertex_count(),
        tris,
        a.seed,
        gen_s,
        mesh.triangle_count() as f64 / gen_s / 1e6,
        t1.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `cbvh gen ... -o FILE.ply`: generates and writes in one pass, with a
/// progress bar over both.
fn write_ply(a: &GenArgs, tris: usize) -> CliResult {
    let path = &a.output;
    let io_err = IoError::at(path);
    let t0 = Instant::now();
    // Created first: an unwritable directory fails before any work.
    let mut out = AtomicFile::create(path).map_err(io_err)?;
    let pb = super::progress_bar("generating", 1);
    let written =
        crate::scene::generate_to_ply(a.kind, tris, a.seed, &mut out, &mut |done, total| {
            pb.set_length(total);
            pb.set_position(done);
        });
    pb.finish_and_clear();
    let written = match written {
        Ok(w) => w,
        Err(GenWriteError::Io(e)) => return Err(io_err(e).into()),
        Err(e) => return Err(e.into()),
    };
    out.commit().map_err(io_err)?;
    let s = t0.elapsed().as_secs_f64();
    eprintln!(
        "{}: {} triangles, {} vertices ({} requested, seed {}); generated and written in {:.2} s ({:.2} M triangles/s{})",
        path.display(),
        written.triangles,
        written.vertices,
        tris,
        a.seed,
        s,
        written.triangles as f64 / s / 1e6,
        if a.kind.streams() { ", streamed" } else { "" }
    );
    Ok(())
}
