//! `lucy-on-turbine`: a generated statue (or any mesh) dropped onto a fixed
//! generated turbine (or any mesh), 215 steps at 60 Hz as in the RACBVH
//! paper, once per shape: parry's TriMesh and every cbvh codec, side by side.

mod common;

use std::path::PathBuf;
use std::process::ExitCode;

use cbvh::scene::Kind;
use clap::Parser;

/// Drop a statue on a turbine and time the narrow phase per step, parry TriMesh vs cbvh.
#[derive(Parser, Debug)]
#[command(name = "lucy-on-turbine", version, about)]
struct Args {
    /// Triangles of the generated statue.
    #[arg(long, default_value_t = 200_000)]
    statue_tris: usize,
    /// Triangles of the generated turbine.
    #[arg(long, default_value_t = 100_000)]
    turbine_tris: usize,
    /// Use this mesh file (or cbvh codec file) as the statue instead (any units and offset: it is scaled and placed).
    #[arg(long)]
    statue: Option<PathBuf>,
    /// Use this mesh file (or cbvh codec file) as the turbine instead.
    #[arg(long)]
    turbine: Option<PathBuf>,
    /// Axis of the generated turbine: `x` stands it upright like the CAD
    /// turbine of the papers (`shared/data/turbine.off` has its axis along x),
    /// `y` lays it flat.
    #[arg(long, default_value = "x", value_parser = ["x", "y"])]
    turbine_axis: String,
    #[command(flatten)]
    sim: common::SimArgs,
}

fn main() -> ExitCode {
    let a = Args::parse();
    let run = || -> Result<(), String> {
        common::validate(&a.sim)?;
        common::init_threads(&a.sim)?;
        // Reject bad shape names before generating meshes.
        common::run_specs(&a.sim)?;
        let (statue, sn) =
            common::mesh_from(&a.statue, Kind::Statue, a.statue_tris, a.sim.seed, "statue")?;
        let (mut turbine, tn) = common::mesh_from(
            &a.turbine,
            Kind::Turbine,
            a.turbine_tris,
            a.sim.seed,
            "turbine",
        )?;
        if a.turbine.is_none() && a.turbine_axis == "x" {
            // The generator builds the rotor around y: turn it about z so the
            // axis lies along x and the rotor stands on its rim.
            for v in &mut turbine.vertices {
                *v = [v[1], -v[0], v[2]];
            }
        }
        common::run_sim("lucy-on-turbine", statue, turbine, (sn, tn), &a.sim)
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
