//! Mass properties of closed meshes for every codec: mass, centre of mass
//! and the full inertia tensor (so the principal moments and their frame)
//! of the shape as built and of the shape of its codec's file read back
//! (hcc-ooc also paged, out of core) equal parry's `TriMesh` of the same
//! mesh (`MassProperties::from_trimesh`, what rapier gives a `TriMesh`
//! collider), at two densities, to a relative 1e-4.

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::racbvh::RacOptions;
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind, OpenOptions};
use cbvh::parry::CbvhShape;
use cbvh::scene::{Kind, generate};
use cbvh::sim::slide::{box_mesh, icosphere_mesh};
use parry3d::mass_properties::MassProperties;
use parry3d::math::Vector;
use parry3d::shape::{Shape, TriMesh};

/// Relative tolerance of every figure.
const REL: f32 = 1e-4;

fn options() -> AnyOptions {
    AnyOptions {
        racbvh: RacOptions {
            cluster_nodes: 256,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// `m` moved by `by`, so that no centre of mass is at the origin.
fn moved(mut m: Mesh, by: [f32; 3]) -> Mesh {
    for v in &mut m.vertices {
        for k in 0..3 {
            v[k] += by[k];
        }
    }
    m
}

/// A closed, non-symmetric solid: a box with one corner pulled far out
/// and another pushed in, so that the centre of mass is off the box's
/// centre and the inertia tensor has products of inertia.
fn lopsided_solid() -> Mesh {
    let mut vertices = vec![];
    for k in 0..8 {
        vertices.push([
            if k & 1 == 0 { -0.5 } else { 0.5 },
            if k & 2 == 0 { -0.3 } else { 0.3 },
            if k & 4 == 0 { -0.2 } else { 0.2 },
        ]);
    }
    vertices[7] = [1.1, 0.8, 0.6];
    vertices[0] = [-0.35, -0.2, -0.1];
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Mesh::new(vertices, triangles)
}

/// The closed meshes under test, by name.
fn solids() -> Vec<(&'static str, Mesh)> {
    let statue = generate(Kind::Statue, 3000, 4, &mut |_, _| {}).unwrap();
    vec![
        ("lopsided solid", moved(lopsided_solid(), [0.4, -1.3, 2.2])),
        (
            "box",
            moved(box_mesh(Vector::new(0.7, 0.3, 0.45)), [-2.0, 0.5, 1.0]),
        ),
        ("icosphere", moved(icosphere_mesh(0.8, 3), [1.5, 2.0, -0.5])),
        ("statue", statue),
    ]
}

fn parry_reference(mesh: &Mesh, density: f32) -> MassProperties {
    let vertices = mesh
        .vertices
        .iter()
        .map(|v| Vector::from_array(*v))
        .collect();
    TriMesh::new(vertices, mesh.triangles.clone())
        .unwrap()
        .mass_properties(density)
}

/// The shapes of every codec for `mesh`: as built, and from its file read
/// back whole and, with a one-byte cache budget, paged where the codec can.
fn shapes(mesh: &Mesh) -> Vec<(String, CbvhShape)> {
    let mut out = Vec::new();
    for &kind in CodecKind::ALL {
        let s = CbvhShape::build(mesh, &BuildOptions::default(), kind, &options())
            .unwrap_or_else(|e| panic!("{kind}: {e}"));
        let bytes = s.codec().to_bytes();
        for budget in [usize::MAX, 1] {
            let o = OpenOptions {
                verify: true,
                cache_budget_bytes: budget,
            };
            let c =
                AnyCodec::from_bytes(kind, &bytes, &o).unwrap_or_else(|e| panic!("{kind}: {e}"));
            out.push((
                format!("{kind} read back (budget {budget})"),
                CbvhShape::new(c),
            ));
        }
        out.push((format!("{kind} built"), s));
    }
    out
}

fn close(a: f32, b: f32, scale: f32) -> bool {
    (a - b).abs() <= REL * scale
}

/// Mass, centre of mass, principal moments and the full inertia tensor
/// (which fixes the principal frame) of every codec's shape equal parry's.
#[test]
fn closed_meshes_have_parrys_mass_properties_in_every_codec() {
    for (name, mesh) in solids() {
        let plain = CbvhShape::plain(&mesh, &BuildOptions::default()).unwrap();
        assert!(plain.edge_flags().is_closed(), "{name}: a closed mesh");
        let (lo, hi) = mesh.bounds().unwrap();
        let size = (Vector::from(hi) - Vector::from(lo)).length();
        for (what, s) in shapes(&mesh) {
            for density in [1.0f32, 2.5] {
                let want = parry_reference(&mesh, density);
                let got = s.mass_properties(density);
                let at = format!("{name}, {what}, density {density}");
                assert!(want.mass() > 0.0, "{at}: parry sees a solid");
                assert!(
                    close(got.mass(), want.mass(), want.mass()),
                    "{at}: mass {} vs parry {}",
                    got.mass(),
                    want.mass()
                );
                assert!(
                    (got.local_com - want.local_com).length() <= REL * size,
                    "{at}: centre of mass {:?} vs parry {:?}",
                    got.local_com,
                    want.local_com
                );
                let (gi, wi) = (
                    got.reconstruct_inertia_matrix().to_cols_array(),
                    want.reconstruct_inertia_matrix().to_cols_array(),
                );
                let scale = wi.iter().fold(0f32, |m, x| m.max(x.abs()));
                assert!(
                    gi.iter().zip(&wi).all(|(g, w)| close(*g, *w, scale)),
                    "{at}: inertia tensor {gi:?} vs parry {wi:?}"
                );
                let mut gp = got.principal_inertia().to_array();
                let mut wp = want.principal_inertia().to_array();
                gp.sort_by(f32::total_cmp);
                wp.sort_by(f32::total_cmp);
                assert!(
                    gp.iter().zip(&wp).all(|(g, w)| close(*g, *w, scale)),
                    "{at}: principal inertia {gp:?} vs parry {wp:?}"
                );
            }
        }
    }
}
