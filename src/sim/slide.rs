//! Physics scenes with analytic answers, run in rapier for every way of
//! representing the ground and the moving body, each reporting what it
//! measured against what mechanics predicts: the yardstick for the
//! contacts' behaviour in motion (the drop test of [`super::droptest`]
//! times contacts; this checks that they push the right way).
//!
//! The scenes ([`Scene`]):
//!
//! - [`Scene::Slide`]: a cube on a ramp tilted by θ, friction μ on both
//!   colliders (rapier averages them): it accelerates along the slope at
//!   `g (sin θ − μ cos θ)` when that is positive, else it stays.
//! - [`Scene::Roll`]: a sphere (an icosphere mesh, or parry's ball) rolling
//!   down a ramp: `g sin θ / (1 + I / (m r²))`, with `I`, `m` the body's own
//!   mass properties (a polyhedron is not quite a solid sphere) and `r` the
//!   distance of its centre of mass from the ramp.
//! - [`Scene::Bowl`]: a damped ball released off-centre in a hemispherical
//!   bowl ends on its axis.
//! - [`Scene::Rest`], [`Scene::Stack`], [`Scene::TableEdge`]: a cube
//!   dropped on a flat ground rests at half its side, a stack of cubes
//!   stands, a cube over a table's edge stays or tips off depending on
//!   which side of the edge its centre is.
//! - [`Scene::Rock`]: a flat-bottomed block balanced on a dome (the
//!   rocking stone): it rocks back when its centre of mass is lower above
//!   its base than the dome's radius and tips off when higher, the drop
//!   test's statue on the flat rotor's nose dome in miniature.
//!
//! Every body starts at rest, placed at its contact pose (the slopes, the
//! stack, the table) or just above the surface (the drop, the bowl), and
//! cannot sleep. rapier runs at its default [`IntegrationParameters`]
//! (60 Hz) with gravity [`GRAVITY`]; the narrow phase is
//! [`Dispatcher`] chained to parry's default dispatcher, with the contact
//! mode of the cbvh shapes in the scene. A slope's acceleration is the
//! least-squares slope ([`least_squares_slope`]) of the centre of mass's
//! velocity along the slope over [`FIT_WINDOW`].
//!
//! The ground and the body each take a [`Rep`]: a parry primitive, parry's
//! `TriMesh` (default flags or `FIX_INTERNAL_EDGES`), or a [`CbvhShape`] of
//! a codec in one of the two contact modes ([`CbvhMode`]). Meshes are made
//! here ([`ramp_mesh`], [`cube_mesh`], [`box_mesh`], [`icosphere_mesh`],
//! [`bowl_mesh`], [`dome_mesh`]),
//! every triangle wound counter-clockwise seen from outside (from above for
//! the ramp, from the bowl's inside).
//!
//! [`IntegrationParameters`]: rapier3d::prelude::IntegrationParameters

use std::collections::HashMap;
use std::fmt;
use std::str::FromStr;
use std::time::Instant;

use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::{SharedShape, TriMesh, TriMeshFlags};
use rapier3d::prelude::{
    ColliderBuilder, NarrowPhase, PhysicsWorld, RigidBody, RigidBodyBuilder, RigidBodyHandle,
};

use super::trace::{Trace, com_height};
use crate::build::BuildOptions;
use crate::codec::{AnyOptions, CodecKind};
use crate::contact::PatchOptions;
use crate::mesh::Mesh;
use crate::parry::{CbvhShape, ContactMode, Dispatcher, ShapeBuildError, parry_trimesh};

/// The factors of [`Rep::Scaled`]: non-uniform, and mirrored along y.
pub const SCALED_BY: [f32; 3] = [2.0, -0.5, 1.25];
/// Gravity's magnitude (m/s²), pointing down −y.
pub const GRAVITY: f32 = 9.81;
/// Friction of both colliders in [`Scene::slide`] and of the bowl scene.
pub const DEFAULT_FRICTION: f32 = 0.6;
/// Friction of both colliders in [`Scene::roll`].
pub const ROLL_FRICTION: f32 = 1.0;
/// Ramp angle of [`Scene::roll`] (degrees).
pub const ROLL_ANGLE_DEG: f32 = 15.0;
/// Largest relative error of a measured acceleration (or rest height).
pub const REL_TOLERANCE: f32 = 0.10;
/// Largest move of the centre of mass (m) of a body that should stay,
/// over the whole run.
pub const STAY_LIMIT: f32 = 0.01;
/// A body moved uphill if its centre of mass ever went further than this
/// (m) against the downhill direction from where it started.
pub const UPHILL_LIMIT: f32 = 1e-3;
/// Goal for the ball's final distance from the bowl's axis (m).
pub const BOWL_GOAL: f32 = 0.02;
/// Largest error of a resting height (m): of a dropped cube's centre, and
/// of each cube of a stack above the one below it.
pub const REST_TOLERANCE: f32 = 0.01;
/// A body whose centre of mass is faster than this at the end (m/s) is
/// still moving.
pub const MOVING_SPEED: f32 = 0.01;
/// Side of the square ground plane (the ramps, the flat ground, the table)
/// (m).
pub const PLANE_SIZE: f32 = 8.0;
/// Thickness of the primitive ground (a cuboid whose top face is the
/// plane) (m).
pub const GROUND_THICKNESS: f32 = 0.1;
/// Side of every cube (m).
pub const CUBE_SIDE: f32 = 1.0;
/// Radius of the rolling sphere (m).
pub const SPHERE_RADIUS: f32 = 0.5;
/// Subdivisions of the icosphere meshes (4: 5120 triangles).
pub const SPHERE_SUBDIVISIONS: u32 = 4;
/// Subdivisions of the fine icosphere of [`Scene::fine_roll`] (5: 20 480
/// triangles, edges half of [`SPHERE_SUBDIVISIONS`]'s).
pub const FINE_SPHERE_SUBDIVISIONS: u32 = 6;
/// Radius of the bowl (m).
pub const BOWL_RADIUS: f32 = 2.0;
/// Segments around the bowl (its rings are a quarter as many).
pub const BOWL_SEGMENTS: usize = 96;
/// Radius of the ball in the bowl (m).
pub const BOWL_BALL_RADIUS: f32 = 0.25;
/// Where a body starts on a ramp: its contact point this far along the
/// downhill direction from the ramp's centre (m; negative is uphill, so
/// that a sliding body crosses the 2-triangle ramp's diagonal).
pub const START_ALONG: f32 = -1.0;
/// Length of a slope run (s).
pub const SLOPE_SECONDS: f32 = 1.5;
/// The window of a slope run over which the acceleration is fitted (s).
pub const FIT_WINDOW: (f32, f32) = (0.25, 1.5);
/// Length of the bowl run (s).
pub const BOWL_SECONDS: f32 = 10.0;
/// Length of the rest, stack and table runs (s).
pub const REST_SECONDS: f32 = 3.0;
/// Height of the dropped cube's bottom above the ground at the start (m).
pub const DROP_GAP: f32 = 0.05;
/// Radius of the dome of [`Scene::Rock`] (m).
pub const DOME_RADIUS: f32 = 1.0;
/// Segments around the dome (its rings are a quarter as many: 4° apart).
pub const DOME_SEGMENTS: usize = 96;
/// Tilt [`Scene::Rock`]'s block starts at, rolled over the dome (degrees).
pub const ROCK_START_DEG: f32 = 8.0;
/// Length of the rocking run (s).
pub const ROCK_SECONDS: f32 = 4.0;
/// A rocking block that tips ends tilted more than this (degrees).
pub const TIPPED_DEG: f32 = 45.0;
/// A rocking block that holds stays tilted less than this (degrees).
pub const ROCK_HOLD_DEG: f32 = 20.0;

/// A ramp's directions: the plane through the origin with `normal`, tilted
/// from the horizontal about the x axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlopeFrame {
    /// The upward unit normal.
    pub normal: Vector,
    /// The unit direction down the slope (`+z` at 0°).
    pub downhill: Vector,
    /// The unit direction across the slope (`+x`).
    pub across: Vector,
    /// The rotation taking the horizontal plane (normal `+y`) to the ramp.
    pub rotation: Rotation,
}

impl SlopeFrame {
    /// The frame of a ramp tilted by `angle_deg` degrees.
    pub fn new(angle_deg: f32) -> Self {
        let (s, c) = angle_deg.to_radians().sin_cos();
        Self {
            normal: Vector::new(0.0, c, s),
            downhill: Vector::new(0.0, -s, c),
            across: Vector::X,
            rotation: Rotation::from_rotation_x(angle_deg.to_radians()),
        }
    }
}

/// The unnormalised normal of triangle `t` of `m`
/// (`(b − a) × (c − a)`).
fn triangle_normal(m: &Mesh, t: usize) -> Vector {
    let [a, b, c] = m.triangle_vertices(t).map(Vector::from_array);
    (b - a).cross(c - a)
}

/// `m` with every triangle whose normal points away from
/// `want(centroid)` turned over.
fn orient(mut m: Mesh, want: impl Fn(Vector) -> Vector) -> Mesh {
    for t in 0..m.triangles.len() {
        let [a, b, c] = m.triangle_vertices(t).map(Vector::from_array);
        if triangle_normal(&m, t).dot(want((a + b + c) / 3.0)) < 0.0 {
            m.triangles[t].swap(1, 2);
        }
    }
    m
}

/// A square plane of side `size` centred on the origin, tilted about the x
/// axis by `angle_deg` (its frame is [`SlopeFrame::new`]`(angle_deg)`), of
/// `cells_per_side` × `cells_per_side` quads split into two triangles each
/// (at least one cell: `1` is the 2-triangle ramp, whose diagonal runs
/// from the uphill `+x` corner to the downhill `−x` one), wound
/// counter-clockwise seen from above.
pub fn ramp_mesh(angle_deg: f32, cells_per_side: usize, size: f32) -> Mesh {
    let n = cells_per_side.max(1);
    let frame = SlopeFrame::new(angle_deg);
    let coord = |i: usize| size * (i as f32 / n as f32 - 0.5);
    let mut vertices = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            vertices.push((frame.across * coord(i) + frame.downhill * coord(j)).to_array());
        }
    }
    let index = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut triangles = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let (v00, v10) = (index(i, j), index(i + 1, j));
            let (v01, v11) = (index(i, j + 1), index(i + 1, j + 1));
            triangles.push([v00, v01, v10]);
            triangles.push([v10, v01, v11]);
        }
    }
    orient(Mesh::new(vertices, triangles), |_| frame.normal)
}

/// A closed cube of side `side` centred on the origin, axis-aligned: 8
/// vertices, 12 triangles wound outward.
pub fn cube_mesh(side: f32) -> Mesh {
    let h = 0.5 * side;
    box_mesh(Vector::splat(h))
}

/// A closed axis-aligned box of half extents `half` centred on the origin:
/// 8 vertices, 12 triangles wound outward.
pub fn box_mesh(half: Vector) -> Mesh {
    let cuboid = Mesh::cuboid((-half).to_array(), half.to_array());
    orient(cuboid, |c| c)
}

/// A sphere of radius `radius` centred on the origin: an icosahedron whose
/// triangles are split in four `subdivisions` times, every vertex on the
/// sphere (`20 · 4^subdivisions` triangles: 5120 at 4), wound outward.
pub fn icosphere_mesh(radius: f32, subdivisions: u32) -> Mesh {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut vertices: Vec<Vector> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .into_iter()
    .map(|v| Vector::from_array(v).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut split = Vec::with_capacity(4 * triangles.len());
        for &[a, b, c] in &triangles {
            let mut mid = |p: u32, q: u32| {
                *midpoints.entry((p.min(q), p.max(q))).or_insert_with(|| {
                    let m = (vertices[p as usize] + vertices[q as usize]).normalize();
                    vertices.push(m);
                    (vertices.len() - 1) as u32
                })
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            split.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = split;
    }
    let vertices = vertices.iter().map(|v| (*v * radius).to_array()).collect();
    orient(Mesh::new(vertices, triangles), |c| c)
}

/// The rings of [`bowl_mesh`]`(_, segments)`: a quarter of the segments,
/// at least one.
fn bowl_rings(segments: usize) -> usize {
    (segments.max(3) / 4).max(1)
}

/// An open hemispherical bowl: the lower half of the sphere of radius
/// `radius` centred at `(0, radius, 0)`, so that its bottom is at the
/// origin and its rim at height `radius`. `segments` (at least 3) around,
/// a quarter as many rings from the bottom to the rim, the bottom a fan
/// around one vertex; wound counter-clockwise seen from the inside (from
/// above at the bottom).
pub fn bowl_mesh(radius: f32, segments: usize) -> Mesh {
    let segments = segments.max(3);
    let rings = bowl_rings(segments);
    let centre = Vector::new(0.0, radius, 0.0);
    let mut vertices = vec![[0.0, 0.0, 0.0]];
    for k in 1..=rings {
        let (sp, cp) = (k as f32 / rings as f32 * std::f32::consts::FRAC_PI_2).sin_cos();
        for j in 0..segments {
            let (sa, ca) = (j as f32 / segments as f32 * std::f32::consts::TAU).sin_cos();
            vertices.push((centre + Vector::new(sp * ca, -cp, sp * sa) * radius).to_array());
        }
    }
    let ring = |k: usize, j: usize| (1 + (k - 1) * segments + j % segments) as u32;
    let mut triangles = Vec::with_capacity(segments * (2 * rings - 1));
    for j in 0..segments {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for k in 1..rings {
        for j in 0..segments {
            let (i0, i1) = (ring(k, j), ring(k, j + 1));
            let (o0, o1) = (ring(k + 1, j), ring(k + 1, j + 1));
            triangles.push([i0, o0, o1]);
            triangles.push([i0, o1, i1]);
        }
    }
    orient(Mesh::new(vertices, triangles), |c| centre - c)
}

/// An open hemispherical dome: the upper half of the sphere of radius
/// `radius` centred on the origin, its top at `(0, radius, 0)` (the fan
/// vertex) and its rim at `y = 0`; [`bowl_mesh`]'s tessellation turned
/// upside down, wound counter-clockwise seen from outside.
pub fn dome_mesh(radius: f32, segments: usize) -> Mesh {
    let bowl = bowl_mesh(radius, segments);
    let vertices = bowl
        .vertices
        .iter()
        .map(|v| [v[0], radius - v[1], v[2]])
        .collect();
    orient(Mesh::new(vertices, bowl.triangles), |c| c)
}

/// The smallest distance from the centre of [`bowl_mesh`]`(radius,
/// segments)` to its surface, bounded from below: `radius · cos δ`, with δ
/// the angle a cell's diagonal spans.
fn bowl_inner_radius(radius: f32, segments: usize) -> f32 {
    let segments = segments.max(3);
    let around = std::f32::consts::TAU / segments as f32;
    let down = std::f32::consts::FRAC_PI_2 / bowl_rings(segments) as f32;
    radius * around.hypot(down).cos()
}

/// The least-squares slope of `y` against `t` (0 for fewer than two
/// distinct times; the shorter length is used).
pub fn least_squares_slope(t: &[f32], y: &[f32]) -> f32 {
    let n = t.len().min(y.len());
    if n < 2 {
        return 0.0;
    }
    let mean = |v: &[f32]| v[..n].iter().map(|x| f64::from(*x)).sum::<f64>() / n as f64;
    let (mt, my) = (mean(t), mean(y));
    let (mut sty, mut stt) = (0.0f64, 0.0f64);
    for (a, b) in t[..n].iter().zip(&y[..n]) {
        let dt = f64::from(*a) - mt;
        sty += dt * (f64::from(*b) - my);
        stt += dt * dt;
    }
    if stt == 0.0 { 0.0 } else { (sty / stt) as f32 }
}

/// How a cbvh shape's contacts become manifolds (see [`ContactMode`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CbvhMode {
    /// Contact patches ([`ContactMode::Patches`] with the default
    /// [`PatchOptions`]), the dispatcher's default.
    Patches,
    /// One manifold per triangle pair ([`ContactMode::PerTrianglePair`]).
    Pairs,
}

impl CbvhMode {
    /// Both modes, patches first.
    pub const ALL: [CbvhMode; 2] = [CbvhMode::Patches, CbvhMode::Pairs];

    /// The dispatcher's contact mode.
    pub fn contact_mode(self) -> ContactMode {
        match self {
            CbvhMode::Patches => ContactMode::Patches(PatchOptions::default()),
            CbvhMode::Pairs => ContactMode::PerTrianglePair,
        }
    }
}

/// How a shape (the ground or the moving body) is represented.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Rep {
    /// A parry primitive: a cuboid for a cube, a ball for a sphere, a thin
    /// cuboid ([`GROUND_THICKNESS`]) whose top face is the ground plane.
    /// No bowl has one.
    Primitive,
    /// parry's `TriMesh` with its default flags.
    TriMesh,
    /// parry's `TriMesh` with `TriMeshFlags::FIX_INTERNAL_EDGES`.
    TriMeshFixed,
    /// A [`CbvhShape`] of the codec, its tree built with the default
    /// [`BuildOptions`] and the codec's default options, its contacts in
    /// the mode.
    Cbvh(CodecKind, CbvhMode),
    /// A [`CbvhShape`] as [`Rep::Cbvh`], built from the mesh with its
    /// vertices divided by [`SCALED_BY`] and handed to rapier scaled back
    /// by it ([`CbvhShape::scaled`]: a non-uniform, mirrored view over the
    /// same tree). The shape is the scene's mesh again, so every scene's
    /// answer holds for it.
    Scaled(CodecKind, CbvhMode),
    /// parry's convex hull of the mesh's vertices, for a body: the same
    /// polyhedron as the mesh with parry's exact convex contacts, the
    /// reference for what a faceted body does (an icosphere rolls slower
    /// than a sphere: it bumps over its edges).
    Hull,
}

impl Rep {
    /// The name in reports and on command lines: `primitive`, `trimesh`,
    /// `trimesh-fixed`, or the codec's name, followed by `-pairs` in the
    /// per-pair mode (`plain`, `plain-pairs`, as the drop test's
    /// [`RunSpec::name`](super::RunSpec::name)).
    pub fn name(self) -> String {
        match self {
            Rep::Primitive => "primitive".into(),
            Rep::TriMesh => "trimesh".into(),
            Rep::TriMeshFixed => "trimesh-fixed".into(),
            Rep::Hull => "hull".into(),
            Rep::Cbvh(k, CbvhMode::Patches) => k.name().into(),
            Rep::Cbvh(k, CbvhMode::Pairs) => format!("{}-pairs", k.name()),
            Rep::Scaled(k, CbvhMode::Patches) => format!("{}-scaled", k.name()),
            Rep::Scaled(k, CbvhMode::Pairs) => format!("{}-scaled-pairs", k.name()),
        }
    }

    /// The contact mode of a cbvh representation (`None` for parry's).
    pub fn cbvh_mode(self) -> Option<CbvhMode> {
        match self {
            Rep::Cbvh(_, m) | Rep::Scaled(_, m) => Some(m),
            _ => None,
        }
    }

    /// `mesh` as a collision shape of this representation (an error for
    /// [`Rep::Primitive`], which has no mesh).
    pub fn mesh_shape(self, mesh: &Mesh) -> Result<SharedShape, SlideError> {
        let trimesh_error = |e| SlideError::TriMesh(format!("{e:?}"));
        Ok(match self {
            Rep::Primitive => return Err(SlideError::NoPrimitive("a mesh".into())),
            Rep::TriMesh => SharedShape::new(parry_trimesh(mesh).map_err(trimesh_error)?),
            Rep::TriMeshFixed => SharedShape::new(
                TriMesh::with_flags(
                    mesh.vertices
                        .iter()
                        .map(|v| Vector::from_array(*v))
                        .collect(),
                    mesh.triangles.clone(),
                    TriMeshFlags::FIX_INTERNAL_EDGES,
                )
                .map_err(trimesh_error)?,
            ),
            Rep::Hull => {
                let points: Vec<Vector> = mesh
                    .vertices
                    .iter()
                    .map(|v| Vector::from_array(*v))
                    .collect();
                let hull = SharedShape::convex_hull(&points)
                    .ok_or_else(|| SlideError::TriMesh("no convex hull of the mesh".into()))?;
                // parry 0.31 merges the hull's near-coplanar triangles into
                // faces; on a finely tessellated sphere (an icosphere of 5 or
                // more subdivisions) it can end with no face at all, and its
                // contacts then index an empty face list and panic.
                if hull
                    .as_convex_polyhedron()
                    .is_some_and(|p| p.faces().is_empty())
                {
                    return Err(SlideError::TriMesh(format!(
                        "parry's convex hull of the mesh ({} vertices) has no faces",
                        points.len()
                    )));
                }
                hull
            }
            Rep::Cbvh(kind, _) => SharedShape::new(CbvhShape::build(
                mesh,
                &BuildOptions::default(),
                kind,
                &AnyOptions::default(),
            )?),
            Rep::Scaled(kind, _) => {
                let s = SCALED_BY;
                let unit = Mesh::new(
                    mesh.vertices
                        .iter()
                        .map(|v| [v[0] / s[0], v[1] / s[1], v[2] / s[2]])
                        .collect(),
                    mesh.triangles.clone(),
                );
                let shape = CbvhShape::build(
                    &unit,
                    &BuildOptions::default(),
                    kind,
                    &AnyOptions::default(),
                )?;
                SharedShape::new(
                    shape
                        .scaled(Vector::from_array(s))
                        .expect("SCALED_BY's factors are finite and non-zero"),
                )
            }
        })
    }
}

impl fmt::Display for Rep {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl FromStr for Rep {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        match s {
            "primitive" => return Ok(Rep::Primitive),
            "trimesh" => return Ok(Rep::TriMesh),
            "trimesh-fixed" => return Ok(Rep::TriMeshFixed),
            "hull" => return Ok(Rep::Hull),
            _ => {}
        }
        let (codec, mode) = match s.strip_suffix("-pairs") {
            Some(c) => (c, CbvhMode::Pairs),
            None => (s, CbvhMode::Patches),
        };
        let (codec, scaled) = match codec.strip_suffix("-scaled") {
            Some(c) => (c, true),
            None => (codec, false),
        };
        let kind: CodecKind = codec.parse().map_err(|e| {
            format!(
                "{e} (or primitive, trimesh, trimesh-fixed, hull; a codec may end in -scaled, \
                 then in -pairs)"
            )
        })?;
        Ok(if scaled {
            Rep::Scaled(kind, mode)
        } else {
            Rep::Cbvh(kind, mode)
        })
    }
}

/// The ground and body pairings the example runs for `codecs`: each
/// representation on itself (a primitive on a primitive, a `TriMesh` on a
/// `TriMesh`, a codec on the same codec in the same mode), a primitive
/// body on every mesh ground, and the body's convex hull on the primitive
/// ground (the faceted body's reference). `scaled` codecs also run as
/// [`Rep::Scaled`] shapes, in both modes. A scene skips the grounds it has
/// none of ([`Scene::has_ground`]).
pub fn pairings(codecs: &[CodecKind], scaled: &[CodecKind]) -> Vec<(Rep, Rep)> {
    let mut grounds = vec![Rep::TriMesh, Rep::TriMeshFixed];
    for &k in codecs {
        grounds.extend(CbvhMode::ALL.map(|m| Rep::Cbvh(k, m)));
    }
    for &k in scaled {
        grounds.extend(CbvhMode::ALL.map(|m| Rep::Scaled(k, m)));
    }
    let mut all = vec![
        (Rep::Primitive, Rep::Primitive),
        (Rep::Primitive, Rep::Hull),
    ];
    for g in grounds {
        all.push((g, g));
        all.push((g, Rep::Primitive));
    }
    all
}

/// What goes wrong setting a scene up.
#[derive(Debug, thiserror::Error)]
pub enum SlideError {
    /// The scene has no primitive for this shape.
    #[error("there is no primitive for {0}")]
    NoPrimitive(String),
    /// The ground and the body are cbvh shapes in different contact modes
    /// (the dispatcher has one).
    #[error("the ground ({ground}) and the body ({body}) ask for different contact modes")]
    ModeMismatch {
        /// The ground's representation.
        ground: String,
        /// The body's representation.
        body: String,
    },
    /// parry could not build a `TriMesh`.
    #[error("parry TriMesh: {0}")]
    TriMesh(String),
    /// A cbvh shape could not be built.
    #[error(transparent)]
    Cbvh(#[from] ShapeBuildError),
}

/// One scene: what it sets up, and the answer mechanics gives (see the
/// module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scene {
    /// A cube of side [`CUBE_SIDE`] resting on a ramp tilted by
    /// `angle_deg`, aligned with it, friction `friction` on both: its
    /// acceleration along the slope over [`FIT_WINDOW`] is
    /// `g (sin θ − μ cos θ)` if positive (within [`REL_TOLERANCE`], never
    /// uphill), else it stays (moves less than [`STAY_LIMIT`]).
    Slide {
        /// Ramp angle (degrees).
        angle_deg: f32,
        /// Friction of the cube and the ramp.
        friction: f32,
        /// Cells per side of the ramp mesh ([`ramp_mesh`]).
        cells: usize,
    },
    /// A sphere of radius [`SPHERE_RADIUS`] (an icosphere of
    /// `subdivisions`, or parry's ball) resting on a ramp: it rolls at
    /// `g sin θ / (1 + I/(m r²))` within [`REL_TOLERANCE`] and never moves
    /// uphill (it slides at `g (sin θ − μ cos θ)` if the friction cannot
    /// hold the rolling).
    ///
    /// That is a smooth sphere's answer. A rigid icosphere also loses a
    /// little energy each time a new facet lands (an inelastic impact,
    /// as a rolling polygon does), so it rolls slower by roughly its
    /// facets' angle: about 11 % at [`SPHERE_SUBDIVISIONS`] even with
    /// parry's exact convex contacts ([`Rep::Hull`]), a few percent at
    /// [`FINE_SPHERE_SUBDIVISIONS`].
    Roll {
        /// Ramp angle (degrees).
        angle_deg: f32,
        /// Friction of the sphere and the ramp.
        friction: f32,
        /// Cells per side of the ramp mesh.
        cells: usize,
        /// Subdivisions of the icosphere mesh ([`icosphere_mesh`]).
        subdivisions: u32,
    },
    /// A ball of radius [`BOWL_BALL_RADIUS`] released at rest inside a bowl
    /// of radius [`BOWL_RADIUS`] (no primitive ground), `release_deg` up its
    /// side, with linear and angular damping `damping`: after
    /// [`BOWL_SECONDS`] it is within [`BOWL_GOAL`] of the bowl's axis
    /// (whether it still moves is reported, not judged: on a faceted bowl
    /// a ball rocks a little).
    Bowl {
        /// Angle of the release point from the bottom, seen from the bowl's
        /// centre (degrees).
        release_deg: f32,
        /// The ball's linear and angular damping.
        damping: f32,
    },
    /// A cube dropped from [`DROP_GAP`] onto the flat ground's centre
    /// rests at half its side (within [`REST_TOLERANCE`]), not moving.
    Rest {
        /// Cells per side of the ground mesh.
        cells: usize,
    },
    /// `count` cubes stacked at the flat ground's centre, each resting on
    /// the one below: every cube stays within [`REST_TOLERANCE`] per cube
    /// below it of its height, drifts less than [`STAY_LIMIT`], and ends
    /// at rest.
    Stack {
        /// Number of cubes.
        count: usize,
        /// Cells per side of the ground mesh.
        cells: usize,
    },
    /// A cube resting on the flat ground by its edge at `x =`
    /// [`PLANE_SIZE`]` / 2`, its centre `overhang` sides past the edge:
    /// over the table (`overhang <= 0`) it stays (moves less than
    /// [`STAY_LIMIT`]); past it, it tips off (its centre ends below the
    /// table's top).
    TableEdge {
        /// How far the cube's centre is past the edge, in sides.
        overhang: f32,
        /// Cells per side of the ground mesh.
        cells: usize,
    },
    /// The rocking stone: a block of base [`CUBE_SIDE`] × [`CUBE_SIDE`]
    /// whose centre of mass is `height` dome radii above its flat base,
    /// balanced on a hemispherical dome of radius [`DOME_RADIUS`] (parry's
    /// ball, or [`dome_mesh`]), started rolled [`ROCK_START_DEG`] off the
    /// top, friction [`ROLL_FRICTION`]. Rolled by φ without slipping, the
    /// centre of mass sits `(h − R) φ` beyond the contact point, so the
    /// block rocks back when `h < R` (it swings back through upright and
    /// stays tilted less than [`ROCK_HOLD_DEG`]) and tips off when `h > R`
    /// (it ends tilted more than [`TIPPED_DEG`]), however finely the dome
    /// is tessellated.
    Rock {
        /// Height of the block's centre of mass above its base, in dome
        /// radii.
        height: f32,
    },
}

/// The moving body of a scene.
#[derive(Clone, Copy, Debug)]
enum Body {
    Cube,
    /// A sphere of this radius: parry's ball, or an icosphere mesh of these
    /// subdivisions.
    Sphere(f32, u32),
    /// A box of these half extents.
    Block(Vector),
}

impl Body {
    fn mesh(self) -> Mesh {
        match self {
            Body::Cube => cube_mesh(CUBE_SIDE),
            Body::Sphere(r, subdivisions) => icosphere_mesh(r, subdivisions),
            Body::Block(half) => box_mesh(half),
        }
    }

    fn shape(self, rep: Rep) -> Result<SharedShape, SlideError> {
        match (rep, self) {
            (Rep::Primitive, Body::Cube) => {
                let h = 0.5 * CUBE_SIDE;
                Ok(SharedShape::cuboid(h, h, h))
            }
            (Rep::Primitive, Body::Sphere(r, _)) => Ok(SharedShape::ball(r)),
            (Rep::Primitive, Body::Block(h)) => Ok(SharedShape::cuboid(h.x, h.y, h.z)),
            _ => rep.mesh_shape(&self.mesh()),
        }
    }

    /// How far the body, turned by `rotation`, reaches from its origin
    /// along the unit direction `dir`.
    fn reach(self, rep: Rep, rotation: Rotation, dir: Vector) -> f32 {
        if let (Rep::Primitive, Body::Sphere(r, _)) = (rep, self) {
            return r;
        }
        self.mesh()
            .vertices
            .iter()
            .map(|v| (rotation * Vector::from_array(*v)).dot(dir))
            .fold(f32::NEG_INFINITY, f32::max)
    }
}

/// The ground of a scene.
#[derive(Clone, Copy, Debug)]
enum Ground {
    Plane { angle_deg: f32, cells: usize },
    Bowl,
    Dome,
}

/// What a body did along a slope.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct SlopeMotion {
    /// Displacement of the centre of mass along the downhill direction at
    /// the end (m).
    pub travel: f32,
    /// Largest displacement against the downhill direction (m, ≥ 0).
    pub max_uphill: f32,
    /// Whether `max_uphill` exceeded [`UPHILL_LIMIT`].
    pub moved_uphill: bool,
    /// Largest drift across the slope (m, ≥ 0).
    pub max_sideways: f32,
    /// Largest rise along the ramp's normal (m, ≥ 0): a body that hops.
    pub max_lift: f32,
}

/// What one scene measured, against what it should have.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Report {
    /// The scene's name ([`Scene::name`]).
    pub scene: String,
    /// The ground's representation ([`Rep::name`]).
    pub ground: String,
    /// The body's representation.
    pub body: String,
    /// What `measured` and `expected` are, with the unit.
    pub quantity: String,
    /// The measured value.
    pub measured: f32,
    /// The value mechanics gives.
    pub expected: f32,
    /// `|measured − expected| / |expected|`, when the check is relative.
    pub rel_error: Option<f32>,
    /// The pass criterion, in words.
    pub criterion: String,
    /// Whether the run met the criterion.
    pub pass: bool,
    /// Largest distance of a body's centre of mass from where it started
    /// (m).
    pub max_travel: f32,
    /// A body's largest speed at the end (m/s).
    pub final_speed: f32,
    /// Whether `final_speed` exceeds [`MOVING_SPEED`].
    pub still_moving: bool,
    /// The motion along the slope (ramp scenes only).
    pub slope: Option<SlopeMotion>,
    /// Wall-clock time of the run, setup included (s).
    pub wall_seconds: f64,
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} on {} / {}: {} measured {:.4}, expected {:.4}",
            self.scene, self.ground, self.body, self.quantity, self.measured, self.expected
        )?;
        if let Some(e) = self.rel_error {
            write!(f, " ({:.1} %)", 100.0 * e)?;
        }
        write!(
            f,
            "; moved up to {:.4} m, final speed {:.4} m/s",
            self.max_travel, self.final_speed
        )?;
        if let Some(s) = &self.slope {
            write!(
                f,
                "; along slope {:.4} m, uphill {:.4} m, sideways {:.4} m, lift {:.4} m",
                s.travel, s.max_uphill, s.max_sideways, s.max_lift
            )?;
        }
        write!(
            f,
            " [{}: {}]",
            self.criterion,
            if self.pass { "PASS" } else { "FAIL" }
        )
    }
}

/// A body's centre of mass over a run: one sample before the first step,
/// then one after each.
#[derive(Clone, Debug, Default)]
struct Track {
    t: Vec<f32>,
    com: Vec<Vector>,
    vel: Vec<Vector>,
    /// The body's own `+y` axis in the world.
    up: Vec<Vector>,
}

impl Track {
    fn push(&mut self, t: f32, b: &RigidBody) {
        self.t.push(t);
        self.com.push(com_of(b));
        self.vel.push(b.linvel());
        self.up.push(*b.rotation() * Vector::Y);
    }

    /// Angles (degrees) between the body's `+y` axis and the world's.
    fn tilts(&self) -> impl Iterator<Item = f32> + '_ {
        self.up
            .iter()
            .map(|u| u.dot(Vector::Y).clamp(-1.0, 1.0).acos().to_degrees())
    }

    /// Largest distance from the first sample.
    fn max_travel(&self) -> f32 {
        self.com
            .iter()
            .map(|c| c.distance(self.com[0]))
            .fold(0.0, f32::max)
    }

    fn final_speed(&self) -> f32 {
        self.vel.last().map_or(0.0, |v| v.length())
    }
}

/// The world position of `b`'s centre of mass.
fn com_of(b: &RigidBody) -> Vector {
    b.position()
        .transform_point(b.mass_properties().local_mprops.local_com)
}

/// A world with the scene's gravity and a dispatcher in the contact mode of
/// the cbvh representation among `ground` and `body`.
pub(super) fn new_world(ground: Rep, body: Rep) -> Result<PhysicsWorld, SlideError> {
    let mode = match (ground.cbvh_mode(), body.cbvh_mode()) {
        (Some(a), Some(b)) if a != b => {
            return Err(SlideError::ModeMismatch {
                ground: ground.name(),
                body: body.name(),
            });
        }
        (Some(m), _) | (_, Some(m)) => m.contact_mode(),
        _ => ContactMode::default(),
    };
    let mut world = PhysicsWorld {
        gravity: Vector::new(0.0, -GRAVITY, 0.0),
        ..Default::default()
    };
    world.narrow_phase = NarrowPhase::with_query_dispatcher(Dispatcher::new(mode).then_default());
    Ok(world)
}

/// Adds the fixed ground of representation `rep`, with friction `friction`.
fn add_ground(
    world: &mut PhysicsWorld,
    ground: Ground,
    rep: Rep,
    friction: f32,
) -> Result<(), SlideError> {
    let collider = match (ground, rep) {
        (Ground::Plane { angle_deg, .. }, Rep::Primitive) => {
            let frame = SlopeFrame::new(angle_deg);
            let (h, t) = (0.5 * PLANE_SIZE, 0.5 * GROUND_THICKNESS);
            ColliderBuilder::cuboid(h, t, h)
                .position(Pose::from_parts(-frame.normal * t, frame.rotation))
        }
        (Ground::Plane { angle_deg, cells }, _) => {
            ColliderBuilder::new(rep.mesh_shape(&ramp_mesh(angle_deg, cells, PLANE_SIZE))?)
        }
        (Ground::Bowl, Rep::Primitive) => return Err(SlideError::NoPrimitive("a bowl".into())),
        (Ground::Bowl, _) => {
            ColliderBuilder::new(rep.mesh_shape(&bowl_mesh(BOWL_RADIUS, BOWL_SEGMENTS))?)
        }
        (Ground::Dome, Rep::Primitive) => ColliderBuilder::ball(DOME_RADIUS),
        (Ground::Dome, _) => {
            ColliderBuilder::new(rep.mesh_shape(&dome_mesh(DOME_RADIUS, DOME_SEGMENTS))?)
        }
    };
    let fixed = world.bodies.insert(RigidBodyBuilder::fixed());
    world
        .colliders
        .insert_with_parent(collider.friction(friction), fixed, &mut world.bodies);
    Ok(())
}

/// Adds a dynamic body of density 1 that cannot sleep, at rest at `pose`.
fn add_body(
    world: &mut PhysicsWorld,
    shape: SharedShape,
    pose: Pose,
    friction: f32,
    damping: f32,
) -> RigidBodyHandle {
    let handle = world.bodies.insert(
        RigidBodyBuilder::dynamic()
            .pose(pose)
            .linear_damping(damping)
            .angular_damping(damping)
            .can_sleep(false),
    );
    world.colliders.insert_with_parent(
        ColliderBuilder::new(shape).density(1.0).friction(friction),
        handle,
        &mut world.bodies,
    );
    handle
}

/// Steps `world` for `seconds` and tracks `bodies`; `trace` records the
/// first body's energy and contacts at every step.
fn simulate(
    world: &mut PhysicsWorld,
    bodies: &[RigidBodyHandle],
    seconds: f32,
    mut trace: Option<&mut Trace>,
) -> Vec<Track> {
    let dt = world.integration_parameters.dt;
    let steps = (seconds / dt).round() as usize;
    let mut tracks = vec![Track::default(); bodies.len()];
    for (track, h) in tracks.iter_mut().zip(bodies) {
        track.push(0.0, &world.bodies[*h]);
    }
    let y0 = bodies.first().map(|h| com_height(world, *h));
    for step in 1..=steps {
        world.step();
        let t = step as f32 * dt;
        for (track, h) in tracks.iter_mut().zip(bodies) {
            track.push(t, &world.bodies[*h]);
        }
        if let (Some(trace), Some(y0)) = (trace.as_deref_mut(), y0) {
            trace.record(world, bodies[0], t, y0, GRAVITY);
        }
    }
    tracks
}

/// The names of cells per side in scene names: `2tri` for one cell, else
/// `NxN`.
fn cells_name(cells: usize) -> String {
    match cells.max(1) {
        1 => "2tri".into(),
        n => format!("{n}x{n}"),
    }
}

/// The parts of a report a scene fills in.
struct Outcome {
    quantity: &'static str,
    measured: f32,
    expected: f32,
    relative: bool,
    criterion: String,
    pass: bool,
    max_travel: f32,
    final_speed: f32,
    slope: Option<SlopeMotion>,
}

impl Scene {
    /// A cube on a ramp of `cells` per side at `angle_deg`, friction
    /// [`DEFAULT_FRICTION`].
    pub fn slide(angle_deg: f32, cells: usize) -> Scene {
        Scene::Slide {
            angle_deg,
            friction: DEFAULT_FRICTION,
            cells,
        }
    }

    /// A sphere (an icosphere of [`SPHERE_SUBDIVISIONS`]) rolling down a
    /// ramp of `cells` per side at [`ROLL_ANGLE_DEG`], friction
    /// [`ROLL_FRICTION`].
    pub fn roll(cells: usize) -> Scene {
        Scene::roll_of(cells, SPHERE_SUBDIVISIONS)
    }

    /// [`Scene::roll`] with an icosphere of [`FINE_SPHERE_SUBDIVISIONS`]:
    /// facets fine enough for the smooth sphere's answer.
    pub fn fine_roll(cells: usize) -> Scene {
        Scene::roll_of(cells, FINE_SPHERE_SUBDIVISIONS)
    }

    /// [`Scene::roll`] with an icosphere of `subdivisions`.
    pub fn roll_of(cells: usize, subdivisions: u32) -> Scene {
        Scene::Roll {
            angle_deg: ROLL_ANGLE_DEG,
            friction: ROLL_FRICTION,
            cells,
            subdivisions,
        }
    }

    /// The ball in the bowl, released 20° up the side, damping 1.
    pub fn bowl() -> Scene {
        Scene::Bowl {
            release_deg: 20.0,
            damping: 1.0,
        }
    }

    /// The scenes the example runs: the slide at 20° (stays) and 40°
    /// (slides) and the roll, each on the 2-triangle and the 64 × 64 ramp;
    /// the bowl; the drop, a stack of 5 and the table edge both ways (a
    /// tenth of a side) on the 2-triangle ground.
    pub fn standard() -> Vec<Scene> {
        let mut all = Vec::new();
        for cells in [1, 64] {
            all.push(Scene::slide(20.0, cells));
            all.push(Scene::slide(40.0, cells));
        }
        all.extend([Scene::roll(1), Scene::roll(64)]);
        all.extend([Scene::fine_roll(1), Scene::fine_roll(64), Scene::bowl()]);
        all.extend([
            Scene::Rest { cells: 1 },
            Scene::Stack { count: 5, cells: 1 },
            Scene::TableEdge {
                overhang: -0.1,
                cells: 1,
            },
            Scene::TableEdge {
                overhang: 0.1,
                cells: 1,
            },
            Scene::Rock { height: 0.5 },
            Scene::Rock { height: 2.0 },
        ]);
        all
    }

    /// The name in reports: `slide-40deg-64x64`, `roll-15deg-2tri` (an
    /// icosphere of other than [`SPHERE_SUBDIVISIONS`] adds its
    /// subdivisions: `roll-15deg-2tri-ico6`),
    /// `bowl`, `rest-2tri`, `stack5-2tri`, `table-stays-2tri`,
    /// `table-tips-2tri`, `rock-0.5r`.
    pub fn name(&self) -> String {
        match *self {
            Scene::Slide {
                angle_deg, cells, ..
            } => format!("slide-{angle_deg}deg-{}", cells_name(cells)),
            Scene::Roll {
                angle_deg,
                cells,
                subdivisions,
                ..
            } => {
                let ico = if subdivisions == SPHERE_SUBDIVISIONS {
                    String::new()
                } else {
                    format!("-ico{subdivisions}")
                };
                format!("roll-{angle_deg}deg-{}{ico}", cells_name(cells))
            }
            Scene::Bowl { .. } => "bowl".into(),
            Scene::Rock { height } => format!("rock-{height}r"),
            Scene::Rest { cells } => format!("rest-{}", cells_name(cells)),
            Scene::Stack { count, cells } => format!("stack{count}-{}", cells_name(cells)),
            Scene::TableEdge { overhang, cells } => format!(
                "table-{}-{}",
                if overhang > 0.0 { "tips" } else { "stays" },
                cells_name(cells)
            ),
        }
    }

    /// Whether the scene has a ground of representation `rep` (every scene
    /// but the bowl has a primitive one).
    pub fn has_ground(&self, rep: Rep) -> bool {
        !matches!((self, rep), (Scene::Bowl { .. }, Rep::Primitive))
    }

    /// Runs the scene with the ground and the body(ies) represented as
    /// `ground` and `body` (two cbvh representations must share the
    /// contact mode).
    pub fn run(&self, ground: Rep, body: Rep) -> Result<Report, SlideError> {
        self.run_with(ground, body, None)
    }

    /// [`run`](Self::run), tracing the (first) moving body's energy and
    /// contacts at every step into `trace` (see [`super::trace`]).
    pub fn run_traced(
        &self,
        ground: Rep,
        body: Rep,
        trace: &mut Trace,
    ) -> Result<Report, SlideError> {
        self.run_with(ground, body, Some(trace))
    }

    fn run_with(
        &self,
        ground: Rep,
        body: Rep,
        trace: Option<&mut Trace>,
    ) -> Result<Report, SlideError> {
        let t0 = Instant::now();
        let mut world = new_world(ground, body)?;
        let o = match *self {
            Scene::Slide {
                angle_deg,
                friction,
                cells,
            } => slide(
                &mut world,
                angle_deg,
                friction,
                cells,
                (ground, body),
                trace,
            )?,
            Scene::Roll {
                angle_deg,
                friction,
                cells,
                subdivisions,
            } => roll(
                &mut world,
                angle_deg,
                friction,
                cells,
                Body::Sphere(SPHERE_RADIUS, subdivisions),
                (ground, body),
                trace,
            )?,
            Scene::Bowl {
                release_deg,
                damping,
            } => bowl(&mut world, release_deg, damping, (ground, body), trace)?,
            Scene::Rest { cells } => rest(&mut world, cells, (ground, body), trace)?,
            Scene::Stack { count, cells } => {
                stack(&mut world, count, cells, (ground, body), trace)?
            }
            Scene::TableEdge { overhang, cells } => {
                table_edge(&mut world, overhang, cells, (ground, body), trace)?
            }
            Scene::Rock { height } => rock(&mut world, height, (ground, body), trace)?,
        };
        let rel_error = o
            .relative
            .then(|| (o.measured - o.expected).abs() / o.expected.abs());
        Ok(Report {
            scene: self.name(),
            ground: ground.name(),
            body: body.name(),
            quantity: o.quantity.into(),
            measured: o.measured,
            expected: o.expected,
            rel_error,
            criterion: o.criterion,
            // A NaN measurement fails every comparison, hence `pass` too.
            pass: o.pass,
            max_travel: o.max_travel,
            final_speed: o.final_speed,
            still_moving: o.final_speed.is_nan() || o.final_speed > MOVING_SPEED,
            slope: o.slope,
            wall_seconds: t0.elapsed().as_secs_f64(),
        })
    }
}

/// A body placed resting on a ramp and let go for [`SLOPE_SECONDS`]: its
/// track, the ramp's frame, and the body's mass, inertia about the axis
/// across the slope, and the distance of its centre of mass from the ramp.
struct SlopeRun {
    track: Track,
    frame: SlopeFrame,
    mass: f32,
    inertia_across: f32,
    height: f32,
}

fn slope_run(
    world: &mut PhysicsWorld,
    body: Body,
    angle_deg: f32,
    friction: f32,
    cells: usize,
    (ground_rep, body_rep): (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<SlopeRun, SlideError> {
    add_ground(
        world,
        Ground::Plane { angle_deg, cells },
        ground_rep,
        friction,
    )?;
    let frame = SlopeFrame::new(angle_deg);
    let rotation = match body {
        Body::Cube | Body::Block(_) => frame.rotation,
        Body::Sphere(..) => Rotation::IDENTITY,
    };
    let reach = body.reach(body_rep, rotation, -frame.normal);
    let origin = frame.downhill * START_ALONG + frame.normal * reach;
    let shape = body.shape(body_rep)?;
    let h = add_body(
        world,
        shape,
        Pose::from_parts(origin, rotation),
        friction,
        0.0,
    );
    let b = &world.bodies[h];
    let mprops = b.mass_properties().local_mprops;
    let axis = rotation.inverse() * frame.across;
    let inertia_across = axis.dot(mprops.reconstruct_inertia_matrix() * axis);
    let (mass, height) = (b.mass(), com_of(b).dot(frame.normal));
    let track = simulate(world, &[h], SLOPE_SECONDS, trace).remove(0);
    Ok(SlopeRun {
        track,
        frame,
        mass,
        inertia_across,
        height,
    })
}

impl SlopeRun {
    /// The motion along the slope.
    fn motion(&self) -> SlopeMotion {
        let f = &self.frame;
        let rel: Vec<Vector> = self
            .track
            .com
            .iter()
            .map(|c| *c - self.track.com[0])
            .collect();
        let max_uphill = rel.iter().map(|d| -d.dot(f.downhill)).fold(0.0, f32::max);
        SlopeMotion {
            travel: rel.last().map_or(0.0, |d| d.dot(f.downhill)),
            max_uphill,
            moved_uphill: max_uphill.is_nan() || max_uphill > UPHILL_LIMIT,
            max_sideways: rel
                .iter()
                .map(|d| d.dot(f.across).abs())
                .fold(0.0, f32::max),
            max_lift: rel.iter().map(|d| d.dot(f.normal)).fold(0.0, f32::max),
        }
    }

    /// The fitted acceleration along the slope over [`FIT_WINDOW`].
    fn acceleration(&self) -> f32 {
        let (t, v): (Vec<f32>, Vec<f32>) = self
            .track
            .t
            .iter()
            .zip(&self.track.vel)
            .filter(|(t, _)| (FIT_WINDOW.0..=FIT_WINDOW.1).contains(*t))
            .map(|(t, v)| (*t, v.dot(self.frame.downhill)))
            .unzip();
        least_squares_slope(&t, &v)
    }

    /// The outcome against `expected`: within [`REL_TOLERANCE`] and never
    /// uphill if positive, else staying.
    fn outcome(&self, expected: f32) -> Outcome {
        let (measured, motion) = (self.acceleration(), self.motion());
        let max_travel = self.track.max_travel();
        let (relative, criterion, pass) = if expected > 0.0 {
            let within = (measured - expected).abs() <= REL_TOLERANCE * expected;
            (
                true,
                format!("within {} %, never uphill", (REL_TOLERANCE * 100.0).round()),
                within && !motion.moved_uphill,
            )
        } else {
            (
                false,
                format!("stays (moves < {} m)", STAY_LIMIT),
                max_travel < STAY_LIMIT,
            )
        };
        Outcome {
            quantity: "a along slope (m/s²)",
            measured,
            expected,
            relative,
            criterion,
            pass,
            max_travel,
            final_speed: self.track.final_speed(),
            slope: Some(motion),
        }
    }
}

fn slide(
    world: &mut PhysicsWorld,
    angle_deg: f32,
    friction: f32,
    cells: usize,
    reps: (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Outcome, SlideError> {
    let run = slope_run(world, Body::Cube, angle_deg, friction, cells, reps, trace)?;
    let (s, c) = angle_deg.to_radians().sin_cos();
    Ok(run.outcome((GRAVITY * (s - friction * c)).max(0.0)))
}

fn roll(
    world: &mut PhysicsWorld,
    angle_deg: f32,
    friction: f32,
    cells: usize,
    sphere: Body,
    reps: (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Outcome, SlideError> {
    let run = slope_run(world, sphere, angle_deg, friction, cells, reps, trace)?;
    let (s, c) = angle_deg.to_radians().sin_cos();
    // Rolling without slipping: m a = m g sin θ − F, F r = I a / r, so
    // a = g sin θ / (1 + k) with k = I / (m r²), and the friction force
    // F = m k a must stay within μ m g cos θ; beyond, it slides.
    let k = run.inertia_across / (run.mass * run.height * run.height);
    let rolling = GRAVITY * s / (1.0 + k);
    let expected = if k * rolling <= friction * GRAVITY * c {
        rolling
    } else {
        (GRAVITY * (s - friction * c)).max(0.0)
    };
    Ok(run.outcome(expected))
}

fn bowl(
    world: &mut PhysicsWorld,
    release_deg: f32,
    damping: f32,
    (ground, body): (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Outcome, SlideError> {
    add_ground(world, Ground::Bowl, ground, DEFAULT_FRICTION)?;
    let ball = Body::Sphere(BOWL_BALL_RADIUS, SPHERE_SUBDIVISIONS);
    let centre = Vector::new(0.0, BOWL_RADIUS, 0.0);
    let (s, c) = release_deg.to_radians().sin_cos();
    let out = Vector::new(s, -c, 0.0);
    let reach = ball.reach(body, Rotation::IDENTITY, out);
    let origin = centre + out * (bowl_inner_radius(BOWL_RADIUS, BOWL_SEGMENTS) - reach);
    let h = add_body(
        world,
        ball.shape(body)?,
        Pose::from_translation(origin),
        DEFAULT_FRICTION,
        damping,
    );
    let track = simulate(world, &[h], BOWL_SECONDS, trace).remove(0);
    let end = track.com.last().copied().unwrap_or(origin);
    let measured = end.x.hypot(end.z);
    let final_speed = track.final_speed();
    Ok(Outcome {
        quantity: "distance from axis (m)",
        measured,
        expected: 0.0,
        relative: false,
        criterion: format!("< {BOWL_GOAL} m"),
        pass: measured < BOWL_GOAL,
        max_travel: track.max_travel(),
        final_speed,
        slope: None,
    })
}

/// Adds `positions.len()` axis-aligned cubes (centres at `positions`) to a
/// world holding a flat ground of `cells` per side, and runs it for
/// [`REST_SECONDS`].
fn cubes_on_flat(
    world: &mut PhysicsWorld,
    cells: usize,
    positions: &[Vector],
    (ground, body): (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Vec<Track>, SlideError> {
    add_ground(
        world,
        Ground::Plane {
            angle_deg: 0.0,
            cells,
        },
        ground,
        DEFAULT_FRICTION,
    )?;
    let shape = Body::Cube.shape(body)?;
    let handles: Vec<RigidBodyHandle> = positions
        .iter()
        .map(|p| {
            add_body(
                world,
                shape.clone(),
                Pose::from_translation(*p),
                DEFAULT_FRICTION,
                0.0,
            )
        })
        .collect();
    Ok(simulate(world, &handles, REST_SECONDS, trace))
}

fn rest(
    world: &mut PhysicsWorld,
    cells: usize,
    reps: (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Outcome, SlideError> {
    let expected = 0.5 * CUBE_SIDE;
    let start = Vector::new(0.0, expected + DROP_GAP, 0.0);
    let track = cubes_on_flat(world, cells, &[start], reps, trace)?.remove(0);
    let measured = track.com.last().map_or(f32::NAN, |c| c.y);
    let final_speed = track.final_speed();
    Ok(Outcome {
        quantity: "rest height (m)",
        measured,
        expected,
        relative: true,
        criterion: format!("within {REST_TOLERANCE} m, at rest"),
        pass: (measured - expected).abs() <= REST_TOLERANCE && final_speed <= MOVING_SPEED,
        max_travel: track.max_travel(),
        final_speed,
        slope: None,
    })
}

fn stack(
    world: &mut PhysicsWorld,
    count: usize,
    cells: usize,
    reps: (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Outcome, SlideError> {
    let count = count.max(1);
    let height = |i: usize| (i as f32 + 0.5) * CUBE_SIDE;
    let starts: Vec<Vector> = (0..count)
        .map(|i| Vector::new(0.0, height(i), 0.0))
        .collect();
    let tracks = cubes_on_flat(world, cells, &starts, reps, trace)?;
    let ends: Vec<Vector> = tracks
        .iter()
        .map(|t| t.com.last().copied().unwrap_or(Vector::NAN))
        .collect();
    let heights_ok = ends
        .iter()
        .enumerate()
        .all(|(i, e)| (e.y - height(i)).abs() <= (i + 1) as f32 * REST_TOLERANCE);
    let drift = tracks
        .iter()
        .flat_map(|t| t.com.iter().map(|c| (*c - t.com[0]).with_y(0.0).length()))
        .fold(0.0, f32::max);
    let final_speed = tracks.iter().map(Track::final_speed).fold(0.0, f32::max);
    Ok(Outcome {
        quantity: "top cube height (m)",
        measured: ends[count - 1].y,
        expected: height(count - 1),
        relative: true,
        criterion: format!(
            "each within {REST_TOLERANCE} m per cube of its height, drift < {STAY_LIMIT} m, at rest"
        ),
        pass: heights_ok && drift < STAY_LIMIT && final_speed <= MOVING_SPEED,
        max_travel: tracks.iter().map(Track::max_travel).fold(0.0, f32::max),
        final_speed,
        slope: None,
    })
}

fn table_edge(
    world: &mut PhysicsWorld,
    overhang: f32,
    cells: usize,
    reps: (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Outcome, SlideError> {
    let start = Vector::new(
        0.5 * PLANE_SIZE + overhang * CUBE_SIDE,
        0.5 * CUBE_SIDE,
        0.0,
    );
    let track = cubes_on_flat(world, cells, &[start], reps, trace)?.remove(0);
    let max_travel = track.max_travel();
    let final_speed = track.final_speed();
    Ok(if overhang > 0.0 {
        let measured = track.com.last().map_or(f32::NAN, |c| c.y);
        Outcome {
            quantity: "final height (m)",
            measured,
            expected: 0.0,
            relative: false,
            criterion: "tips off (ends below the table's top)".into(),
            pass: measured < 0.0,
            max_travel,
            final_speed,
            slope: None,
        }
    } else {
        Outcome {
            quantity: "largest move (m)",
            measured: max_travel,
            expected: 0.0,
            relative: false,
            criterion: format!("stays (moves < {STAY_LIMIT} m)"),
            pass: max_travel < STAY_LIMIT,
            max_travel,
            final_speed,
            slope: None,
        }
    })
}

fn rock(
    world: &mut PhysicsWorld,
    height: f32,
    (ground, body): (Rep, Rep),
    trace: Option<&mut Trace>,
) -> Result<Outcome, SlideError> {
    add_ground(world, Ground::Dome, ground, ROLL_FRICTION)?;
    let r = DOME_RADIUS;
    let half = Vector::new(0.5 * CUBE_SIDE, height * r, 0.5 * CUBE_SIDE);
    let block = Body::Block(half);
    // Rolled by φ without slipping from the top: the contact is at angle φ
    // on the dome, the base's centre R φ back along the base from it.
    let phi = ROCK_START_DEG.to_radians();
    let (s, c) = phi.sin_cos();
    let (normal, tangent) = (Vector::new(s, c, 0.0), Vector::new(c, -s, 0.0));
    let base_centre = normal * r - tangent * (r * phi);
    let rotation = Rotation::from_rotation_z(-phi);
    let h = add_body(
        world,
        block.shape(body)?,
        Pose::from_parts(base_centre + normal * half.y, rotation),
        ROLL_FRICTION,
        0.0,
    );
    let track = simulate(world, &[h], ROCK_SECONDS, trace).remove(0);
    let max_tilt = track.tilts().fold(0.0, f32::max);
    let final_tilt = track.tilts().last().unwrap_or(f32::NAN);
    let (max_travel, final_speed) = (track.max_travel(), track.final_speed());
    Ok(if height < 1.0 {
        // rapier's integrator adds a little energy to rocking (parry's own
        // cuboid on its ball swings from 8° to 13° in 4 s), so "rocks back"
        // is: it swings back through upright and stays well short of
        // running off its base (at R φ = half its width, 28.6°).
        let rocked_back = track.up.iter().any(|u| u.x * track.up[0].x < 0.0);
        Outcome {
            quantity: "largest tilt (deg)",
            measured: max_tilt,
            expected: ROCK_START_DEG,
            relative: false,
            criterion: format!("rocks back through upright, tilt < {ROCK_HOLD_DEG} deg"),
            pass: rocked_back && max_tilt < ROCK_HOLD_DEG,
            max_travel,
            final_speed,
            slope: None,
        }
    } else {
        Outcome {
            quantity: "final tilt (deg)",
            measured: final_tilt,
            expected: 90.0,
            relative: false,
            criterion: format!("tips off (ends tilted > {TIPPED_DEG} deg)"),
            pass: final_tilt > TIPPED_DEG,
            max_travel,
            final_speed,
            slope: None,
        }
    })
}
