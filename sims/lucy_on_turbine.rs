//! `lucy-on-turbine`: the same as `cbvh lucy-on-turbine` (see
//! `cbvh::app::drop::lucy`), under the name the papers' scene goes by.

use std::process::ExitCode;

use cbvh::app::drop::lucy::LucyArgs;
use clap::Parser;

fn main() -> ExitCode {
    cbvh::app::exit(cbvh::app::drop::lucy::run(LucyArgs::parse()))
}
