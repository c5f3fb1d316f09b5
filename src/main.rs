//! The `cbvh` command line: generate meshes, inspect them, build and
//! measure BVHs, render, and run the drop tests. `cbvh --help` lists the
//! subcommands; the front end itself is `cbvh::app` (feature `app`).

fn main() -> std::process::ExitCode {
    cbvh::app::main()
}
