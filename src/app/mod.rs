//! The command-line front end (feature `app`), one for every binary: the
//! `cbvh` command's subcommands, the drop tests (also the binaries
//! `lucy-on-turbine` and `robot-in-plant`), and what they share: where a
//! mesh comes from (a file, a codec file, a generator), progress bars, the
//! codec names on the command line, and how an error ends the process.
//!
//! - [`generate`](mod@generate), [`info`], [`build`], [`render`]: `cbvh gen`, `info`,
//!   `build`, `render`.
//! - [`drop`](mod@drop): `cbvh lucy-on-turbine` and `cbvh robot-in-plant`.
//! - [`plot`]: the drop tests' PNG line plots.
//! - [`check_output`], [`check_threads`], [`check_tris`]: the checks every
//!   command makes of its flags before any work, naming the flag.
//! - [`values`]: the numeric flags' value parsers (negative numbers, and
//!   codec settings against the bounds the codecs declare).
//!
//! The binaries are a line each: [`main`] for `cbvh`, and
//! [`exit`]`(drop::lucy::run(...))` for a drop test under its own name.

pub mod build;
pub mod drop;
pub mod generate;
pub mod info;
pub mod plot;
pub mod render;
pub mod values;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use crate::Mesh;
use crate::codec::clbvh::ClOptions;
use crate::codec::hcc::HccOptions;
use crate::codec::racbvh::RacOptions;
use crate::codec::settings::Setting;
use crate::codec::{AnyCodec, CodecKind, OpenOptions};
use crate::scene::Kind;
use indicatif::{ProgressBar, ProgressStyle};
use values::whole;

/// A subcommand's error: printed after `error: `, exit status 1.
pub type CliResult = Result<(), Box<dyn std::error::Error>>;

/// A progress bar on stderr when it is a terminal, hidden otherwise.
pub fn progress_bar(message: &str, total: u64) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template(
            "{msg:>12} [{bar:40}] {percent:>3}% {elapsed_precise} eta {eta}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    pb.set_message(message.to_string());
    pb
}

/// Named figures (a codec's bytes by part, header fields or build fields)
/// as a JSON object, for the `--json` reports.
pub(crate) fn json_object<'a, V: Into<serde_json::Value>>(
    fields: impl IntoIterator<Item = (&'a str, V)>,
) -> serde_json::Map<String, serde_json::Value> {
    fields
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.into()))
        .collect()
}

/// Checks, before any work, that a command can write its output `path`,
/// given by `flag` (named in every error): the path names a file, not a
/// directory; its directory exists (it is never created); a file can be
/// made there (probed with the temporary file every save goes through,
/// [`crate::files`], removed at once); and, unless `exts` is empty, its
/// extension is one of `exts` (lower case; any case accepted). Nothing is
/// left behind.
pub fn check_output(flag: &str, path: &Path, exts: &[&str]) -> Result<(), String> {
    let shown = path.display();
    if !exts.is_empty() {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        if !exts.contains(&ext.as_str()) {
            let names: Vec<String> = exts.iter().map(|e| format!(".{e}")).collect();
            return Err(format!(
                "{flag} {shown}: name the file {}",
                names.join(" or ")
            ));
        }
    }
    let fail = |why: String| format!("{flag} {shown}: cannot write there: {why}");
    if path.file_name().is_none() || path.is_dir() {
        return Err(fail("it is a directory: name a file".into()));
    }
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(fail(if dir.exists() {
            format!("{} is not a directory", dir.display())
        } else {
            format!("directory {} does not exist", dir.display())
        }));
    }
    // Dropped uncommitted: the temporary file is removed.
    crate::files::AtomicFile::create(path).map_err(|e| fail(e.to_string()))?;
    Ok(())
}

/// Checks `--threads` before any work: at least 1, and at most 4 × the
/// machine's hardware threads (more only adds stacks and switching; a
/// pool of a hundred thousand threads can take the machine down).
pub fn check_threads(threads: Option<usize>) -> Result<(), String> {
    match threads {
        Some(0) => Err("--threads must be at least 1".into()),
        Some(t) => {
            let machine = std::thread::available_parallelism().map_or(1, |n| n.get());
            if t > 4 * machine {
                Err(format!(
                    "--threads {t} is more than 4 × the {machine} hardware threads of this machine"
                ))
            } else {
                Ok(())
            }
        }
        None => Ok(()),
    }
}

/// Checks a generator's triangle count, given by `flag`, before any work:
/// from [`crate::scene::MIN_TRIS`] to `max` ([`crate::scene::MAX_TRIS`],
/// or [`crate::scene::MAX_STREAMED_TRIS`] where the kind streams to a file).
pub fn check_tris(flag: &str, kind: Kind, tris: usize, max: usize) -> Result<(), String> {
    let min = crate::scene::MIN_TRIS;
    if (min..=max).contains(&tris) {
        Ok(())
    } else {
        Err(format!(
            "{flag} {tris}: the {kind} generator makes {min} to {max} triangles"
        ))
    }
}

/// The machine's memory (Linux `MemTotal`), if known.
pub(crate) fn machine_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// What a `cbvh gen` or `cbvh build` of `output` killed half way left
/// beside it: the output's temporary file (`.NAME.tmp-PID-N`, see
/// [`crate::files`]) and an out-of-core build's directory
/// (`.NAME.cbvh-build-PID`). Those whose process is gone are removed, and
/// said so; those of a running process are named.
pub fn clear_stale(output: &std::path::Path) {
    let dir = match output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The build's directory, and the output's temporary file
    // (`crate::files`: `.NAME.tmp-PID-N`).
    let (dir_prefix, file_prefix) = (format!(".{name}.cbvh-build-"), format!(".{name}.tmp-"));
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return;
    };
    for e in entries.flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        let pid = match (n.strip_prefix(&dir_prefix), n.strip_prefix(&file_prefix)) {
            (Some(pid), _) => pid,
            (None, Some(rest)) => rest.split('-').next().unwrap_or(""),
            _ => continue,
        };
        if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
            continue;
        }
        let alive = std::path::Path::new(&format!("/proc/{pid}")).exists();
        let removed = || {
            let p = e.path();
            if p.is_dir() {
                std::fs::remove_dir_all(&p).is_ok()
            } else {
                std::fs::remove_file(&p).is_ok()
            }
        };
        if alive {
            eprintln!(
                "note: {} belongs to a build still running (process {pid})",
                e.path().display()
            );
        } else if removed() {
            eprintln!(
                "note: removed {}, left by a run that was stopped half way",
                e.path().display()
            );
        }
    }
}

/// Where a subcommand's mesh comes from: a file, or a generator.
#[derive(clap::Args, Debug, Clone)]
pub struct MeshSource {
    /// A mesh file (.off, .ply, .obj, .stl), or a cbvh codec file written by
    /// `cbvh build ... -o FILE` (recognised by its content, whatever its name).
    #[arg(required_unless_present = "gen_kind", conflicts_with = "gen_kind")]
    pub mesh: Option<PathBuf>,
    /// Codec files: skip `verify` when opening (only for files you wrote).
    #[arg(long)]
    pub no_verify: bool,
    /// Codec files of codecs that decode into a cache (racbvh's clusters,
    /// hcc-ooc's low-level trees): the cache's budget in MiB. An hcc-ooc
    /// file whose i-HCCMesh fits is decoded whole; one that does not runs
    /// out of core, memory-mapped.
    #[arg(long, value_name = "MIB", default_value_t = 1024, allow_negative_numbers = true,
          value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub cache_mib: usize,
    /// Generate the mesh instead: statue, turbine, plant, robot or isosurface.
    #[arg(long = "gen", value_name = "KIND")]
    pub gen_kind: Option<Kind>,
    /// Triangle count to generate, 1 000 to 200 000 000 (default: the
    /// kind's default).
    #[arg(long, requires = "gen_kind", allow_negative_numbers = true,
          value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub tris: Option<usize>,
    /// Generator seed.
    #[arg(long, default_value_t = 0, requires = "gen_kind", allow_negative_numbers = true,
          value_parser = whole::<u64>(0, u64::MAX))]
    pub seed: u64,
}

impl MeshSource {
    /// Checks the flags before any work: `--tris` within the generator's
    /// range (the mesh is generated in memory: up to
    /// [`crate::scene::MAX_TRIS`]).
    pub fn check(&self) -> Result<(), String> {
        match (self.gen_kind, self.tris) {
            (Some(kind), Some(tris)) => check_tris("--tris", kind, tris, crate::scene::MAX_TRIS),
            _ => Ok(()),
        }
    }

    /// Loads a mesh or opens a codec file (chosen by the file's magic), or
    /// generates a mesh.
    pub fn load_any(&self) -> Result<Loaded, Box<dyn std::error::Error>> {
        if let Some(path) = &self.mesh
            && CodecKind::of_file(path).is_some()
        {
            let opts = OpenOptions {
                verify: !self.no_verify,
                cache_budget_bytes: self.cache_mib.saturating_mul(1 << 20),
            };
            let codec = AnyCodec::open(path, &opts)?;
            return Ok(Loaded::Codec(Box::new(codec), path.display().to_string()));
        }
        let (mesh, name) = self.load()?;
        Ok(Loaded::Mesh(mesh, name))
    }

    /// Loads or generates the mesh, with a progress bar for generation;
    /// a codec file gives its stored mesh. Returns the mesh and a name for
    /// reports.
    pub fn load(&self) -> Result<(Mesh, String), Box<dyn std::error::Error>> {
        if let Some(path) = &self.mesh
            && CodecKind::of_file(path).is_some()
        {
            let Loaded::Codec(codec, name) = self.load_any()? else {
                unreachable!("a codec file loads as a codec")
            };
            return Ok((codec.decoded_mesh(), name));
        }
        if let Some(kind) = self.gen_kind {
            let tris = self
                .tris
                .unwrap_or_else(|| crate::scene::default_tris(kind));
            let mesh = generate(kind, tris, self.seed, "generating")?;
            Ok((
                mesh,
                format!("{kind} ({tris} requested, seed {})", self.seed),
            ))
        } else {
            let path = self.mesh.as_ref().expect("clap requires a mesh or --gen");
            Ok((crate::mesh::load(path)?, path.display().to_string()))
        }
    }
}

/// A loaded input: a mesh, or an opened (and verified) codec file; each
/// with a name for reports.
pub enum Loaded {
    /// A mesh (loaded or generated).
    Mesh(Mesh, String),
    /// A codec file.
    Codec(Box<AnyCodec>, String),
}

/// What `cbvh build` and `cbvh render` make: a codec of the registry, or
/// parry's own `TriMesh` for comparison. Parsed from the codecs' names and
/// `parry`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Structure {
    /// A cbvh codec.
    Codec(CodecKind),
    /// parry3d's own TriMesh.
    Parry,
}

impl Structure {
    /// The name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Structure::Codec(k) => k.name(),
            Structure::Parry => "parry",
        }
    }

    /// Every structure: the codecs in registry order, then parry.
    fn all() -> impl Iterator<Item = Structure> {
        CodecKind::ALL
            .iter()
            .map(|&k| Structure::Codec(k))
            .chain([Structure::Parry])
    }

    /// clap's parser for `--codec`: the names of `Structure::all`, each
    /// with its summary in `--help`.
    pub fn parser() -> impl clap::builder::TypedValueParser<Value = Structure> {
        use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
        let values = Structure::all().map(|s| {
            PossibleValue::new(s.name()).help(match s {
                Structure::Codec(k) if k.builds_out_of_core() => {
                    format!("{} (builds out of core)", k.summary())
                }
                Structure::Codec(k) => k.summary().to_string(),
                Structure::Parry => "parry3d's own TriMesh, for comparison".to_string(),
            })
        });
        PossibleValuesParser::new(values).map(|name| {
            Structure::all()
                .find(|s| s.name() == name)
                .expect("clap accepts only the possible values")
        })
    }
}

impl std::fmt::Display for Structure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The codec settings of every command that encodes (`cbvh build`, the
/// drop tests): the common ones, and each codec's own as `--set
/// CODEC.KEY=VALUE`, turned into options by the codecs themselves
/// ([`crate::codec::settings`]), so that no codec's field is named here
/// but in the shorthands of the last six flags, which take their keys and
/// bounds from the codecs' declared settings ([`Setting`]). Every value is
/// checked against its codec whether that codec is in use or not: a
/// setting for a codec the command does not build is a mistake.
#[derive(clap::Args, Debug, Clone)]
pub struct CodecFlags {
    /// The most triangles a leaf of the canonical tree holds (1, the
    /// papers' form, by default): plain, racbvh and hcc leaves hold up to
    /// that many (hcc's multi-triangle leaves); CLBVH collapses its own
    /// leaves from that tree, of up to 4 triangles (compact: 6) or this
    /// many if more.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true,
          value_parser = whole::<u16>(1, u16::MAX.into()))]
    pub leaf_size: u16,
    /// Bits per quantized vertex coordinate; 0 keeps vertices as f32.
    /// Unset: each codec's default (racbvh 16, hcc f32, hcc-ooc 16, which
    /// always quantizes: 0 gives it 16). Bits that no codec quantizes to
    /// are refused, and a codec in use refuses bits it does not take (the
    /// error says what each takes).
    #[arg(long, allow_negative_numbers = true, value_parser = values::vertex_bits())]
    pub vertex_bits: Option<u32>,
    /// A codec's own setting, CODEC.KEY=VALUE (repeatable; a later one
    /// wins). The settings, and the values they take, from the registry:
    #[arg(long = "set", value_name = "CODEC.KEY=VALUE", long_help = settings_help())]
    pub set: Vec<String>,
    /// RACBVH: nodes per cluster (shorthand for --set
    /// racbvh.cluster-nodes=N, which takes the same values; 4096 by
    /// default).
    #[arg(long, allow_negative_numbers = true,
          value_parser = values::setting::<u32>(CodecKind::Racbvh, RacOptions::CLUSTER_NODES))]
    pub cluster_nodes: Option<u32>,
    /// RACBVH: bits per quantized box coordinate (shorthand for --set
    /// racbvh.bits=N, which takes the same values; 16 by default).
    #[arg(long, allow_negative_numbers = true,
          value_parser = values::setting::<u32>(CodecKind::Racbvh, RacOptions::BITS))]
    pub bits: Option<u32>,
    /// CLBVH: `M`, the most triangles its SAH collapse merges into one
    /// leaf; subtrees of at most `8 · M` triangles become compressed
    /// multi-leaf nodes (the paper's `N × M` threshold). Shorthand for
    /// --set clbvh.leaf-size=M --set clbvh-compact.leaf-size=M, which take
    /// the same values.
    #[arg(long, value_name = "M", allow_negative_numbers = true,
          value_parser = values::setting::<usize>(CodecKind::Clbvh, ClOptions::LEAF_SIZE))]
    pub clbvh_leaf_size: Option<usize>,
    /// CLBVH: regular 8-wide nodes only, no compressed multi-leaf nodes
    /// (the paper's uncompressed BVH8 reference; shorthand for --set
    /// clbvh.multi-leaf=false --set clbvh-compact.multi-leaf=false).
    #[arg(long)]
    pub clbvh_uncompressed: bool,
    /// hcc: drop the input's vertex ids (part vertex-ids): smaller, but the
    /// decoded mesh repeats the vertices low-level trees share (shorthand
    /// for --set hcc.vertex-ids=false).
    #[arg(long)]
    pub no_vertex_ids: bool,
    /// hcc: number triangles and vertices in the tree's order, storing
    /// neither id map (parts ids and vertex-ids): the smallest form. The
    /// file's triangle ids and decoded mesh are then in that order, not the
    /// input's (shorthand for --set hcc.tree-order=true).
    #[arg(long)]
    pub tree_order: bool,
}

/// `CODEC.KEY=VALUE` for codec `kind`'s `setting`.
fn shorthand(kind: CodecKind, setting: Setting, value: impl std::fmt::Display) -> String {
    format!("{kind}.{}={value}", setting.key)
}

impl CodecFlags {
    /// The settings, shorthands first and then `--set` in order.
    pub fn settings(&self) -> Result<crate::codec::Settings, crate::codec::SettingsError> {
        let mut s = crate::codec::Settings::new(usize::from(self.leaf_size), self.vertex_bits);
        let mut shorthands = Vec::new();
        let rac = CodecKind::Racbvh;
        if let Some(n) = self.cluster_nodes {
            shorthands.push(shorthand(rac, RacOptions::CLUSTER_NODES, n));
        }
        if let Some(n) = self.bits {
            shorthands.push(shorthand(rac, RacOptions::BITS, n));
        }
        for codec in [CodecKind::Clbvh, CodecKind::ClbvhCompact] {
            if let Some(m) = self.clbvh_leaf_size {
                shorthands.push(shorthand(codec, ClOptions::LEAF_SIZE, m));
            }
            if self.clbvh_uncompressed {
                shorthands.push(shorthand(codec, ClOptions::MULTI_LEAF, false));
            }
        }
        if self.no_vertex_ids {
            shorthands.push(shorthand(CodecKind::Hcc, HccOptions::VERTEX_IDS, false));
        }
        if self.tree_order {
            shorthands.push(shorthand(CodecKind::Hcc, HccOptions::TREE_ORDER, true));
        }
        for spec in shorthands.iter().chain(&self.set) {
            s.set(spec)?;
        }
        Ok(s)
    }

    /// The options of the codecs `kinds` from these flags (the others
    /// keep their defaults, but their settings are checked all the same:
    /// [`AnyOptions::from_settings`](crate::codec::AnyOptions::from_settings)).
    pub fn options(
        &self,
        kinds: &[CodecKind],
    ) -> Result<crate::codec::AnyOptions, crate::codec::SettingsError> {
        crate::codec::AnyOptions::from_settings(&self.settings()?, kinds)
    }
}

/// `--set`'s help: every codec's settings, from the registry.
fn settings_help() -> String {
    let mut help = String::from(
        "A codec's own setting, CODEC.KEY=VALUE (repeatable; a later one wins). The settings:",
    );
    for k in CodecKind::ALL {
        let settings = k.settings();
        if !settings.is_empty() {
            let keys: Vec<&str> = settings.iter().map(|s| s.key).collect();
            help.push_str(&format!("\n  {}: {}", k.name(), keys.join(", ")));
        }
    }
    help.push_str("\nThe values they take (checked for every codec, in use or not):");
    for k in CodecKind::ALL {
        for s in k.settings() {
            help.push_str(&format!("\n  {k}.{}: {}", s.key, s.values));
        }
    }
    help.push_str("\nThe bits per vertex coordinate (--vertex-bits) the codecs quantize to:");
    for k in CodecKind::ALL {
        if let Some(v) = k.vertex_bits() {
            help.push_str(&format!("\n  {k}: {v}"));
        }
    }
    help
}

/// Generates a mesh with a progress bar (showing `label`) on a terminal.
pub fn generate(
    kind: Kind,
    tris: usize,
    seed: u64,
    label: &str,
) -> Result<Mesh, crate::scene::GenError> {
    let pb = progress_bar(label, 1);
    let mesh = crate::scene::generate(kind, tris, seed, &mut |done, total| {
        pb.set_length(total);
        pb.set_position(done);
    })?;
    pb.finish_and_clear();
    Ok(mesh)
}

/// cbvh: compressed bounding volume hierarchies for collision detection and ray tracing.
#[derive(Parser)]
#[command(name = "cbvh", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Generate a deterministic procedural mesh and write it as PLY or OBJ.
    Gen(generate::GenArgs),
    /// Print a mesh file's triangles, vertices, bounds, degenerate triangles and boundary edges,
    /// or a codec file's header, sizes per part and verification.
    Info(info::InfoArgs),
    /// Build a BVH with a codec and report its size and build time.
    Build(build::BuildArgs),
    /// Ray-trace a mesh (Whitted: shadows, reflections) through a codec and write a PNG.
    Render(render::RenderArgs),
    /// Drop a statue on a turbine and time the narrow phase per step, parry TriMesh vs cbvh
    /// (also the binary `lucy-on-turbine`).
    LucyOnTurbine(drop::lucy::LucyArgs),
    /// Drop a robot into a power plant and time the narrow phase per step, parry TriMesh vs
    /// cbvh (also the binary `robot-in-plant`).
    RobotInPlant(drop::robot::RobotArgs),
}

/// The `cbvh` command: parses the process's arguments, runs the
/// subcommand, and returns its exit status.
pub fn main() -> ExitCode {
    crate::logger::init_stderr();
    let cli = Cli::parse();
    match cli.command {
        Command::Gen(a) => exit(generate::run(a)),
        Command::Info(a) => exit(info::run(a)),
        Command::Build(a) => exit(build::run(a)),
        Command::Render(a) => exit(render::run(a)),
        Command::LucyOnTurbine(a) => exit(drop::lucy::run(a)),
        Command::RobotInPlant(a) => exit(drop::robot::run(a)),
    }
}

/// A command's result as its exit status: success, or the error printed
/// after `error: ` and status 1.
pub fn exit<E: std::fmt::Display>(result: Result<(), E>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
