//! `cbvh info FILE [--json]`

use std::path::PathBuf;

use cbvh::mesh::{MeshStats, load_with_detail};

use super::CliResult;

/// Arguments of `cbvh info`.
#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    /// The mesh file (.off, .ply, .obj, .stl).
    pub file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `cbvh info`.
pub fn run(a: InfoArgs) -> CliResult {
    let (mesh, detail) = load_with_detail(&a.file)?;
    let s = MeshStats::of(&mesh);
    if a.json {
        let v = serde_json::json!({
            "file": a.file.display().to_string(),
            "triangles": s.triangles,
            "vertices": s.vertices,
            "bounds_min": s.bounds_min,
            "bounds_max": s.bounds_max,
            "degenerate_triangles": s.degenerate_triangles,
            "boundary_edges": s.boundary_edges,
            "format": detail.format.name(),
            "encoding": detail.to_string(),
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let f = |v: [f32; 3]| format!("({}, {}, {})", v[0], v[1], v[2]);
        println!("file                  {}", a.file.display());
        println!("format                {detail}");
        println!("triangles             {}", s.triangles);
        println!("vertices              {}", s.vertices);
        println!("bounds min            {}", f(s.bounds_min));
        println!("bounds max            {}", f(s.bounds_max));
        println!("degenerate triangles  {}", s.degenerate_triangles);
        println!(
            "boundary edges        {}{}",
            s.boundary_edges,
            if s.boundary_edges == 0 {
                " (closed)"
            } else {
                " (open)"
            }
        );
    }
    Ok(())
}
