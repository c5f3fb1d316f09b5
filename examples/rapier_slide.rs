//! The analytic scenes of [`cbvh::sim::slide`] for every representation
//! of the ground and the body, as a table of measured against expected:
//! a cube sliding (or staying) on a ramp, a sphere rolling down one, a
//! ball settling in a bowl, a cube dropped on the ground, a stack of cubes,
//! a cube at a table's edge. Grounds are a parry primitive (where the scene
//! has one), parry's `TriMesh` with and without `FIX_INTERNAL_EDGES`, and
//! cbvh shapes of the plain, hcc and clbvh codecs in both contact modes;
//! the body is of the same representation, and a primitive body is run on
//! every mesh ground too (see [`cbvh::sim::slide::pairings`]).
//!
//! ```sh
//! cargo run --release --features sims --example rapier_slide
//! cargo run --release --features sims --example rapier_slide -- --scene slide --rep plain-pairs --json out.json
//! ```
//!
//! `--scene NAME` keeps the scenes whose name contains NAME; `--rep NAMES`
//! (comma-separated) the runs whose ground or body is one of NAMES
//! (`primitive`, `trimesh`, `trimesh-fixed`, `plain`, `plain-pairs`, ...);
//! `--json FILE` writes every report; `--codecs NAMES` the codecs to run
//! (default `plain,hcc,clbvh`); `--trace DIR` writes, for every run, the
//! moving body's energy and contacts at every step
//! ([`cbvh::sim::trace`]) as `DIR/SCENE.GROUND.BODY.steps.csv` and
//! `.contacts.csv`, and prints a summary line after the run's row.
//! Failing scenes do not fail the
//! program: the table is the result. A pairing that cannot be set up is
//! listed as not run, with the reason (parry's convex hull of the fine
//! icosphere, which parry leaves without faces).

use std::io::Write;
use std::time::Instant;

use cbvh::codec::CodecKind;
use cbvh::sim::slide::{Rep, Report, Scene, pairings};
use cbvh::sim::trace::Trace;

/// The codecs the example runs by default, by name.
const CODECS: &str = "plain,hcc,clbvh";

struct Args {
    scene: Option<String>,
    reps: Option<Vec<Rep>>,
    json: Option<String>,
    codecs: String,
    trace: Option<std::path::PathBuf>,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        scene: None,
        reps: None,
        json: None,
        codecs: CODECS.into(),
        trace: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--scene" => args.scene = Some(value()?),
            "--rep" => {
                args.reps = Some(
                    value()?
                        .split(',')
                        .map(str::parse)
                        .collect::<Result<Vec<Rep>, String>>()?,
                )
            }
            "--json" => args.json = Some(value()?),
            "--codecs" => args.codecs = value()?,
            "--trace" => args.trace = Some(value()?.into()),
            "-h" | "--help" => {
                println!(
                    "rapier_slide [--scene NAME] [--rep NAME[,NAME...]] [--json FILE]\n\
                     \x20            [--codecs NAME[,NAME...]] [--trace DIR]\n\
                     scenes: {}",
                    Scene::standard()
                        .iter()
                        .map(Scene::name)
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other:?} (see --help)")),
        }
    }
    Ok(args)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    cbvh::logger::init_stderr();
    let args = parse_args()?;
    let codecs = args
        .codecs
        .split(',')
        .map(|n| n.trim().parse::<CodecKind>())
        .collect::<Result<Vec<_>, _>>()?;
    let keep = |ground: Rep, body: Rep| {
        args.reps
            .as_ref()
            .is_none_or(|r| r.contains(&ground) || r.contains(&body))
    };
    let t0 = Instant::now();
    let mut reports: Vec<Report> = Vec::new();
    let mut skipped = 0;
    println!(
        "{:<18} {:<14} {:<14} {:<22} {:>9} {:>9} {:>7} {:>8} {:>8} {:>8}  result",
        "scene",
        "ground",
        "body",
        "quantity",
        "measured",
        "expected",
        "err %",
        "uphill",
        "side",
        "moved"
    );
    for scene in Scene::standard() {
        if args
            .scene
            .as_ref()
            .is_some_and(|s| !scene.name().contains(s.as_str()))
        {
            continue;
        }
        for (ground, body) in pairings(&codecs) {
            if !scene.has_ground(ground) || !keep(ground, body) {
                continue;
            }
            let mut trace = Trace::default();
            let result = if args.trace.is_some() {
                scene.run_traced(ground, body, &mut trace)
            } else {
                scene.run(ground, body)
            };
            let r = match result {
                Ok(r) => r,
                Err(e) => {
                    println!(
                        "{:<18} {:<14} {:<14} not run: {e}",
                        scene.name(),
                        ground,
                        body
                    );
                    skipped += 1;
                    continue;
                }
            };
            let err = r
                .rel_error
                .map_or_else(|| "-".into(), |e| format!("{:.1}", 100.0 * e));
            let (uphill, side) = r.slope.map_or_else(
                || ("-".into(), "-".into()),
                |s| {
                    (
                        format!("{:.4}", s.max_uphill),
                        format!("{:.4}", s.max_sideways),
                    )
                },
            );
            println!(
                "{:<18} {:<14} {:<14} {:<22} {:>9.4} {:>9.4} {:>7} {:>8} {:>8} {:>8.4}  {}",
                r.scene,
                r.ground,
                r.body,
                r.quantity,
                r.measured,
                r.expected,
                err,
                uphill,
                side,
                r.max_travel,
                if r.pass { "PASS" } else { "FAIL" }
            );
            if let Some(dir) = &args.trace {
                std::fs::create_dir_all(dir)?;
                let stem = format!("{}.{}.{}", r.scene, r.ground, r.body);
                let steps = dir.join(format!("{stem}.steps.csv"));
                std::fs::write(&steps, trace.steps_csv())?;
                std::fs::write(
                    dir.join(format!("{stem}.contacts.csv")),
                    trace.contacts_csv(),
                )?;
                let s = trace.summary();
                println!(
                    "    trace: lost {:.4} J ({:.1} % of the potential released), {} drops, \
                     {:.1} points a step, ids kept {:.1} %, impulse {:.4} N s a step -> {}",
                    s.energy_lost,
                    100.0 * s.lost_fraction,
                    s.drops,
                    s.mean_points,
                    100.0 * s.ids_kept,
                    s.mean_impulse,
                    steps.display()
                );
            }
            std::io::stdout().flush()?;
            reports.push(r);
        }
    }
    let passed = reports.iter().filter(|r| r.pass).count();
    println!(
        "{passed} of {} pass, {} fail, {skipped} could not be set up ({:.1} s)",
        reports.len(),
        reports.len() - passed,
        t0.elapsed().as_secs_f64()
    );
    if let Some(path) = &args.json {
        cbvh::files::atomic_write(
            path.as_ref(),
            serde_json::to_string_pretty(&reports)?.as_bytes(),
        )?;
    }
    Ok(())
}
