//! Continuous collision detection in rapier, against the analytic first
//! contact: fast bodies that must stop at the surface they hit instead of
//! tunnelling through it, for every way of representing the surface and
//! the body ([`Rep`]).
//!
//! The scenes ([`CcdScene`]), each with gravity off, friction and
//! restitution zero, at rapier's default [`IntegrationParameters`] (60 Hz):
//!
//! - [`CcdScene::Shot`]: a ball, a cube or a capsule ([`Projectile`]) of
//!   radius (half side) [`RADIUS`] shot along `+x` at a wall of zero
//!   thickness, the square `x = 0` of side `2 ·` [`WALL_HALF`] in `cells` ×
//!   `cells` quads ([`wall_mesh`]). It starts [`SHOT_STEPS_AWAY`] steps of
//!   flight from the wall, so that it reaches the wall inside a step, not
//!   at one's end. Its first contact is when its leading point reaches the
//!   plane: the centre at `x = −extent`.
//! - [`CcdScene::Spin`]: a bar of half length [`BAR_HALF_LENGTH`] and half
//!   thickness [`BAR_HALF_WIDTH`], centred on the origin and spinning about
//!   `z` at `omega`, sweeps up towards a zero-thickness strip in the plane
//!   `y = 0` from `x =` [`STRIP_INNER`] outwards ([`strip_mesh`]). Its top
//!   face first touches the strip's inner edge when the bar's angle is
//!   `−asin(half width / inner)`; a bar that tunnels has corners above the
//!   strip (a bar stopped by it is knocked down, away from it).
//!
//! Each run reports ([`CcdReport`]) where the body was at its first
//! contact (the end of the first step whose motion was cut short, by the
//! continuous pass or by a contact), the error of that against the
//! analytic answer in metres at the contact point, how far past the
//! surface the body ever got, and whether it ended on the far side.
//!
//! rapier 0.36 sweeps every dynamic body fast enough for its
//! `ccd_thickness` (its thinnest collider's, see
//! [`CbvhShape::ccd_thickness`](crate::parry::CbvhShape::ccd_thickness)),
//! CCD enabled or not; bodies here also enable it.
//!
//! [`IntegrationParameters`]: rapier3d::prelude::IntegrationParameters

use std::fmt;

use parry3d::math::{Rotation, Vector};
use parry3d::shape::SharedShape;
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

use super::slide::{self, CbvhMode, Rep, SlideError, box_mesh, cube_mesh, icosphere_mesh};
use crate::codec::CodecKind;
use crate::mesh::Mesh;

/// Radius of the ball and the capsule, half side of the cube (m).
pub const RADIUS: f32 = 0.1;
/// Half the capsule's segment (m), along `y` (across the shot).
pub const CAPSULE_HALF_HEIGHT: f32 = 0.1;
/// Half the side of the square wall (m).
pub const WALL_HALF: f32 = 2.0;
/// Steps of flight between the body's start and its first contact (a
/// fraction, so that the contact falls inside a step).
pub const SHOT_STEPS_AWAY: f32 = 3.37;
/// Half length of the spinning bar (m).
pub const BAR_HALF_LENGTH: f32 = 1.0;
/// Half thickness of the spinning bar (m).
pub const BAR_HALF_WIDTH: f32 = 0.05;
/// Distance from the bar's axis to the strip's inner edge (m).
pub const STRIP_INNER: f32 = 0.3;
/// Distance from the bar's axis to the strip's outer edge (m).
pub const STRIP_OUTER: f32 = 3.0;
/// The bar's starting angle (radians, about `z` from `+x`).
pub const BAR_START_ANGLE: f32 = -1.0;
/// Largest error of a first contact (m), the goal of the tests.
pub const CONTACT_TOLERANCE: f32 = 1e-3;
/// Deepest a body may sink past the surface after its first contact (m).
/// The continuous pass stops a body at the contact with its velocity
/// kept; the next step's contact takes the velocity out through rapier's
/// soft contact constraints, which let a fast body sink a little: up to
/// 2.2 mm for parry's convex hull of the ball mesh on parry's `TriMesh`
/// wall at 10 to 360 m/s.
pub const SINK_TOLERANCE: f32 = 2.5e-3;
/// Steps each scene runs (1 s at 60 Hz).
pub const STEPS: usize = 60;
/// Subdivisions of the icosphere that stands for a ball as a mesh (1 280
/// triangles).
pub const BALL_SUBDIVISIONS: u32 = 3;

/// The shape shot at the wall.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Projectile {
    /// A ball of radius [`RADIUS`] (an icosphere as a mesh).
    Ball,
    /// An axis-aligned cube of half side [`RADIUS`].
    Cube,
    /// A capsule of radius [`RADIUS`] along `y` (a primitive only).
    Capsule,
}

impl Projectile {
    /// Every projectile.
    pub const ALL: [Projectile; 3] = [Projectile::Ball, Projectile::Cube, Projectile::Capsule];

    /// `ball`, `cube` or `capsule`.
    pub fn name(self) -> &'static str {
        match self {
            Projectile::Ball => "ball",
            Projectile::Cube => "cube",
            Projectile::Capsule => "capsule",
        }
    }

    /// The mesh standing for the projectile, if it has one.
    pub fn mesh(self) -> Option<Mesh> {
        match self {
            Projectile::Ball => Some(icosphere_mesh(RADIUS, BALL_SUBDIVISIONS)),
            Projectile::Cube => Some(cube_mesh(2.0 * RADIUS)),
            Projectile::Capsule => None,
        }
    }

    /// The projectile as `rep`, and how far it reaches along `+x` from its
    /// centre (the mesh's farthest vertex for a mesh).
    fn shape(self, rep: Rep) -> Result<(SharedShape, f32), SlideError> {
        if rep == Rep::Primitive {
            let s = match self {
                Projectile::Ball => SharedShape::ball(RADIUS),
                Projectile::Cube => SharedShape::cuboid(RADIUS, RADIUS, RADIUS),
                Projectile::Capsule => SharedShape::capsule_y(CAPSULE_HALF_HEIGHT, RADIUS),
            };
            return Ok((s, RADIUS));
        }
        let mesh = self
            .mesh()
            .ok_or_else(|| SlideError::NoPrimitive(format!("a {} mesh", self.name())))?;
        let extent = mesh.vertices.iter().map(|v| v[0]).fold(f32::MIN, f32::max);
        Ok((rep.mesh_shape(&mesh)?, extent))
    }
}

/// A rectangle centred on `centre`, spanned by the half sides `u` and `v`,
/// in `cells` × `cells` quads split in two triangles each, wound
/// counter-clockwise about `u × v`.
pub fn rect_mesh(centre: Vector, u: Vector, v: Vector, cells: usize) -> Mesh {
    let n = cells.max(1);
    let mut vertices = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let a = 2.0 * i as f32 / n as f32 - 1.0;
            let b = 2.0 * j as f32 / n as f32 - 1.0;
            vertices.push((centre + a * u + b * v).to_array());
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut triangles = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    Mesh::new(vertices, triangles)
}

/// The wall of [`CcdScene::Shot`]: the square `x = 0`, facing `−x`.
pub fn wall_mesh(cells: usize) -> Mesh {
    rect_mesh(
        Vector::ZERO,
        Vector::new(0.0, 0.0, WALL_HALF),
        Vector::new(0.0, WALL_HALF, 0.0),
        cells,
    )
}

/// The strip of [`CcdScene::Spin`]: `y = 0`, `x` from [`STRIP_INNER`] to
/// [`STRIP_OUTER`], `z` within ±1, facing `−y`.
pub fn strip_mesh(cells: usize) -> Mesh {
    let half = 0.5 * (STRIP_OUTER - STRIP_INNER);
    rect_mesh(
        Vector::new(STRIP_INNER + half, 0.0, 0.0),
        Vector::new(half, 0.0, 0.0),
        Vector::new(0.0, 0.0, 1.0),
        cells,
    )
}

/// One scene (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CcdScene {
    /// A projectile shot at `speed` (m/s) at a wall of `cells` × `cells`
    /// quads.
    Shot {
        /// What is shot.
        projectile: Projectile,
        /// Its speed (m/s).
        speed: f32,
        /// Quads per side of the wall.
        cells: usize,
    },
    /// The bar spinning at `omega` (rad/s) towards a strip of `cells` ×
    /// `cells` quads.
    Spin {
        /// Angular speed (rad/s).
        omega: f32,
        /// Quads per side of the strip.
        cells: usize,
    },
}

/// What a run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct CcdReport {
    /// The scene's name.
    pub scene: String,
    /// The surface's representation.
    pub target: String,
    /// The body's representation.
    pub body: String,
    /// The analytic first contact: the centre's `x` (m) for a shot, the
    /// bar's angle (rad) for the spin.
    pub expected: f32,
    /// The same, measured at the end of the first step whose motion was
    /// cut short; `None` if no step was.
    pub first_contact: Option<f32>,
    /// `|first_contact − expected|` in metres at the contact point
    /// (infinite without a first contact).
    pub contact_error: f32,
    /// The deepest the body ever got past the surface (m): its leading
    /// point past the wall; for the spin, the strip's inner edge inside the
    /// bar or a corner of the bar over the strip above its plane.
    pub deepest: f32,
    /// The body went through the surface: it ended past the wall, or a
    /// corner of the bar was more than [`CONTACT_TOLERANCE`] above the
    /// strip.
    pub crossed: bool,
}

impl CcdReport {
    /// The first contact is within [`CONTACT_TOLERANCE`] of the analytic
    /// one, the body never sank more than [`SINK_TOLERANCE`] past the
    /// surface, and it did not go through.
    pub fn passes(&self) -> bool {
        self.contact_error <= CONTACT_TOLERANCE && self.deepest <= SINK_TOLERANCE && !self.crossed
    }
}

impl fmt::Display for CcdReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let first = match self.first_contact {
            Some(x) => format!("{x:>9.5}"),
            None => format!("{:>9}", "none"),
        };
        write!(
            f,
            "{:<28} {:<16} {:<16} expected {:>9.5} first {first} error {:>8.2} mm deepest {:>8.2} mm{}",
            self.scene,
            self.target,
            self.body,
            self.expected,
            self.contact_error * 1e3,
            self.deepest * 1e3,
            if self.crossed { "  TUNNELLED" } else { "" }
        )
    }
}

/// [`slide`](super::slide)'s world (the contact mode of the cbvh shapes in
/// the scene) without gravity.
fn new_world(target: Rep, body: Rep) -> Result<PhysicsWorld, SlideError> {
    let mut world = slide::new_world(target, body)?;
    world.gravity = Vector::ZERO;
    Ok(world)
}

fn add_fixed(world: &mut PhysicsWorld, shape: SharedShape) {
    let fixed = world.bodies.insert(RigidBodyBuilder::fixed());
    world.colliders.insert_with_parent(
        ColliderBuilder::new(shape).friction(0.0).restitution(0.0),
        fixed,
        &mut world.bodies,
    );
}

fn add_body(
    world: &mut PhysicsWorld,
    body: RigidBodyBuilder,
    shape: SharedShape,
) -> RigidBodyHandle {
    let h = world.bodies.insert(body.ccd_enabled(true).can_sleep(false));
    world.colliders.insert_with_parent(
        ColliderBuilder::new(shape).friction(0.0).restitution(0.0),
        h,
        &mut world.bodies,
    );
    h
}

/// The bar's angle about `z` (radians, from `+x`).
fn angle_z(r: Rotation) -> f32 {
    let x = r * Vector::X;
    x.y.atan2(x.x)
}

impl CcdScene {
    /// The scene's name in reports.
    pub fn name(&self) -> String {
        match *self {
            CcdScene::Shot {
                projectile,
                speed,
                cells,
            } => format!("shot {} {speed} m/s {cells}x{cells}", projectile.name()),
            CcdScene::Spin { omega, cells } => format!("spin {omega} rad/s {cells}x{cells}"),
        }
    }

    /// Runs the scene with the surface as `target` and the moving body as
    /// `body`.
    pub fn run(&self, target: Rep, body: Rep) -> Result<CcdReport, SlideError> {
        let mut world = new_world(target, body)?;
        let dt = world.integration_parameters.dt;
        let report =
            |expected, first_contact: Option<f32>, lever: f32, deepest, crossed| CcdReport {
                scene: self.name(),
                target: target.name(),
                body: body.name(),
                expected,
                first_contact,
                contact_error: first_contact
                    .map(|x: f32| (x - expected).abs() * lever)
                    .unwrap_or(f32::INFINITY),
                deepest,
                crossed,
            };
        match *self {
            CcdScene::Shot {
                projectile,
                speed,
                cells,
            } => {
                add_fixed(&mut world, target.mesh_shape(&wall_mesh(cells))?);
                let (shape, extent) = projectile.shape(body)?;
                let start = -extent - SHOT_STEPS_AWAY * speed * dt;
                let h = add_body(
                    &mut world,
                    RigidBodyBuilder::dynamic()
                        .translation(Vector::new(start, 0.0, 0.0))
                        .linvel(Vector::new(speed, 0.0, 0.0)),
                    shape,
                );
                let (mut first, mut deepest, mut x) = (None, f32::MIN, start);
                for _ in 0..STEPS {
                    world.step();
                    let nx = world.bodies[h].translation().x;
                    if first.is_none() && nx - x < 0.999 * speed * dt {
                        first = Some(nx);
                    }
                    deepest = deepest.max(nx + extent);
                    x = nx;
                }
                Ok(report(-extent, first, 1.0, deepest, x - extent > 0.0))
            }
            CcdScene::Spin { omega, cells } => {
                add_fixed(&mut world, target.mesh_shape(&strip_mesh(cells))?);
                let half = Vector::new(BAR_HALF_LENGTH, BAR_HALF_WIDTH, BAR_HALF_WIDTH);
                let shape = match body {
                    Rep::Primitive => SharedShape::cuboid(half.x, half.y, half.z),
                    rep => rep.mesh_shape(&box_mesh(half))?,
                };
                let h = add_body(
                    &mut world,
                    RigidBodyBuilder::dynamic()
                        .rotation(Vector::new(0.0, 0.0, BAR_START_ANGLE))
                        .angvel(Vector::new(0.0, 0.0, omega)),
                    shape,
                );
                let expected = -(BAR_HALF_WIDTH / STRIP_INNER).asin();
                let edge = Vector::new(STRIP_INNER, 0.0, 0.0);
                let (mut first, mut deepest, mut a) = (None, f32::MIN, BAR_START_ANGLE);
                let mut crossed = false;
                for _ in 0..STEPS {
                    world.step();
                    let pose = *world.bodies[h].position();
                    let na = angle_z(pose.rotation);
                    if first.is_none() && na - a < 0.99 * omega * dt {
                        first = Some(na);
                    }
                    // The strip's inner edge inside the bar's box: the
                    // least of the box's half extents less the edge's
                    // distance from its centre plane (positive inside).
                    let p = pose.inverse_transform_point(edge);
                    deepest = deepest.max((half - p.abs()).min_element());
                    // A corner of the bar over the strip and above its
                    // plane went through it (the bar knocked off the
                    // strip's edge falls away below it).
                    for k in 0..8 {
                        let sign = |bit: usize| if k & bit == 0 { -1.0 } else { 1.0 };
                        let corner = pose
                            * Vector::new(sign(1) * half.x, sign(2) * half.y, sign(4) * half.z);
                        if corner.x > STRIP_INNER && corner.x < STRIP_OUTER && corner.z.abs() < 1.0
                        {
                            deepest = deepest.max(corner.y);
                            crossed |= corner.y > CONTACT_TOLERANCE;
                        }
                    }
                    a = na;
                }
                Ok(report(expected, first, STRIP_INNER, deepest, crossed))
            }
        }
    }
}

/// The scenes of the table: each projectile at 1 m/s (slow enough for the
/// contacts alone: the control), 10, 60 and 360 m/s at an 8 × 8 wall, and
/// the bar spinning at 30 and 120 rad/s into an 8 × 8 strip.
pub fn standard() -> Vec<CcdScene> {
    let mut all = Vec::new();
    for projectile in Projectile::ALL {
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

/// The (surface, body) pairs of the table for `codecs` (and `scaled`
/// codecs as [`Rep::Scaled`]), each cbvh one in both contact modes: a
/// primitive body at every surface; a cbvh body of the surface's own
/// representation at a cbvh surface, parry's convex hull at parry's
/// `TriMesh`; and a plain cbvh body (both modes) at parry's `TriMesh`.
pub fn pairings(codecs: &[CodecKind], scaled: &[CodecKind]) -> Vec<(Rep, Rep)> {
    let mut targets = vec![Rep::TriMesh, Rep::TriMeshFixed];
    for &kind in codecs {
        targets.extend(CbvhMode::ALL.map(|m| Rep::Cbvh(kind, m)));
    }
    for &kind in scaled {
        targets.extend(CbvhMode::ALL.map(|m| Rep::Scaled(kind, m)));
    }
    let mut all = Vec::new();
    for t in targets {
        all.push((t, Rep::Primitive));
        if t.cbvh_mode().is_some() {
            all.push((t, t));
        } else {
            all.push((t, Rep::Hull));
        }
    }
    for m in CbvhMode::ALL {
        all.push((Rep::TriMesh, Rep::Cbvh(CodecKind::Plain, m)));
    }
    all
}
