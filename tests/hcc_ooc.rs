//! o-HCCMesh: decoding gives the i-HCCMesh built directly from the same
//! tree and options, byte for byte; damaged and forged files give errors,
//! never panics or hangs. (The shared suite in `codec_suite.rs` runs the
//! queries on the `hcc-ooc` codec.)

mod common;

use cbvh::Mesh;
use cbvh::build::{BuildOptions, CanonicalBvh, Layout, build};
use cbvh::codec::hcc::HccBvh;
use cbvh::codec::hcc::ooc::{HccOocBvh, OocError, OocOptions};
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind, OpenOptions};
use cbvh::scene::{Kind, generate};
use common::*;
use xxhash_rust::xxh3::xxh3_64;

fn tree(mesh: &Mesh, layout: Layout, leaf: usize) -> CanonicalBvh {
    let opts = BuildOptions {
        layout,
        max_leaf_triangles: leaf,
        ..Default::default()
    };
    build(mesh, &opts, &|_, _| {}).expect("build")
}

fn mesh_of(kind: Kind, tris: usize) -> Mesh {
    generate(kind, tris, 1, &mut |_, _| {}).expect("generate")
}

fn options() -> Vec<OocOptions> {
    let o = OocOptions::default();
    vec![
        o,
        OocOptions {
            vertex_bits: 8,
            ..o
        },
        OocOptions {
            vertex_bits: 24,
            ..o
        },
        OocOptions {
            triangle_ids: true,
            vertex_ids: true,
            ..o
        },
        OocOptions {
            vertex_ids: true,
            ..o
        },
    ]
}

/// o → i equals the direct i-HCCMesh: file bytes and figures.
fn check_same(mesh: &Mesh, layout: Layout, leaf: usize, o: &OocOptions) {
    let bvh = tree(mesh, layout, leaf);
    let direct = HccBvh::encode_with(&bvh, mesh, &o.hcc()).expect("encode");
    let (bytes, sizes) = direct.to_ooc().expect("to_ooc");
    assert_eq!(sizes.total() as usize, bytes.len());
    let back = HccBvh::from_ooc(&bytes).expect("from_ooc");
    assert!(
        back.to_bytes() == direct.to_bytes(),
        "{o:?}, {layout:?}, leaves of {leaf}, {} triangles: o → i differs from the direct i-HCCMesh",
        mesh.triangles.len()
    );
    assert_eq!(back.stats(), direct.stats(), "{o:?}: figures differ");
    back.verify().expect("verify");
    // The codec's own path gives the same.
    let codec = HccOocBvh::encode_with(&bvh, mesh, o).expect("encode");
    assert_eq!(codec.file_bytes(), &bytes[..]);
    let opened = HccOocBvh::from_bytes(&bytes).expect("from_bytes");
    assert!(opened.hcc().to_bytes() == direct.to_bytes());
}

#[test]
fn o_to_i_decode_equals_the_directly_built_i_hccmesh() {
    let mut meshes = vec![
        mesh_of(Kind::Statue, 20_000),
        mesh_of(Kind::Turbine, 8_000),
        mesh_of(Kind::Plant, 4_000),
        mesh_of(Kind::Isosurface, 4_000),
        soup(3, 3_000, 10.0),
    ];
    meshes.extend(edge_case_meshes());
    meshes.push(Mesh::new(Vec::new(), Vec::new()));
    for (i, mesh) in meshes.iter().enumerate() {
        let layouts: &[Layout] = if i == 0 {
            &[Layout::DepthFirst, Layout::VanEmdeBoas]
        } else {
            &[Layout::DepthFirst]
        };
        for &layout in layouts {
            for o in options() {
                check_same(mesh, layout, 1, &o);
            }
        }
        // Multi-triangle leaves (the i-HCCMesh's §7 extension).
        for leaf in [4, 64] {
            check_same(mesh, Layout::DepthFirst, leaf, &OocOptions::default());
        }
    }
}

/// The shared suite's edge meshes beyond `edge_case_meshes`: a flat grid,
/// collinear corners, coordinates far from the origin, duplicates.
fn more_edge_meshes() -> Vec<(&'static str, Mesh)> {
    let mut out: Vec<(&'static str, Mesh)> = Vec::new();
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
    out.push(("flat", Mesh::new(vertices, triangles)));
    let line: Vec<[f32; 3]> = (0..30).map(|i| [i as f32 * 0.5, i as f32, 2.0]).collect();
    let tris = (0..28u32).map(|i| [i, i + 1, i + 2]).collect();
    out.push(("collinear", Mesh::new(line, tris)));
    let mut far = soup(3, 200, 5.0);
    for v in &mut far.vertices {
        for c in v.iter_mut() {
            *c += 1e6;
        }
    }
    out.push(("offset 1e6", far));
    let mut dup = soup(4, 60, 3.0);
    let twice: Vec<[u32; 3]> = dup
        .triangles
        .iter()
        .chain(&dup.triangles)
        .copied()
        .collect();
    dup.triangles = twice;
    out.push(("duplicates", dup));
    for (i, m) in edge_case_meshes().into_iter().enumerate() {
        out.push((["one", "same", "point", "huge"][i], m));
    }
    out
}

#[test]
fn edge_meshes_round_trip_in_every_option_and_leaf_size() {
    for (name, mesh) in more_edge_meshes() {
        for (layout, leaf) in [(Layout::VanEmdeBoas, 1), (Layout::DepthFirst, 4)] {
            for o in options() {
                eprintln!("{name}, {layout:?}, leaves of {leaf}, {o:?}");
                check_same(&mesh, layout, leaf, &o);
            }
        }
    }
}

#[test]
fn every_template_and_tree_shape_survives_the_round_trip() {
    // A soup spreads triangles so that low-level trees are small and
    // uneven: templates of every height, template leaves beside leaves.
    let mesh = soup(11, 6_000, 100.0);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    let direct = HccBvh::encode_with(&bvh, &mesh, &OocOptions::default().hcc()).unwrap();
    let used = direct.stats().templates.iter().filter(|&&n| n > 0).count();
    assert!(used >= 20, "only {used} templates occur");
    let (bytes, _) = direct.to_ooc().unwrap();
    assert!(HccBvh::from_ooc(&bytes).unwrap().to_bytes() == direct.to_bytes());
}

#[test]
fn f32_vertices_are_an_error() {
    let mesh = mesh_of(Kind::Statue, 2_000);
    let direct = HccBvh::encode(&tree(&mesh, Layout::DepthFirst, 1), &mesh).unwrap();
    assert_eq!(direct.to_ooc().unwrap_err(), OocError::NotQuantized);
}

/// A tiny deterministic generator for the damage tests.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
}

const TABLE: usize = 140;
const HEADER_LEN: usize = 292;

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// Rewrites every section checksum and the header's so that damage
/// inside the sections reaches the decoder (a forged file).
fn reframe(b: &mut [u8]) {
    for k in 0..6 {
        let at = TABLE + 24 * k;
        let (off, len) = (u64_at(b, at) as usize, u64_at(b, at + 8) as usize);
        let h = xxh3_64(&b[off..off + len]);
        b[at + 16..at + 24].copy_from_slice(&h.to_le_bytes());
    }
    let h = xxh3_64(&b[..HEADER_LEN - 8]);
    b[HEADER_LEN - 8..HEADER_LEN].copy_from_slice(&h.to_le_bytes());
}

#[test]
fn damaged_and_forged_files_give_errors_not_panics() {
    let mesh = mesh_of(Kind::Statue, 3_000);
    for (leaf, o) in [
        (1, OocOptions::default()),
        (
            1,
            OocOptions {
                triangle_ids: true,
                vertex_ids: true,
                ..OocOptions::default()
            },
        ),
        (8, OocOptions::default()),
    ] {
        let bvh = tree(&mesh, Layout::DepthFirst, leaf);
        let (bytes, _) = HccBvh::encode_with(&bvh, &mesh, &o.hcc())
            .unwrap()
            .to_ooc()
            .unwrap();
        let n = bytes.len();
        // Truncations: always an error.
        for len in (0..n).step_by(n / 97 + 1).chain([n - 1]) {
            assert!(
                HccBvh::from_ooc(&bytes[..len]).is_err(),
                "truncated to {len}"
            );
        }
        let mut rng = Lcg(7);
        let mut noticed = 0;
        for round in 0..600 {
            let mut b = bytes.clone();
            // Plain flips are caught by the checksums.
            let at = rng.next() as usize % n;
            b[at] ^= 1 << (rng.next() % 8);
            assert!(
                HccBvh::from_ooc(&b).is_err(),
                "a flip at byte {at} went unnoticed"
            );
            // Forged: flips (one to eight) inside the sections with the
            // checksums rewritten; decoding must end in an error or in an
            // i-HCCMesh that verify judges, never in a panic or a hang.
            let mut b = bytes.clone();
            for _ in 0..1 + round % 8 {
                let at = HEADER_LEN + rng.next() as usize % (n - HEADER_LEN);
                b[at] ^= 1 << (rng.next() % 8);
            }
            reframe(&mut b);
            match HccBvh::from_ooc(&b) {
                Err(_) => noticed += 1,
                Ok(h) => {
                    let _ = h.verify();
                }
            }
        }
        assert!(
            noticed > 100,
            "only {noticed} of 600 forged files were errors"
        );
    }
}

#[test]
fn the_registry_builds_saves_and_opens_hcc_ooc() {
    let mesh = mesh_of(Kind::Statue, 5_000);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    let codec = AnyCodec::encode(CodecKind::HccOoc, &bvh, &mesh, &AnyOptions::default()).unwrap();
    assert_eq!(codec.name(), "hcc-ooc");
    let path = std::env::temp_dir().join(format!("cbvh-hcc-ooc-{}.hccz", std::process::id()));
    codec.save(&path).unwrap();
    let opened = AnyCodec::open(&path, &OpenOptions::default()).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(opened.kind(), CodecKind::HccOoc);
    assert_eq!(opened.to_bytes(), codec.to_bytes());
    assert_eq!(opened.decoded_mesh(), codec.decoded_mesh());
    let per_tri = codec.to_bytes().len() as f64 / mesh.triangles.len() as f64;
    assert!(per_tri < 8.0, "{per_tri} bytes a triangle");
}
