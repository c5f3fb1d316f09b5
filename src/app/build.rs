//! `cbvh build (MESH | --gen KIND --tris N) --codec C [--layout L] [--json]`

use std::time::Instant;

use crate::build::{BuildOptions, Layout, build};
use crate::codec::{AnyCodec, ByteSize, CodecKind, OpenOptions};

use super::{CliResult, CodecFlags, MeshSource, Structure, progress_bar};

/// Arguments of `cbvh build`.
#[derive(clap::Args, Debug)]
pub struct BuildArgs {
    /// Where the mesh comes from.
    #[command(flatten)]
    pub source: MeshSource,
    /// The codec to build.
    #[arg(long, value_parser = Structure::parser(), default_value_t = Structure::Codec(CodecKind::Plain))]
    pub codec: Structure,
    /// Node layout: depth-first, van-emde-boas or cache-efficient.
    #[arg(long, default_value = "depth-first")]
    pub layout: Layout,
    /// The codecs' settings.
    #[command(flatten)]
    pub settings: CodecFlags,
    /// Write the codec's self-contained file here (any codec but parry);
    /// `cbvh info`, `cbvh render`, `cbvh build` and the sims open it like a
    /// mesh, and `cbvh::codec::AnyCodec::open` / `CbvhShape::open` in a
    /// program.
    #[arg(short, long)]
    pub output: Option<std::path::PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Peak resident memory of this process so far (Linux `VmHWM`), in bytes.
pub fn peak_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The canonical tree with the arguments' layout and leaf size, with a
/// progress bar on a terminal.
fn build_with_progress(
    mesh: &crate::Mesh,
    a: &BuildArgs,
) -> Result<crate::CanonicalBvh, crate::build::BuildError> {
    let opts = BuildOptions {
        layout: a.layout,
        max_leaf_triangles: usize::from(a.settings.leaf_size),
        ..Default::default()
    };
    let pb = progress_bar("building", mesh.triangle_count() as u64);
    let bvh = build(mesh, &opts, &|done, total| {
        pb.set_length(total);
        pb.set_position(done);
    });
    pb.finish_and_clear();
    bvh
}

/// Runs `cbvh build`.
pub fn run(a: BuildArgs) -> CliResult {
    if a.output.is_some() && a.codec == Structure::Parry {
        return Err(format!(
            "--codec parry has no cbvh file to write: choose --codec {} with -o",
            CodecKind::names(" or ")
        )
        .into());
    }
    // The codecs check their settings before any work.
    let kinds = match a.codec {
        Structure::Codec(kind) => vec![kind],
        Structure::Parry => vec![],
    };
    let options = a.settings.options(&kinds)?;
    let (mesh, name) = a.source.load()?;
    let tris = mesh.triangle_count();
    let mesh_rss = peak_rss_bytes();
    let t0 = Instant::now();
    let (parts, layout, extra): (Vec<(&str, usize)>, Option<Layout>, serde_json::Value) =
        match a.codec {
            Structure::Codec(kind) => {
                let bvh = build_with_progress(&mesh, &a)?;
                let pb = progress_bar("encoding", 0);
                let codec =
                    AnyCodec::encode_with_progress(kind, &bvh, &mesh, &options, &|done, total| {
                        pb.set_length(total);
                        pb.set_position(done);
                    });
                pb.finish_and_clear();
                let codec = codec?;
                drop(bvh);
                if let Some(path) = &a.output {
                    codec.save(path)?;
                    // Read it back (and verify it) so that a bad file is
                    // caught here.
                    AnyCodec::open(path, &OpenOptions::default())?;
                }
                let extra: serde_json::Map<String, serde_json::Value> = codec
                    .build_fields()
                    .into_iter()
                    .map(|(k, v)| (k.to_string(), v))
                    .collect();
                (codec.bytes_by_part(), Some(a.layout), extra.into())
            }
            Structure::Parry => {
                let t = crate::parry::parry_trimesh(&mesh)
                    .map_err(|e| format!("parry could not build a TriMesh: {e:?}"))?;
                (
                    crate::parry::trimesh_bytes_by_part(&t),
                    None,
                    serde_json::json!({}),
                )
            }
        };
    let secs = t0.elapsed().as_secs_f64();
    let total: usize = parts.iter().map(|p| p.1).sum();
    let per_tri = total as f64 / tris.max(1) as f64;
    let peak = peak_rss_bytes();
    let threads = rayon::current_num_threads();
    if a.json {
        let by_part: serde_json::Map<String, serde_json::Value> = parts
            .iter()
            .map(|(k, v)| (k.to_string(), (*v).into()))
            .collect();
        let mut v = serde_json::json!({
            "mesh": name,
            "triangles": tris,
            "codec": a.codec.name(),
            "layout": layout.map(|l| l.name()),
            "build_seconds": secs,
            "triangles_per_second": tris as f64 / secs,
            "threads": threads,
            "bytes_total": total,
            "bytes_per_triangle": per_tri,
            "bytes_by_part": by_part,
            "peak_rss_bytes": peak,
            "mesh_rss_bytes": mesh_rss,
        });
        if let (Some(o), serde_json::Value::Object(e)) = (v.as_object_mut(), extra) {
            o.extend(e);
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("mesh              {name}");
        println!("triangles         {tris}");
        println!(
            "codec             {}{}",
            a.codec.name(),
            layout.map(|l| format!(" ({l} layout)")).unwrap_or_default()
        );
        println!(
            "build             {secs:.3} s ({:.2} M triangles/s on {threads} threads)",
            tris as f64 / secs / 1e6
        );
        if let Some(o) = extra.as_object() {
            for (k, v) in o {
                println!("{k:<17} {v}");
            }
        }
        for (k, v) in &parts {
            println!(
                "  {k:<15} {v:>14} bytes  {:>8.2} B/triangle",
                *v as f64 / tris.max(1) as f64
            );
        }
        println!("total             {total} bytes, {per_tri:.2} B/triangle");
        if let Some(p) = peak {
            println!(
                "peak memory       {:.1} MiB (after loading the mesh: {:.1} MiB)",
                p as f64 / 1048576.0,
                mesh_rss.unwrap_or(0) as f64 / 1048576.0
            );
        }
    }
    Ok(())
}
