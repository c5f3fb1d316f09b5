//! The shared codec test suite: every codec's cursor is checked against
//! brute force over the mesh it was built from.
#![allow(dead_code)]

use std::collections::BTreeSet;
use std::ops::ControlFlow;

use cbvh::cursor::{Children, MAX_CHILDREN, NodeCursor};
use cbvh::geom::{
    Aabb, Pose, Ray, Triangle, closest_point_on_triangle, ray_triangle, triangle_from_arrays,
};
use cbvh::query::{self, RayCursor};
use cbvh::{Mesh, TraversalStats};
use glam::{Quat, Vec3, Vec3A};

/// A small deterministic PRNG for test inputs (SplitMix64).
pub struct Rng(pub u64);
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)`.
    pub fn f32(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next_u64() >> 40) as f32 / (1u64 << 24) as f32)
    }
    pub fn vec(&mut self, lo: f32, hi: f32) -> Vec3A {
        Vec3A::new(self.f32(lo, hi), self.f32(lo, hi), self.f32(lo, hi))
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// The canonical tree of `mesh` in `layout` with up to `leaf` triangles a
/// leaf (the builder's defaults otherwise).
pub fn tree(mesh: &Mesh, layout: cbvh::Layout, leaf: usize) -> cbvh::CanonicalBvh {
    let opts = cbvh::BuildOptions {
        layout,
        max_leaf_triangles: leaf,
        ..Default::default()
    };
    cbvh::build::build(mesh, &opts, &|_, _| {}).expect("build")
}

/// A random triangle soup of `n` triangles in a box of size `extent`, with
/// some tiny and some degenerate triangles.
pub fn soup(seed: u64, n: usize, extent: f32) -> Mesh {
    let mut rng = Rng(seed);
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for t in 0..n {
        let c = rng.vec(-extent, extent);
        let size = if t % 7 == 0 {
            extent * 0.001
        } else {
            extent * 0.2
        };
        let base = vertices.len() as u32;
        for _ in 0..3 {
            vertices.push((c + rng.vec(-size, size)).to_array());
        }
        if t % 11 == 5 {
            // Degenerate: repeated corner.
            triangles.push([base, base, base + 1]);
        } else {
            triangles.push([base, base + 1, base + 2]);
        }
    }
    Mesh::new(vertices, triangles)
}

/// The edge-case meshes every codec is tested on: one triangle, 40
/// identical triangles, an all-degenerate (single point) mesh, and huge
/// coordinates (1e9: ray and distance arithmetic multiplies coordinates, and
/// must stay finite in f32).
pub fn edge_case_meshes() -> Vec<Mesh> {
    let one = Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    );
    let same = Mesh::new(one.vertices.clone(), vec![[0, 1, 2]; 40]);
    let flat = Mesh::new(vec![[1.0; 3]; 3], vec![[0, 1, 2]; 9]);
    let huge = Mesh::new(
        vec![
            [1e9, 1e9, 1e9],
            [-1e9, 1e9, 0.0],
            [0.0, -1e9, 1e9],
            [3e9, 0.0, 0.0],
        ],
        vec![[0, 1, 2], [1, 2, 3], [0, 2, 3]],
    );
    vec![one, same, flat, huge]
}

pub fn tri(mesh: &Mesh, id: u32) -> Triangle {
    triangle_from_arrays(mesh.triangle_vertices(id as usize))
}

/// Every node's box contains every triangle below it, each triangle id
/// appears exactly once, and the cursor's triangles equal the mesh's.
pub fn check_structure<C: NodeCursor>(c: &C, mesh: &Mesh) {
    let (root, root_box) = c.root();
    let mut seen = vec![0u32; mesh.triangles.len()];
    // Stack of (node, chain of ancestor boxes incl. own).
    let mut stack = vec![(root, vec![root_box])];
    while let Some((n, boxes)) = stack.pop() {
        if c.is_leaf(&n) {
            // The keyed walk names the same triangles, in the same order,
            // and its keys turn into their ids.
            let mut by_id = Vec::new();
            c.for_each_triangle(&n, |id, t| by_id.push((id, *t)));
            let mut by_key = Vec::new();
            c.for_each_triangle_keyed(&n, |key, t| by_key.push((c.id_of_key(key), *t)));
            assert_eq!(by_key, by_id, "keyed triangles differ from the leaf's");
            c.for_each_triangle(&n, |id, t| {
                seen[id as usize] += 1;
                assert_eq!(*t, tri(mesh, id), "triangle {id} differs from the mesh");
                let tb = Aabb::of_triangle(t);
                for b in &boxes {
                    assert!(
                        b.contains(&tb),
                        "box {b:?} does not contain triangle {id} {tb:?}"
                    );
                }
            });
        } else {
            // The batch the traversals use and the child-by-child view
            // agree: the same number of children, the same boxes to the
            // bit, lane `i` being child `i`; the walk follows the batch's
            // handles, so the checks below hold for those.
            let mut one_by_one = Vec::new();
            c.for_each_child(&n, |_, b| one_by_one.push(b));
            let mut batch = Children::new(n);
            c.children(&n, &mut batch);
            assert_eq!(batch.len(), one_by_one.len(), "children vs for_each_child");
            let bits = |b: &Aabb| {
                let f = |v: Vec3A| v.to_array().map(f32::to_bits);
                (f(b.min), f(b.max))
            };
            for (i, b) in one_by_one.iter().enumerate() {
                let lane = batch.boxes().get(i);
                assert_eq!(bits(&lane), bits(b), "lane {i}: {lane:?} vs {b:?}");
                let mut chain = boxes.clone();
                chain.push(lane);
                stack.push((batch.node(i), chain));
            }
        }
    }
    assert!(
        seen.iter().all(|&k| k == 1),
        "every triangle appears exactly once"
    );
    assert_eq!(c.triangle_count(), mesh.triangles.len());
}

pub fn brute_closest(mesh: &Mesh, ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
    let mut best: Option<(f32, u32)> = None;
    for id in 0..mesh.triangles.len() as u32 {
        if let Some(h) = ray_triangle(ray, &tri(mesh, id), t_max)
            && best.is_none_or(|b| h.t < b.0)
        {
            best = Some((h.t, id));
        }
    }
    best
}

/// Bits of a hit, so that two hits compare equal only when identical
/// (`-0.0` and `0.0`, or two NaNs, are told apart).
pub fn hit_bits(h: Option<query::RayHit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.t.to_bits(), h.triangle, h.u.to_bits(), h.v.to_bits()))
}

/// Rays: random ones and ones aimed at triangle centroids.
pub fn test_rays(mesh: &Mesh, seed: u64, n: usize) -> Vec<Ray> {
    let mut rng = Rng(seed);
    let (lo, hi) = mesh.bounds().unwrap_or(([0.0; 3], [1.0; 3]));
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    let size = (hi - lo).length().max(1e-3);
    (0..n)
        .map(|k| {
            let origin = (lo + hi) * 0.5 + rng.vec(-1.0, 1.0).normalize_or(Vec3A::X) * size;
            let target = if k % 2 == 0 && !mesh.triangles.is_empty() {
                let t = tri(mesh, rng.below(mesh.triangles.len()) as u32);
                (t[0] + t[1] + t[2]) / 3.0
            } else {
                lo + (hi - lo) * Vec3A::new(rng.f32(0.0, 1.0), rng.f32(0.0, 1.0), rng.f32(0.0, 1.0))
            };
            let mut dir = target - origin;
            if k % 5 == 1 {
                // An axis-parallel ray.
                let a = rng.below(3);
                dir = Vec3A::ZERO;
                dir[a] = if target[a] > origin[a] { 1.0 } else { -1.0 };
            }
            Ray::new(origin, dir.normalize_or(Vec3A::Z))
        })
        .collect()
}

/// A camera's coherent fan of 24 × 24 rays from in front of `mesh`'s box
/// through its middle plane.
pub fn camera_rays(mesh: &Mesh) -> Vec<Ray> {
    let (lo, hi) = mesh.bounds().unwrap();
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    let eye = (lo + hi) * 0.5 + Vec3A::new(0.1, 0.2, 2.5) * (hi - lo).length().max(1e-3);
    let mut rays = Vec::with_capacity(24 * 24);
    for y in 0..24 {
        for x in 0..24 {
            let p = lo + (hi - lo) * Vec3A::new(x as f32 / 23.0, y as f32 / 23.0, 0.5);
            rays.push(Ray::new(eye, (p - eye).normalize_or(Vec3A::Z)));
        }
    }
    rays
}

/// A codec's own ray traversal (`query::closest_hit` and
/// `query::any_hit`) against the generic one over its cursor, for every
/// ray up to every limit in `t_maxes`: the same closest hit, bit for bit,
/// and the same any hit. Returns how many (ray, limit) pairs hit; `what`
/// names the case in failures.
pub fn check_own_traversal_is_generic<C: RayCursor>(
    c: &C,
    rays: &[Ray],
    t_maxes: [f32; 3],
    what: &str,
) -> usize {
    let mut s = TraversalStats::default();
    let mut hits = 0;
    for ray in rays {
        for t_max in t_maxes {
            let own = query::closest_hit(c, ray, t_max, &mut s);
            let generic = query::ray::closest_hit_generic(c, ray, t_max, &mut s);
            assert_eq!(
                hit_bits(own),
                hit_bits(generic),
                "{what}, {ray:?}, t_max {t_max}"
            );
            hits += usize::from(own.is_some());
            assert_eq!(
                query::any_hit(c, ray, t_max, &mut s),
                query::ray::any_hit_generic(c, ray, t_max, &mut s),
                "{what}, {ray:?}, t_max {t_max}"
            );
        }
    }
    hits
}

/// Closest hit, any hit, overlap and closest point equal brute force.
pub fn check_queries<C: RayCursor>(c: &C, mesh: &Mesh, seed: u64) {
    let mut stats = TraversalStats::default();
    for ray in test_rays(mesh, seed, 64) {
        for t_max in [f32::INFINITY, 1.0] {
            let got = query::closest_hit(c, &ray, t_max, &mut stats);
            let want = brute_closest(mesh, &ray, t_max);
            match (got, want) {
                (None, None) => {}
                (Some(g), Some((t, id))) => {
                    assert!(
                        (g.t - t).abs() <= 1e-5 * t.abs().max(1.0),
                        "t {} vs {t}",
                        g.t
                    );
                    if g.triangle != id {
                        // A tie: both triangles are hit at the same distance.
                        let other = ray_triangle(&ray, &tri(mesh, id), t_max).unwrap();
                        assert!((other.t - g.t).abs() <= 1e-5 * t.abs().max(1.0));
                    }
                }
                (g, w) => panic!("closest hit {g:?} but brute force {w:?} for {ray:?}"),
            }
            let any = query::any_hit(c, &ray, t_max, &mut stats);
            assert_eq!(any, want.is_some(), "any hit disagrees for {ray:?}");
        }
    }
    let packet_hits = check_packets(c, mesh, seed, &mut stats);
    if mesh.triangles.len() >= 100 {
        assert!(packet_hits > 50, "only {packet_hits} packet rays hit");
    }
    let mut rng = Rng(seed ^ 0xABCD);
    let (lo, hi) = mesh.bounds().unwrap_or(([0.0; 3], [1.0; 3]));
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    for _ in 0..32 {
        let p =
            lo + (hi - lo) * Vec3A::new(rng.f32(-0.2, 1.2), rng.f32(-0.2, 1.2), rng.f32(-0.2, 1.2));
        let q = p
            + (hi - lo)
                * rng.f32(0.0, 0.3)
                * Vec3A::new(rng.f32(0.0, 1.0), rng.f32(0.0, 1.0), rng.f32(0.0, 1.0));
        let qbox = Aabb::new(p.min(q), p.max(q));
        let mut got = BTreeSet::new();
        query::overlap(c, &qbox, &mut stats, |id, _| {
            assert!(got.insert(id), "triangle {id} reported twice");
            ControlFlow::Continue(())
        });
        let want: BTreeSet<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&id| Aabb::of_triangle(&tri(mesh, id)).intersects(&qbox))
            .collect();
        assert_eq!(got, want, "overlap set differs for {qbox:?}");

        check_closest_point(c, mesh, p, &mut stats);
    }
    // Points on the surface: inside a face, on an edge, on a vertex.
    for k in 0..mesh.triangles.len().min(16) {
        let t = tri(mesh, rng.below(mesh.triangles.len()) as u32);
        let on = [
            0.2 * t[0] + 0.3 * t[1] + 0.5 * t[2],
            0.6 * t[0] + 0.4 * t[1],
            t[k % 3],
        ];
        for p in on {
            check_closest_point(c, mesh, p, &mut stats);
        }
    }
    assert!(stats.nodes_visited > 0);
}

/// The closest point to `p` equals brute force: the distance, the point
/// (the named triangle's own closest point, not a corner of it) and the
/// triangle (the lowest id among the closest, or one equally close).
pub fn check_closest_point<C: NodeCursor>(
    c: &C,
    mesh: &Mesh,
    p: Vec3A,
    stats: &mut TraversalStats,
) {
    let got = query::closest_point(c, p, f32::INFINITY, stats);
    let want = (0..mesh.triangles.len() as u32)
        .map(|id| {
            let q = closest_point_on_triangle(p, &tri(mesh, id)).0;
            ((q - p).length_squared(), id)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    match (got, want) {
        (None, None) => {}
        (Some(g), Some((d2, id))) => {
            let d = d2.sqrt();
            let tol = 1e-5 * d.max(1.0);
            assert!(
                g.distance == d || (g.distance - d).abs() <= tol,
                "closest point {g:?} vs brute force {d} on triangle {id}"
            );
            assert!(
                (g.triangle as usize) < mesh.triangles.len(),
                "closest point {g:?}: no such triangle"
            );
            let own = closest_point_on_triangle(p, &tri(mesh, g.triangle)).0;
            let scale = p.abs().max_element().max(1.0);
            assert!(
                (g.point - own).length() <= 1e-6 * scale,
                "closest point {g:?} to {p:?} is not triangle {}'s closest point {own:?}",
                g.triangle
            );
            assert!(
                ((g.point - p).length() - g.distance).abs() <= tol,
                "closest point {g:?} to {p:?}: the distance is not the point's"
            );
            if g.triangle != id {
                // A tie: both triangles are equally close.
                assert!(
                    ((own - p).length() - d).abs() <= tol,
                    "closest point {g:?} to {p:?} names triangle {}, brute force {id} at {d}",
                    g.triangle
                );
            }
        }
        (g, w) => panic!("closest point {g:?} vs brute force {w:?}"),
    }
}

/// Packets give the single-ray hits, ray for ray: incoherent packets of
/// the test rays (every size up to the largest), and coherent 8×8 camera
/// tiles looking at the mesh from several sides.
/// Returns how many packet rays hit.
pub fn check_packets<C: RayCursor>(
    c: &C,
    mesh: &Mesh,
    seed: u64,
    stats: &mut TraversalStats,
) -> usize {
    let mut packets: Vec<Vec<Ray>> = Vec::new();
    let rays = test_rays(mesh, seed, 130);
    packets.push(rays[..64].to_vec());
    packets.push(rays[64..127].to_vec());
    packets.push(rays[127..].to_vec());
    packets.push(Vec::new());
    let (lo, hi) = mesh.bounds().unwrap_or(([0.0; 3], [1.0; 3]));
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    let centre = (lo + hi) * 0.5;
    let r = (hi - lo).length().max(1e-3);
    for (k, side) in [
        Vec3A::X,
        Vec3A::NEG_Y,
        Vec3A::new(0.3, 0.5, -1.0).normalize(),
    ]
    .into_iter()
    .enumerate()
    {
        let eye = centre + side * r * 1.5;
        let fwd = (centre - eye).normalize();
        let right = fwd.any_orthonormal_vector();
        let up = right.cross(fwd);
        // A tile over the middle of the view and one at its edge.
        for offset in [0.0f32, 0.3 + 0.1 * k as f32] {
            packets.push(
                (0..64)
                    .map(|p| {
                        let (x, y) = ((p % 8) as f32 / 7.0 - 0.5, (p / 8) as f32 / 7.0 - 0.5);
                        let d = fwd + right * (x * 0.6 + offset) + up * (y * 0.6);
                        Ray::new(eye, d.normalize())
                    })
                    .collect(),
            );
        }
    }
    let mut hits = 0;
    for packet in &packets {
        for t_max in [f32::INFINITY, r] {
            let mut got = vec![None; packet.len()];
            query::closest_hits(c, packet, t_max, &mut got, stats);
            for (ray, g) in packet.iter().zip(&got) {
                let want = query::closest_hit(c, ray, t_max, stats);
                assert_eq!(*g, want, "packet and single ray differ for {ray:?}");
                hits += usize::from(g.is_some());
            }
        }
    }
    hits
}

/// A few relative poses of B in A's frame: identity, shifted, rotated.
pub fn test_poses(mesh: &Mesh, seed: u64) -> Vec<Pose> {
    let mut rng = Rng(seed);
    let (lo, hi) = mesh.bounds().unwrap_or(([0.0; 3], [1.0; 3]));
    let size = (Vec3A::from(hi) - Vec3A::from(lo)).length();
    let mut poses = vec![Pose::IDENTITY];
    for _ in 0..4 {
        let q = Quat::from_euler(
            glam::EulerRot::XYZ,
            rng.f32(-3.0, 3.0),
            rng.f32(-3.0, 3.0),
            rng.f32(-3.0, 3.0),
        );
        let t = Vec3::from(rng.vec(-0.5, 0.5) * size);
        poses.push(Pose::from_rotation_translation(q, t));
    }
    poses
}

/// BVTT pairs between `a` and `b` equal brute force for several poses and
/// prediction distances.
pub fn check_bvtt<A: NodeCursor, B: NodeCursor>(a: &A, ma: &Mesh, b: &B, mb: &Mesh, seed: u64) {
    let mut stats = TraversalStats::default();
    for pose in test_poses(ma, seed) {
        for prediction in [0.0, 0.05] {
            let got = query::bvtt_pairs(a, b, &pose, prediction, &mut stats);
            let mut want = Vec::new();
            for i in 0..ma.triangles.len() as u32 {
                let bi = Aabb::of_triangle(&tri(ma, i)).loosened(prediction);
                for j in 0..mb.triangles.len() as u32 {
                    let moved = tri(mb, j).map(|p| pose.transform_point(p));
                    if bi.intersects(&Aabb::of_triangle(&moved)) {
                        want.push((i, j));
                    }
                }
            }
            assert_eq!(
                got, want,
                "BVTT pairs differ at {pose:?}, prediction {prediction}"
            );
        }
    }
    // Early exit stops at the first pair.
    let mut count = 0;
    let stopped = query::bvtt(a, b, &Pose::IDENTITY, 0.0, &mut stats, |_, _, _, _| {
        count += 1;
        ControlFlow::Break(())
    });
    assert_eq!(stopped, count == 1);
    assert!(count <= 1);
}

/// Best-first search ([`query::find_best`]) with the squared distance to a
/// point as the cost finds brute force's closest triangle, and finds nothing
/// when the bound is below the best cost.
pub fn check_best_first<C: NodeCursor>(c: &C, mesh: &Mesh, seed: u64) {
    let mut stats = TraversalStats::default();
    let mut rng = Rng(seed ^ 0xBE57);
    let (lo, hi) = mesh.bounds().unwrap_or(([0.0; 3], [1.0; 3]));
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    for _ in 0..16 {
        let p =
            lo + (hi - lo) * Vec3A::new(rng.f32(-0.5, 1.5), rng.f32(-0.5, 1.5), rng.f32(-0.5, 1.5));
        let cost = |t: &Triangle| (closest_point_on_triangle(p, t).0 - p).length_squared();
        let want = (0..mesh.triangles.len() as u32)
            .map(|id| (cost(&tri(mesh, id)), id))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let search = |max_cost: f32, stats: &mut TraversalStats| {
            query::find_best(
                c,
                max_cost,
                stats,
                |b| b.distance_squared(p),
                |id, t, best| {
                    let k = cost(t);
                    (k < best).then_some((k, id))
                },
            )
        };
        let got = search(f32::INFINITY, &mut stats);
        match (got, want) {
            (None, None) => {}
            (Some((id, k, payload)), Some((wk, wid))) => {
                assert_eq!(id, payload, "the payload belongs to the best triangle");
                assert!(
                    k == wk || (k - wk).abs() <= 1e-5 * wk.max(1.0),
                    "best-first cost {k} on {id}, brute force {wk} on {wid} from {p:?}"
                );
                assert!(
                    (cost(&tri(mesh, id)) - k).abs() <= 1e-6 * k.max(1.0),
                    "best-first names triangle {id} whose cost is not {k}"
                );
                if wk > 0.0 {
                    let bounded = search(wk * 0.5, &mut stats);
                    assert!(
                        bounded.is_none(),
                        "found {bounded:?} below half the best cost {wk}"
                    );
                }
            }
            (g, w) => panic!("best-first {g:?} vs brute force {w:?}"),
        }
    }
}

/// Distance between two boxes (0 when they overlap).
fn box_distance(x: &Aabb, y: &Aabb) -> f32 {
    (x.min - y.max).max(y.min - x.max).max(Vec3A::ZERO).length()
}

/// The parallel two-tree traversal ([`query::bvtt_par`], from fronts of
/// several sizes, none overshooting its size by a whole expansion) reports
/// brute force's pairs, and branch-and-bound over two
/// trees ([`query::bvtt_min`], with the distance between the triangles'
/// boxes as the cost) finds brute force's smallest cost, for several poses.
pub fn check_bvtt_par_and_min<A: NodeCursor, B: NodeCursor>(
    a: &A,
    ma: &Mesh,
    b: &B,
    mb: &Mesh,
    seed: u64,
) {
    let mut stats = TraversalStats::default();
    for pose in test_poses(ma, seed) {
        let moved: Vec<Aabb> = (0..mb.triangles.len() as u32)
            .map(|j| Aabb::of_triangle(&tri(mb, j).map(|p| pose.transform_point(p))))
            .collect();
        let boxes_a: Vec<Aabb> = (0..ma.triangles.len() as u32)
            .map(|i| Aabb::of_triangle(&tri(ma, i)))
            .collect();
        let prediction = 0.05;
        let mut want = Vec::new();
        let mut best: Option<(f32, u32, u32)> = None;
        for (i, bi) in boxes_a.iter().enumerate() {
            for (j, bj) in moved.iter().enumerate() {
                if bi.loosened(prediction).intersects(bj) {
                    want.push((i as u32, j as u32));
                }
                let d = box_distance(bi, bj);
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, i as u32, j as u32));
                }
            }
        }
        for target in [1, 8, 64] {
            // The front stops expanding once it reaches the target: at
            // most one expansion's children beyond it (a task each).
            let front = query::bvtt_front(a, b, &pose, prediction, target, &mut stats);
            assert!(
                front.len() < target + MAX_CHILDREN,
                "a front of {} pairs for a target of {target} at {pose:?}",
                front.len()
            );
            let (states, _) = query::bvtt_par(
                a,
                b,
                &pose,
                prediction,
                target,
                Vec::new,
                |s: &mut Vec<(u32, u32)>, i, ti, j, tj| {
                    // Both triangles arrive in A's frame.
                    assert_eq!(*ti, tri(ma, i), "bvtt_par: triangle {i} of A");
                    assert_eq!(
                        *tj,
                        tri(mb, j).map(|p| pose.transform_point(p)),
                        "bvtt_par: triangle {j} of B"
                    );
                    s.push((i, j))
                },
            );
            let mut got: Vec<(u32, u32)> = states.into_iter().flatten().collect();
            let n = got.len();
            got.sort_unstable();
            got.dedup();
            assert_eq!(n, got.len(), "bvtt_par reported a pair twice");
            assert_eq!(
                got, want,
                "bvtt_par pairs differ at {pose:?}, front {target}"
            );
        }
        let got = query::bvtt_min(
            a,
            b,
            &pose,
            f32::INFINITY,
            &mut stats,
            |i, _, j, _, best| {
                let d = box_distance(&boxes_a[i as usize], &moved[j as usize]);
                (d < best).then_some((d, ()))
            },
        );
        match (got, best) {
            (None, None) => {}
            (Some((i, j, d, ())), Some((wd, wi, wj))) => {
                let tol = 1e-5 * wd.max(1.0);
                assert!(
                    (d - wd).abs() <= tol,
                    "bvtt_min {d} on ({i}, {j}), brute force {wd} on ({wi}, {wj}) at {pose:?}"
                );
            }
            (g, w) => panic!("bvtt_min {g:?} vs brute force {w:?} at {pose:?}"),
        }
    }
}

/// Runs the `cbvh` command with `args`: (success, stdout, stderr).
#[cfg(feature = "app")]
pub fn cbvh(args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cbvh"))
        .args(args)
        .output()
        .expect("run cbvh");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Runs the binary `bin` with `args` for at most `secs` seconds:
/// `Some((success, stdout, stderr))` if it ended by then, `None` if it was
/// still running (it is then killed). For checks that a bad flag stops a
/// command before any work, without running that work if it does not.
#[cfg(feature = "app")]
pub fn run_within(bin: &str, args: &[&str], secs: u64) -> Option<(bool, String, String)> {
    use std::io::Read;
    use std::process::{Command, Stdio};
    let mut child = Command::new(bin)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run the binary");
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait for the binary") {
            break Some(status);
        }
        if start.elapsed().as_secs() >= secs {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let (mut out, mut err) = (String::new(), String::new());
    child.stdout.take().map(|mut o| o.read_to_string(&mut out));
    child.stderr.take().map(|mut e| e.read_to_string(&mut err));
    status.map(|s| (s.success(), out, err))
}

/// `cbvh` with `args`, refused within `secs` seconds: the test fails if
/// it succeeds or is still running then. Returns its stderr.
#[cfg(feature = "app")]
pub fn cbvh_refuses_within(args: &[&str], secs: u64) -> String {
    match run_within(env!("CARGO_BIN_EXE_cbvh"), args, secs) {
        Some((false, _, stderr)) => stderr,
        Some((true, stdout, stderr)) => panic!("{args:?} was accepted: {stdout}{stderr}"),
        None => panic!("{args:?} still ran after {secs} s: not refused before the work"),
    }
}

/// `cbvh build MODEL --codec CODEC --out-of-core --chunk-triangles 12000
/// -o OUT`'s arguments: the out-of-core build the command-line tests ask
/// for.
#[cfg(feature = "app")]
pub fn out_of_core_build<'a>(model: &'a str, codec: &'a str, out: &'a str) -> [&'a str; 9] {
    [
        "build",
        model,
        "--codec",
        codec,
        "--out-of-core",
        "--chunk-triangles",
        "12000",
        "-o",
        out,
    ]
}

/// What the out-of-core codecs' command-line tests share: a 100 k-triangle
/// statue saved as `m.ply` in `d`; `cbvh build m.ply --codec CODEC
/// --out-of-core --chunk-triangles 12000 -o OUT --json` reports an
/// out-of-core build of 7 chunks or more holding every triangle; `cbvh info
/// OUT` names the codec; and over a 24 MiB budget the codec builds out of
/// core by itself. Returns the model's path and the first build's report.
#[cfg(feature = "app")]
pub fn cli_builds_out_of_core(
    d: &std::path::Path,
    codec: &str,
    out: &std::path::Path,
) -> (std::path::PathBuf, serde_json::Value) {
    use cbvh::scene::{Kind, generate};
    let mesh = generate(Kind::Statue, 100_000, 1, &mut |_, _| {}).unwrap();
    let ply = d.join("m.ply");
    cbvh::mesh::save(&mesh, &ply).unwrap();
    let (p, out) = (ply.to_str().unwrap(), out.to_str().unwrap());
    let (ok, stdout, stderr) = cbvh(&[&out_of_core_build(p, codec, out)[..], &["--json"]].concat());
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["out_of_core"], true);
    assert!(v["chunks"].as_u64().unwrap() >= 7, "{stdout}");
    assert_eq!(v["triangles"], mesh.triangles.len() as u64);
    let (ok, info, stderr) = cbvh(&["info", out]);
    assert!(ok && info.contains(codec), "{info}{stderr}");
    // Over the budget: out of core by itself.
    let (ok, stdout, stderr) = cbvh(&[
        "build",
        p,
        "--codec",
        codec,
        "--memory-mib",
        "24",
        "-o",
        out,
    ]);
    assert!(
        ok && stdout.contains("built out of core"),
        "{stdout}{stderr}"
    );
    (ply, v)
}

/// A fresh temporary directory for test `name` of the suite part `part`
/// (one per process, so parallel runs do not meet).
pub fn temp_dir_for(part: &str, name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("cbvh-{part}-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs an out-of-core encoder on `mesh` split into chunks of `chunk`
/// triangles (`encode` gets the chunks and build options with leaves of up
/// to `leaf` triangles), the chunks' temporary directory beside `out`, and
/// checks that directory is gone once the chunks are dropped.
pub fn through_chunks<R>(
    mesh: &Mesh,
    chunk: u64,
    leaf: usize,
    out: &std::path::Path,
    encode: impl FnOnce(&cbvh::build::chunked::ChunkedMesh, &cbvh::build::BuildOptions) -> R,
) -> R {
    use cbvh::build::chunked::{ChunkOptions, ChunkedMesh};
    let temp = out.with_extension("tmp-dir");
    let input = ChunkedMesh::from_mesh(
        mesh,
        &ChunkOptions {
            chunk_triangles: chunk,
            temp_dir: temp.clone(),
        },
        &|_, _, _| {},
    )
    .expect("chunks");
    let b = cbvh::build::BuildOptions {
        max_leaf_triangles: leaf,
        ..Default::default()
    };
    let r = encode(&input, &b);
    drop(input);
    assert!(!temp.exists(), "the temporary directory is removed");
    r
}

/// Each triangle as its corners' position bits, sorted: a mesh's
/// triangles whatever their order.
pub fn triangle_set(m: &Mesh) -> Vec<[[u32; 3]; 3]> {
    let mut v: Vec<_> = m
        .triangles
        .iter()
        .map(|t| t.map(|i| m.vertices[i as usize].map(f32::to_bits)))
        .collect();
    v.sort_unstable();
    v
}

/// What a file built out of core (`streamed`, at `out`, from `mesh` in
/// `chunks` chunks of at most `chunk` triangles) must share with the
/// in-memory build of the same mesh (`direct`): the same triangles (one
/// grid), the edge flags its own triangles give (counters included), the
/// mass within rounding, more than one chunk for one triangle a chunk
/// (unless the centroids coincide), and opening out of core through the
/// registry with a small cache. `what` names the case in failures.
#[allow(clippy::too_many_arguments)]
pub fn check_streamed_like_direct<S: cbvh::codec::Codec, D: cbvh::codec::Codec>(
    what: &str,
    streamed: &S,
    direct: &D,
    out: &std::path::Path,
    mesh: &Mesh,
    chunk: u64,
    chunks: usize,
    same_centroids: bool,
) {
    use cbvh::codec::common::edges;
    use cbvh::codec::{AnyCodec, OpenOptions};
    let dm = streamed.decoded_mesh();
    assert_eq!(
        triangle_set(&dm),
        triangle_set(&direct.decoded_mesh()),
        "{what}"
    );
    let want = edges::of_cursor(streamed);
    let got = streamed.edge_flags();
    assert_eq!(got.as_slice(), want.as_slice(), "{what}");
    assert_eq!(
        (got.boundary_edges, got.flat_edges, got.misoriented_edges),
        (want.boundary_edges, want.flat_edges, want.misoriented_edges),
        "{what}"
    );
    let (a, b) = (streamed.mass(), direct.mass());
    assert!(
        (a.mass - b.mass).abs() <= 1e-4 * b.mass.abs().max(1e-9),
        "{what}: {a:?} vs {b:?}"
    );
    if chunk == 1 && mesh.triangles.len() > 1 && !same_centroids {
        assert!(chunks > 1, "{what}: {chunks} chunks");
    }
    let paged = AnyCodec::open(
        out,
        &OpenOptions {
            cache_budget_bytes: 4096,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(paged.triangle_count(), mesh.triangles.len(), "{what}");
}

/// The models both out-of-core codecs' streamed builds are checked on: a
/// statue, a robot and a turbine, a soup, and [`edge_case_meshes`] (named
/// one, same, flat and huge).
pub fn streamed_meshes() -> Vec<(&'static str, Mesh)> {
    use cbvh::scene::{Kind, generate};
    let g = |k, n| generate(k, n, 1, &mut |_, _| {}).unwrap();
    let mut v = vec![
        ("statue", g(Kind::Statue, 3000)),
        ("robot", g(Kind::Robot, 4000)),
        ("turbine", g(Kind::Turbine, 3000)),
        ("soup", soup(7, 500, 2.0)),
    ];
    for (k, m) in edge_case_meshes().into_iter().enumerate() {
        v.push((["one", "same", "flat", "huge"][k], m));
    }
    v
}

/// Runs `f` in a rayon pool of `threads` workers.
pub fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// The bytes `run(threads)` writes are the same run in pools of 1, 2 and
/// 3 threads.
pub fn check_same_bytes_in_1_2_3_threads(run: impl Fn(usize) -> Vec<u8> + Sync) {
    let one = in_pool(1, || run(1));
    assert_eq!(one, in_pool(2, || run(2)));
    assert_eq!(one, in_pool(3, || run(3)));
}

/// The directory `d` is empty: a refused build left no temporary file.
pub fn assert_no_file_left(d: &std::path::Path) {
    assert_eq!(
        std::fs::read_dir(d).unwrap().count(),
        0,
        "no temporary file"
    );
}

/// Meshes at the edges of what a builder and a codec take:
/// [`edge_case_meshes`], a flat grid, collinear corners, coordinates far
/// from the origin, duplicate triangles.
pub fn edge_meshes() -> Vec<(&'static str, Mesh)> {
    let mut out: Vec<(&'static str, Mesh)> = Vec::new();
    let [one, same, point, huge]: [Mesh; 4] = edge_case_meshes().try_into().unwrap();
    out.push(("one triangle", one));
    out.push(("40 identical triangles", same));
    out.push(("all corners one point", point));
    out.push(("coordinates of 1e9", huge));
    // A flat grid, every z = 0.
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for y in 0..8u32 {
        for x in 0..8u32 {
            vertices.push([x as f32, y as f32, 0.0]);
        }
    }
    for y in 0..7u32 {
        for x in 0..7u32 {
            let i = y * 8 + x;
            triangles.push([i, i + 1, i + 8]);
            triangles.push([i + 1, i + 9, i + 8]);
        }
    }
    out.push(("flat, z = 0", Mesh::new(vertices, triangles)));
    // Every corner on one line (zero-area triangles).
    let line: Vec<[f32; 3]> = (0..30).map(|i| [i as f32 * 0.5, i as f32, 2.0]).collect();
    let tris = (0..28u32).map(|i| [i, i + 1, i + 2]).collect();
    out.push(("collinear", Mesh::new(line, tris)));
    // Far from the origin: a soup offset by 1e6.
    let mut far = soup(3, 200, 5.0);
    for v in &mut far.vertices {
        for c in v.iter_mut() {
            *c += 1e6;
        }
    }
    out.push(("offset 1e6", far));
    // Duplicates: the same triangles twice, under other ids.
    let mut dup = soup(4, 60, 3.0);
    let twice: Vec<[u32; 3]> = dup
        .triangles
        .iter()
        .chain(&dup.triangles)
        .copied()
        .collect();
    dup.triangles = twice;
    out.push(("duplicate triangles", dup));
    out
}
