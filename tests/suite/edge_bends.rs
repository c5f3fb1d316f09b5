//! Bends: surfaces folded along one edge by 3°, 10°, 30° and 60°, convex
//! (a ridge) and concave (a valley), and what every codec makes of them.
//!
//! - The flags (`cbvh::contact::EdgeFlags`'s docs): an edge whose two triangles are
//!   within the flat angle (`EdgeFlags::DEFAULT_FLAT_DEG`, 5°) of each
//!   other is inactive from both sides; a sharper one is active from the
//!   side it is convex from and inactive from the side it is concave from.
//!   Each codec stores its own flags; they are read through
//!   [`CbvhShape::edge_flags_of`], on the shape as built and on the shape
//!   of the codec's file read back, for open two-triangle folds (wound up
//!   and wound down) and closed folded prisms.

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::racbvh::RacOptions;
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind, OpenOptions};
use cbvh::parry::CbvhShape;
use parry3d::math::Vector;

/// The bends under test (degrees).
const BENDS: [f32; 4] = [3.0, 10.0, 30.0, 60.0];

/// The flat angle the docs promise (`EdgeFlags::DEFAULT_FLAT_DEG`, 5°,
/// Jolt's default), written out rather than read from the constant, so
/// that a changed threshold fails here.
const DOCUMENTED_FLAT_DEG: f32 = 5.0;

/// Which way the second half of a fold turns, seen from above (the side
/// the floor's top faces, or the solid's outside).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Fold {
    /// Down: a ridge, convex from above.
    Convex,
    /// Up: a valley, concave from above.
    Concave,
}

impl Fold {
    const ALL: [Fold; 2] = [Fold::Convex, Fold::Concave];

    /// The sign of the second half's rise along `+x`.
    fn rise(self) -> f32 {
        match self {
            Fold::Convex => -1.0,
            Fold::Concave => 1.0,
        }
    }
}

/// Every codec's options, RACBVH with clusters of 256 nodes.
fn options() -> AnyOptions {
    AnyOptions {
        racbvh: RacOptions {
            cluster_nodes: 256,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn shape(mesh: &Mesh, kind: CodecKind) -> CbvhShape {
    CbvhShape::build(mesh, &BuildOptions::default(), kind, &options())
        .unwrap_or_else(|e| panic!("{kind}: {e}"))
}

/// The shape of `s`'s codec written to bytes and read back (the flags
/// then come from the file's section).
fn reopened(s: &CbvhShape) -> CbvhShape {
    let kind = s.codec().kind();
    let bytes = s.codec().to_bytes();
    let codec = AnyCodec::from_bytes(kind, &bytes, &OpenOptions::default())
        .unwrap_or_else(|e| panic!("{kind}: {e}"));
    CbvhShape::new(codec)
}

/// The floor's profile point at `x` along the fold: `(x, 0)` before the
/// crease (`x ≤ 0`), then `x` along the bent half.
fn bent(x: f32, bend_deg: f32, fold: Fold) -> [f32; 2] {
    if x <= 0.0 {
        return [x, 0.0];
    }
    let (s, c) = bend_deg.to_radians().sin_cos();
    [x * c, fold.rise() * x * s]
}

/// Two triangles sharing the edge from `(0, 0, -1)` to `(0, 0, 1)`: one
/// in the plane `y = 0` on `x < 0`, the other bent `bend_deg` down (convex)
/// or up (concave) on `x > 0`; wound counter-clockwise seen from above,
/// or from below when `wound_down`.
fn two_triangles(bend_deg: f32, fold: Fold, wound_down: bool) -> Mesh {
    let [dx, dy] = bent(1.0, bend_deg, fold);
    let vertices = vec![
        [0.0, 0.0, -1.0],
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [dx, dy, 0.0],
    ];
    let mut triangles = vec![[0, 2, 1], [0, 1, 3]];
    if wound_down {
        triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    Mesh::new(vertices, triangles)
}

/// A closed prism whose top is the fold: the profile `(-1, 0)`, the
/// crease `(0, 0)`, the bent end one unit along, straight down to
/// `y = -2`, back along the bottom; extruded over `z ∈ [-1, 1]`, wound
/// outward. Its top crease runs from `(0, 0, -1)` to `(0, 0, 1)`.
fn folded_prism(bend_deg: f32, fold: Fold) -> Mesh {
    let end = bent(1.0, bend_deg, fold);
    // Counter-clockwise in the xy-plane: the interior on the left.
    let profile = [[-1.0, 0.0], [-1.0, -2.0], [end[0], -2.0], end, [0.0, 0.0]];
    let n = profile.len() as u32;
    let mut vertices = Vec::new();
    for z in [-1.0f32, 1.0] {
        vertices.extend(profile.iter().map(|p| [p[0], p[1], z]));
    }
    let (back, front) = (|i: u32| i % n, |i: u32| n + i % n);
    let mut triangles = Vec::new();
    // The sides: a quad per profile edge, its outward normal the edge's
    // right-hand one (counter-clockwise profile).
    for i in 0..n {
        let (a, b, c, d) = (back(i), back(i + 1), front(i + 1), front(i));
        triangles.extend([[a, b, c], [a, c, d]]);
    }
    // The caps: fans from the crease (vertex 4), which sees every other
    // corner of the profile (its one reflex corner when folded up).
    for i in 0..n - 2 {
        let (p, q) = (i, i + 1);
        triangles.push([front(4), front(p), front(q)]);
        triangles.push([back(4), back(q), back(p)]);
    }
    Mesh::new(vertices, triangles)
}

fn sub(a: Vector, b: Vector) -> Vector {
    a - b
}

/// The edges of `s`'s triangles (by the codec's ids and corners) that
/// join points within 0.05 of `p` and `q`, either way round.
fn edges_between(s: &CbvhShape, p: Vector, q: Vector) -> Vec<(u32, usize)> {
    let near = |a: Vector, b: Vector| sub(a, b).length() < 0.05;
    let mut out = Vec::new();
    for id in 0..s.triangle_count() as u32 {
        let t = s.parry_triangle(id);
        let v = [t.a, t.b, t.c];
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            if (near(a, p) && near(b, q)) || (near(a, q) && near(b, p)) {
                out.push((id, k));
            }
        }
    }
    out
}

/// The flags the docs promise for edge `k` of triangle `id` of `s`, a
/// crease edge that is convex seen from above when `convex_from_above`:
/// `(front, back)` active.
fn promised(s: &CbvhShape, id: u32, bend_deg: f32, convex_from_above: bool) -> (bool, bool) {
    if bend_deg < DOCUMENTED_FLAT_DEG {
        return (false, false);
    }
    let t = s.parry_triangle(id);
    let front_is_above = sub(t.b, t.a).cross(sub(t.c, t.a)).y > 0.0;
    let convex_from_front = convex_from_above == front_is_above;
    (convex_from_front, !convex_from_front)
}

/// `(front, back)` activity of edge `k` in the flags byte `f`.
fn activity(f: u8, k: usize) -> (bool, bool) {
    (f & (1 << k) != 0, f & (8 << k) != 0)
}

/// Asserts the crease's flags on `s` (and on its codec's file read back)
/// and, for an open fold, that every other edge is a boundary: active from
/// both sides.
fn check_crease(s: &CbvhShape, what: &str, bend_deg: f32, fold: Fold, closed: bool) {
    let kind = s.codec().kind();
    let at = format!("{kind}, {what}, {fold:?} {bend_deg}°");
    assert_eq!(s.edge_flags().is_closed(), closed, "{at}: closed");
    let (p, q) = (Vector::new(0.0, 0.0, -1.0), Vector::new(0.0, 0.0, 1.0));
    let crease = edges_between(s, p, q);
    assert_eq!(crease.len(), 2, "{at}: the crease has two triangles");
    let file = reopened(s);
    for &(id, k) in &crease {
        let want = promised(s, id, bend_deg, fold == Fold::Convex);
        let got = activity(s.edge_flags_of(id), k);
        assert_eq!(
            got,
            want,
            "{at}: triangle {id} edge {k} (front, back) active; flags {:#08b}",
            s.edge_flags_of(id)
        );
        assert_eq!(
            activity(file.edge_flags_of(id), k),
            want,
            "{at}: triangle {id} edge {k} as read from the codec's file"
        );
    }
    if !closed {
        for (id, k) in (0..s.triangle_count() as u32).flat_map(|id| (0..3).map(move |k| (id, k))) {
            if !crease.contains(&(id, k)) {
                assert_eq!(
                    activity(s.edge_flags_of(id), k),
                    (true, true),
                    "{at}: boundary edge {k} of triangle {id}"
                );
            }
        }
    }
    let flat = u64::from(bend_deg < DOCUMENTED_FLAT_DEG);
    if !closed {
        assert_eq!(s.edge_flags().flat_edges, flat, "{at}: flat edges");
    }
}

/// Every codec gives the crease of a two-triangle fold, wound either way,
/// the activity the flag docs promise: none within the flat angle, else
/// active from the convex side only.
#[test]
fn two_triangle_folds_flag_the_crease_as_documented() {
    for bend in BENDS {
        for fold in Fold::ALL {
            for wound_down in [false, true] {
                let mesh = two_triangles(bend, fold, wound_down);
                let what = if wound_down {
                    "two triangles wound down"
                } else {
                    "two triangles wound up"
                };
                for &kind in CodecKind::ALL {
                    check_crease(&shape(&mesh, kind), what, bend, fold, false);
                }
            }
        }
    }
}

/// The same for the crease on top of a closed folded prism (its outside
/// above the crease): a ridge is active from the outside, a valley from
/// the inside, a 3° fold from neither.
#[test]
fn folded_solids_flag_the_crease_as_documented() {
    for bend in BENDS {
        for fold in Fold::ALL {
            let mesh = folded_prism(bend, fold);
            for &kind in CodecKind::ALL {
                let s = shape(&mesh, kind);
                assert!(
                    s.edge_flags().signed_volume > 0.0,
                    "{kind}: the prism is wound outward"
                );
                check_crease(&s, "closed prism", bend, fold, true);
            }
        }
    }
}
