//! `cbvh gen KIND --tris N [--seed S] -o FILE`

use std::path::PathBuf;
use std::time::Instant;

use crate::scene::Kind;

use super::CliResult;

/// Arguments of `cbvh gen`.
#[derive(clap::Args, Debug)]
pub struct GenArgs {
    /// What to generate: statue, turbine, plant, robot or isosurface.
    pub kind: Kind,
    /// Requested triangle count (the result is within 5 %; default: the kind's default).
    #[arg(long)]
    pub tris: Option<usize>,
    /// Seed: the same seed gives the same mesh.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output file, .ply (binary) or .obj.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `cbvh gen`.
pub fn run(a: GenArgs) -> CliResult {
    // Check the output extension before spending time generating.
    match crate::mesh::Format::from_path(&a.output)? {
        crate::mesh::Format::Ply | crate::mesh::Format::Obj => {}
        _ => {
            return Err(
                format!("{}: can only write .ply or .obj files", a.output.display()).into(),
            );
        }
    }
    let tris = a.tris.unwrap_or_else(|| crate::scene::default_tris(a.kind));
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
