//! Continuous collision in rapier against the analytic first contact
//! ([`cbvh::sim::ccd`]): a ball, a cube and a capsule shot at a
//! zero-thickness cbvh wall at 10, 60 and 360 m/s, cbvh bodies shot at
//! cbvh walls and at parry's `TriMesh`, and a bar spun into a
//! zero-thickness cbvh strip, for every codec in both contact modes. Each
//! run's first contact is within 1 mm of the analytic one, the body never
//! sinks more than [`SINK_TOLERANCE`] past the surface and never goes
//! through it. The harness test checks the yardstick: without the
//! continuous pass (a body too thick for rapier to sweep) the same shot
//! tunnels.
//!
//! The table of every pairing, parry's `TriMesh` included:
//! `cargo run --release --features sims --example rapier_slide -- --scene shot` (and `spin`).

use cbvh::codec::CodecKind;
use cbvh::sim::ccd::{CcdReport, CcdScene, Projectile, SINK_TOLERANCE};
use cbvh::sim::slide::{CbvhMode, Rep};

const CODECS: [CodecKind; 4] = [
    CodecKind::Plain,
    CodecKind::Hcc,
    CodecKind::Racbvh,
    CodecKind::Clbvh,
];

fn run(scene: CcdScene, target: Rep, body: Rep) -> CcdReport {
    let r = scene
        .run(target, body)
        .unwrap_or_else(|e| panic!("{} on {target} / {body}: {e}", scene.name()));
    println!("{r}");
    r
}

fn check(reports: &[CcdReport]) {
    let bad: Vec<String> = reports
        .iter()
        .filter(|r| !r.passes())
        .map(|r| r.to_string())
        .collect();
    assert!(
        bad.is_empty(),
        "{} runs fail:\n{}",
        bad.len(),
        bad.join("\n")
    );
}

fn every_codec_and_mode() -> impl Iterator<Item = Rep> {
    CODECS
        .into_iter()
        .flat_map(|k| CbvhMode::ALL.map(move |m| Rep::Cbvh(k, m)))
}

#[test]
fn primitives_shot_at_a_cbvh_wall_stop_at_the_first_contact() {
    let mut reports = Vec::new();
    for target in every_codec_and_mode() {
        for projectile in Projectile::ALL {
            for speed in [10.0, 60.0, 360.0] {
                let scene = CcdScene::Shot {
                    projectile,
                    speed,
                    cells: 4,
                };
                reports.push(run(scene, target, Rep::Primitive));
            }
        }
    }
    check(&reports);
}

#[test]
fn cbvh_cubes_shot_at_cbvh_walls_and_parry_trimesh_stop_at_the_first_contact() {
    let mut reports = Vec::new();
    for rep in every_codec_and_mode() {
        for speed in [10.0, 60.0, 360.0] {
            let scene = CcdScene::Shot {
                projectile: Projectile::Cube,
                speed,
                cells: 4,
            };
            reports.push(run(scene, rep, rep));
        }
    }
    for speed in [10.0, 360.0] {
        let scene = CcdScene::Shot {
            projectile: Projectile::Cube,
            speed,
            cells: 4,
        };
        reports.push(run(
            scene,
            Rep::TriMesh,
            Rep::Cbvh(CodecKind::Plain, CbvhMode::Pairs),
        ));
    }
    check(&reports);
}

#[test]
fn cbvh_balls_shot_at_cbvh_walls_meet_them_at_the_first_contact() {
    let mut reports = Vec::new();
    for rep in [
        Rep::Cbvh(CodecKind::Plain, CbvhMode::Patches),
        Rep::Cbvh(CodecKind::Clbvh, CbvhMode::Pairs),
        Rep::Cbvh(CodecKind::Hcc, CbvhMode::Patches),
    ] {
        for speed in [60.0, 360.0] {
            let scene = CcdScene::Shot {
                projectile: Projectile::Ball,
                speed,
                cells: 4,
            };
            reports.push(run(scene, rep, rep));
        }
    }
    check(&reports);
}

/// Scaled shapes ([`Rep::Scaled`]: a non-uniform, mirrored view) as the
/// wall and as the fast body: the ball and the cube at 60 and 360 m/s, a
/// primitive and a scaled cbvh body of the wall's codec and mode, and the
/// bar spun into a scaled strip.
#[test]
fn scaled_cbvh_shapes_stop_fast_bodies_at_the_first_contact() {
    let mut reports = Vec::new();
    for rep in [
        Rep::Scaled(CodecKind::Plain, CbvhMode::Patches),
        Rep::Scaled(CodecKind::Hcc, CbvhMode::Pairs),
        Rep::Scaled(CodecKind::Clbvh, CbvhMode::Patches),
    ] {
        for projectile in [Projectile::Ball, Projectile::Cube] {
            for speed in [60.0, 360.0] {
                let scene = CcdScene::Shot {
                    projectile,
                    speed,
                    cells: 4,
                };
                reports.push(run(scene, rep, Rep::Primitive));
                reports.push(run(scene, rep, rep));
            }
        }
        let spin = CcdScene::Spin {
            omega: 30.0,
            cells: 4,
        };
        reports.push(run(spin, rep, Rep::Primitive));
    }
    check(&reports);
}

/// The bar spun into a cbvh strip stops at the first contact, as a parry
/// cuboid and as a cbvh box of the strip's codec and mode. (The cbvh bar
/// once met the strip right and then went through it: the triangle pairs
/// in contact at the start of each later sweep answered the sweep's start,
/// which rapier discards, and that answer hid the later contacts.)
#[test]
fn a_bar_spun_into_a_cbvh_strip_stops_at_the_first_contact() {
    let mut reports = Vec::new();
    let spin = CcdScene::Spin {
        omega: 30.0,
        cells: 4,
    };
    for target in every_codec_and_mode() {
        reports.push(run(spin, target, Rep::Primitive));
        reports.push(run(spin, target, target));
    }
    check(&reports);
}

/// A cbvh bar spun into a parry `TriMesh` strip stops at the first
/// contact in pairs mode. (Cast triangle by triangle against the whole
/// `TriMesh`, the pairs in contact at a sweep's start answered that start,
/// which rapier discards, and the bar went through the strip.)
#[test]
fn a_cbvh_bar_spun_into_a_parry_trimesh_strip_stops_at_the_first_contact() {
    let reports: Vec<CcdReport> = [CodecKind::Plain, CodecKind::Clbvh]
        .map(|k| run(TRIMESH_SPIN, Rep::TriMesh, Rep::Cbvh(k, CbvhMode::Pairs)))
        .into();
    check(&reports);
}

/// The same in patch mode: the sweep meets the strip at the first contact
/// (0.11 mm), but patch contacts against a `TriMesh` then let the bar sink
/// 22 mm (plain) or turn through the strip (clbvh), as they let a cube
/// pushed into a `TriMesh` wall sink (below).
#[test]
#[ignore = "cbvh_trimesh's patch contacts let a cbvh bar spun into a parry TriMesh strip sink 22 mm (plain) or pass (clbvh) after a right first contact"]
fn a_cbvh_bar_spun_into_a_parry_trimesh_strip_stops_in_patch_mode() {
    let reports: Vec<CcdReport> = [CodecKind::Plain, CodecKind::Clbvh]
        .map(|k| run(TRIMESH_SPIN, Rep::TriMesh, Rep::Cbvh(k, CbvhMode::Patches)))
        .into();
    check(&reports);
}

const TRIMESH_SPIN: CcdScene = CcdScene::Spin {
    omega: 30.0,
    cells: 4,
};

/// The yardstick: the scenes measure what they claim. A first contact is
/// found where the body stops; the exact first contact of the shot is the
/// wall's plane; a body that misses a wall is reported as crossing it.
#[test]
fn harness_reports_a_shot_through_a_wall_as_tunnelling() {
    // parry's TriMesh as the moving body is never swept by rapier (it is a
    // mesh): at 360 m/s a mesh cube goes through a thin wall.
    let r = run(
        CcdScene::Shot {
            projectile: Projectile::Cube,
            speed: 360.0,
            cells: 4,
        },
        Rep::TriMesh,
        Rep::TriMesh,
    );
    assert!(r.crossed && !r.passes(), "{r}");
    assert!(r.deepest > 1.0, "{r}");
    // A slow shot is stopped by the contacts alone, at the wall.
    let r = run(
        CcdScene::Shot {
            projectile: Projectile::Ball,
            speed: 1.0,
            cells: 4,
        },
        Rep::TriMesh,
        Rep::Primitive,
    );
    assert!(!r.crossed, "{r}");
    assert!((r.expected + 0.1).abs() < 1e-6, "{r}");
    assert!(r.deepest < SINK_TOLERANCE, "{r}");
}

/// A cbvh cube pushed slowly (no sweep: the contacts alone) into parry's
/// `TriMesh` wall stops at it in both contact modes. Fails in patch mode:
/// the cube sinks 6.6 mm at 1 m/s and, shot at 10 m/s or faster, goes
/// through after a right first contact; the per-pair mode holds, and so
/// does the patch mode against a cbvh wall of the same triangles.
#[test]
#[ignore = "cbvh_trimesh's patch contacts let a cbvh cube flush against a parry TriMesh wall sink 6.6 mm at 1 m/s"]
fn a_cbvh_cube_pushed_into_a_parry_trimesh_wall_stops_in_both_modes() {
    let mut reports = Vec::new();
    for mode in CbvhMode::ALL {
        for speed in [1.0, 10.0] {
            let scene = CcdScene::Shot {
                projectile: Projectile::Cube,
                speed,
                cells: 4,
            };
            reports.push(run(scene, Rep::TriMesh, Rep::Cbvh(CodecKind::Plain, mode)));
        }
    }
    check(&reports);
}
