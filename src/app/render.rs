//! `cbvh render (MESH | --gen KIND --tris N) --codec C [--width W --height H
//! --lights L --reflect-depth D --threads T] -o out.png [--json]
//! [--turntable N --turntable-out anim.png]`

use std::path::PathBuf;
use std::time::Instant;

use crate::Mesh;
use crate::build::{BuildOptions, Layout, build};
use crate::codec::{AnyCodec, AnyOptions, CodecKind};
use crate::render::{
    Image, RayTarget, RenderOptions, RenderStats, Scene, VertexNormals, any_target, render,
    render_turntable, save_animation,
};

use super::values::whole;
use super::{CliResult, Loaded, MeshSource, Structure, progress_bar};

/// Arguments of `cbvh render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Where the mesh comes from.
    #[command(flatten)]
    pub source: MeshSource,
    /// The structure to trace rays through (default: a codec file's own
    /// codec, plain for a mesh; a codec file given another codec is
    /// re-encoded from its stored mesh).
    #[arg(long, value_parser = Structure::parser())]
    pub codec: Option<Structure>,
    /// Node layout of cbvh codecs: depth-first, van-emde-boas or cache-efficient.
    #[arg(long, default_value = "depth-first")]
    pub layout: Layout,
    /// Image width in pixels (1 to 16384).
    #[arg(long, default_value_t = 800, allow_negative_numbers = true,
          value_parser = whole::<u32>(1, 16384))]
    pub width: u32,
    /// Image height in pixels (1 to 16384).
    #[arg(long, default_value_t = 600, allow_negative_numbers = true,
          value_parser = whole::<u32>(1, 16384))]
    pub height: u32,
    /// Number of point lights (0 to 32), each with shadow rays.
    #[arg(long, default_value_t = 3, allow_negative_numbers = true,
          value_parser = whole::<u32>(0, 32))]
    pub lights: u32,
    /// Mirror reflection bounces (0 to 16).
    #[arg(long, default_value_t = 2, allow_negative_numbers = true,
          value_parser = whole::<u32>(0, 16))]
    pub reflect_depth: u32,
    /// Primary rays only: no shadow rays and no reflections.
    #[arg(long)]
    pub primary_only: bool,
    /// Render threads (a local rayon pool; at most 4 × the machine's
    /// hardware threads); default: all cores.
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u32>(1, u32::MAX.into()))]
    pub threads: Option<u32>,
    /// Camera direction around the vertical axis, degrees (0: from +z).
    #[arg(long, default_value_t = 25.0, allow_negative_numbers = true)]
    pub azimuth: f32,
    /// Camera elevation above the horizon, degrees (-89 to 89).
    #[arg(long, default_value_t = 18.0, allow_negative_numbers = true)]
    pub elevation: f32,
    /// Output PNG file.
    #[arg(short = 'o', long, value_name = "PNG")]
    pub output: PathBuf,
    /// Also render an animated turntable of N frames (camera and lights
    /// circling the scene), 1 to 3600. The frames are held in memory until
    /// they are written: N × width × height × 3 bytes must be within half
    /// the machine's memory, checked before any work.
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u32>(1, 3600))]
    pub turntable: Option<u32>,
    /// Where to write the turntable: `.png` (animated PNG, lossless) or
    /// `.gif` (256 colours a frame); default: OUT with `-turntable` added
    /// to its name.
    #[arg(long, value_name = "PNG|GIF", requires = "turntable")]
    pub turntable_out: Option<PathBuf>,
    /// Turntable frames per second.
    #[arg(long, default_value_t = 24, allow_negative_numbers = true,
          value_parser = whole::<u16>(1, 1000))]
    pub fps: u16,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Builds the structure `codec` over `mesh` (codecs with a cache get one
/// that holds the whole tree).
fn make_target(
    codec: Structure,
    mesh: &Mesh,
    layout: Layout,
) -> Result<Box<dyn RayTarget>, Box<dyn std::error::Error>> {
    Ok(match codec {
        Structure::Codec(kind) => {
            let options = AnyOptions::default().with_cache_budget(usize::MAX);
            any_target(AnyCodec::encode(
                kind,
                &build_tree(mesh, layout)?,
                mesh,
                &options,
            )?)
        }
        Structure::Parry => Box::new(
            crate::parry::parry_trimesh(mesh)
                .map_err(|e| format!("parry could not build a TriMesh: {e:?}"))?,
        ),
    })
}

fn build_tree(
    mesh: &Mesh,
    layout: Layout,
) -> Result<crate::CanonicalBvh, crate::build::BuildError> {
    let pb = progress_bar("building", mesh.triangle_count() as u64);
    let opts = BuildOptions {
        layout,
        ..Default::default()
    };
    let bvh = build(mesh, &opts, &|done, total| {
        pb.set_length(total);
        pb.set_position(done);
    });
    pb.finish_and_clear();
    bvh
}

fn turntable_path(a: &RenderArgs) -> PathBuf {
    a.turntable_out.clone().unwrap_or_else(|| {
        let stem = a
            .output
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("render");
        a.output.with_file_name(format!("{stem}-turntable.png"))
    })
}

/// The flags clap's ranges do not cover, checked before any work: the
/// thread count against the machine, `--tris`, the turntable's memory and
/// the camera angles.
fn check_flags(a: &RenderArgs) -> CliResult {
    super::check_threads(a.threads.map(|t| t as usize))?;
    a.source.check()?;
    if let Some(frames) = a.turntable {
        let need = turntable_bytes(frames, a.width, a.height);
        let (limit, whose) = match super::machine_memory() {
            Some(m) => (m / 2, "half this machine's memory"),
            None => (
                TURNTABLE_BYTES_UNKNOWN_MEMORY,
                "the limit where the machine's memory is unknown",
            ),
        };
        if need > limit {
            return Err(format!(
                "--turntable {frames} at --width {} --height {} holds {frames} frames of {} × {} \
                 pixels in memory until they are written: {:.1} GiB, over {whose} ({:.1} GiB); \
                 give fewer frames or a smaller image",
                a.width,
                a.height,
                a.width,
                a.height,
                need as f64 / (1u64 << 30) as f64,
                limit as f64 / (1u64 << 30) as f64
            )
            .into());
        }
    }
    if !a.azimuth.is_finite() {
        return Err(format!("--azimuth {} must be a finite number of degrees", a.azimuth).into());
    }
    if !(-89.0..=89.0).contains(&a.elevation) {
        return Err(format!("--elevation {} must be from -89 to 89 degrees", a.elevation).into());
    }
    Ok(())
}

/// Bytes a turntable's frames hold: every frame is kept (3 bytes a pixel)
/// until they are written together.
fn turntable_bytes(frames: u32, width: u32, height: u32) -> u64 {
    u64::from(frames) * u64::from(width) * u64::from(height) * 3
}

/// The most bytes of frames a turntable may hold where the machine's
/// memory is unknown (elsewhere: half of it).
const TURNTABLE_BYTES_UNKNOWN_MEMORY: u64 = 4 << 30;

/// A still image, its stats, and the turntable's frames and stats if asked.
type Rendered = (Image, RenderStats, Option<(Vec<Image>, RenderStats)>);

/// Runs `cbvh render`.
pub fn run(mut a: RenderArgs) -> CliResult {
    check_flags(&a)?;
    super::check_output("--output", &a.output, &["png"])?;
    if a.turntable.is_some() {
        super::check_output("--turntable-out", &turntable_path(&a), &["png", "gif"])?;
    }
    let t0 = Instant::now();
    let (mesh, name, target) = match a.source.load_any()? {
        Loaded::Codec(codec, name)
            if a.codec.is_none_or(|c| c == Structure::Codec(codec.kind())) =>
        {
            // The file's own codec, as stored: nothing is rebuilt. Smooth
            // normals need the decoded mesh (about 18 bytes a triangle);
            // a model whose mesh is over both the cache budget and 1 GiB
            // is shaded flat instead of being decoded whole (one out of
            // core stays so). Small models look the same at any budget.
            a.codec = Some(Structure::Codec(codec.kind()));
            let mesh_bytes = codec.triangle_count().saturating_mul(18);
            let budget = a.source.cache_mib.saturating_mul(1 << 20).max(1 << 30);
            let mesh = if mesh_bytes > budget {
                eprintln!(
                    "note: flat shading: smooth normals would decode the whole mesh ({:.1} GiB, \
                     over --cache-mib {} and 1 GiB)",
                    mesh_bytes as f64 / (1u64 << 30) as f64,
                    a.source.cache_mib
                );
                None
            } else {
                Some(codec.decoded_mesh())
            };
            (mesh, name, any_target(*codec))
        }
        loaded => {
            let (mesh, name) = match loaded {
                Loaded::Codec(codec, name) => (codec.decoded_mesh(), name),
                Loaded::Mesh(mesh, name) => (mesh, name),
            };
            mesh.validate(&name)?;
            let codec = *a.codec.get_or_insert(Structure::Codec(CodecKind::Plain));
            let target = make_target(codec, &mesh, a.layout)?;
            (Some(mesh), name, target)
        }
    };
    let build_seconds = t0.elapsed().as_secs_f64();
    let tris = target.triangle_count();
    let normals = mesh.as_ref().map(VertexNormals::from_mesh);
    drop(mesh);
    let scene = Scene::single(target.as_ref(), normals.as_ref());
    let mut opts = RenderOptions {
        width: a.width,
        height: a.height,
        lights: a.lights as usize,
        reflect_depth: a.reflect_depth,
        azimuth_deg: a.azimuth,
        elevation_deg: a.elevation,
        ..Default::default()
    };
    if a.primary_only {
        opts = opts.primary_only();
    }
    let work = || -> Result<Rendered, crate::render::RenderError> {
        let pb = progress_bar("rendering", 1);
        let (image, stats) = render(&scene, &opts, &|d, t| {
            pb.set_length(t);
            pb.set_position(d);
        })?;
        pb.finish_and_clear();
        let turntable = match a.turntable {
            Some(n) => {
                let pb = progress_bar("turntable", 1);
                let r = render_turntable(&scene, &opts, n, &|d, t| {
                    pb.set_length(t);
                    pb.set_position(d);
                })?;
                pb.finish_and_clear();
                Some(r)
            }
            None => None,
        };
        Ok((image, stats, turntable))
    };
    let (image, stats, turntable) = match a.threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t as usize)
            .build()?
            .install(work)?,
        None => work()?,
    };
    image.save_png(&a.output)?;
    let turntable_out = turntable_path(&a);
    if let Some((frames, _)) = &turntable {
        save_animation(frames, &turntable_out, a.fps)?;
    }
    report(
        &a,
        &name,
        tris,
        target.as_ref(),
        build_seconds,
        &stats,
        turntable
            .as_ref()
            .map(|t| (&t.1, t.0.len(), &turntable_out)),
    )
}

fn per_ray(target: &dyn RayTarget, count: u64, rays: u64) -> Option<f64> {
    target
        .counts_traversal()
        .then(|| count as f64 / rays.max(1) as f64)
}

fn report(
    a: &RenderArgs,
    name: &str,
    tris: usize,
    target: &dyn RayTarget,
    build_seconds: f64,
    s: &RenderStats,
    turntable: Option<(&RenderStats, usize, &PathBuf)>,
) -> CliResult {
    let codec = a.codec.unwrap_or(Structure::Codec(CodecKind::Plain));
    let rays = s.rays.total();
    let steps = per_ray(target, s.rays.traversal.nodes_visited, rays);
    let prims = per_ray(target, s.rays.traversal.primitive_tests, rays);
    if a.json {
        let mut v = serde_json::json!({
            "mesh": name,
            "triangles": tris,
            "codec": codec.name(),
            "layout": (codec != Structure::Parry).then(|| a.layout.name()),
            "width": a.width,
            "height": a.height,
            "lights": a.lights,
            "reflect_depth": if a.primary_only { 0 } else { a.reflect_depth },
            "shadows": !a.primary_only,
            "build_seconds": build_seconds,
            "rays": rays,
            "primary_rays": s.rays.primary,
            "shadow_rays": s.rays.shadow,
            "reflection_rays": s.rays.reflection,
            "seconds": s.seconds,
            "rays_per_second": s.rays_per_second(),
            "threads": s.threads,
            "traversal_steps_per_ray": steps,
            "primitive_tests_per_ray": prims,
            "bytes_per_triangle": target.bytes_per_triangle(),
            "output": a.output.display().to_string(),
            "cache": target.cache_stats(),
        });
        if let (Some((t, frames, path)), Some(o)) = (turntable, v.as_object_mut()) {
            o.insert(
                "turntable".into(),
                serde_json::json!({
                    "frames": frames,
                    "rays": t.rays.total(),
                    "seconds": t.seconds,
                    "rays_per_second": t.rays_per_second(),
                    "output": path.display().to_string(),
                }),
            );
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let fmt = |x: Option<f64>| {
            x.map_or("n/a (parry does not count)".to_string(), |x| {
                format!("{x:.2}")
            })
        };
        println!("mesh              {name}");
        println!("triangles         {tris}");
        println!(
            "codec             {} ({:.2} B/triangle, built in {build_seconds:.3} s)",
            codec.name(),
            target.bytes_per_triangle()
        );
        println!(
            "image             {} × {} → {}",
            a.width,
            a.height,
            a.output.display()
        );
        println!(
            "rays              {rays} ({} primary, {} shadow, {} reflection)",
            s.rays.primary, s.rays.shadow, s.rays.reflection
        );
        println!(
            "time              {:.3} s, {:.2} M rays/s on {} threads",
            s.seconds,
            s.rays_per_second() / 1e6,
            s.threads
        );
        println!("traversal steps   {} per ray", fmt(steps));
        println!("primitive tests   {} per ray", fmt(prims));
        if let Some(c) = target.cache_stats() {
            println!("decode cache      {}", c.summary());
        }
        if let Some((t, frames, path)) = turntable {
            println!(
                "turntable         {frames} frames → {} ({:.3} s, {:.2} M rays/s)",
                path.display(),
                t.seconds,
                t.rays_per_second() / 1e6
            );
        }
    }
    Ok(())
}
