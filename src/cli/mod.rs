//! Subcommands of the `cbvh` binary and what they share.

pub mod build;
pub mod generate;
pub mod info;
pub mod render;

use std::io::IsTerminal;
use std::path::PathBuf;

use cbvh::Mesh;
use cbvh::codec::{AnyCodec, CodecKind, OpenOptions};
use cbvh::scene::Kind;
use indicatif::{ProgressBar, ProgressStyle};

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
    #[arg(long, value_name = "MIB", default_value_t = 1024)]
    pub cache_mib: usize,
    /// Generate the mesh instead: statue, turbine, plant, robot or isosurface.
    #[arg(long = "gen", value_name = "KIND")]
    pub gen_kind: Option<Kind>,
    /// Triangle count to generate (default: the kind's default).
    #[arg(long, requires = "gen_kind")]
    pub tris: Option<usize>,
    /// Generator seed.
    #[arg(long, default_value_t = 0, requires = "gen_kind")]
    pub seed: u64,
}

impl MeshSource {
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
            let tris = self.tris.unwrap_or_else(|| cbvh::scene::default_tris(kind));
            let mesh = generate(kind, tris, self.seed)?;
            Ok((
                mesh,
                format!("{kind} ({tris} requested, seed {})", self.seed),
            ))
        } else {
            let path = self.mesh.as_ref().expect("clap requires a mesh or --gen");
            Ok((cbvh::mesh::load(path)?, path.display().to_string()))
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

    /// clap's parser for `--codec`: the names of [`Structure::all`], each
    /// with its summary in `--help`.
    pub fn parser() -> impl clap::builder::TypedValueParser<Value = Structure> {
        use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
        let values = Structure::all().map(|s| {
            PossibleValue::new(s.name()).help(match s {
                Structure::Codec(k) => k.summary(),
                Structure::Parry => "parry3d's own TriMesh, for comparison",
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

/// Generates a mesh with a progress bar on a terminal.
pub fn generate(kind: Kind, tris: usize, seed: u64) -> Result<Mesh, cbvh::scene::GenError> {
    let pb = progress_bar("generating", 1);
    let mesh = cbvh::scene::generate(kind, tris, seed, &mut |done, total| {
        pb.set_length(total);
        pb.set_position(done);
    })?;
    pb.finish_and_clear();
    Ok(mesh)
}
