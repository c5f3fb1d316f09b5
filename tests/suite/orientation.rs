//! Oriented contacts as properties over random poses (see
//! `cbvh::contact::orient`):
//!
//! - between two closed meshes, no manifold's normal points into either
//!   mesh's solid at its triangle: some triangle around it (it, or one
//!   sharing a corner with it) faces along the normal, to within the 6°
//!   the rule lets a normal lean past a face's plane at an active edge (a
//!   box tilting on the ground meets it along its side faces' edges; see
//!   `cbvh::contact::orient`), and in the patch mode the patch angle on
//!   top (a patch's normal is its first member's, and the others' lie
//!   within that angle of it);
//! - in both modes, no two manifolds push one point both ways (normals
//!   within 25° of opposite, at the same contact point: the two manifolds
//!   of the old contacts on a 2-triangle ramp, or of two triangles sharing
//!   an edge whose pairs each leaned over their own active edge, statue in
//!   statue, before the per-pair mode had the guard); a thin part squeezed from both sides
//!   has contacts millimetres apart with opposite normals, rightly, and
//!   so does a triangle straddling it;
//! - against a flat tessellated plane, every normal is the plane's own
//!   (within the flat angle of the edge flags), however a body meets the
//!   internal edges between the plane's triangles, and the same poses with
//!   every edge marked active do produce normals off the plane (the check
//!   can fail).
//!
//! Both contact modes, two codecs.

use cbvh::build::{BuildOptions, build};
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind};
use cbvh::contact::EdgeFlags;
use cbvh::mesh::Mesh;
use cbvh::parry::{CbvhShape, ContactMode, Dispatcher};
use cbvh::scene::{Kind, generate};
use cbvh::sim::slide::{box_mesh, icosphere_mesh, ramp_mesh};
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::query::{ContactManifold, PersistentQueryDispatcher};
use parry3d::shape::Shape;
use proptest::prelude::*;

const MODES: [ContactMode; 2] = [
    ContactMode::Patches(cbvh::contact::PatchOptions {
        max_angle_deg: 5.0,
        gap_fraction: 0.1,
        motion_factor: None,
    }),
    ContactMode::PerTrianglePair,
];

fn shape(mesh: &Mesh, kind: CodecKind) -> CbvhShape {
    CbvhShape::build(mesh, &BuildOptions::default(), kind, &AnyOptions::default())
        .expect("small meshes build")
}

fn manifolds(
    mode: ContactMode,
    pos12: &Pose,
    g1: &dyn Shape,
    g2: &dyn Shape,
) -> Vec<ContactManifold<(), ()>> {
    let mut ms = Vec::new();
    Dispatcher::new(mode)
        .then_default()
        .contact_manifolds(pos12, g1, g2, 0.02, &mut ms, &mut None)
        .expect("cbvh pairs are supported");
    ms.retain(|m| !m.points.is_empty());
    ms
}

/// A closed mesh's triangles around each of its triangles (those sharing
/// a corner with it, itself included), by the ids its codec gives them,
/// and every triangle's unit face normal, wound as stored, times
/// `outward`.
struct Around {
    ids: Vec<Vec<u32>>,
    normals: Vec<Vector>,
}

impl Around {
    fn of(s: &CbvhShape) -> Self {
        let n = s.triangle_count();
        let outward = s.edge_flags().outward();
        let tris: Vec<[Vector; 3]> = (0..n as u32)
            .map(|i| {
                let t = s.parry_triangle(i);
                [t.a, t.b, t.c]
            })
            .collect();
        let key = |v: Vector| (v.x.to_bits(), v.y.to_bits(), v.z.to_bits());
        let mut at_corner: std::collections::HashMap<_, Vec<u32>> = Default::default();
        for (i, t) in tris.iter().enumerate() {
            for v in t {
                at_corner.entry(key(*v)).or_default().push(i as u32);
            }
        }
        let ids = tris
            .iter()
            .map(|t| {
                let mut ids: Vec<u32> =
                    t.iter().flat_map(|v| at_corner[&key(*v)].clone()).collect();
                ids.sort_unstable();
                ids.dedup();
                ids
            })
            .collect();
        let normals = tris
            .iter()
            .map(|[a, b, c]| (*b - *a).cross(*c - *a).normalize_or_zero() * outward)
            .collect();
        Self { ids, normals }
    }

    /// The face normals around triangle `t`.
    fn normals_around(&self, t: u32) -> Vec<Vector> {
        self.ids[t as usize]
            .iter()
            .map(|k| self.normals[*k as usize])
            .collect()
    }
}

/// The largest `n · f` over the neighbourhood's face normals: negative
/// when `n` points into the solid at every triangle around.
fn facing(normals: &[Vector], n: Vector) -> f32 {
    normals
        .iter()
        .map(|f| f.dot(n))
        .fold(f32::NEG_INFINITY, f32::max)
}

/// Two manifolds whose normals are within 25° of opposite and that lie in
/// one region: on the same or neighbouring triangles of either shape
/// (`near1`, `near2`), or with contact points (on shape 1) within `gap` of
/// each other. That region is given to the solver as pushed both ways.
fn opposed_in_one_region(
    ms: &[ContactManifold<(), ()>],
    near1: impl Fn(u32, u32) -> bool,
    near2: impl Fn(u32, u32) -> bool,
    gap: f32,
) -> Option<(usize, usize)> {
    let close = |a: &ContactManifold<(), ()>, b: &ContactManifold<(), ()>| {
        a.points.iter().any(|p| {
            b.points
                .iter()
                .any(|q| (p.local_p1 - q.local_p1).length() <= gap)
        })
    };
    for i in 0..ms.len() {
        for j in i + 1..ms.len() {
            let (a, b) = (&ms[i], &ms[j]);
            let opposed = a.local_n1.dot(b.local_n1) < -(25f32.to_radians().cos());
            let region =
                near1(a.subshape1, b.subshape1) || near2(a.subshape2, b.subshape2) || close(a, b);
            if opposed && region {
                return Some((i, j));
            }
        }
    }
    None
}

fn pose(t: [f32; 3], r: [f32; 3]) -> Pose {
    Pose::from_parts(
        Vector::from_array(t),
        Rotation::from_euler(glam::EulerRot::XYZ, r[0], r[1], r[2]),
    )
}

struct Closed {
    name: &'static str,
    shapes: Vec<(CbvhShape, Around)>,
}

/// The closed meshes of the first property, in the plain and hcc codecs.
fn closed_meshes() -> Vec<Closed> {
    let statue = generate(Kind::Statue, 3000, 3, &mut |_, _| {}).expect("generates");
    let (lo, hi) = statue.bounds().expect("a statue has vertices");
    let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0f32, f32::max);
    let centre: Vec<f32> = (0..3).map(|k| 0.5 * (lo[k] + hi[k])).collect();
    let statue = Mesh::new(
        statue
            .vertices
            .iter()
            .map(|v| std::array::from_fn(|k| (v[k] - centre[k]) / size))
            .collect(),
        statue.triangles.clone(),
    );
    let meshes = [
        ("cube", box_mesh(Vector::new(0.4, 0.3, 0.5))),
        ("icosphere", icosphere_mesh(0.5, 2)),
        ("statue", statue),
    ];
    meshes
        .into_iter()
        .map(|(name, m)| Closed {
            name,
            shapes: [CodecKind::Plain, CodecKind::Hcc]
                .into_iter()
                .map(|k| {
                    let s = shape(&m, k);
                    assert!(s.edge_flags().is_closed(), "{name} is closed");
                    let n = Around::of(&s);
                    (s, n)
                })
                .collect(),
        })
        .collect()
}

/// One pose of the property below: shape `a` and shape `b` of
/// [`closed_meshes`] in codec `codec` and mode `MODES[mode]`, shape 2 at
/// `dist` along `dir`, rotated by the Euler angles `rot`.
#[allow(clippy::too_many_arguments)]
fn check_pose(
    meshes: &[Closed],
    a: usize,
    b: usize,
    codec: usize,
    mode: usize,
    dir: (f32, f32, f32),
    dist: f32,
    rot: (f32, f32, f32),
) -> Result<(), TestCaseError> {
    let (s1, n1) = &meshes[a].shapes[codec];
    let (s2, n2) = &meshes[b].shapes[codec];
    let d = Vector::new(dir.0, dir.1, dir.2).normalize_or(Vector::X) * dist;
    let pos12 = pose(d.to_array(), [rot.0, rot.1, rot.2]);
    let ms = manifolds(MODES[mode], &pos12, s1, s2);
    if let Some((i, j)) = opposed_in_one_region(&ms, |_, _| false, |_, _| false, 1e-6) {
        prop_assert!(
            false,
            "{} vs {} ({:?}, {}): manifolds {i} and {j} oppose each other in one \
             region:\n  {:?} on {}/{} at {:?}\n  {:?} on {}/{} at {:?}",
            meshes[a].name,
            meshes[b].name,
            MODES[mode].name(),
            codec,
            ms[i].local_n1,
            ms[i].subshape1,
            ms[i].subshape2,
            ms[i]
                .points
                .iter()
                .map(|p| (p.local_p1, p.dist))
                .collect::<Vec<_>>(),
            ms[j].local_n1,
            ms[j].subshape1,
            ms[j].subshape2,
            ms[j]
                .points
                .iter()
                .map(|p| (p.local_p1, p.dist))
                .collect::<Vec<_>>()
        );
    }
    // The rule lets a normal lean up to about 96° from a face at an active
    // edge; a patch's normal is one member's, within the patch angle of the
    // others'.
    let limit = match MODES[mode] {
        ContactMode::Patches(o) => (96.0 + o.max_angle_deg).to_radians().cos(),
        _ => 96f32.to_radians().cos(),
    };
    for m in ms {
        let f1 = facing(&n1.normals_around(m.subshape1), m.local_n1);
        let f2 = facing(&n2.normals_around(m.subshape2), m.local_n2);
        prop_assert!(
            f1 >= limit && f2 >= limit,
            "{} vs {} ({:?}, {}): normal {:?} / {:?} into the surface \
             (best facing {f1:.3} on triangle {}, {f2:.3} on triangle {})",
            meshes[a].name,
            meshes[b].name,
            MODES[mode].name(),
            codec,
            m.local_n1,
            m.local_n2,
            m.subshape1,
            m.subshape2
        );
    }
    Ok(())
}

thread_local! {
    static MESHES: Vec<Closed> = closed_meshes();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// No normal points into either closed mesh's solid at its triangle,
    /// for overlapping, touching and nearly touching random poses.
    #[test]
    fn no_normal_points_into_a_closed_mesh(
        a in 0usize..3,
        b in 0usize..3,
        codec in 0usize..2,
        mode in 0usize..2,
        dir in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        dist in 0.3f32..1.0,
        rot in (-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2),
    ) {
        MESHES.with(|meshes| check_pose(meshes, a, b, codec, mode, dir, dist, rot))?;
    }
}

/// Poses the property once failed on, every run.
#[test]
fn poses_the_property_once_failed_on() {
    // Cube on statue, per pair: the cube's inactive bottom diagonal met an
    // active edge of the statue, and the snap to the cube's face normal
    // leaned 97° from the statue's triangle, into it.
    let cube_on_statue = (0, 2, 0, 1, (0.7750133, -0.6043468, 0.0), 0.3);
    let rot = (-2.811283, -1.4557664, -2.3132844);
    // Statue in statue, per pair: two triangles sharing an edge, each
    // pair's axis over its own active edge, opposite normals at one corner
    // (a few float steps apart).
    let statue_in_statue = (2, 2, 0, 1, (0.11689708, 0.010077395, 0.5285613), 0.4468842);
    let rot2 = (-0.9476531, 2.7519922, 2.5792544);
    let statue_edge = (2, 2, 0, 1, (-0.28848684, 0.0, -0.3741245), 0.3);
    let rot3 = (3.148102, 0.8174471, 1.9532281);
    MESHES.with(|meshes| {
        for ((a, b, codec, mode, dir, dist), rot) in [
            (cube_on_statue, rot),
            (statue_in_statue, rot2),
            (statue_edge, rot3),
        ] {
            if let Err(e) = check_pose(meshes, a, b, codec, mode, dir, dist, rot) {
                panic!("{e}");
            }
        }
    });
}

/// A small deterministic generator (the poses of the plane test).
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}

/// Over `poses` random poses of `body` touching the plane (its lowest
/// corner from 5 mm above to 2 cm below it, its centre far from the
/// plane's rim), the largest angle in degrees between a manifold's normal
/// out of the plane and the plane's normal, and how many manifolds there
/// were.
fn worst_angle_on_plane(plane: &CbvhShape, body: &CbvhShape, mode: ContactMode) -> (f32, usize) {
    let mut rng = Lcg(7);
    let (mut worst, mut count) = (0.0f32, 0);
    for _ in 0..150 {
        let rot = Rotation::from_euler(
            glam::EulerRot::XYZ,
            rng.range(-3.2, 3.2),
            rng.range(-3.2, 3.2),
            rng.range(-3.2, 3.2),
        );
        let low = (0..body.triangle_count() as u32)
            .flat_map(|i| {
                let t = body.parry_triangle(i);
                [t.a, t.b, t.c]
            })
            .map(|v| (rot * v).y)
            .fold(f32::INFINITY, f32::min);
        let depth = rng.range(-0.005, 0.02);
        let at = Vector::new(rng.range(-1.0, 1.0), -low - depth, rng.range(-1.0, 1.0));
        let pos12 = Pose::from_parts(at, rot);
        for m in manifolds(mode, &pos12, plane, body) {
            count += 1;
            let cos = m.local_n1.dot(Vector::Y).clamp(-1.0, 1.0);
            worst = worst.max(cos.acos().to_degrees());
        }
    }
    (worst, count)
}

/// Internal edges of a flat tessellated plane give the plane's normal; with
/// every edge active they do not (so the check can fail).
#[test]
fn internal_edges_of_a_flat_plane_give_the_plane_normal() {
    // A 4 × 4 plane of 16 × 16 cells (cells of 0.25), wound upward.
    let plane_mesh = ramp_mesh(0.0, 16, 4.0);
    let bodies = [
        ("cube", box_mesh(Vector::new(0.3, 0.2, 0.35))),
        ("icosphere", icosphere_mesh(0.4, 2)),
    ];
    for kind in [CodecKind::Plain, CodecKind::Hcc] {
        let plane = shape(&plane_mesh, kind);
        let bvh = build(&plane_mesh, &BuildOptions::default(), &|_, _| {}).expect("builds");
        let codec =
            AnyCodec::encode(kind, &bvh, &plane_mesh, &AnyOptions::default()).expect("encodes");
        let all_active =
            CbvhShape::with_edges(codec, EdgeFlags::all_active(plane_mesh.triangles.len()));
        for (name, m) in &bodies {
            let body = shape(m, kind);
            for mode in MODES {
                let (worst, count) = worst_angle_on_plane(&plane, &body, mode);
                println!(
                    "{kind} {name} {}: {count} manifolds, worst {worst:.3} deg",
                    mode.name()
                );
                assert!(count > 100, "{kind} {name} {}: few contacts", mode.name());
                assert!(
                    worst <= 5.01,
                    "{kind} {name} {}: a normal {worst:.2} deg off the plane",
                    mode.name()
                );
            }
        }
        // The same poses with every edge active: the cube's corners and
        // edges catch on the plane's internal edges.
        let body = shape(&bodies[0].1, kind);
        let (worst, _) = worst_angle_on_plane(&all_active, &body, MODES[1]);
        println!("{kind} cube on the all-active plane: worst {worst:.3} deg");
        assert!(
            worst > 10.0,
            "{kind}: all-active edges should give off-plane normals ({worst:.2} deg)"
        );
    }
}

/// The region check of the first property finds the two manifolds of the
/// old contacts on a 2-triangle ramp (the ramp's normal and its opposite
/// at the same points, on the same triangles), and passes manifolds that
/// push apart at two separate places (a body wedged between two walls, or
/// a thin plate squeezed from both sides).
#[test]
fn opposed_manifolds_in_one_region_are_found() {
    use parry3d::query::TrackedContact;
    use parry3d::shape::PackedFeatureId;
    let manifold = |n: Vector, tri: u32, points: &[Vector]| {
        let mut m = ContactManifold::<(), ()>::new();
        m.local_n1 = n;
        m.local_n2 = -n;
        m.subshape1 = tri;
        m.subshape2 = tri;
        let id = PackedFeatureId::UNKNOWN;
        m.points = points
            .iter()
            .map(|&p| TrackedContact::new(p, p, id, id, 0.0))
            .collect();
        m
    };
    let square = |y: f32, x: f32| {
        [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)].map(|(a, b)| Vector::new(x + a, y, b))
    };
    let same = |t: u32, u: u32| t == u;
    let up = manifold(Vector::Y, 0, &square(0.0, 0.0));
    // The ramp's two manifolds: same triangles, same points.
    let down = manifold(Vector::NEG_Y, 0, &square(0.0, 0.0));
    assert_eq!(
        opposed_in_one_region(&[up.clone(), down], same, same, 1e-6),
        Some((0, 1))
    );
    // Other triangles, but the same place.
    let down = manifold(Vector::NEG_Y, 7, &square(0.0, 0.0)[1..]);
    assert_eq!(
        opposed_in_one_region(&[up.clone(), down], same, same, 1e-6),
        Some((0, 1))
    );
    // A wall elsewhere, and a plate's other side 1 cm below.
    let wall = manifold(Vector::NEG_Y, 3, &square(0.0, 2.0));
    let under = manifold(Vector::NEG_Y, 4, &square(-0.01, 0.0));
    assert_eq!(
        opposed_in_one_region(&[up.clone(), wall, under], same, same, 1e-6),
        None
    );
    let along = manifold(Vector::Y, 0, &square(0.0, 0.0));
    assert_eq!(opposed_in_one_region(&[up, along], same, same, 1e-6), None);
}
