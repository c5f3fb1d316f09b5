//! `robot-in-plant`: the same as `cbvh robot-in-plant` (see
//! `cbvh::app::drop::robot`).

use std::process::ExitCode;

use cbvh::app::drop::robot::RobotArgs;
use clap::Parser;

fn main() -> ExitCode {
    cbvh::app::exit(cbvh::app::drop::robot::run(RobotArgs::parse()))
}
