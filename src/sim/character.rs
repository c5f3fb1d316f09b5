//! rapier's `KinematicCharacterController` on mesh grounds: a capsule (and
//! along a wall, a box) walked frame by frame as a game moves its
//! character, each walk measured against the answer the geometry gives.
//!
//! The walks ([`Walk`]):
//!
//! - [`Walk::Terrain`]: 4 m/s across a gently rolling 32 × 32-cell
//!   heightfield while asking to fall at 2 m/s: the capsule stays grounded,
//!   its distance from the surface the controller's offset.
//! - [`Walk::Ramp`]: uphill at 3 m/s into a ramp 0.8 m high: one under the
//!   controller's 45° climb angle (30°) is climbed to the plateau, the
//!   capsule ending an offset above it; one over it (60°) stops the capsule
//!   at its foot, the lower ball against the slope.
//! - [`Walk::Stairs`]: with autostep (0.25 m up, 0.3 m of room) at
//!   2 m/s: four 0.15 m steps are climbed to the landing; one 0.4 m step
//!   stops the capsule an offset before its riser.
//! - [`Walk::Wall`]: diagonally into a wall (2 m/s along it, 3 m/s into
//!   it, falling at 2 m/s): the capsule, or a box as tall and deep, stops
//!   an offset from the wall.
//! - [`Walk::Snap`]: off a plateau 1 m up and down a 20° slope at 3 m/s
//!   with no fall asked: snapping to the ground keeps the capsule on the
//!   slope at the clearance a ball on a plane has.
//!
//! The ground takes a [`Rep`] ([`Walk::has_ground`]): parry's `TriMesh`,
//! a cbvh shape (plain or scaled), or, for the stairs and the wall, parry
//! cuboids. The character is a kinematic body with its collider in the
//! world, excluded from its own queries, moved each frame by
//! `move_shape` through the broad phase's query pipeline with the cbvh
//! [`Dispatcher`](crate::parry::Dispatcher) installed, and the world
//! stepped at 60 Hz. [`walk`] runs a walk on any colliders, for tests
//! that compare two grounds frame by frame.

use std::fmt;

use parry3d::math::{Pose, Real, Vector};
use parry3d::query::{DefaultQueryDispatcher, QueryDispatcher};
use parry3d::shape::{Capsule, Cuboid, SharedShape, TriMesh};
use rapier3d::control::{CharacterAutostep, CharacterLength, KinematicCharacterController};
use rapier3d::prelude::{ColliderBuilder, QueryFilter, RigidBodyBuilder};

use super::slide::{self, CbvhMode, Rep, SlideError};
use crate::codec::CodecKind;
use crate::mesh::Mesh;
use crate::parry::parry_trimesh;

/// The frame time (s): rapier's default 60 Hz.
pub const DT: Real = 1.0 / 60.0;
/// The capsule's half height (of its segment).
pub const HALF_HEIGHT: Real = 0.3;
/// The capsule's radius: with [`HALF_HEIGHT`], 1 m tall.
pub const RADIUS: Real = 0.2;
/// The controller's offset (1 % of the character's height).
pub const OFFSET: Real = 0.01;

/// The capsule character, along `y`.
pub fn capsule() -> Capsule {
    Capsule::new_y(HALF_HEIGHT, RADIUS)
}

/// The box character of the wall: as tall and as deep as the capsule (its
/// bottom as far below its centre, its front as far ahead).
pub fn box_character() -> Cuboid {
    Cuboid::new(Vector::new(RADIUS, HALF_HEIGHT + RADIUS, RADIUS))
}

/// The height of the character's lowest point when its centre is at `y`.
pub fn bottom(y: Real) -> Real {
    y - HALF_HEIGHT - RADIUS
}

/// Where a ball of the capsule's radius, [`OFFSET`] off a plane tilted by
/// `angle` (radians), has its lowest point above the plane point under its
/// centre.
pub fn tilted_clearance(angle: Real) -> Real {
    (RADIUS + OFFSET) / angle.cos() - RADIUS
}

/// The controller of every walk: rapier's defaults (45° climb, snapping
/// 0.2 m) with the offset [`OFFSET`].
pub fn walker() -> KinematicCharacterController {
    KinematicCharacterController {
        offset: CharacterLength::Absolute(OFFSET),
        ..Default::default()
    }
}

/// [`walker`] with autostep: at most 0.25 m up, 0.3 m of room.
pub fn stepper() -> KinematicCharacterController {
    KinematicCharacterController {
        autostep: Some(CharacterAutostep {
            max_height: CharacterLength::Absolute(0.25),
            min_width: CharacterLength::Absolute(0.3),
            include_dynamic_bodies: true,
        }),
        ..walker()
    }
}

/// A surface extruded along x from a profile of (z, y) points, from
/// `x = -w` to `x = w`, `cells` quads across and each profile segment
/// split into segments of at most `step` along it, wound so that the
/// normal of a rising or flat segment points up.
pub fn extrude(profile: &[(Real, Real)], w: Real, cells: usize, step: Real) -> Mesh {
    let mut points = vec![profile[0]];
    for p in profile.windows(2) {
        let ((z0, y0), (z1, y1)) = (p[0], p[1]);
        let n = (((z1 - z0).hypot(y1 - y0) / step).ceil() as usize).max(1);
        for i in 1..=n {
            let t = i as Real / n as Real;
            points.push((z0 + (z1 - z0) * t, y0 + (y1 - y0) * t));
        }
    }
    let mut vertices = vec![];
    for &(z, y) in &points {
        for i in 0..=cells {
            let x = -w + 2.0 * w * i as Real / cells as Real;
            vertices.push([x, y, z]);
        }
    }
    let at = |j: usize, i: usize| (j * (cells + 1) + i) as u32;
    let mut triangles = vec![];
    for j in 0..points.len() - 1 {
        for i in 0..cells {
            triangles.push([at(j, i), at(j + 1, i), at(j + 1, i + 1)]);
            triangles.push([at(j, i), at(j + 1, i + 1), at(j, i + 1)]);
        }
    }
    Mesh::new(vertices, triangles)
}

/// The gently rolling terrain's height: amplitude 0.3 m over 16 m.
pub fn terrain_height(x: Real, z: Real) -> Real {
    0.3 * (0.35 * x).sin() * (0.25 * z + 0.5).cos() + 0.1 * (0.2 * (x + z)).sin()
}

/// The terrain as a 32 × 32-cell heightfield mesh over [-8, 8]².
pub fn terrain_mesh() -> Mesh {
    let n = 32;
    let coord = |i: usize| -8.0 + 16.0 * i as Real / n as Real;
    let mut vertices = vec![];
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (coord(i), coord(j));
            vertices.push([x, terrain_height(x, z), z]);
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut triangles = vec![];
    for j in 0..n {
        for i in 0..n {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    Mesh::new(vertices, triangles)
}

/// A floor at 0 up to z = 0, a ramp of `angle` degrees up to `height`,
/// then a plateau; and the ramp's horizontal run.
pub fn ramp_profile(angle: Real, height: Real) -> (Vec<(Real, Real)>, Real) {
    let run = height / angle.to_radians().tan();
    (
        vec![(-4.0, 0.0), (0.0, 0.0), (run, height), (run + 4.0, height)],
        run,
    )
}

/// The stairs: a floor at 0 up to z = 0, then `steps` steps of `rise`
/// and 0.5 m deep, then a landing, 6 m wide; the same stairs as boxes (a
/// floor slab and one box per step, from its riser to the far end); and
/// the landing's height.
pub fn stairs(rise: Real, steps: usize) -> (Mesh, Vec<(Cuboid, Pose)>, Real) {
    let depth = 0.5;
    let end = steps as Real * depth + 4.0;
    let mut profile = vec![(-4.0, 0.0), (0.0, 0.0)];
    let mut boxes = vec![(
        Cuboid::new(Vector::new(3.0, 0.5, (end + 4.0) / 2.0)),
        Pose::from_translation(Vector::new(0.0, -0.5, (end - 4.0) / 2.0)),
    )];
    for i in 0..steps {
        let z = i as Real * depth;
        let h1 = (i + 1) as Real * rise;
        profile.push((z, h1));
        profile.push((z + depth, h1));
        boxes.push((
            Cuboid::new(Vector::new(3.0, h1 / 2.0, (end - z) / 2.0)),
            Pose::from_translation(Vector::new(0.0, h1 / 2.0, (end + z) / 2.0)),
        ));
    }
    profile.push((end, steps as Real * rise));
    (extrude(&profile, 3.0, 6, 0.25), boxes, steps as Real * rise)
}

/// The wall at z = 2, 3 m high, over a floor at 0, 12 m wide; and the
/// same as two boxes.
pub fn wall() -> (Mesh, Vec<(Cuboid, Pose)>) {
    let mesh = extrude(
        &[(-4.0, 0.0), (2.0, 0.0), (2.0, 3.0), (4.0, 3.0)],
        6.0,
        12,
        0.25,
    );
    let boxes = vec![
        (
            Cuboid::new(Vector::new(6.0, 0.5, 4.0)),
            Pose::from_translation(Vector::new(0.0, -0.5, 0.0)),
        ),
        (
            Cuboid::new(Vector::new(6.0, 1.5, 1.0)),
            Pose::from_translation(Vector::new(0.0, 1.5, 3.0)),
        ),
    ];
    (mesh, boxes)
}

/// The snap walk's slope (degrees).
pub const SNAP_SLOPE_DEG: Real = 20.0;

/// A plateau 1 m up to z = 0, a [`SNAP_SLOPE_DEG`] slope down to the
/// floor, then the floor; and the slope's horizontal run.
pub fn snap_slope() -> (Mesh, Real) {
    let run = 1.0 / SNAP_SLOPE_DEG.to_radians().tan();
    (
        extrude(
            &[(-4.0, 1.0), (0.0, 1.0), (run, 0.0), (run + 4.0, 0.0)],
            3.0,
            6,
            0.25,
        ),
        run,
    )
}

/// The snap slope's height at `z` (see [`snap_slope`]).
pub fn snap_ground(z: Real) -> Real {
    (1.0 - z.max(0.0) * SNAP_SLOPE_DEG.to_radians().tan()).max(0.0)
}

/// How far above [`snap_ground`] a grounded capsule's bottom lies at
/// `z`: [`tilted_clearance`] on the slope (`run` long), the offset on the
/// plateau and the floor, `None` where it rounds an edge.
pub fn snap_clearance(z: Real, run: Real) -> Option<Real> {
    if z > 0.3 && z < run - 0.3 {
        Some(tilted_clearance(SNAP_SLOPE_DEG.to_radians()))
    } else if z < -0.1 || z > run + 0.3 {
        Some(OFFSET)
    } else {
        None
    }
}

/// One frame of a walk: the character's centre after the move, and the
/// controller's grounded flag.
pub type Frame = (Vector, bool);

/// Walks `character` from `start` for `frames` frames, asking for
/// `desired(frame)` each frame, over the fixed colliders `ground` (shapes
/// with their poses), in a world with cbvh's dispatcher chained to
/// parry's, its contacts in `mode` (the default, patches, for `None`).
pub fn walk(
    mode: Option<CbvhMode>,
    character: &SharedShape,
    ground: &[(SharedShape, Pose)],
    controller: &KinematicCharacterController,
    start: Vector,
    frames: usize,
    desired: impl Fn(usize) -> Vector,
) -> Vec<Frame> {
    let rep = mode.map_or(Rep::TriMesh, |m| Rep::Cbvh(CodecKind::Plain, m));
    let mut world = slide::new_world(rep, Rep::Primitive)
        .expect("a primitive body takes any ground's contact mode");
    world.gravity = Vector::ZERO;
    for (shape, pose) in ground {
        world
            .colliders
            .insert(ColliderBuilder::new(shape.clone()).position(*pose));
    }
    let body = world
        .bodies
        .insert(RigidBodyBuilder::kinematic_position_based().translation(start));
    world.colliders.insert_with_parent(
        ColliderBuilder::new(character.clone()),
        body,
        &mut world.bodies,
    );
    world.step();
    let mut track = Vec::with_capacity(frames);
    for f in 0..frames {
        let pos = *world.bodies[body].position();
        let filter = QueryFilter::default().exclude_rigid_body(body);
        let q = world.broad_phase.as_query_pipeline(
            world.narrow_phase.query_dispatcher(),
            &world.bodies,
            &world.colliders,
            filter,
        );
        let m = controller.move_shape(DT, &q, &*character.0, &pos, desired(f), |_| {});
        let next = pos.translation + m.translation;
        world.bodies[body].set_next_kinematic_translation(next);
        world.step();
        track.push((next, m.grounded));
    }
    track
}

/// One walk (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Walk {
    /// Across the rolling terrain.
    Terrain,
    /// Into a ramp of `angle_deg` degrees, 0.8 m high.
    Ramp {
        /// The ramp's angle (degrees).
        angle_deg: Real,
    },
    /// Up `steps` steps of `rise` (m), with autostep.
    Stairs {
        /// Each step's height (m).
        rise: Real,
        /// How many steps.
        steps: usize,
    },
    /// Along and into a wall; a box character if `boxy`, else the capsule.
    Wall {
        /// The character is [`box_character`].
        boxy: bool,
    },
    /// Down the snap slope.
    Snap,
}

/// What a walk measured.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkReport {
    /// The walk's name.
    pub walk: String,
    /// The ground's representation.
    pub ground: String,
    /// What is measured.
    pub quantity: &'static str,
    /// The measured value (m).
    pub measured: Real,
    /// What the geometry says (m).
    pub expected: Real,
    /// How far `measured` may be from `expected` (m).
    pub tolerance: Real,
    /// Frames in which the controller said it was not grounded (counted
    /// from the tenth frame on, where every walk is on the ground).
    pub ungrounded: usize,
    /// The character's centre after the last frame.
    pub end: Vector,
    /// Whether it got where the walk goes (the plateau, the landing, the
    /// floor below the slope, along the wall; for the terrain, 90 % of
    /// the asked travel) or, for a ramp above the climb angle and a step
    /// above the autostep, stayed below it.
    pub arrived: bool,
}

impl WalkReport {
    /// Within tolerance, grounded in every frame from the tenth, and
    /// arrived.
    pub fn passes(&self) -> bool {
        (self.measured - self.expected).abs() <= self.tolerance
            && self.ungrounded == 0
            && self.arrived
    }
}

impl fmt::Display for WalkReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:<18} {:<16} {:<30} {:>9.4} {:>9.4} {:>8.2} mm  ungrounded {:<3} end ({:.3}, {:.3}, {:.3}){}",
            self.walk,
            self.ground,
            self.quantity,
            self.measured,
            self.expected,
            (self.measured - self.expected).abs() * 1e3,
            self.ungrounded,
            self.end.x,
            self.end.y,
            self.end.z,
            if self.arrived { "" } else { "  did not arrive" }
        )
    }
}

/// How a walk is walked: the character, its controller, where it starts,
/// the velocity it asks for every frame, and for how many frames.
pub struct Plan {
    /// The character's shape.
    pub character: SharedShape,
    /// The controller moving it.
    pub controller: KinematicCharacterController,
    /// The character's centre at the start.
    pub start: Vector,
    /// The velocity asked for every frame (m/s).
    pub velocity: Vector,
    /// How many frames.
    pub frames: usize,
}

impl Walk {
    /// The walks of the table and the tests.
    pub fn standard() -> Vec<Walk> {
        vec![
            Walk::Terrain,
            Walk::Ramp { angle_deg: 30.0 },
            Walk::Ramp { angle_deg: 60.0 },
            Walk::Stairs {
                rise: 0.15,
                steps: 4,
            },
            Walk::Stairs {
                rise: 0.4,
                steps: 1,
            },
            Walk::Wall { boxy: false },
            Walk::Wall { boxy: true },
            Walk::Snap,
        ]
    }

    /// The walk's name in reports.
    pub fn name(&self) -> String {
        match *self {
            Walk::Terrain => "walk terrain".into(),
            Walk::Ramp { angle_deg } => format!("walk ramp {angle_deg}deg"),
            Walk::Stairs { rise, steps } => format!("walk stairs {steps}x{rise}"),
            Walk::Wall { boxy: false } => "walk wall capsule".into(),
            Walk::Wall { boxy: true } => "walk wall box".into(),
            Walk::Snap => "walk snap".into(),
        }
    }

    /// The ground's mesh.
    pub fn mesh(&self) -> Mesh {
        match *self {
            Walk::Terrain => terrain_mesh(),
            Walk::Ramp { angle_deg } => extrude(&ramp_profile(angle_deg, 0.8).0, 3.0, 6, 0.25),
            Walk::Stairs { rise, steps } => stairs(rise, steps).0,
            Walk::Wall { .. } => wall().0,
            Walk::Snap => snap_slope().0,
        }
    }

    /// The ground made of parry cuboids, where the walk has one.
    pub fn boxes(&self) -> Option<Vec<(Cuboid, Pose)>> {
        match *self {
            Walk::Stairs { rise, steps } => Some(stairs(rise, steps).1),
            Walk::Wall { .. } => Some(wall().1),
            _ => None,
        }
    }

    /// Whether the walk has a ground of representation `rep`: a mesh one
    /// always (not parry's hull), a primitive one where it has
    /// [`boxes`](Self::boxes).
    pub fn has_ground(&self, rep: Rep) -> bool {
        match rep {
            Rep::Primitive => self.boxes().is_some(),
            Rep::Hull => false,
            _ => true,
        }
    }

    /// The ground as `rep`'s colliders.
    pub fn ground(&self, rep: Rep) -> Result<Vec<(SharedShape, Pose)>, SlideError> {
        if rep == Rep::Primitive {
            let boxes = self
                .boxes()
                .ok_or_else(|| SlideError::NoPrimitive(format!("the {} ground", self.name())))?;
            return Ok(boxes
                .into_iter()
                .map(|(b, p)| (SharedShape::new(b), p))
                .collect());
        }
        Ok(vec![(rep.mesh_shape(&self.mesh())?, Pose::IDENTITY)])
    }

    /// The walk's [`Plan`].
    pub fn plan(&self) -> Plan {
        let on_floor = Vector::new(0.0, bottom(0.0).abs() + OFFSET + 0.02, 0.0);
        let (character, controller, start, velocity, frames) = match *self {
            Walk::Terrain => (
                SharedShape::new(capsule()),
                walker(),
                Vector::new(-6.0, terrain_height(-6.0, -5.0) + 0.6, -5.0),
                Vector::new(4.0, -2.0, 3.0),
                150,
            ),
            Walk::Ramp { .. } => (
                SharedShape::new(capsule()),
                walker(),
                on_floor.with_z(-1.5),
                Vector::new(0.0, -2.0, 3.0),
                120,
            ),
            Walk::Stairs { .. } => (
                SharedShape::new(capsule()),
                stepper(),
                on_floor.with_z(-1.0),
                Vector::new(0.0, 0.0, 2.0),
                150,
            ),
            Walk::Wall { boxy } => (
                if boxy {
                    SharedShape::new(box_character())
                } else {
                    SharedShape::new(capsule())
                },
                walker(),
                on_floor.with_x(-2.0),
                Vector::new(2.0, -2.0, 3.0),
                120,
            ),
            Walk::Snap => (
                SharedShape::new(capsule()),
                walker(),
                Vector::new(0.0, 1.0 + bottom(0.0).abs() + OFFSET, -1.0),
                Vector::new(0.0, 0.0, 3.0),
                90,
            ),
        };
        Plan {
            character,
            controller,
            start,
            velocity,
            frames,
        }
    }

    /// The walk's frames over the colliders `ground`, the world's contacts
    /// in `mode` (see [`walk`]).
    pub fn frames(&self, mode: Option<CbvhMode>, ground: &[(SharedShape, Pose)]) -> Vec<Frame> {
        let p = self.plan();
        walk(
            mode,
            &p.character,
            ground,
            &p.controller,
            p.start,
            p.frames,
            |_| p.velocity * DT,
        )
    }

    /// Runs the walk over a ground of representation `rep` and measures
    /// it against the geometry's answer.
    pub fn run(&self, rep: Rep) -> Result<WalkReport, SlideError> {
        let track = self.frames(rep.cbvh_mode(), &self.ground(rep)?);
        Ok(self.judge(rep.name(), &track))
    }

    /// Measures `track` (the walk's frames over any ground of the walk's
    /// geometry, named `ground`) against the geometry's answer.
    pub fn judge(&self, ground: String, track: &[Frame]) -> WalkReport {
        let plan = self.plan();
        let (end, _) = *track.last().expect("a walk has frames");
        let ungrounded = track.iter().skip(10).filter(|f| !f.1).count();
        let worst = |devs: &mut dyn Iterator<Item = Real>| devs.fold(0.0, Real::max);
        let (quantity, measured, expected, tolerance, arrived) = match *self {
            Walk::Terrain => {
                let surface: TriMesh = parry_trimesh(&self.mesh()).expect("the terrain is valid");
                let gap = |c: Vector| {
                    DefaultQueryDispatcher
                        .distance(&Pose::from_translation(c), &surface, &capsule())
                        .expect("parry answers a capsule's distance to a TriMesh")
                        .distance
                };
                // The gap the controller keeps, worst frame first.
                let dev = worst(&mut track.iter().skip(10).map(|f| (gap(f.0) - OFFSET).abs()));
                let travel = (end - plan.start).with_y(0.0).length();
                let asked = plan.frames as Real * DT * plan.velocity.with_y(0.0).length();
                (
                    "worst |gap - offset| (m)",
                    dev,
                    0.0,
                    0.01,
                    travel >= 0.9 * asked,
                )
            }
            Walk::Ramp { angle_deg } => {
                let (_, run) = ramp_profile(angle_deg, 0.8);
                if angle_deg < 45.0 {
                    (
                        "bottom above plateau (m)",
                        bottom(end.y) - 0.8,
                        OFFSET,
                        2e-3,
                        end.z > run + 0.5,
                    )
                } else {
                    // The lower ball (centre R + offset above the floor)
                    // an offset from the slope through the origin.
                    let a = angle_deg.to_radians();
                    let foot = -(RADIUS + OFFSET) * (1.0 - a.cos()) / a.sin();
                    ("centre z at the foot (m)", end.z, foot, 0.01, end.z < 0.1)
                }
            }
            Walk::Stairs { rise, steps } => {
                let top = steps as Real * rise;
                if rise <= 0.25 {
                    (
                        "bottom above landing (m)",
                        bottom(end.y) - top,
                        OFFSET,
                        2e-3,
                        end.z > 2.5,
                    )
                } else {
                    let highest = track.iter().map(|f| f.0.y).fold(Real::MIN, Real::max);
                    (
                        "centre z before riser (m)",
                        end.z,
                        -(RADIUS + OFFSET),
                        3e-3,
                        highest < plan.start.y + 0.01 && (bottom(end.y) - OFFSET).abs() < 2e-3,
                    )
                }
            }
            Walk::Wall { .. } => {
                let stop = 2.0 - RADIUS - OFFSET;
                let deepest = track.iter().map(|f| f.0.z).fold(Real::MIN, Real::max);
                let along = end.x - plan.start.x;
                let asked = plan.velocity.x * plan.frames as Real * DT;
                (
                    "centre z at the wall (m)",
                    end.z,
                    stop,
                    3e-3,
                    deepest <= stop + 1e-3
                        && along >= 0.95 * asked
                        && along <= asked + 1e-3
                        && (bottom(end.y) - OFFSET).abs() < 2e-3,
                )
            }
            Walk::Snap => {
                let (_, run) = snap_slope();
                let dev = worst(&mut track.iter().filter_map(|&(p, _)| {
                    let want = snap_clearance(p.z, run)?;
                    Some((bottom(p.y) - snap_ground(p.z) - want).abs())
                }));
                (
                    "worst |clearance - want| (m)",
                    dev,
                    0.0,
                    3e-3,
                    end.z > run + 0.5,
                )
            }
        };
        WalkReport {
            walk: self.name(),
            ground,
            quantity,
            measured,
            expected,
            tolerance,
            ungrounded,
            end,
            arrived,
        }
    }
}

/// The grounds the table walks on for `codecs` (and `scaled` codecs as
/// [`Rep::Scaled`]): parry's `TriMesh` with and without
/// `FIX_INTERNAL_EDGES`, parry cuboids, and each codec in both contact
/// modes. A walk skips the grounds it has none of ([`Walk::has_ground`]).
pub fn grounds(codecs: &[CodecKind], scaled: &[CodecKind]) -> Vec<Rep> {
    let mut all = vec![Rep::Primitive, Rep::TriMesh, Rep::TriMeshFixed];
    for &k in codecs {
        all.extend(CbvhMode::ALL.map(|m| Rep::Cbvh(k, m)));
    }
    for &k in scaled {
        all.extend(CbvhMode::ALL.map(|m| Rep::Scaled(k, m)));
    }
    all
}
