//! The continuous-collision scenes of [`cbvh::sim::ccd`] for every
//! representation of the surface and the fast body, as a table of the
//! measured first contact against the analytic one: a ball, a cube and a
//! capsule shot at a zero-thickness wall at 1, 10, 60 and 360 m/s, and a bar
//! spun into a zero-thickness strip. Surfaces are parry's `TriMesh` with
//! and without `FIX_INTERNAL_EDGES` and cbvh shapes of the plain, hcc,
//! racbvh and clbvh codecs in both contact modes; the body is a parry
//! primitive, and (where the scene has a mesh for it) a cbvh shape of the
//! surface's codec, parry's convex hull of the mesh, or a cbvh body against
//! parry's `TriMesh`.
//!
//! ```sh
//! cargo run --release --features sims --example rapier_ccd
//! cargo run --release --features sims --example rapier_ccd -- --scene spin --rep plain
//! ```
//!
//! `--scene NAME` keeps the scenes whose name contains NAME; `--rep NAMES`
//! (comma-separated) the runs whose surface or body is one of NAMES. Each
//! row ends `ok` when the first contact is within 1 mm of the analytic one
//! and the body never got more than 1 mm past the surface, `FAIL`
//! otherwise; the program does not fail on a `FAIL`: the table is the
//! result.

use std::time::Instant;

use cbvh::codec::CodecKind;
use cbvh::sim::ccd::{CcdScene, Projectile};
use cbvh::sim::slide::{CbvhMode, Rep};

/// The scenes of the table.
fn scenes() -> Vec<CcdScene> {
    let mut all = Vec::new();
    for projectile in Projectile::ALL {
        // 1 m/s: slow enough for the contacts alone (the control).
        for speed in [1.0, 10.0, 60.0, 360.0] {
            all.push(CcdScene::Shot {
                projectile,
                speed,
                cells: 8,
            });
        }
    }
    for omega in [30.0, 120.0] {
        all.push(CcdScene::Spin { omega, cells: 8 });
    }
    all
}

/// The (surface, body) pairs of the table.
fn pairings() -> Vec<(Rep, Rep)> {
    let mut targets = vec![Rep::TriMesh, Rep::TriMeshFixed];
    for kind in [
        CodecKind::Plain,
        CodecKind::Hcc,
        CodecKind::Racbvh,
        CodecKind::Clbvh,
    ] {
        targets.extend(CbvhMode::ALL.map(|m| Rep::Cbvh(kind, m)));
    }
    let mut all = Vec::new();
    for t in targets {
        all.push((t, Rep::Primitive));
        match t {
            Rep::Cbvh(..) => all.push((t, t)),
            _ => all.push((t, Rep::Hull)),
        }
    }
    all.push((Rep::TriMesh, Rep::Cbvh(CodecKind::Plain, CbvhMode::Patches)));
    all.push((Rep::TriMesh, Rep::Cbvh(CodecKind::Plain, CbvhMode::Pairs)));
    all
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    cbvh::logger::init_stderr();
    let mut scene_filter = None;
    let mut reps: Option<Vec<Rep>> = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--scene" => scene_filter = Some(value()?),
            "--rep" => {
                reps = Some(
                    value()?
                        .split(',')
                        .map(str::parse)
                        .collect::<Result<Vec<Rep>, String>>()?,
                )
            }
            "-h" | "--help" => {
                println!("rapier_ccd [--scene NAME] [--rep NAME[,NAME...]]");
                return Ok(());
            }
            other => return Err(format!("unknown argument {other:?} (see --help)").into()),
        }
    }
    let (mut runs, mut fails) = (0, 0);
    for scene in scenes() {
        if scene_filter
            .as_ref()
            .is_some_and(|f| !scene.name().contains(f.as_str()))
        {
            continue;
        }
        for (target, body) in pairings() {
            if reps
                .as_ref()
                .is_some_and(|r| !r.contains(&target) && !r.contains(&body))
            {
                continue;
            }
            let t0 = Instant::now();
            match scene.run(target, body) {
                Ok(r) => {
                    runs += 1;
                    let ok = r.passes();
                    fails += usize::from(!ok);
                    println!(
                        "{r} {:>7.1} ms {}",
                        t0.elapsed().as_secs_f64() * 1e3,
                        if ok { "ok" } else { "FAIL" }
                    );
                }
                Err(e) => println!("{} {target} / {body}: not run ({e})", scene.name()),
            }
        }
    }
    println!("{runs} runs, {fails} failing");
    Ok(())
}
