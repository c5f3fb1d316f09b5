//! `cbvh info FILE [--no-verify] [--json]`: a mesh file's statistics, or a
//! codec file's header, sizes by part and verification.

use std::path::PathBuf;
use std::time::Instant;

use crate::codec::{AnyCodec, ByteSize, CodecKind, OpenOptions};
use crate::mesh::{MeshStats, load_with_detail};

use super::CliResult;

/// Arguments of `cbvh info`.
#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    /// A mesh file (.off, .ply, .obj, .stl) or a cbvh codec file (written by
    /// `cbvh build ... -o FILE`, recognised by its content).
    pub file: PathBuf,
    /// Codec files: do not run `verify` (which proves every node, box,
    /// leaf and checksum).
    #[arg(long)]
    pub no_verify: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `cbvh info`.
pub fn run(a: InfoArgs) -> CliResult {
    if CodecKind::of_file(&a.file).is_some() {
        return codec_info(&a);
    }
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

/// `cbvh info` of a codec file: opened (O(header) for RACBVH), then
/// verified unless `--no-verify`, each timed.
fn codec_info(a: &InfoArgs) -> CliResult {
    let file_bytes = std::fs::metadata(&a.file)?.len();
    let t0 = Instant::now();
    // A cache that holds the whole decompressed tree (1 GiB at most), so
    // verify decodes each cluster once.
    let opts = OpenOptions {
        verify: false,
        cache_budget_bytes: 1 << 30,
    };
    let codec = AnyCodec::open(&a.file, &opts)?;
    let open_s = t0.elapsed().as_secs_f64();
    let verify_s = if a.no_verify {
        None
    } else {
        let t = Instant::now();
        codec
            .verify()
            .map_err(|e| format!("{}: verify failed: {e}", a.file.display()))?;
        Some(t.elapsed().as_secs_f64())
    };
    let tris = codec.triangle_count();
    let parts = codec.bytes_by_part();
    let per_tri = |b: u64| b as f64 / tris.max(1) as f64;
    if a.json {
        let fields = super::json_object(codec.header_fields());
        let by_part = super::json_object(parts.iter().copied());
        let v = serde_json::json!({
            "file": a.file.display().to_string(),
            "codec": codec.name(),
            "header": fields,
            "file_bytes": file_bytes,
            "bytes_per_triangle": per_tri(file_bytes),
            "bytes_by_part": by_part,
            "open_seconds": open_s,
            "verify_seconds": verify_s,
            "verified": verify_s.is_some(),
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("file                  {}", a.file.display());
        for (k, v) in codec.header_fields() {
            println!("{k:<21} {v}");
        }
        println!(
            "file size             {file_bytes} bytes, {:.2} B/triangle",
            per_tri(file_bytes)
        );
        for (k, v) in &parts {
            println!(
                "  {k:<19} {v:>12} bytes  {:>8.2} B/triangle",
                per_tri(*v as u64)
            );
        }
        println!("open                  {:.3} ms", open_s * 1e3);
        match verify_s {
            Some(s) => println!("verify                ok, {:.3} ms", s * 1e3),
            None => println!("verify                skipped (--no-verify)"),
        }
    }
    Ok(())
}
