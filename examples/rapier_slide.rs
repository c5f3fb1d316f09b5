//! Every analytic scene of [`cbvh::sim`] for every representation of the
//! ground and the body, as one table of measured against expected, in
//! three parts:
//!
//! - contacts ([`cbvh::sim::slide`]): a cube sliding (or staying) on a
//!   ramp, a sphere rolling down one, a ball settling in a bowl, a cube
//!   dropped on the ground, a stack of cubes, a cube at a table's edge, a
//!   block rocking on a dome;
//! - continuous collision ([`cbvh::sim::ccd`]): a ball, a cube and a
//!   capsule shot at a zero-thickness wall at 1 to 360 m/s and a bar spun
//!   into a strip, with CCD on, against the analytic first contact;
//! - characters ([`cbvh::sim::character`]): rapier's kinematic character
//!   controller walking a capsule over terrain, ramps, stairs, along a
//!   wall and down a slope it snaps to.
//!
//! Grounds are a parry primitive (where the scene has one), parry's
//! `TriMesh` with and without `FIX_INTERNAL_EDGES`, cbvh shapes of each
//! codec in both contact modes, and scaled cbvh shapes
//! ([`cbvh::sim::slide::Rep::Scaled`]: built from the mesh squeezed by a
//! non-uniform, mirrored factor and handed to rapier scaled back by it).
//! The body is of the same representation, and a primitive body runs on
//! every mesh ground too (see [`cbvh::sim::slide::pairings`] and
//! [`cbvh::sim::ccd::pairings`]).
//!
//! ```sh
//! cargo run --release --features sims --example rapier_slide
//! cargo run --release --features sims --example rapier_slide -- --scene shot --rep plain-pairs --json out.json
//! ```
//!
//! `--scene NAME` keeps the scenes whose name contains NAME (`slide`,
//! `roll`, `shot`, `spin`, `walk`, ...); `--rep NAMES` (comma-separated)
//! the runs whose ground or body is one of NAMES (`primitive`, `trimesh`,
//! `trimesh-fixed`, `hull`, `plain`, `plain-pairs`, `plain-scaled`,
//! `plain-scaled-pairs`, ...); `--codecs NAMES` the codecs to run (default
//! `plain,hcc,clbvh`); `--scaled NAMES` the codecs also run scaled
//! (default `plain`; `--scaled none` for none); `--json FILE` writes the
//! contact scenes' reports; `--trace DIR` writes, for every contact
//! scene's run, the moving body's energy and contacts at every step
//! ([`cbvh::sim::trace`]) as `DIR/SCENE.GROUND.BODY.steps.csv` and
//! `.contacts.csv`, and prints a summary line after the run's row.
//! Failing scenes do not fail the program: the table is the result. A
//! pairing that cannot be set up is listed as not run, with the reason
//! (parry's convex hull of the fine icosphere, which parry leaves without
//! faces).

use std::io::Write;
use std::time::Instant;

use cbvh::codec::CodecKind;
use cbvh::sim::ccd;
use cbvh::sim::character::{self, Walk};
use cbvh::sim::slide::{Rep, Report, Scene, pairings};
use cbvh::sim::trace::Trace;

/// The codecs the example runs by default, by name.
const CODECS: &str = "plain,hcc,clbvh";
/// The codecs it also runs scaled by default.
const SCALED: &str = "plain";

struct Args {
    scene: Option<String>,
    reps: Option<Vec<Rep>>,
    json: Option<String>,
    codecs: String,
    scaled: String,
    trace: Option<std::path::PathBuf>,
}

/// The codecs named in `list` (comma-separated; `none` for none).
fn parse_codecs(list: &str) -> Result<Vec<CodecKind>, cbvh::codec::UnknownCodec> {
    if list.trim() == "none" {
        return Ok(vec![]);
    }
    list.split(',').map(|n| n.trim().parse()).collect()
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        scene: None,
        reps: None,
        json: None,
        codecs: CODECS.into(),
        scaled: SCALED.into(),
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
            "--scaled" => args.scaled = value()?,
            "--trace" => args.trace = Some(value()?.into()),
            "-h" | "--help" => {
                println!(
                    "rapier_slide [--scene NAME] [--rep NAME[,NAME...]] [--json FILE]\n\
                     \x20            [--codecs NAME[,NAME...]] [--scaled NAME[,NAME...]|none]\n\
                     \x20            [--trace DIR]\n\
                     scenes: {}",
                    Scene::standard()
                        .iter()
                        .map(Scene::name)
                        .chain(ccd::standard().iter().map(ccd::CcdScene::name))
                        .chain(Walk::standard().iter().map(Walk::name))
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
    let codecs = parse_codecs(&args.codecs)?;
    let scaled = parse_codecs(&args.scaled)?;
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
        for (ground, body) in pairings(&codecs, &scaled) {
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
        "contacts: {passed} of {} pass, {} fail, {skipped} could not be set up ({:.1} s)\n",
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
    let wanted = |name: String| {
        args.scene
            .as_ref()
            .is_none_or(|s| name.contains(s.as_str()))
    };

    // Continuous collision.
    let t0 = Instant::now();
    let (mut runs, mut fails) = (0, 0);
    println!(
        "{:<28} {:<16} {:<16} first contact (m or rad) against the analytic one; \
         error and deepest sinking at the contact point",
        "ccd scene", "surface", "body"
    );
    for scene in ccd::standard() {
        if !wanted(scene.name()) {
            continue;
        }
        for (target, body) in ccd::pairings(&codecs, &scaled) {
            if !keep(target, body) {
                continue;
            }
            let t = Instant::now();
            match scene.run(target, body) {
                Ok(r) => {
                    runs += 1;
                    let ok = r.passes();
                    fails += usize::from(!ok);
                    println!(
                        "{r} {:>7.1} ms  {}",
                        t.elapsed().as_secs_f64() * 1e3,
                        if ok { "PASS" } else { "FAIL" }
                    );
                }
                Err(e) => println!("{:<28} {target:<16} {body:<16} not run: {e}", scene.name()),
            }
            std::io::stdout().flush()?;
        }
    }
    println!(
        "ccd: {} of {runs} pass, {fails} fail ({:.1} s)\n",
        runs - fails,
        t0.elapsed().as_secs_f64()
    );

    // Characters.
    let t0 = Instant::now();
    let (mut runs, mut fails) = (0, 0);
    println!(
        "{:<18} {:<16} {:<30} {:>9} {:>9} {:>11}",
        "walk", "ground", "quantity", "measured", "expected", "error"
    );
    for walk in Walk::standard() {
        if !wanted(walk.name()) {
            continue;
        }
        for ground in character::grounds(&codecs, &scaled) {
            if !walk.has_ground(ground) || !keep(ground, ground) {
                continue;
            }
            match walk.run(ground) {
                Ok(r) => {
                    runs += 1;
                    let ok = r.passes();
                    fails += usize::from(!ok);
                    println!("{r}  {}", if ok { "PASS" } else { "FAIL" });
                }
                Err(e) => println!("{:<18} {ground:<16} not run: {e}", walk.name()),
            }
            std::io::stdout().flush()?;
        }
    }
    println!(
        "characters: {} of {runs} pass, {fails} fail ({:.1} s)",
        runs - fails,
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
