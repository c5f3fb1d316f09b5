//! The drop tests (`cbvh lucy-on-turbine`, `cbvh robot-in-plant`, and
//! the binaries of the same names): the options they share, running every
//! shape, the table, the JSON report and the plot.

pub mod lucy;
pub mod robot;

use std::path::PathBuf;

use crate::Mesh;
use crate::build::BuildOptions;
use crate::codec::{AnyCodec, CodecKind, OpenOptions};
use crate::parry::ContactMode;
use crate::scene::Kind;
use crate::sim::droptest::{
    self, DropScene, DroppedFile, Placement, Replay, RunReport, RunSpec, ShapeKind,
};

use super::progress_bar as bar;
use super::values::whole;

/// Options common to the sims.
#[derive(clap::Args, Debug, Clone)]
pub struct SimArgs {
    /// Number of steps at 60 Hz.
    #[arg(long, default_value_t = 215, allow_negative_numbers = true, value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub steps: usize,
    /// Comma-separated shapes to run (default: all of them): parry
    /// (parry's TriMesh), parry-fixed (the same with FIX_INTERNAL_EDGES,
    /// not run by default), a codec's name (a decode cache, if the codec has
    /// one, holds the whole tree), or a cached codec's name with -10pct
    /// (a cache of 10 % of the decompressed tree).
    /// A cbvh name may end in -pairs or -patches to fix its contact mode
    /// (plain-pairs); bare cbvh names run in the modes of --contacts.
    #[arg(
        long,
        default_values_t = ShapeKind::all().into_iter().map(ShapeKind::name),
        value_delimiter = ','
    )]
    pub shapes: Vec<String>,
    /// Contact modes of the cbvh shapes: patches (cbvh's triangle-pair
    /// kernel reduced into contact patches), pairs (one parry manifold per
    /// triangle pair, parry's own contacts), or both, side by side.
    #[arg(long, default_value = "both", value_parser = ["patches", "pairs", "both"])]
    pub contacts: String,
    /// Write the report as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the per-step narrow-phase and interference times of every run
    /// to this PNG (two panels, log scales).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Worker threads for building trees (rapier's step runs on one thread).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub threads: Option<usize>,
    /// Generator seed.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true,
          value_parser = whole::<u64>(0, u64::MAX))]
    pub seed: u64,
    /// Width of the dropped mesh as a fraction of the base's width
    /// (default: 0.5 for lucy-on-turbine, 0.1 for robot-in-plant, whose
    /// robot is small next to its plant).
    #[arg(long, allow_negative_numbers = true)]
    pub width_fraction: Option<f32>,
    /// Gap above the base's top, as a fraction of the dropped mesh's height.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub gap: f32,
    /// Ray-trace the final frame (of the last run) to this PNG.
    #[arg(long)]
    pub render: Option<PathBuf>,
    /// Let rapier reuse the contacts of pairs that barely moved (skips the
    /// narrow phase on those steps, so off by default when timing).
    #[arg(long)]
    pub contact_recycling: bool,
    /// Horizontal offset of the drop point, as fractions of the base width:
    /// X,Z (e.g. `--offset -0.2,0.1`).
    #[arg(
        long,
        default_value = "0,0",
        allow_hyphen_values = true,
        value_name = "X,Z"
    )]
    pub offset: Offset,
    /// After each run, time its narrow phase once more along the first
    /// run's trajectory (the poses rapier asked the first run's narrow
    /// phase for, step by step), so that every shape's replay median is
    /// of the same contact work; a run's own median follows its own
    /// trajectory, which parts from another's as soon as two shapes order
    /// their contacts differently.
    #[arg(long)]
    pub replay: bool,
    /// How many times `--replay` replays the trajectory, 1 to 1000; each
    /// step keeps its best time. More rounds take more out of a noisy
    /// machine's timings, but each costs about one run's narrow phase per
    /// shape, and a best time falls ever less with more of them: 1000 is
    /// ten times the 100 that steadies a busy machine.
    #[arg(
        long,
        default_value_t = droptest::REPLAY_ROUNDS as u32,
        allow_negative_numbers = true,
        value_parser = whole::<u32>(1, MAX_REPLAY_ROUNDS.into()),
        requires = "replay"
    )]
    pub replay_rounds: u32,
    /// Midpoint-subdivide the dropped mesh this many times (each ×4
    /// triangles, same shape): a scan at a higher resolution, e.g. the
    /// 75 k bunny with 3 gives 4.8 M triangles. At most 6, and the result
    /// must stay within the 4 294 967 295 triangles a mesh can number
    /// (checked before any work from the generator's plan or the file's
    /// header, and once the mesh is loaded).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true,
          value_parser = whole::<u32>(0, u32::MAX.into()))]
    pub subdivide: u32,
    /// The cbvh shapes' codec settings.
    #[command(flatten)]
    pub codecs: super::CodecFlags,
}

impl SimArgs {
    /// `--width-fraction`, or 0.5 when a sim has set no default of its own.
    pub fn width_fraction(&self) -> f32 {
        self.width_fraction.unwrap_or(0.5)
    }
}

/// `--offset X,Z`: two comma-separated numbers, either may be negative.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Offset(pub [f32; 2]);

impl std::str::FromStr for Offset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let [x, z] = parts[..] else {
            return Err(format!(
                "{s:?} is not X,Z: give two comma-separated numbers, e.g. -0.2,0.1"
            ));
        };
        let num = |t: &str| {
            t.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{t:?} in {s:?} is not a finite number"))
        };
        Ok(Offset([num(x)?, num(z)?]))
    }
}

impl std::fmt::Display for Offset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{}", self.0[0], self.0[1])
    }
}

/// The most steps a run takes: its per-step timings and samples are kept.
pub const MAX_STEPS: usize = 1_000_000;

/// The most `--replay-rounds`: ten times the 100 that steadies a busy
/// machine's timings. Each round replays the trajectory once per shape
/// (about one run's narrow phase), and a step's best time falls ever less
/// with more rounds: beyond this they only multiply the time.
pub const MAX_REPLAY_ROUNDS: u32 = 1000;

/// The most `--subdivide`: 4^6 = 4096 times the triangles.
pub const MAX_SUBDIVIDE: u32 = 6;

/// The largest `--width-fraction`, `--gap` and `--offset` component: a
/// dropped mesh a thousand times the base's width, or that far away, is no
/// drop test, and larger fractions only reach the coordinate limit.
pub const MAX_FRACTION: f32 = 1000.0;

/// Checks every flag of [`SimArgs`] before anything runs, so that a bad
/// value never ends a run half-way (or, worse, runs and reports nonsense):
/// steps, width fraction, gap and offset finite and in range, the cluster
/// size, the thread count ([`check_threads`](super::check_threads)), and
/// that the JSON, plot and render files can be written
/// ([`check_output`](super::check_output)). [`start`] also checks the
/// meshes' flags ([`validate_meshes`]).
pub fn validate(args: &SimArgs) -> Result<(), String> {
    if args.steps == 0 {
        return Err("--steps must be at least 1".into());
    }
    if args.steps > MAX_STEPS {
        return Err(format!(
            "--steps {} is more than {MAX_STEPS} (4.6 hours at 60 Hz, each step's timings kept)",
            args.steps
        ));
    }
    super::check_threads(args.threads)?;
    if args.shapes.is_empty() {
        return Err("--shapes names no shape".into());
    }
    let width_fraction = args.width_fraction();
    if !(width_fraction > 0.0 && width_fraction <= MAX_FRACTION) {
        return Err(format!(
            "--width-fraction {width_fraction} must be above 0 and at most {MAX_FRACTION} (0.5: half the base's width)"
        ));
    }
    if !(args.gap >= 0.0 && args.gap <= MAX_FRACTION) {
        return Err(format!(
            "--gap {} must be 0 to {MAX_FRACTION} (a fraction of the dropped mesh's height)",
            args.gap
        ));
    }
    if args.offset.0.iter().any(|v| v.abs() > MAX_FRACTION) {
        return Err(format!(
            "--offset {} must be two numbers from -{MAX_FRACTION} to {MAX_FRACTION} (fractions of the base's width)",
            args.offset
        ));
    }
    if args.subdivide > MAX_SUBDIVIDE {
        return Err(format!(
            "--subdivide {} multiplies the triangles by 4^{}: use at most {MAX_SUBDIVIDE} (×4096)",
            args.subdivide, args.subdivide
        ));
    }
    options(args, &run_specs(args)?)?;
    // The report is JSON whatever its name; the plot and the frame PNG.
    for (flag, path, exts) in [
        ("--json", &args.json, &[][..]),
        ("--plot", &args.plot, &["png"][..]),
        ("--render", &args.render, &["png"][..]),
    ] {
        if let Some(p) = path {
            super::check_output(flag, p, exts)?;
        }
    }
    Ok(())
}

/// One of a drop test's two meshes as its flags give it: a file
/// (`--statue FILE`), or else generated at `--statue-tris N` triangles.
#[derive(Clone, Copy, Debug)]
pub struct MeshFlags<'a> {
    /// The file flag, e.g. `--statue`, and its value.
    pub file: (&'static str, &'a Option<PathBuf>),
    /// The count flag, e.g. `--statue-tris`, and its value.
    pub tris: (&'static str, usize),
    /// What the generator makes.
    pub kind: Kind,
}

/// Checks the meshes' flags before any mesh is made: a generated mesh's
/// count within the generator's range; a file that opens and, for the
/// dropped mesh under `--subdivide`, is a mesh file (not a codec file,
/// used as stored) whose header's count subdivided stays within what a
/// mesh can number; a generated dropped mesh's planned count likewise.
pub fn validate_meshes(
    args: &SimArgs,
    dropped: &MeshFlags,
    base: &MeshFlags,
) -> Result<(), String> {
    for (m, is_dropped) in [(dropped, true), (base, false)] {
        let subdivide = if is_dropped { args.subdivide } else { 0 };
        match m.file.1 {
            None => {
                let (flag, tris) = m.tris;
                super::check_tris(flag, m.kind, tris, crate::scene::MAX_TRIS)?;
                if subdivide > 0 {
                    let planned = crate::scene::planned_triangles(m.kind, tris, args.seed)
                        .map_err(|e| format!("{flag} {tris}: {e}"))?;
                    check_subdivide(
                        subdivide,
                        planned as u64,
                        &format!("the {} of {flag} {tris}", m.kind),
                    )?;
                }
            }
            Some(p) if CodecKind::of_file(p).is_some() => {
                if subdivide > 0 {
                    return Err(format!(
                        "--subdivide needs a mesh to subdivide: {} {} is a codec file, used as \
                         stored; give the mesh file instead",
                        m.file.0,
                        p.display()
                    ));
                }
            }
            Some(p) => {
                let stated =
                    crate::mesh::header_triangles(p).map_err(|e| format!("{} {}", m.file.0, e))?;
                if let Some(t) = stated.filter(|_| subdivide > 0) {
                    check_subdivide(subdivide, t, &p.display().to_string())?;
                }
            }
        }
    }
    Ok(())
}

/// Checks that `triangles` (those of `what`) subdivided `times` times stay
/// within the [`crate::mesh::MAX_SUBDIVIDED`] triangles a mesh can number.
pub fn check_subdivide(times: u32, triangles: u64, what: &str) -> Result<(), String> {
    if crate::mesh::subdivided_triangles(triangles, times).is_some() {
        return Ok(());
    }
    Err(format!(
        "--subdivide {times}: {what} has {triangles} triangles, and 4^{times} times as many are \
         more than the {} a mesh can number; subdivide fewer times or start from fewer triangles",
        crate::mesh::MAX_SUBDIVIDED
    ))
}

/// The runs `--shapes` and `--contacts` ask for, in order: a bare cbvh
/// name runs once per mode of `--contacts` (patches first).
pub fn run_specs(args: &SimArgs) -> Result<Vec<RunSpec>, String> {
    let modes: Vec<ContactMode> = match args.contacts.as_str() {
        "patches" => vec![ContactMode::default()],
        "pairs" => vec![ContactMode::PerTrianglePair],
        _ => vec![ContactMode::default(), ContactMode::PerTrianglePair],
    };
    let mut specs = Vec::new();
    for name in &args.shapes {
        let explicit = name.ends_with("-pairs") || name.ends_with("-patches");
        let first = RunSpec::parse(name, modes[0])?;
        if explicit || first.kind.is_parry() {
            specs.push(first);
        } else {
            for m in &modes {
                specs.push(RunSpec {
                    kind: first.kind,
                    mode: *m,
                });
            }
        }
    }
    if specs.is_empty() {
        return Err("--shapes names no shape".into());
    }
    // `plain,plain-pairs` with both modes names plain-pairs twice: run it once.
    let mut seen = std::collections::HashSet::new();
    specs.retain(|s| seen.insert(s.name()));
    Ok(specs)
}

/// The options of the codecs the runs use, from the codec flags.
fn options(args: &SimArgs, specs: &[RunSpec]) -> Result<crate::codec::AnyOptions, String> {
    args.codecs
        .options(&codecs_of(specs))
        .map_err(|e| e.to_string())
}

/// The codecs the runs `specs` use, each once, in registry order.
fn codecs_of(specs: &[RunSpec]) -> Vec<CodecKind> {
    CodecKind::ALL
        .iter()
        .copied()
        .filter(|&k| {
            specs.iter().any(|s| match s.kind {
                ShapeKind::Cbvh(c) | ShapeKind::CbvhTenthCache(c) => c == k,
                ShapeKind::Parry | ShapeKind::ParryFixed => false,
            })
        })
        .collect()
}

/// The dropped mesh of a drop test: a mesh, or a cbvh codec file used as
/// stored (see [`DropScene::dropped_file`]).
pub enum Dropped {
    /// A mesh (loaded or generated): placed over the base.
    Mesh(Mesh),
    /// A codec file: the runs of its codec open it as it is (a model
    /// built out of core need never be held as a mesh), the other runs
    /// build from its decoded mesh; the base is placed around it.
    File(DroppedFile),
}

/// The dropped mesh from a file (a mesh, or a codec file used as stored),
/// or generated; a mesh's count is checked against `subdivide` as soon as
/// it is known ([`check_subdivide`]), before anything else is made.
pub fn dropped_from(m: &MeshFlags, seed: u64, subdivide: u32) -> Result<(Dropped, String), String> {
    match m.file.1 {
        // Opened and verified once, out of core (1 MiB cache): nothing of
        // it is held but what verify reads.
        Some(p) if CodecKind::of_file(p).is_some() => {
            let codec = AnyCodec::open(
                p,
                &OpenOptions {
                    verify: true,
                    cache_budget_bytes: 1 << 20,
                },
            )
            // Every CodecFileError names the file.
            .map_err(|e| e.to_string())?;
            let b = codec.root_box();
            let f = DroppedFile {
                path: p.clone(),
                kind: codec.kind(),
                triangles: codec.triangle_count(),
                bounds: (b.min.to_array(), b.max.to_array()),
            };
            let name = format!("{} ({} file, used as stored)", p.display(), codec.name());
            Ok((Dropped::File(f), name))
        }
        _ => {
            let (mesh, n) = mesh_from(m, seed)?;
            check_subdivide(subdivide, mesh.triangle_count() as u64, &n)?;
            Ok((Dropped::Mesh(mesh), n))
        }
    }
}

/// A mesh from a file (a mesh, or a cbvh codec file's stored mesh), or
/// generated.
pub fn mesh_from(m: &MeshFlags, seed: u64) -> Result<(Mesh, String), String> {
    let (kind, tris) = (m.kind, m.tris.1);
    match m.file.1 {
        // A cbvh codec file (recognised by its magic): opened, verified, and
        // its stored mesh used; each shape is then built from it.
        Some(p) if CodecKind::of_file(p).is_some() => {
            let codec = AnyCodec::open(p, &OpenOptions::default()).map_err(|e| e.to_string())?;
            Ok((
                codec.decoded_mesh(),
                format!("{} ({} file)", p.display(), codec.name()),
            ))
        }
        Some(p) => crate::mesh::load(p)
            .map(|m| (m, p.display().to_string()))
            .map_err(|e| e.to_string()),
        None => {
            let mesh = super::generate(kind, tris, seed, &format!("gen {kind}"))
                .map_err(|e| e.to_string())?;
            Ok((
                mesh,
                format!("generated {kind} ({tris} requested, seed {seed})"),
            ))
        }
    }
}

/// Everything a drop test does before it makes a mesh: every flag
/// checked ([`validate`], shape names included, and [`validate_meshes`]),
/// then the thread pool and the logger ([`init_threads`]).
pub fn start(args: &SimArgs, dropped: &MeshFlags, base: &MeshFlags) -> Result<(), String> {
    validate(args)?;
    validate_meshes(args, dropped, base)?;
    init_threads(args)
}

/// Sizes rayon's global pool from `--threads`. Call it first: mesh
/// generation and loading already use the pool.
pub fn init_threads(args: &SimArgs) -> Result<(), String> {
    crate::logger::init_stderr();
    super::check_threads(args.threads)?;
    match args.threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .map_err(|e| format!("--threads {t}: {e}")),
        None => Ok(()),
    }
}

/// Places `dropped` over `base`, runs every shape, prints the table and
/// writes the JSON and plot. `names` = (dropped, base) for the report.
pub fn run_sim(
    title: &str,
    dropped: Dropped,
    mut base: Mesh,
    names: (String, String),
    args: &SimArgs,
) -> Result<(), String> {
    if args.steps == 0 {
        return Err("--steps must be at least 1".into());
    }
    let specs = run_specs(args)?;
    let placement = Placement {
        width_fraction: args.width_fraction(),
        gap_fraction: args.gap,
        offset_fraction: args.offset.0,
    };
    let (mut dropped, dropped_file, scale) = match dropped {
        Dropped::Mesh(mut m) => {
            for _ in 0..args.subdivide {
                m = m
                    .subdivided()
                    .map_err(|e| format!("--subdivide {}: {e}", args.subdivide))?;
            }
            let scale = droptest::place(&mut m, &base, &placement);
            (m, None, scale)
        }
        Dropped::File(f) => {
            if args.subdivide > 0 {
                return Err(
                    "--subdivide needs a mesh to subdivide: a codec file is used as \
                            stored; give the mesh file instead"
                        .into(),
                );
            }
            // The file as stored; the base goes around it.
            let scale = droptest::place_base(f.bounds, &mut base, &placement);
            (Mesh::default(), Some(f), scale)
        }
    };
    if let Some(f) = &dropped_file {
        // Runs of other codecs (and parry) build from the decoded mesh.
        let own = |k: &ShapeKind| matches!(k, ShapeKind::Cbvh(c) | ShapeKind::CbvhTenthCache(c) if *c == f.kind);
        if specs.iter().any(|s| !own(&s.kind)) {
            let codec = AnyCodec::open(
                &f.path,
                &OpenOptions {
                    verify: false,
                    cache_budget_bytes: usize::MAX,
                },
            )
            .map_err(|e| e.to_string())?;
            dropped = codec.decoded_mesh();
        }
    }
    let names = match args.subdivide {
        0 => names,
        n => (format!("{}, subdivided {n}×", names.0), names.1),
    };
    // A large base times a large fraction can still leave the supported
    // coordinates: say which flags placed it there.
    let (moved, name) = match dropped_file {
        None => (&dropped, &names.0),
        Some(_) => (&base, &names.1),
    };
    moved.validate(name).map_err(|e| {
        format!(
            "the {} mesh as placed by --width-fraction {} --gap {} --offset {}: {e}",
            if dropped_file.is_none() {
                "dropped"
            } else {
                "base"
            },
            args.width_fraction(),
            args.gap,
            args.offset
        )
    })?;
    let (blo, bhi) = base.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
    let leaf_size = usize::from(args.codecs.leaf_size);
    let scene = DropScene {
        length_unit: if dropped_file.is_some() {
            1.0 / scale
        } else {
            1.0
        },
        dropped,
        dropped_file,
        base,
        steps: args.steps,
        dt: 1.0 / 60.0,
        contact_recycling: args.contact_recycling,
        codec_options: options(args, &specs)?,
        build_options: BuildOptions {
            max_leaf_triangles: leaf_size,
            ..Default::default()
        },
    };
    let (dlo, dhi) = scene.dropped_bounds().unwrap_or(([0.0; 3], [0.0; 3]));
    let statue_size = (0..3).map(|k| dhi[k] - dlo[k]).fold(0.0f32, f32::max);
    let threads = rayon::current_num_threads();
    let scaled = match &scene.dropped_file {
        None => format!("scaled ×{scale:.4}"),
        Some(_) => format!(
            "as stored, the base and the scene's unit (gravity, tolerances) scaled ×{:.4}",
            1.0 / scale
        ),
    };
    eprintln!(
        "{title}: dropping {} ({} triangles, {scaled}) onto {} ({} triangles), {} steps at 60 Hz, cbvh trees of up to {leaf_size} triangle(s) a leaf",
        names.0,
        scene.dropped_triangles(),
        names.1,
        scene.base.triangle_count(),
        scene.steps
    );
    // Each codec's options as used, for the report (none named here).
    let codec_options: serde_json::Map<String, serde_json::Value> = codecs_of(&specs)
        .into_iter()
        .map(|k| (k.name().to_string(), scene.codec_options.describe(k).into()))
        .collect();
    let mut runs: Vec<RunReport> = Vec::new();
    for spec in specs {
        let pb = bar(&spec.name(), scene.steps as u64);
        let replay = match runs.first() {
            _ if !args.replay => Replay::Off,
            None => Replay::Own,
            Some(first) => Replay::Along(&first.trajectory),
        };
        let r = droptest::run_replaying(
            &scene,
            spec,
            replay,
            args.replay_rounds as usize,
            &mut |s, _| pb.set_position(s as u64),
        )
        .map_err(|e| e.to_string())?;
        pb.finish_and_clear();
        let replayed = match (&r.replay_along, r.replay_narrow_phase_ms) {
            (Some(along), Some(t)) => format!(", along {along}'s trajectory {:.3} ms", t.median),
            _ => String::new(),
        };
        eprintln!(
            "  {:<13} done: narrow phase median {:.3} ms{replayed}, interference median {:.3} ms",
            r.shape, r.narrow_phase_ms.median, r.interference_ms.median
        );
        runs.push(r);
    }
    print_table(&runs, statue_size);
    let scene_json = serde_json::json!({
        "title": title,
        "dropped": names.0,
        "base": names.1,
        "dropped_triangles": scene.dropped_triangles(),
        "base_triangles": scene.base.triangle_count(),
        "dropped_scale": scale,
        "length_unit": scene.length_unit,
        "dropped_size": statue_size,
        "base_bounds": [blo, bhi],
        "steps": scene.steps,
        "dt": scene.dt,
        "codec_options": serde_json::Value::Object(codec_options),
        "leaf_size": leaf_size,
        "threads": threads,
        "machine": machine(),
    });
    if let Some(path) = &args.json {
        let v = serde_json::json!({ "scene": scene_json, "runs": runs });
        crate::files::save(
            path,
            serde_json::to_string_pretty(&v)
                .map_err(|e| e.to_string())?
                .as_bytes(),
        )
        .map_err(|e| e.to_string())?;
        eprintln!("wrote {}", path.display());
    }
    if args.render.is_some() && scene.dropped.triangles.is_empty() {
        eprintln!(
            "note: --render draws the meshes, and the dropped one was used as stored without \
             decoding it: render it with `cbvh render` instead"
        );
    } else if let (Some(path), Some(last)) = (&args.render, runs.last()) {
        let r = last.final_rotation;
        let t = last.final_translation;
        let pose = crate::geom::Pose::from_rotation_translation(
            glam::Quat::from_xyzw(r[0], r[1], r[2], r[3]),
            glam::Vec3::from(t),
        );
        let opts = crate::render::RenderOptions {
            width: 960,
            height: 720,
            ..Default::default()
        };
        let image = crate::render::render_meshes(
            &[
                (&scene.base, crate::geom::Pose::IDENTITY),
                (&scene.dropped, pose),
            ],
            &opts,
        )
        .map_err(|e| e.to_string())?;
        image.save_png(path).map_err(|e| e.to_string())?;
        eprintln!(
            "wrote {} (final frame of the {} run)",
            path.display(),
            last.shape
        );
    }
    if let Some(path) = &args.plot {
        let narrow: Vec<(String, Vec<f64>)> = runs
            .iter()
            .map(|r| (r.shape.clone(), r.narrow_phase_ms_per_step.clone()))
            .collect();
        let interference: Vec<(String, Vec<f64>)> = runs
            .iter()
            .map(|r| (r.shape.clone(), r.interference_ms_per_step.clone()))
            .collect();
        let panels = [
            crate::app::plot::Panel {
                title: "narrow phase (contact manifolds) per step",
                y_label: "ms",
                series: &narrow,
            },
            crate::app::plot::Panel {
                title: "interference (intersecting triangle pairs) per step",
                y_label: "ms",
                series: &interference,
            },
        ];
        crate::app::plot::line_plot_png(path, title, &panels, (1000, 900))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The CPU model and core count, for reports.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    format!(
        "{cpu}, {} cores",
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    )
}

fn print_table(runs: &[RunReport], size: f32) {
    println!();
    println!(
        "{:<19} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8} {:>7} {:>8} {:>9} {:>6} {:>7} {:>7} {:>8} {:>9} {:>8}",
        "shape",
        "np median",
        "np p95",
        "np max",
        "step med",
        "interf",
        "contact",
        "pairs",
        "manifold",
        "points",
        "interf",
        "max pen",
        "n ang",
        "E gain",
        "B/tri",
        "RSS",
        "final y",
        "fallback"
    );
    println!(
        "{:<19} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8} {:>7} {:>8} {:>9} {:>6} {:>7} {:>7} {:>8}",
        "",
        "ms",
        "ms",
        "ms",
        "ms",
        "med ms",
        "steps",
        "max",
        "max",
        "max",
        "pairs",
        "",
        "deg",
        "%",
        "",
        "MB"
    );
    for r in runs {
        println!(
            "{:<19} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>8} {:>8} {:>8} {:>7} {:>8} {:>9.5} {:>6.1} {:>7.2} {:>7.1} {:>8} {:>9.4} {:>8}",
            r.shape,
            r.narrow_phase_ms.median,
            r.narrow_phase_ms.p95,
            r.narrow_phase_ms.max,
            r.step_ms.median,
            r.interference_ms.median,
            r.steps_in_contact,
            r.max_contact_pairs,
            r.max_manifolds,
            r.max_contact_points,
            r.max_interference_pairs,
            r.max_penetration,
            r.max_normal_angle_deg,
            100.0 * r.energy_gain,
            r.bytes_per_triangle,
            r.peak_rss_bytes
                .map(|b| format!("{:.0}", b as f64 / 1e6))
                .unwrap_or_else(|| "n/a".into()),
            r.final_translation[1],
            if r.fallback_bvh_built { "BUILT" } else { "no" }
        );
    }
    println!(
        "E gain: the largest rise of the dropped body's energy after its first contact, in % of \
         its weight × size; contacts without restitution only take energy out, so a rise is \
         energy the contacts put in"
    );
    if let Some(along) = runs.first().and_then(|r| r.replay_along.clone()) {
        println!();
        println!(
            "narrow phase replayed along {along}'s trajectory (the same poses for every shape), over its steps in contact:"
        );
        let first = runs[0].replay_narrow_phase_ms.unwrap_or_default().median;
        for r in runs {
            if let Some(t) = r.replay_narrow_phase_ms {
                println!(
                    "{:<19} median {:>8.3} ms  p95 {:>8.3} ms  max {:>8.3} ms  {:.3}× {along}'s",
                    r.shape,
                    t.median,
                    t.p95,
                    t.max,
                    t.median / first.max(1e-9)
                );
            }
        }
    }
    if let Some(base) = runs.iter().find(|r| r.shape == "parry") {
        println!();
        for r in runs.iter().filter(|r| r.shape != "parry") {
            let ratio = r.narrow_phase_ms.median / base.narrow_phase_ms.median.max(1e-9);
            let step = r.step_ms.median / base.step_ms.median.max(1e-9);
            let dy = (r.final_translation[1] - base.final_translation[1]).abs();
            let speed = if ratio <= 1.0 {
                format!("{:.1}× faster", 1.0 / ratio.max(1e-9))
            } else {
                format!("{ratio:.1}× slower")
            };
            println!(
                "{}: narrow-phase median {ratio:.3}× parry's ({speed}), whole step {step:.3}×; {:.2}× the memory per triangle; final height differs from parry's by {:.2} % of the dropped mesh's size; largest penetration {:.2}× parry's",
                r.shape,
                r.bytes_per_triangle / base.bytes_per_triangle,
                100.0 * dy / size.max(1e-9),
                r.max_penetration / base.max_penetration.max(1e-12)
            );
        }
    }
    // Patches against the per-pair mode of the same codec.
    for r in runs.iter().filter(|r| r.contact_mode == "patches") {
        let pairs_name = format!("{}-pairs", r.shape);
        if let Some(p) = runs.iter().find(|q| q.shape == pairs_name) {
            let dy = (r.final_translation[1] - p.final_translation[1]).abs();
            println!(
                "{}: narrow phase {:.3}× the pairs mode's; final height within {:.2} % of the dropped mesh's size of {}",
                r.shape,
                r.narrow_phase_ms.median / p.narrow_phase_ms.median.max(1e-9),
                100.0 * dy / size.max(1e-9),
                p.shape
            );
        }
    }
    for r in runs {
        if let Some(c) = &r.caches {
            let part = |name: &str, c: &crate::codec::CacheStats| format!("{name} {}", c.summary());
            println!(
                "{}: caches: {}; {}",
                r.shape,
                part("dropped", &c[0]),
                part("base", &c[1])
            );
        }
        println!(
            "{}: final speed {:.4} ({}), final translation ({:.4}, {:.4}, {:.4})",
            r.shape,
            r.final_speed,
            r.final_state,
            r.final_translation[0],
            r.final_translation[1],
            r.final_translation[2]
        );
    }
}
