//! `robot-in-plant`: the small robot (16 k triangles, standing in for the
//! RACBVH paper's Hubo) dropped into a generated power plant, with the same
//! side-by-side report as `lucy-on-turbine`.

mod common;

use std::path::PathBuf;
use std::process::ExitCode;

use cbvh::scene::Kind;
use clap::Parser;

/// Drop a robot into a power plant and time the narrow phase per step, parry TriMesh vs cbvh.
#[derive(Parser, Debug)]
#[command(name = "robot-in-plant", version, about)]
struct Args {
    /// Triangles of the generated robot.
    #[arg(long, default_value_t = 16_000)]
    robot_tris: usize,
    /// Triangles of the generated plant.
    #[arg(long, default_value_t = 200_000)]
    plant_tris: usize,
    /// Use this mesh file (or cbvh codec file) as the robot instead.
    #[arg(long)]
    robot: Option<PathBuf>,
    /// Use this mesh file (or cbvh codec file) as the plant instead.
    #[arg(long)]
    plant: Option<PathBuf>,
    #[command(flatten)]
    sim: common::SimArgs,
}

fn main() -> ExitCode {
    let mut a = Args::parse();
    // The robot is small next to a plant: default to a tenth of its width
    // unless the user chose a width.
    if !std::env::args().any(|s| s.starts_with("--width-fraction")) {
        a.sim.width_fraction = 0.1;
    }
    let run = || -> Result<(), String> {
        common::validate(&a.sim)?;
        common::init_threads(&a.sim)?;
        // Reject bad shape names before generating meshes.
        common::run_specs(&a.sim)?;
        let (robot, rn) =
            common::mesh_from(&a.robot, Kind::Robot, a.robot_tris, a.sim.seed, "robot")?;
        let (plant, pn) =
            common::mesh_from(&a.plant, Kind::Plant, a.plant_tris, a.sim.seed, "plant")?;
        common::run_sim("robot-in-plant", robot, plant, (rn, pn), &a.sim)
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
