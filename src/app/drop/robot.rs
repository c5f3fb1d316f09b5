//! `robot-in-plant`: the small robot (16 k triangles, standing in for the
//! RACBVH paper's Hubo) dropped into a generated power plant, with the same
//! side-by-side report as `lucy-on-turbine`.

use std::path::PathBuf;

use crate::app::values::whole;
use crate::scene::Kind;

/// Drop a robot into a power plant and time the narrow phase per step, parry TriMesh vs cbvh.
#[derive(clap::Parser, Debug)]
#[command(name = "robot-in-plant", version, about)]
pub struct RobotArgs {
    /// Triangles of the generated robot (1 000 to 200 000 000).
    #[arg(long, default_value_t = 16_000, allow_negative_numbers = true, value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub robot_tris: usize,
    /// Triangles of the generated plant (1 000 to 200 000 000).
    #[arg(long, default_value_t = 200_000, allow_negative_numbers = true, value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub plant_tris: usize,
    /// Use this mesh file (or cbvh codec file) as the robot instead.
    #[arg(long)]
    pub robot: Option<PathBuf>,
    /// Use this mesh file (or cbvh codec file) as the plant instead.
    #[arg(long)]
    pub plant: Option<PathBuf>,
    /// The options every drop test shares.
    #[command(flatten)]
    pub sim: super::SimArgs,
}

/// Runs the drop test.
pub fn run(mut a: RobotArgs) -> Result<(), String> {
    // The robot is small next to a plant: a tenth of its width unless the
    // user chose a width.
    a.sim.width_fraction.get_or_insert(0.1);
    let robot = super::MeshFlags {
        file: ("--robot", &a.robot),
        tris: ("--robot-tris", a.robot_tris),
        kind: Kind::Robot,
    };
    let plant = super::MeshFlags {
        file: ("--plant", &a.plant),
        tris: ("--plant-tris", a.plant_tris),
        kind: Kind::Plant,
    };
    super::start(&a.sim, &robot, &plant)?;
    let (robot, rn) = super::dropped_from(&robot, a.sim.seed, a.sim.subdivide)?;
    let (plant, pn) = super::mesh_from(&plant, a.sim.seed)?;
    super::run_sim("robot-in-plant", robot, plant, (rn, pn), &a.sim)
}
