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
fn check_same(mesh: &Mesh, layout: Layout, o: &OocOptions) {
    let bvh = tree(mesh, layout, 1);
    let direct = HccBvh::encode_with(&bvh, mesh, &o.hcc()).expect("encode");
    let (bytes, sizes) = direct.to_ooc().expect("to_ooc");
    assert_eq!(sizes.total() as usize, bytes.len());
    let back = HccBvh::from_ooc(&bytes).expect("from_ooc");
    assert!(
        back.to_bytes() == direct.to_bytes(),
        "{o:?}, {layout:?}, {} triangles: o → i differs from the direct i-HCCMesh",
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
                check_same(mesh, layout, &o);
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
fn f32_vertices_and_multi_triangle_leaves_are_errors() {
    let mesh = mesh_of(Kind::Statue, 2_000);
    let direct = HccBvh::encode(&tree(&mesh, Layout::DepthFirst, 1), &mesh).unwrap();
    assert_eq!(direct.to_ooc().unwrap_err(), OocError::NotQuantized);
    let multi = tree(&mesh, Layout::DepthFirst, 4);
    assert_eq!(
        HccOocBvh::encode_with(&multi, &mesh, &OocOptions::default()).unwrap_err(),
        OocError::MultiLeaves
    );
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
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    for o in [
        OocOptions::default(),
        OocOptions {
            triangle_ids: true,
            vertex_ids: true,
            ..OocOptions::default()
        },
    ] {
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
