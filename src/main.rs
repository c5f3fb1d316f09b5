//! The `cbvh` command line: generate meshes, inspect them, build and
//! measure BVHs. `cbvh --help` lists the subcommands.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cli;

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
    Gen(cli::generate::GenArgs),
    /// Print a mesh file's triangles, vertices, bounds, degenerate triangles and boundary edges,
    /// or a codec file's header, sizes per part and verification.
    Info(cli::info::InfoArgs),
    /// Build a BVH with a codec and report its size and build time.
    Build(cli::build::BuildArgs),
    /// Ray-trace a mesh (Whitted: shadows, reflections) through a codec and write a PNG.
    Render(cli::render::RenderArgs),
}

fn main() -> ExitCode {
    cbvh::logger::init_stderr();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Gen(a) => cli::generate::run(a),
        Command::Info(a) => cli::info::run(a),
        Command::Build(a) => cli::build::run(a),
        Command::Render(a) => cli::render::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
