//! The out-of-core o-HCCMesh build (`build::chunked` + `encode_streamed`):
//! small models forced through it with tiny chunks give files whose every
//! query equals brute force over their decoded mesh, whose triangles are
//! the in-memory build's (same grid), whose edge flags are the ones the
//! whole mesh gives, and whose bytes do not depend on the thread count.

use std::path::{Path, PathBuf};

use crate::common;

use cbvh::Mesh;
use cbvh::build::chunked::{ChunkError, ChunkOptions, ChunkedMesh};
use cbvh::build::{BuildOptions, build};
use cbvh::codec::common::edges;
use cbvh::codec::hcc::HccBvh;
use cbvh::codec::hcc::ooc::{HccOocBvh, OocError, OocOptions, StreamedBuild, encode_streamed};
use cbvh::codec::{AnyCodec, Codec, OpenOptions};
use cbvh::scene::{Kind, generate};
use common::*;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cbvh-stream-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Builds `mesh` out of core in chunks of `chunk` triangles into `out`.
fn streamed(
    mesh: &Mesh,
    chunk: u64,
    leaf: usize,
    o: &OocOptions,
    out: &Path,
) -> Result<StreamedBuild, OocError> {
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
    let b = BuildOptions {
        max_leaf_triangles: leaf,
        ..Default::default()
    };
    let r = encode_streamed(&input, &b, o, out, &|_, _, _| {});
    drop(input);
    assert!(!temp.exists(), "the temporary directory is removed");
    r
}

/// Each triangle as its corners' position bits, sorted: a mesh's
/// triangles whatever their order.
fn triangle_set(m: &Mesh) -> Vec<[[u32; 3]; 3]> {
    let mut v: Vec<_> = m
        .triangles
        .iter()
        .map(|t| t.map(|i| m.vertices[i as usize].map(f32::to_bits)))
        .collect();
    v.sort_unstable();
    v
}

fn meshes() -> Vec<(&'static str, Mesh)> {
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

#[test]
fn streamed_files_answer_like_brute_force_and_hold_the_in_memory_triangles() {
    let d = dir("answers");
    let o = OocOptions::default();
    for (name, mesh) in meshes() {
        let n = mesh.triangles.len() as u64;
        // One triangle a chunk, chunk boundaries through the middle, one
        // chunk.
        for (chunk, leaf) in [(1, 1), (97, 1), (n / 2 + 1, 4), (n, 1)] {
            let out = d.join(format!("{name}-{chunk}-{leaf}.hco"));
            let r = streamed(&mesh, chunk, leaf, &o, &out).unwrap();
            let bytes = std::fs::read(&out).unwrap();
            assert_eq!(r.sizes.total() as usize, bytes.len(), "{name} {chunk}");
            let ooc = HccOocBvh::from_bytes(&bytes)
                .unwrap_or_else(|e| panic!("{name} chunk {chunk}: {e}"));
            let hcc = ooc.hcc().expect("pre-loaded");
            hcc.verify().unwrap();
            let dm = hcc.decoded_mesh();
            check_structure(&ooc, &dm);
            check_queries(&ooc, &dm, chunk);
            // The same triangles as the in-memory build's (one grid).
            let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).unwrap();
            let direct = HccBvh::encode_with(&bvh, &mesh, &o.hcc()).unwrap();
            assert_eq!(
                triangle_set(&dm),
                triangle_set(&direct.decoded_mesh()),
                "{name} chunk {chunk}"
            );
            assert_eq!(hcc.vertex_error(), direct.vertex_error());
            // The edge flags the whole mesh gives, counters included.
            let want = edges::of_cursor(&ooc);
            let got = ooc.edge_flags();
            assert_eq!(got.as_slice(), want.as_slice(), "{name} chunk {chunk}");
            assert_eq!(
                (got.boundary_edges, got.flat_edges, got.misoriented_edges),
                (want.boundary_edges, want.flat_edges, want.misoriented_edges),
                "{name} chunk {chunk}"
            );
            // Mass within rounding of the in-memory file's.
            let (a, b) = (ooc.mass(), direct.mass());
            assert!(
                (a.mass - b.mass).abs() <= 1e-4 * b.mass.abs().max(1e-9),
                "{name}: {a:?} vs {b:?}"
            );
            // (Identical centroids cannot be split.)
            if chunk == 1 && n > 1 && !matches!(name, "same" | "flat") {
                assert!(r.chunks > 1, "{name}: {} chunks", r.chunks);
            }
            // Out of core, through the registry, with a small cache.
            let paged = AnyCodec::open(
                &out,
                &OpenOptions {
                    cache_budget_bytes: 4096,
                    ..Default::default()
                },
            )
            .unwrap();
            assert_eq!(paged.triangle_count(), mesh.triangles.len());
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn streamed_bytes_do_not_depend_on_threads() {
    let d = dir("threads");
    let mesh = generate(Kind::Statue, 6000, 4, &mut |_, _| {}).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let out = d.join(format!("t{threads}.hco"));
        pool.install(|| streamed(&mesh, 700, 1, &OocOptions::default(), &out))
            .unwrap();
        std::fs::read(&out).unwrap()
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn id_maps_are_refused_and_leave_nothing() {
    let d = dir("ids");
    let mesh = generate(Kind::Robot, 1000, 1, &mut |_, _| {}).unwrap();
    let out = d.join("x.hco");
    let o = OocOptions {
        triangle_ids: true,
        ..OocOptions::default()
    };
    let e = streamed(&mesh, 100, 1, &o, &out).unwrap_err();
    assert!(e.to_string().contains("triangle-ids"), "{e}");
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(&d).unwrap().count(),
        0,
        "no temporary file"
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn bad_and_truncated_input_files_give_clear_errors_and_leave_nothing() {
    let d = dir("input");
    let mesh = generate(Kind::Statue, 2000, 1, &mut |_, _| {}).unwrap();
    let ply = d.join("m.ply");
    cbvh::mesh::save(&mesh, &ply).unwrap();
    let full = std::fs::read(&ply).unwrap();
    let temp = d.join("t");
    let chunks = |path: &Path| {
        ChunkedMesh::from_path(
            path,
            &ChunkOptions {
                chunk_triangles: 300,
                temp_dir: temp.clone(),
            },
            &|_, _, _| {},
        )
    };
    // The whole file reads into chunks holding every triangle.
    let c = chunks(&ply).unwrap();
    assert_eq!(c.triangle_count(), mesh.triangles.len() as u64);
    assert_eq!(c.vertices, mesh.vertices);
    drop(c);
    // Cut in the middle of the faces: the error names the face.
    std::fs::write(&ply, &full[..full.len() - 1000]).unwrap();
    let e = chunks(&ply).unwrap_err();
    assert!(matches!(e, ChunkError::Mesh(_)), "{e}");
    assert!(e.to_string().contains("face"), "{e}");
    assert!(!temp.exists(), "the temporary directory is removed");
    // A face naming a vertex past the end.
    let mut bad = full.clone();
    let n = bad.len();
    bad[n - 4..].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(&ply, &bad).unwrap();
    let e = chunks(&ply).unwrap_err();
    assert!(e.to_string().contains("vertex"), "{e}");
    assert!(!temp.exists());
    std::fs::remove_dir_all(&d).ok();
}
