//! o-HCCMesh: decoding gives the i-HCCMesh built directly from the same
//! tree and options, byte for byte; damaged and forged files give errors,
//! never panics or hangs. (The shared suite in `codec_suite.rs` runs the
//! queries on the `hcc-ooc` codec.)

use crate::common;

use cbvh::Mesh;
use cbvh::build::Layout;
use cbvh::codec::hcc::HccBvh;
use cbvh::codec::hcc::ooc::{HccOocBvh, OocError, OocOptions};
use cbvh::codec::{AnyCodec, AnyOptions, Codec, CodecKind, OpenOptions};
use cbvh::cursor::NodeCursor;
use cbvh::scene::{Kind, generate};
use common::*;
use xxhash_rust::xxh3::xxh3_64;

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

/// The leaves and id maps the damage and out-of-core tests run: one
/// triangle a leaf without and with both id maps, and up to 8 a leaf.
fn leaves_and_maps() -> [(usize, OocOptions); 3] {
    let maps = OocOptions {
        triangle_ids: true,
        vertex_ids: true,
        ..OocOptions::default()
    };
    [
        (1, OocOptions::default()),
        (1, maps),
        (8, OocOptions::default()),
    ]
}

/// The o-HCCMesh file of `mesh`'s depth-first tree with up to `leaf`
/// triangles a leaf, through the i-HCCMesh built with `o`.
fn ooc_bytes(mesh: &Mesh, leaf: usize, o: &OocOptions) -> Vec<u8> {
    let bvh = tree(mesh, Layout::DepthFirst, leaf);
    let (bytes, _) = HccBvh::encode_with(&bvh, mesh, &o.hcc())
        .unwrap()
        .to_ooc()
        .unwrap();
    bytes
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
    assert!(opened.hcc().expect("pre-loaded").to_bytes() == direct.to_bytes());
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

#[test]
fn edge_meshes_round_trip_in_every_option_and_leaf_size() {
    for (name, mesh) in edge_meshes() {
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
const HEADER_LEN: usize = 364;

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// Offset and length of section `k`, from the section table.
fn section(b: &[u8], k: usize) -> (usize, usize) {
    let at = TABLE + 24 * k;
    (u64_at(b, at) as usize, u64_at(b, at + 8) as usize)
}

/// Rewrites every section checksum and the header's so that damage
/// inside the sections reaches the decoder (a forged file).
fn reframe(b: &mut [u8]) {
    for k in 0..9 {
        let (off, len) = section(b, k);
        let h = xxh3_64(&b[off..off + len]);
        let at = TABLE + 24 * k + 16;
        b[at..at + 8].copy_from_slice(&h.to_le_bytes());
    }
    let h = xxh3_64(&b[..HEADER_LEN - 8]);
    b[HEADER_LEN - 8..HEADER_LEN].copy_from_slice(&h.to_le_bytes());
}

#[test]
fn damaged_and_forged_files_give_errors_not_panics() {
    let mesh = mesh_of(Kind::Statue, 3_000);
    for (leaf, o) in leaves_and_maps() {
        let bytes = ooc_bytes(&mesh, leaf, &o);
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

/// Every node of a depth-first walk (its box's bits, whether a leaf, its
/// triangles' ids and corners' bits), on an explicit stack.
/// A walked node: its box's bits, whether a leaf, its triangles.
type Walked = (Vec<u32>, bool, Vec<(u32, Vec<u32>)>);

fn walk<C: NodeCursor>(c: &C) -> Vec<Walked> {
    let mut out = Vec::new();
    let (root, b) = c.root();
    let mut stack = vec![(root, b)];
    while let Some((n, b)) = stack.pop() {
        let bits = b
            .min
            .to_array()
            .into_iter()
            .chain(b.max.to_array())
            .map(f32::to_bits)
            .collect();
        let leaf = c.is_leaf(&n);
        let mut tris = Vec::new();
        if leaf {
            c.for_each_triangle(&n, |id, t| {
                tris.push((
                    id,
                    t.iter()
                        .flat_map(|p| p.to_array())
                        .map(f32::to_bits)
                        .collect(),
                ));
            });
        } else {
            c.for_each_child(&n, |k, kb| stack.push((k, kb)));
        }
        out.push((bits, leaf, tris));
    }
    out
}

/// Out of core answers as pre-loaded: the same walk, triangles, vertex
/// indices and decoded mesh, from bytes and from a memory-mapped file,
/// with a cache too small to hold the model (so trees are evicted and
/// decoded again) and with one that holds nothing.
#[test]
fn out_of_core_answers_as_pre_loaded() {
    let mesh = mesh_of(Kind::Statue, 20_000);
    for (leaf, o) in leaves_and_maps() {
        let bvh = tree(&mesh, Layout::DepthFirst, leaf);
        let whole = HccOocBvh::encode_with(&bvh, &mesh, &o).unwrap();
        assert!(!whole.is_paged() && whole.cache_stats().is_none());
        let bytes = whole.file_bytes().to_vec();
        let decoded = whole.decoded_bytes();
        let expect = walk(&whole);
        let rays = test_rays(&mesh, leaf as u64, 300);
        let path = std::env::temp_dir().join(format!(
            "cbvh-hcc-ooc-paged-{}-{leaf}.hccz",
            std::process::id()
        ));
        whole.save(&path).unwrap();
        for budget in [decoded / 10, 1] {
            for mapped in [false, true] {
                let paged = if mapped {
                    HccOocBvh::open_with_budget(&path, budget).unwrap()
                } else {
                    HccOocBvh::from_bytes_with_budget(&bytes, budget).unwrap()
                };
                assert!(paged.is_paged(), "budget {budget} of {decoded}");
                assert!(paged.hcc().is_none());
                // Twice: the second walk meets cached and evicted trees.
                for _ in 0..2 {
                    assert!(
                        walk(&paged) == expect,
                        "{o:?}, leaves of {leaf}, budget {budget}"
                    );
                }
                // Rays through the i-HCCMesh's own traversal over the
                // paged trees: the generic traversal's hits, and the
                // pre-loaded model's.
                let mut st = cbvh::TraversalStats::default();
                let mut hits = 0;
                for ray in &rays {
                    let own = cbvh::query::closest_hit(&paged, ray, f32::INFINITY, &mut st);
                    hits += usize::from(own.is_some());
                    let generic =
                        cbvh::query::ray::closest_hit_generic(&paged, ray, f32::INFINITY, &mut st);
                    let pre = cbvh::query::closest_hit(&whole, ray, f32::INFINITY, &mut st);
                    assert_eq!(
                        hit_bits(own),
                        hit_bits(generic),
                        "{o:?}, leaves of {leaf}, {ray:?}"
                    );
                    assert_eq!(
                        hit_bits(own),
                        hit_bits(pre),
                        "{o:?}, leaves of {leaf}, {ray:?}"
                    );
                    for t_max in [f32::INFINITY, 1e-3] {
                        assert_eq!(
                            cbvh::query::any_hit(&paged, ray, t_max, &mut st),
                            cbvh::query::ray::any_hit_generic(&paged, ray, t_max, &mut st),
                            "{o:?}, leaves of {leaf}, {ray:?}"
                        );
                    }
                }
                assert!(hits > rays.len() / 4, "only {hits} hits");
                for id in (0..mesh.triangles.len() as u32).step_by(97) {
                    assert_eq!(paged.triangle(id), whole.triangle(id));
                    assert_eq!(paged.triangle_vertices(id), whole.triangle_vertices(id));
                }
                assert_eq!(paged.decoded_mesh(), whole.decoded_mesh());
                assert_eq!(paged.mass(), whole.mass());
                assert_eq!(paged.to_bytes(), bytes);
                paged.verify().expect("verify");
                let s = paged.cache_stats().unwrap();
                assert_eq!(s.budget_bytes, budget);
                assert!(s.cached_bytes <= budget, "{s:?}");
                let trees = whole.hcc().unwrap().tree_count() as u64;
                assert!(
                    s.decodes > trees,
                    "the budget evicted nothing: {s:?} for {trees} trees"
                );
                // A tenth of the model: most of it stays out of memory.
                if budget > 1 {
                    assert!(s.hits > 0, "{s:?}");
                    assert!(s.peak_live_bytes < decoded / 2, "{s:?} of {decoded}");
                }
            }
        }
        std::fs::remove_file(&path).ok();
    }
}

/// The registry runs `hcc-ooc` out of core: through `OpenOptions`'
/// budget, and through `with_cache_budget_of` (the sims' `hcc-ooc-10pct`).
#[test]
fn the_registry_opens_hcc_ooc_out_of_core() {
    let mesh = mesh_of(Kind::Statue, 10_000);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    let codec = AnyCodec::encode(CodecKind::HccOoc, &bvh, &mesh, &AnyOptions::default()).unwrap();
    let path = std::env::temp_dir().join(format!("cbvh-hcc-ooc-reg-{}.hccz", std::process::id()));
    codec.save(&path).unwrap();
    let small = OpenOptions {
        cache_budget_bytes: 4096,
        ..OpenOptions::default()
    };
    let opened = AnyCodec::open(&path, &small).unwrap();
    std::fs::remove_file(&path).ok();
    let out_of_core = |c: &AnyCodec| {
        c.header_fields()
            .iter()
            .any(|(k, v)| *k == "mode" && v.starts_with("out of core"))
    };
    assert!(out_of_core(&opened));
    assert_eq!(opened.decoded_mesh(), codec.decoded_mesh());
    let tenth = codec
        .with_cache_budget_of(&|d| d / 10)
        .expect("a cached codec")
        .unwrap();
    assert!(out_of_core(&tenth));
    assert_eq!(tenth.decoded_mesh(), codec.decoded_mesh());
    assert!(
        AnyOptions::default()
            .with_cache_budget(usize::MAX)
            .hcc_ooc
            .cache_budget_bytes
            == usize::MAX
    );
}

/// Out of core, a forged tree stream (checksums rewritten) is found by
/// `verify` and by nothing earlier than the tree's decoding; an unforged
/// flip in the streams fails `verify`'s checksum.
#[test]
fn out_of_core_verify_finds_damaged_trees() {
    let mesh = mesh_of(Kind::Statue, 5_000);
    let bytes = ooc_bytes(&mesh, 1, &OocOptions::default());
    // The streams section, from the section table.
    let (streams, len) = section(&bytes, 3);
    let mut flipped = bytes.clone();
    flipped[streams + len / 2] ^= 0x10;
    let paged = HccOocBvh::from_bytes_with_budget(&flipped, 1).expect("opening skips the streams");
    assert!(matches!(Codec::verify(&paged), Err(OocError::Format(_))));
    let mut forged = 0;
    let mut rng = Lcg(3);
    for _ in 0..40 {
        let mut b = bytes.clone();
        let at = streams + rng.next() as usize % len;
        b[at] ^= 1 << (rng.next() % 8);
        reframe(&mut b);
        let whole = HccBvh::from_ooc(&b).and_then(|h| Ok(h.verify()?));
        let paged = HccOocBvh::from_bytes_with_budget(&b, 1).and_then(|p| Codec::verify(&p));
        // Both modes judge the file alike.
        assert_eq!(whole.is_err(), paged.is_err(), "byte {at}");
        forged += usize::from(paged.is_err());
    }
    assert!(forged > 20, "only {forged} of 40 forged streams were found");
}

/// The high-level boxes are coded against their parents, and the trees'
/// starts and firsts are stored as counts: forged flips in those sections
/// (checksums rewritten) end in errors when the whole file is decoded (the
/// boxes or counts no longer match the trees), never in a panic, whether
/// the file is opened whole or out of core.
#[test]
fn forged_high_level_boxes_and_tree_tables_give_errors_not_panics() {
    let mesh = mesh_of(Kind::Statue, 20_000);
    let bytes = ooc_bytes(&mesh, 1, &OocOptions::default());
    // Tree starts, high-level boxes, tree firsts, from the section table.
    for k in [2, 6, 7] {
        let (at, len) = section(&bytes, k);
        assert!(len > 8, "{len} bytes in section {k}");
        let mut rng = Lcg(11);
        let mut noticed = 0;
        for _ in 0..60 {
            let mut b = bytes.clone();
            let flip = at + rng.next() as usize % len;
            b[flip] ^= 1 << (rng.next() % 8);
            reframe(&mut b);
            noticed += usize::from(HccBvh::from_ooc(&b).is_err());
            if let Ok(p) = HccOocBvh::from_bytes_with_budget(&b, 1) {
                let _ = Codec::verify(&p);
            }
        }
        // Only the last byte's padding bits go unread.
        assert!(
            noticed >= 50,
            "only {noticed} of 60 forged files were errors (section {k})"
        );
    }
}

/// A header that claims more low-level trees than a node handle numbers
/// (its checksum rewritten) is refused when the file is opened, whole or
/// out of core, before any tree is read.
#[test]
fn more_trees_than_handles_number_is_refused() {
    use cbvh::codec::hcc::node::MAX_TREES;
    let mesh = mesh_of(Kind::Statue, 2_000);
    let mut bytes = ooc_bytes(&mesh, 1, &OocOptions::default());
    // The header's counts start at byte 16: high-level nodes, then trees.
    bytes[20..24].copy_from_slice(&(MAX_TREES as u32 + 1).to_le_bytes());
    reframe(&mut bytes);
    for e in [
        HccBvh::from_ooc(&bytes).err().map(|e| e.to_string()),
        HccOocBvh::from_bytes_with_budget(&bytes, 1)
            .err()
            .map(|e| e.to_string()),
    ] {
        let e = e.expect("a file with too many trees was accepted");
        assert!(e.contains("low-level trees"), "{e}");
    }
}
