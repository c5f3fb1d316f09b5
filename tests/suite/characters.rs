//! rapier's `KinematicCharacterController` walking a capsule (and, along
//! a wall, a box) over cbvh ground, every codec, against the same walk over parry's `TriMesh` of
//! the same triangles (the mesh's, or those of a codec that quantizes its
//! corners), over parry primitives where the ground is made of boxes,
//! and against the answer the geometry gives: a rolling terrain (the
//! capsule's bottom stays an offset above the surface), ramps below and
//! above the climb angle, stairs lower and higher than the autostep
//! height, a wall it slides along, and a slope it snaps down.
//!
//! Each cbvh walk has the grounded flag of its `TriMesh` reference in
//! every frame; its centre follows the reference's frame by frame on the
//! terrain and the snap (within 1 mm), and ends near it after slides
//! along walls and over edges, where the controller's path is chaotic
//! ([`Follow`]).
//!
//! The character is a kinematic body with a capsule collider in the
//! world, excluded from its own queries by the filter, moved each frame
//! by `move_shape` through the broad phase's query pipeline with cbvh's
//! dispatcher installed, and the world stepped, as a game does.

use std::fmt::Write as _;

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::racbvh::RacOptions;
use cbvh::codec::{AnyOptions, CodecKind};
use cbvh::parry::{CbvhShape, parry_trimesh};
use cbvh::sim::character::{
    self, DT, Frame, OFFSET, RADIUS, Walk, bottom, capsule, ramp_profile, stairs, terrain_height,
    terrain_mesh, tilted_clearance, walker,
};
use cbvh::sim::slide::{CbvhMode, Rep};
use parry3d::math::{Pose, Real, Vector};
use parry3d::query::{DefaultQueryDispatcher, QueryDispatcher};
use parry3d::shape::{Cuboid, SharedShape, TriMesh};
use rapier3d::control::KinematicCharacterController;

/// What the ground is made of, for one run.
enum Ground {
    /// A cbvh shape, and the name of the run over parry's `TriMesh` of
    /// the same triangles (its reference).
    Cbvh(CbvhShape, String),
    /// parry's `TriMesh`, built as a rapier user builds it (default
    /// flags).
    TriMesh(Box<TriMesh>),
    /// Parry primitives: boxes with their poses.
    Boxes(Vec<(Cuboid, Pose)>),
}

/// A triangle's corners, for comparing triangle sets.
type Corners = [[u32; 3]; 3];

/// The triangles' corners (as bits), sorted: equal for two shapes of the
/// same triangles in any order.
fn triangle_set(tris: impl Iterator<Item = [[f32; 3]; 3]>) -> Vec<Corners> {
    let mut v: Vec<Corners> = tris.map(|t| t.map(|p| p.map(f32::to_bits))).collect();
    v.sort_unstable();
    v
}

/// The runs of one scenario: each codec, parry's `TriMesh` of the mesh,
/// a `TriMesh` of the triangles of each codec that stores other
/// (quantized) corners than the mesh's, and the boxes when the ground has
/// a box form.
fn grounds(mesh: &Mesh, boxes: Option<Vec<(Cuboid, Pose)>>) -> Vec<(String, Ground)> {
    let options = AnyOptions {
        racbvh: RacOptions {
            cluster_nodes: 256,
            ..Default::default()
        },
        ..Default::default()
    };
    let exact = triangle_set(
        mesh.triangles
            .iter()
            .map(|t| t.map(|i| mesh.vertices[i as usize])),
    );
    // The triangle sets other than the mesh's, with their reference's name.
    let mut quantized: Vec<(Vec<Corners>, String, Box<TriMesh>)> = vec![];
    let mut out: Vec<(String, Ground)> = vec![];
    for &k in CodecKind::ALL {
        let s = CbvhShape::build(mesh, &BuildOptions::default(), k, &options).unwrap();
        let tris: Vec<_> = (0..s.triangle_count() as u32)
            .map(|id| s.parry_triangle(id))
            .collect();
        let set = triangle_set(
            tris.iter()
                .map(|t| [t.a.to_array(), t.b.to_array(), t.c.to_array()]),
        );
        let reference = if set == exact {
            "parry TriMesh".to_string()
        } else if let Some((_, name, _)) = quantized.iter().find(|q| q.0 == set) {
            name.clone()
        } else {
            let vertices = tris.iter().flat_map(|t| [t.a, t.b, t.c]).collect();
            let indices = (0..tris.len() as u32)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect();
            let name = format!("parry TriMesh of {k}'s triangles");
            quantized.push((
                set,
                name.clone(),
                Box::new(TriMesh::new(vertices, indices).unwrap()),
            ));
            name
        };
        out.push((k.name().to_string(), Ground::Cbvh(s, reference)));
    }
    out.push((
        "parry TriMesh".into(),
        Ground::TriMesh(Box::new(parry_trimesh(mesh).unwrap())),
    ));
    for (_, name, t) in quantized {
        out.push((name, Ground::TriMesh(t)));
    }
    if let Some(b) = boxes {
        out.push(("parry cuboids".into(), Ground::Boxes(b)));
    }
    out
}

/// Walks `character` from `start` for `frames` frames, asking for
/// `desired(frame)` each frame, over `ground` ([`character::walk`]).
fn walk(
    character: &SharedShape,
    ground: &Ground,
    controller: &KinematicCharacterController,
    start: Vector,
    frames: usize,
    desired: impl Fn(usize) -> Vector,
) -> Vec<Frame> {
    let colliders: Vec<(SharedShape, Pose)> = match ground {
        Ground::Cbvh(s, _) => vec![(SharedShape::new(s.clone()), Pose::IDENTITY)],
        Ground::TriMesh(t) => vec![(SharedShape::new((**t).clone()), Pose::IDENTITY)],
        Ground::Boxes(boxes) => boxes
            .iter()
            .map(|(b, p)| (SharedShape::new(*b), *p))
            .collect(),
    };
    character::walk(
        None, character, &colliders, controller, start, frames, desired,
    )
}

/// The distance from the capsule at `centre` to the ground `t` (parry's
/// `TriMesh` of the mesh: the exact surface).
fn gap(t: &TriMesh, centre: Vector) -> Real {
    DefaultQueryDispatcher
        .distance(&Pose::from_translation(centre), t, &capsule())
        .unwrap()
        .distance
}

/// How closely a cbvh run must follow its reference's (parry's `TriMesh`
/// of the same triangles): every frame, or only at the end. Either way
/// the grounded flags must match frame by frame.
#[derive(Clone, Copy, Debug)]
enum Follow {
    /// Every frame's centre within this distance (m).
    Track(Real),
    /// The last frame's centre within this distance (m), for walks that
    /// slide along a wall or over edges: there the controller's path
    /// depends on the geometry's last tenth of a millimetre. Perturbed by
    /// racbvh's 16-bit corners, parry's own `TriMesh` walk ends 50 mm
    /// from itself on the 30° ramp (a frame's travel) and 78 mm along the
    /// wall; made of boxes, the stairs' and the wall's walks end 93 mm and
    /// 19 mm from the `TriMesh` one (a box character's wall walk: 135 mm). The geometry's answers (heights,
    /// stops, climbs) are checked against the analytic ones separately.
    End(Real),
}

/// Runs the walk `w` ([`Walk::plan`], over [`Walk::mesh`] and
/// [`Walk::boxes`]) on every ground, checks that each cbvh run follows its
/// reference as `follow` asks with the same grounded flags, and returns
/// the runs (codecs, then the `TriMesh` references, then the boxes) with a
/// printed table of final positions.
fn compare(what: &str, w: Walk, follow: Follow) -> Vec<(String, Vec<Frame>)> {
    let plan = w.plan();
    let frames = plan.frames;
    let desired = |_| plan.velocity * DT;
    let (character, controller, start) = (&plan.character, &plan.controller, plan.start);
    let mesh = &w.mesh();
    let boxes = w.boxes();
    let grounds = grounds(mesh, boxes);
    let runs: Vec<(String, Vec<Frame>)> = grounds
        .iter()
        .map(|(name, g)| {
            let track = walk(character, g, controller, start, frames, desired);
            (name.clone(), track)
        })
        .collect();
    let track_of = |name: &str| &runs.iter().find(|r| r.0 == name).unwrap().1;
    let reference_of = |i: usize| match &grounds[i].1 {
        Ground::Cbvh(_, r) => r.clone(),
        _ => "parry TriMesh".to_string(),
    };
    let mut table =
        format!("{what}: final centre, grounded, largest and final deviation from the reference\n");
    for (i, (name, track)) in runs.iter().enumerate() {
        let reference = reference_of(i);
        let other = track_of(&reference);
        let (p, g) = *track.last().unwrap();
        let worst = track
            .iter()
            .zip(other)
            .map(|(a, b)| (a.0 - b.0).length())
            .fold(0.0, Real::max);
        let end = (p - other.last().unwrap().0).length();
        let flags = track.iter().zip(other).filter(|(a, b)| a.1 != b.1).count();
        writeln!(
            table,
            "  {name:<38} ({:8.4}, {:8.4}, {:8.4}) grounded {g:<5} dev {:6.2} mm, end {:6.2} mm, \
             {flags} flags differ from {reference}",
            p.x,
            p.y,
            p.z,
            worst * 1000.0,
            end * 1000.0,
        )
        .unwrap();
    }
    eprintln!("{table}");
    for (i, (name, track)) in runs.iter().enumerate() {
        if !matches!(grounds[i].1, Ground::Cbvh(..)) {
            continue;
        }
        let reference = reference_of(i);
        let other = track_of(&reference);
        for (f, (a, b)) in track.iter().zip(other).enumerate() {
            let tol = match follow {
                Follow::Track(tol) => tol,
                Follow::End(tol) if f + 1 == frames => tol,
                Follow::End(_) => Real::INFINITY,
            };
            assert!(
                (a.0 - b.0).length() <= tol,
                "{what}, {name}, frame {f}: at {:?}, {reference} at {:?}\n{table}",
                a.0,
                b.0
            );
            assert_eq!(
                a.1, b.1,
                "{what}, {name}, frame {f}: grounded {} vs {reference} {}\n{table}",
                a.1, b.1
            );
        }
    }
    runs
}

/// Walking 4 m/s with a 2 m/s fall across the rolling terrain: the capsule
/// stays on it, its bottom an offset above the surface under it (plus what
/// the tilt adds: a ball on a slope of angle a rests (r + offset)/cos a
/// above the surface point below its centre), grounded every frame.
#[test]
fn a_capsule_walks_over_a_tessellated_terrain_as_over_a_trimesh() {
    let mesh = terrain_mesh();
    let start = Walk::Terrain.plan().start;
    let runs = compare("terrain", Walk::Terrain, Follow::Track(1e-3));
    let surface = parry_trimesh(&mesh).unwrap();
    for (name, track) in &runs {
        for (f, &(p, grounded)) in track.iter().enumerate().skip(10) {
            let above = bottom(p.y) - terrain_height(p.x, p.z);
            assert!(grounded, "{name}, frame {f}: not grounded at {p:?}");
            // The slopes stay under 14 degrees: the tilt adds at most
            // 0.2 (1/cos 14° - 1) = 6 mm; the piecewise-linear surface
            // lies up to ~5 mm below the smooth one between vertices.
            assert!(
                (-6e-3..=OFFSET + 0.012).contains(&above),
                "{name}, frame {f}: bottom {above} above the terrain at {p:?}"
            );
            let g = gap(&surface, p);
            assert!(
                (OFFSET - 2e-3..=OFFSET + 0.01).contains(&g),
                "{name}, frame {f}: {g} from the surface at {p:?}"
            );
        }
        // It got across: at least 90 % of the asked horizontal travel.
        let travel = (track.last().unwrap().0 - start).with_y(0.0).length();
        assert!(
            travel >= 0.9 * 150.0 * DT * 5.0,
            "{name}: travelled {travel}"
        );
    }
}

/// Walking uphill at 3 m/s (falling at 2 m/s): a 30-degree ramp, under
/// the controller's 45-degree climb angle, is climbed to the plateau 0.8 m
/// up, the capsule resting on the slope as on a plane on the way; a
/// 60-degree ramp stops it at its foot.
#[test]
fn a_capsule_climbs_a_ramp_below_the_climb_angle_and_not_one_above() {
    for (angle, climbs) in [(30.0, true), (60.0, false)] {
        let (_, run) = ramp_profile(angle, 0.8);
        let what = format!("{angle}-degree ramp");
        let runs = compare(&what, Walk::Ramp { angle_deg: angle }, Follow::End(0.1));
        let slope = angle.to_radians();
        for (name, track) in &runs {
            let (p, grounded) = *track.last().unwrap();
            assert!(grounded, "{what}, {name}: not grounded at {p:?}");
            if climbs {
                // On the plateau, an offset above it.
                assert!(p.z > run + 0.5, "{what}, {name}: stopped at {p:?}");
                let above = bottom(p.y) - 0.8;
                assert!(
                    (above - OFFSET).abs() < 2e-3,
                    "{what}, {name}: bottom {above} above the plateau"
                );
                // On the slope, at the tilted clearance over it.
                let on_slope: Vec<_> = track
                    .iter()
                    .filter(|(p, _)| p.z > 0.3 && p.z < run - 0.3)
                    .collect();
                assert!(
                    on_slope.len() > 10,
                    "{what}, {name}: {} frames on the slope",
                    on_slope.len()
                );
                for (p, _) in on_slope {
                    let above = bottom(p.y) - p.z * slope.tan();
                    assert!(
                        (above - tilted_clearance(slope)).abs() < 3e-3,
                        "{what}, {name}: bottom {above} above the slope at {p:?}, not {}",
                        tilted_clearance(slope)
                    );
                }
            } else {
                // At the foot: on the floor, the lower ball against the
                // slope.
                assert!(p.z < 0.1, "{what}, {name}: climbed to {p:?}");
                let above = bottom(p.y);
                assert!(
                    (above - OFFSET).abs() < 0.02,
                    "{what}, {name}: bottom {above} above the floor at {p:?}"
                );
            }
        }
    }
}

/// With autostep (at most 0.25 m up, 0.3 m of room) and snapping to the
/// ground, walking at 2 m/s: four 0.15 m steps are climbed to the
/// landing, as over the same stairs made of boxes; one 0.4 m step is not,
/// the capsule stopping an offset before its riser. (Asked to fall at
/// 2 m/s as well, the capsule climbed no step on any ground, parry's
/// `TriMesh` and boxes included: it stopped at the first riser, so that
/// walk tells nothing about cbvh. A box character is left out: on the
/// four steps it stops at the first riser on parry's `TriMesh`, on the
/// first step on the `TriMesh` of racbvh's triangles, and climbs them all
/// on parry's boxes.)
#[test]
fn a_capsule_autosteps_low_stairs_and_not_a_high_one() {
    for (rise, steps, climbs) in [(0.15, 4, true), (0.4, 1, false)] {
        let w = Walk::Stairs { rise, steps };
        let (start, top) = (w.plan().start, stairs(rise, steps).2);
        let what = format!("{steps} steps of {rise} m");
        let runs = compare(&what, w, Follow::End(0.15));
        for (name, track) in &runs {
            let (p, grounded) = *track.last().unwrap();
            assert!(grounded, "{what}, {name}: not grounded at {p:?}");
            if climbs {
                assert!(p.z > 2.5, "{what}, {name}: stopped at {p:?}");
                let above = bottom(p.y) - top;
                assert!(
                    (above - OFFSET).abs() < 2e-3,
                    "{what}, {name}: bottom {above} above the landing at {p:?}"
                );
            } else {
                let before = -(RADIUS + OFFSET);
                assert!(
                    (p.z - before).abs() < 3e-3,
                    "{what}, {name}: stopped at {p:?}, not z = {before}"
                );
                assert!(
                    (bottom(p.y) - OFFSET).abs() < 2e-3,
                    "{what}, {name}: bottom at {} above the floor",
                    bottom(p.y)
                );
                let highest = track.iter().map(|f| f.0.y).fold(Real::MIN, Real::max);
                assert!(
                    highest < start.y + 0.01,
                    "{what}, {name}: rose to {highest}"
                );
            }
        }
    }
}

/// Walking diagonally into a wall at z = 2 (2 m/s along it, 3 m/s into
/// it, falling at 2 m/s): the character (the capsule, or the box, its
/// face flat against the wall's) stops an offset from the wall, never
/// crosses it, and slides along it at the asked speed, as against the
/// same floor and wall made of boxes.
#[test]
fn a_character_slides_along_a_wall_and_does_not_pass_through() {
    for (character_name, boxy) in [("capsule", false), ("box", true)] {
        let w = Walk::Wall { boxy };
        let (start, frames) = (w.plan().start, w.plan().frames);
        let what = format!("{character_name}, wall");
        let runs = compare(&what, w, Follow::End(0.1));
        let stop = 2.0 - RADIUS - OFFSET;
        for (name, track) in &runs {
            for (f, (p, _)) in track.iter().enumerate() {
                assert!(
                    p.z <= stop + 1e-3,
                    "{what}, {name}, frame {f}: through to {p:?}"
                );
            }
            let (p, grounded) = *track.last().unwrap();
            assert!(grounded, "{what}, {name}: not grounded at {p:?}");
            assert!(
                (p.z - stop).abs() < 3e-3,
                "{what}, {name}: at {p:?}, not z = {stop}"
            );
            assert!(
                (bottom(p.y) - OFFSET).abs() < 2e-3,
                "{what}, {name}: bottom at {} above the floor",
                bottom(p.y)
            );
            let along = p.x - start.x;
            let asked = 2.0 * frames as Real * DT;
            assert!(
                along >= 0.95 * asked && along <= asked + 1e-3,
                "{what}, {name}: slid {along} of {asked}"
            );
        }
    }
}

/// Walking at 3 m/s with no fall off a plateau 1 m up and down a
/// 20-degree slope: snapping to the ground (0.2 m) keeps the capsule on
/// the slope, grounded every frame, at the tilted clearance above it, down
/// to the floor; without snapping it walks off into the air.
#[test]
fn a_capsule_snaps_to_the_ground_walking_down_a_slope() {
    let (mesh, run) = character::snap_slope();
    let plan = Walk::Snap.plan();
    let runs = compare("snap", Walk::Snap, Follow::Track(1e-3));
    for (name, track) in &runs {
        for (f, &(p, grounded)) in track.iter().enumerate() {
            assert!(grounded, "snap, {name}, frame {f}: not grounded at {p:?}");
            let above = bottom(p.y) - character::snap_ground(p.z);
            let Some(want) = character::snap_clearance(p.z, run) else {
                continue; // Rounding an edge.
            };
            assert!(
                (above - want).abs() < 3e-3,
                "snap, {name}, frame {f}: bottom {above} above the ground at {p:?}, not {want}"
            );
        }
        assert!(track.last().unwrap().0.z > run + 0.5, "snap, {name}");
    }
    // Without snapping the same walk leaves the ground.
    let free = KinematicCharacterController {
        snap_to_ground: None,
        ..walker()
    };
    let track = walk(
        &plan.character,
        &Ground::TriMesh(Box::new(parry_trimesh(&mesh).unwrap())),
        &free,
        plan.start,
        plan.frames,
        |_| plan.velocity * DT,
    );
    let (p, grounded) = *track.last().unwrap();
    assert!(
        !grounded && bottom(p.y) > 0.5,
        "no snap: at {p:?}, grounded {grounded}"
    );
}

/// Every walk of [`Walk::standard`] over cbvh grounds (plain and hcc in
/// both modes, clbvh, and scaled shapes: non-uniform and mirrored) meets
/// the geometry's answer as [`Walk::judge`] measures it (the table's
/// rows: `rapier_slide -- --scene walk`), as it does over parry's
/// `TriMesh`.
#[test]
fn every_walk_meets_the_geometrys_answer_on_plain_compressed_and_scaled_grounds() {
    let grounds = [
        Rep::TriMesh,
        Rep::Cbvh(CodecKind::Plain, CbvhMode::Patches),
        Rep::Cbvh(CodecKind::Hcc, CbvhMode::Pairs),
        Rep::Cbvh(CodecKind::Clbvh, CbvhMode::Patches),
        Rep::Scaled(CodecKind::Plain, CbvhMode::Patches),
        Rep::Scaled(CodecKind::Hcc, CbvhMode::Pairs),
    ];
    let mut failed = vec![];
    for walk in Walk::standard() {
        for ground in grounds {
            let r = walk.run(ground).unwrap();
            eprintln!("{r}");
            if !r.passes() {
                failed.push(r.to_string());
            }
        }
    }
    assert!(failed.is_empty(), "failing walks:\n{}", failed.join("\n"));
}
