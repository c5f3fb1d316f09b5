//! `lucy-on-turbine`: a generated statue (or any mesh) dropped onto a fixed
//! generated turbine (or any mesh), 215 steps at 60 Hz as in the RACBVH
//! paper, once per shape: parry's TriMesh and every cbvh codec, side by side.

use std::path::PathBuf;

use crate::app::values::whole;
use crate::scene::Kind;

/// Drop a statue on a turbine and time the narrow phase per step, parry TriMesh vs cbvh.
#[derive(clap::Parser, Debug)]
#[command(name = "lucy-on-turbine", version, about)]
pub struct LucyArgs {
    /// Triangles of the generated statue (1 000 to 200 000 000).
    #[arg(long, default_value_t = 200_000, allow_negative_numbers = true, value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub statue_tris: usize,
    /// Triangles of the generated turbine (1 000 to 200 000 000).
    #[arg(long, default_value_t = 100_000, allow_negative_numbers = true, value_parser = whole::<usize>(0, usize::MAX as u64))]
    pub turbine_tris: usize,
    /// Use this mesh file (or cbvh codec file) as the statue instead (any units and offset: it is scaled and placed).
    #[arg(long)]
    pub statue: Option<PathBuf>,
    /// Use this mesh file (or cbvh codec file) as the turbine instead.
    #[arg(long)]
    pub turbine: Option<PathBuf>,
    /// Axis of the generated turbine: `x` stands it upright like the CAD
    /// turbine of the papers (`shared/data/turbine.off` has its axis along x),
    /// `y` lays it flat.
    #[arg(long, default_value = "x", value_parser = ["x", "y"])]
    pub turbine_axis: String,
    /// The options every drop test shares.
    #[command(flatten)]
    pub sim: super::SimArgs,
}

/// Runs the drop test.
pub fn run(mut a: LucyArgs) -> Result<(), String> {
    a.sim.width_fraction.get_or_insert(0.5);
    let statue = super::MeshFlags {
        file: ("--statue", &a.statue),
        tris: ("--statue-tris", a.statue_tris),
        kind: Kind::Statue,
    };
    let turbine = super::MeshFlags {
        file: ("--turbine", &a.turbine),
        tris: ("--turbine-tris", a.turbine_tris),
        kind: Kind::Turbine,
    };
    super::start(&a.sim, &statue, &turbine)?;
    let (statue, sn) = super::dropped_from(&statue, a.sim.seed, a.sim.subdivide)?;
    let (mut turbine, tn) = super::mesh_from(&turbine, a.sim.seed)?;
    if a.turbine.is_none() && a.turbine_axis == "x" {
        // The generator builds the rotor around y: turn it about z so the
        // axis lies along x and the rotor stands on its rim.
        for v in &mut turbine.vertices {
            *v = [v[1], -v[0], v[2]];
        }
    }
    super::run_sim("lucy-on-turbine", statue, turbine, (sn, tn), &a.sim)
}
