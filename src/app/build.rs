//! `cbvh build (MESH | --gen KIND --tris N) --codec C [--layout L] [--json]`

use std::time::Instant;

use crate::build::{BuildOptions, Layout, build};
use crate::codec::{AnyCodec, ByteSize, CodecKind, OpenOptions};

use super::values::{Checked, whole, whole_in};
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
    /// Memory the build may use, in MiB (default: half the machine's).
    /// A model whose in-memory build would need more is built out of core
    /// by the codecs that can (marked so in `--codec`'s list) and refused
    /// by the others, before any work. Out of core, the chunks are as large as this allows; without
    /// it, as large as 32 bytes a triangle of the model allow beside the
    /// vertices and flags the build holds (within half the machine's
    /// memory): about 40 bytes a triangle in all for a closed mesh, at any
    /// size. At least 1, and at most the machine's memory (`MemTotal` in
    /// /proc/meminfo; where that cannot be read, 16 TiB): a budget the
    /// machine does not have would let a build go over its memory.
    #[arg(long, value_name = "MIB", allow_negative_numbers = true, value_parser = memory_mib())]
    pub memory_mib: Option<u64>,
    /// Build out of core whatever the model's size (a codec that builds
    /// out of core, marked so in `--codec`'s list; from a mesh file, with
    /// `-o`).
    #[arg(long)]
    pub out_of_core: bool,
    /// Out of core: the most triangles a chunk holds, instead of what the
    /// memory budget allows (smaller chunks cost quality at the top of the
    /// tree; for tests and experiments). From 1 to 4 294 967 295 (a chunk
    /// is built in memory, its triangles numbered by `u32`), and a chunk
    /// of that many of the model's triangles must be buildable within the
    /// memory budget (about 260 bytes a triangle).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u64>(1, MAX_CHUNK_TRIANGLES))]
    pub chunk_triangles: Option<u64>,
}

/// The most `--memory-mib` where the machine's memory cannot be read
/// (not Linux): 16 TiB.
pub const MEMORY_MIB_UNKNOWN_MACHINE: u64 = 16 << 20;

/// `--memory-mib`'s parser: from 1 to the machine's memory in MiB
/// ([`machine_memory`](super::machine_memory), read when the flag is
/// given), or to [`MEMORY_MIB_UNKNOWN_MACHINE`] where that cannot be read.
fn memory_mib() -> Checked<u64> {
    Checked::new(|flag, value| {
        let mib = whole_in(flag, value, 1, u64::MAX)?;
        let (max, what) = match super::machine_memory() {
            Some(bytes) => (bytes >> 20, "this machine has (MemTotal in /proc/meminfo)"),
            None => (
                MEMORY_MIB_UNKNOWN_MACHINE,
                "(16 TiB) allowed where the machine's memory cannot be read",
            ),
        };
        if mib > max {
            return Err(format!(
                "{mib} MiB is more than the {max} MiB {what}: {flag} takes a whole number from 1 \
                 to {max}"
            ));
        }
        Ok(mib)
    })
}

/// The largest `--chunk-triangles`: a chunk is built in memory as a mesh,
/// its triangles numbered by `u32`.
const MAX_CHUNK_TRIANGLES: u64 = u32::MAX as u64;

/// Bytes a triangle the in-memory build holds at its peak (the mesh, the
/// canonical tree with its boxes, the codec's encoder; measured 232 on a
/// 50 M-triangle statue for hcc-ooc): how the build chooses between memory
/// and chunks, and how large a chunk is.
const IN_MEMORY_BYTES_A_TRIANGLE: u64 = 260;

/// The memory an out-of-core build gives its chunks by default, in bytes
/// a triangle of the model (see `--memory-mib`).
const CHUNK_BYTES_A_TRIANGLE: u64 = 32;

/// The build's memory budget in bytes.
fn budget(a: &BuildArgs) -> u64 {
    a.memory_mib.map_or_else(
        || super::machine_memory().map_or(8 << 30, |m| m / 2),
        |m| m.saturating_mul(1 << 20),
    )
}

/// The codecs that build out of core ([`CodecKind::builds_out_of_core`]).
fn out_of_core_codecs() -> impl Iterator<Item = CodecKind> {
    CodecKind::ALL
        .iter()
        .copied()
        .filter(|k| k.builds_out_of_core())
}

/// How an out-of-core build goes: its codec, input, output, chunk size.
struct OutOfCore {
    codec: CodecKind,
    input: std::path::PathBuf,
    output: std::path::PathBuf,
    budget: u64,
    chunk_triangles: u64,
    estimated: (u64, u64),
}

/// `b` bytes in GiB, or MiB below one GiB.
fn size_text(b: u64) -> String {
    if b < 1 << 30 {
        format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64)
    } else {
        format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
    }
}

/// The in-memory build's plan (none), unless `--chunk-triangles` asks for
/// chunks that will not be made: then an error saying `why`.
fn in_memory(a: &BuildArgs, why: &str) -> Result<Option<OutOfCore>, Box<dyn std::error::Error>> {
    match a.chunk_triangles {
        Some(n) => {
            Err(format!("--chunk-triangles {n} sizes an out-of-core build's chunks: {why}").into())
        }
        None => Ok(None),
    }
}

/// Whether (and how) `a` builds out of core; an error for a model too
/// large for the in-memory path of a codec that has no other.
fn plan(a: &BuildArgs) -> Result<Option<OutOfCore>, Box<dyn std::error::Error>> {
    let budget = budget(a);
    let ooc = match a.codec {
        Structure::Codec(k) if k.builds_out_of_core() => Some(k),
        _ => None,
    };
    let file = a
        .source
        .mesh
        .as_ref()
        .filter(|p| CodecKind::of_file(p).is_none());
    let (estimated, what) = match (file, a.source.gen_kind) {
        (Some(p), _) => (crate::mesh::estimate_counts(p)?, p.display().to_string()),
        (None, Some(kind)) => {
            let t = a
                .source
                .tris
                .unwrap_or_else(|| crate::scene::default_tris(kind)) as u64;
            ((t / 2, t), format!("the generated {kind}"))
        }
        (None, None) => return in_memory(a, "a codec file is not rebuilt in chunks"),
    };
    let need = estimated.1.saturating_mul(IN_MEMORY_BYTES_A_TRIANGLE);
    let big = need > budget;
    if !a.out_of_core && !big {
        return in_memory(
            a,
            &format!(
                "{what} builds in memory (about {} of the {} budget); add --out-of-core to build \
                 it in chunks",
                size_text(need),
                size_text(budget)
            ),
        );
    }
    let Some(codec) = ooc else {
        let names: Vec<_> = out_of_core_codecs().map(|k| k.name()).collect();
        let why = if a.out_of_core {
            format!("--codec {} does not build out of core", a.codec)
        } else {
            format!(
                "{what} has about {} triangles: building it in memory needs about {}, over the \
                 {} budget (--memory-mib)",
                estimated.1,
                size_text(need),
                size_text(budget)
            )
        };
        let flags: Vec<_> = names.iter().map(|n| format!("--codec {n}")).collect();
        return Err(format!(
            "{why}; of the codecs only {} build out of core ({}, with -o FILE)",
            names.join(" and "),
            flags.join(" or ")
        )
        .into());
    };
    let Some(input) = file else {
        return Err(format!(
            "{what} would need about {} to build in memory, over the {} budget: an out-of-core \
             build reads a mesh file; write the model with `cbvh gen ... -o FILE.ply` first",
            size_text(need),
            size_text(budget)
        )
        .into());
    };
    let Some(output) = a.output.clone() else {
        return Err("an out-of-core build writes its file: give -o FILE".into());
    };
    // Held for the whole build: the vertices (12 bytes each), a flag byte
    // a triangle, a bit a vertex, and the rest (chunks' high-level trees,
    // buffers) at about a byte a triangle.
    let resident = estimated.0 * 12 + estimated.1 * 2 + (16 << 20);
    if resident.saturating_mul(5) > budget.saturating_mul(4) {
        return Err(format!(
            "{what}: its vertices and per-triangle flags alone need about {}, most of the {} \
             budget; raise --memory-mib",
            size_text(resident),
            size_text(budget)
        )
        .into());
    }
    // A chunk is built in memory: one of as many of the model's triangles
    // as --chunk-triangles asks must fit the budget.
    if let Some(n) = a.chunk_triangles {
        let chunk_bytes = n
            .min(estimated.1)
            .saturating_mul(IN_MEMORY_BYTES_A_TRIANGLE);
        if chunk_bytes > budget {
            return Err(format!(
                "--chunk-triangles {n}: building a chunk of {} triangles in memory needs about \
                 {}, over the {} budget (--memory-mib): give fewer triangles a chunk, or none \
                 to size chunks from the budget",
                n.min(estimated.1),
                size_text(chunk_bytes),
                size_text(budget)
            )
            .into());
        }
    }
    // Chunks as large as the budget allows; without a budget given, as
    // large as 32 bytes a triangle above what the build holds anyway allow
    // (40 a triangle in all for a closed mesh; small chunks cost little at
    // the top of the tree: see the note of issue 32).
    let budget = match a.memory_mib {
        Some(_) => budget,
        None => budget.min(resident + estimated.1.saturating_mul(CHUNK_BYTES_A_TRIANGLE)),
    };
    let chunk_triangles = a
        .chunk_triangles
        .unwrap_or((budget - resident) / IN_MEMORY_BYTES_A_TRIANGLE)
        .max(1);
    Ok(Some(OutOfCore {
        codec,
        input: input.clone(),
        output,
        budget,
        chunk_triangles,
        estimated,
    }))
}

/// The out-of-core build (see [`crate::build::chunked`] and
/// [`Codec::encode_streamed`](crate::codec::Codec::encode_streamed)).
fn run_out_of_core(a: &BuildArgs, p: OutOfCore) -> CliResult {
    use crate::build::chunked::{ChunkOptions, ChunkedMesh};
    let options = a.settings.options(&[p.codec])?;
    super::clear_stale(&p.output);
    let temp = {
        let name = p
            .output
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        p.output
            .with_file_name(format!(".{name}.cbvh-build-{}", std::process::id()))
    };
    let t0 = Instant::now();
    let bar = Phases::new();
    let input = ChunkedMesh::from_path(
        &p.input,
        &ChunkOptions {
            chunk_triangles: p.chunk_triangles,
            temp_dir: temp,
        },
        &|phase, done, total| bar.show(phase, done, total.max(p.estimated.1)),
    )?;
    let read_s = t0.elapsed().as_secs_f64();
    let build_options = BuildOptions {
        layout: a.layout,
        max_leaf_triangles: usize::from(a.settings.leaf_size),
        ..Default::default()
    };
    let t1 = Instant::now();
    let show = |phase: &str, done: u64, total: u64| bar.show(phase, done, total);
    let (mesh, out) = (&input, p.output.as_path());
    let made = options
        .encode_streamed(p.codec, mesh, &build_options, out, &show)
        .expect("plan() chose a codec that builds out of core")?;
    let build_s = t1.elapsed().as_secs_f64();
    let tris = input.triangle_count();
    let vertices = input.vertices.len();
    drop(input);
    // Read it back (and verify it) so that a bad file is caught here,
    // with a cache inside the budget.
    let t2 = Instant::now();
    bar.show("verifying", 0, 0);
    let codec = AnyCodec::open(
        &p.output,
        &OpenOptions {
            verify: true,
            cache_budget_bytes: (p.budget / 2) as usize,
        },
    )?;
    drop(codec);
    let verify_s = t2.elapsed().as_secs_f64();
    bar.finish();
    let secs = t0.elapsed().as_secs_f64();
    let file_bytes = std::fs::metadata(&p.output).map(|m| m.len()).unwrap_or(0);
    let peak = peak_rss_bytes();
    let threads = rayon::current_num_threads();
    let per_tri = file_bytes as f64 / tris.max(1) as f64;
    let parts = &made.parts;
    if a.json {
        let by_part = super::json_object(parts.iter().copied());
        let mut v = serde_json::json!({
            "mesh": p.input.display().to_string(),
            "triangles": tris,
            "vertices": vertices,
            "codec": p.codec.name(),
            "out_of_core": true,
            "layout": a.layout.name(),
            "memory_budget_bytes": p.budget,
            "chunk_triangles": p.chunk_triangles,
            "chunks": made.chunks,
            "largest_chunk": made.largest_chunk,
            "paired_edges": made.paired_edges,
            "read_seconds": read_s,
            "build_seconds": build_s,
            "verify_seconds": verify_s,
            "total_seconds": secs,
            "triangles_per_second": tris as f64 / (read_s + build_s),
            "threads": threads,
            "bytes_total": file_bytes,
            "bytes_per_triangle": per_tri,
            "bytes_by_part": by_part,
            "peak_rss_bytes": peak,
            "peak_rss_bytes_per_triangle": peak.map(|b| b as f64 / tris.max(1) as f64),
        });
        if let Some(o) = v.as_object_mut() {
            for (k, n) in &made.counts {
                o.insert(k.to_string(), (*n).into());
            }
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("mesh              {}", p.input.display());
        println!("triangles         {tris} ({vertices} vertices)");
        println!(
            "codec             {} ({} layout), built out of core",
            p.codec.name(),
            a.layout
        );
        let extra: String = made
            .counts
            .iter()
            .map(|(k, n)| format!("{n} {k}, "))
            .collect();
        println!(
            "chunks            {} of at most {} triangles (largest {}), {extra}{} edges paired across chunks",
            made.chunks, p.chunk_triangles, made.largest_chunk, made.paired_edges
        );
        println!(
            "time              {secs:.1} s: read and grouped {read_s:.1} s, built and coded {build_s:.1} s \
             ({:.2} M triangles/s on {threads} threads), verified {verify_s:.1} s",
            tris as f64 / (read_s + build_s) / 1e6
        );
        for (k, v) in parts {
            println!(
                "  {k:<15} {v:>14.0} bytes  {:>8.2} B/triangle",
                v / tris.max(1) as f64
            );
        }
        println!(
            "total             {file_bytes} bytes, {per_tri:.2} B/triangle, written to {}",
            p.output.display()
        );
        if let Some(b) = peak {
            println!(
                "peak memory       {:.1} MiB, {:.1} B/triangle (budget {:.0} MiB)",
                b as f64 / 1048576.0,
                b as f64 / tris.max(1) as f64,
                p.budget as f64 / 1048576.0
            );
        }
    }
    Ok(())
}

/// A progress bar over the phases of a long job: one bar a phase on a
/// terminal, one line a phase otherwise (for logs).
struct Phases {
    state: std::sync::Mutex<(String, Option<indicatif::ProgressBar>, Instant)>,
}

impl Phases {
    fn new() -> Self {
        Self {
            state: std::sync::Mutex::new((String::new(), None, Instant::now())),
        }
    }

    fn show(&self, phase: &str, done: u64, total: u64) {
        let Ok(mut s) = self.state.lock() else {
            return;
        };
        if s.0 != phase {
            if let Some(pb) = s.1.take() {
                pb.finish_and_clear();
            }
            if !s.0.is_empty() {
                eprintln!("{:>12} done in {:.1} s", s.0, s.2.elapsed().as_secs_f64());
            }
            s.0 = phase.to_string();
            s.2 = Instant::now();
            s.1 = Some(progress_bar(phase, total));
        }
        if let Some(pb) = &s.1 {
            pb.set_length(total.max(done));
            pb.set_position(done);
        }
    }

    fn finish(&self) {
        self.show("", 0, 0);
        if let Ok(mut s) = self.state.lock()
            && let Some(pb) = s.1.take()
        {
            pb.finish_and_clear();
        }
    }
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
    // Every flag before any work: the output's place, the generator's count.
    if let Some(path) = &a.output {
        super::check_output("--output", path, &[])?;
    }
    a.source.check()?;
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
    if let Some(p) = plan(&a)? {
        return run_out_of_core(&a, p);
    }
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
                let extra = super::json_object(codec.build_fields());
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
        let by_part = super::json_object(parts.iter().copied());
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
