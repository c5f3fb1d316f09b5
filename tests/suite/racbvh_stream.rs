//! The out-of-core RACBVH build (`build::chunked` + `racbvh::encode_streamed`):
//! small models forced through it with tiny chunks (a triangle a chunk,
//! chunk boundaries through the mesh, flat and collinear chunks, clusters
//! spanning many chunks) give files that pass `verify`, whose every query
//! equals brute force over their decoded mesh, whose triangles are the
//! in-memory build's (same grid), whose edge flags are the ones the whole
//! mesh gives, and whose bytes do not depend on the thread count.

use std::path::{Path, PathBuf};

use crate::common;

use cbvh::Mesh;
use cbvh::build::{BuildOptions, build};
use cbvh::codec::racbvh::{RacBvh, RacError, RacOptions, StreamedBuild, encode_streamed};
use cbvh::scene::{Kind, generate};
use common::*;

fn dir(name: &str) -> PathBuf {
    temp_dir_for("racstream", name)
}

/// Builds `mesh` out of core in chunks of `chunk` triangles into `out`.
fn streamed(
    mesh: &Mesh,
    chunk: u64,
    leaf: usize,
    o: &RacOptions,
    out: &Path,
) -> Result<StreamedBuild, RacError> {
    through_chunks(mesh, chunk, leaf, out, |input, b| {
        encode_streamed(input, b, o, out, &|_, _, _| {})
    })
}

/// [`streamed_meshes`], and two whose chunks are degenerate.
fn meshes() -> Vec<(&'static str, Mesh)> {
    // Every chunk flat (z = 0), and chunks along a line (below).
    let (mut plane, mut line) = (Vec::new(), Vec::new());
    for i in 0..30 {
        for j in 0..20 {
            plane.push([i as f32, j as f32, 0.0]);
        }
    }
    let mut pt = Vec::new();
    for i in 0..29u32 {
        for j in 0..19u32 {
            let v = i * 20 + j;
            pt.push([v, v + 20, v + 1]);
            pt.push([v + 1, v + 20, v + 21]);
        }
    }
    // Parallel triangles whose centroids lie on the x axis: every split
    // is on x, every one-triangle chunk is flat.
    for i in 0..300 {
        let x = i as f32 * 0.1;
        line.extend([[x, -1.0, -1.0], [x, 2.0, -1.0], [x, -1.0, 2.0]]);
    }
    let lt = (0..300u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    let mut v = streamed_meshes();
    v.push(("plane", Mesh::new(plane, pt)));
    v.push(("line", Mesh::new(line, lt)));
    v
}

#[test]
fn streamed_racbvh_files_verify_answer_like_brute_force_and_hold_the_in_memory_triangles() {
    let d = dir("answers");
    for (name, mesh) in meshes() {
        let n = mesh.triangles.len() as u64;
        // One triangle a chunk (256-node clusters spanning many chunks),
        // chunk boundaries through the middle, several triangles a leaf,
        // one chunk.
        for (chunk, leaf, cluster_nodes) in
            [(1, 1, 256), (97, 1, 256), (n / 2 + 1, 4, 4096), (n, 1, 256)]
        {
            let o = RacOptions {
                cluster_nodes,
                ..Default::default()
            };
            let what = format!("{name} chunk {chunk} leaf {leaf}");
            let out = d.join(format!("{name}-{chunk}-{leaf}.rac"));
            let r =
                streamed(&mesh, chunk, leaf, &o, &out).unwrap_or_else(|e| panic!("{what}: {e}"));
            let bytes = std::fs::read(&out).unwrap();
            assert_eq!(r.bytes as usize, bytes.len(), "{what}");
            let parts: f64 = r.parts().iter().map(|p| p.1).sum();
            assert!(parts <= bytes.len() as f64, "{what}");
            let rac =
                RacBvh::from_bytes(&bytes, 64 << 20).unwrap_or_else(|e| panic!("{what}: {e}"));
            rac.verify().unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(rac.node_count() as u64, r.nodes, "{what}");
            assert_eq!(rac.cluster_count() as u64, r.clusters, "{what}");
            let dm = rac.decoded_mesh();
            check_structure(&rac, &dm);
            check_queries(&rac, &dm, chunk);
            // The same triangles as the in-memory build's (one grid).
            let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).unwrap();
            let direct = RacBvh::encode(&bvh, &mesh, &o).unwrap();
            let same = matches!(name, "same" | "flat");
            check_streamed_like_direct(&what, &rac, &direct, &out, &mesh, chunk, r.chunks, same);
            // The node cache's path.
            let small = RacBvh::open(&out, 4096).unwrap();
            check_queries(&small, &dm, chunk + 1);
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn streamed_racbvh_bytes_do_not_depend_on_threads() {
    let d = dir("threads");
    let mesh = generate(Kind::Statue, 6000, 4, &mut |_, _| {}).unwrap();
    let o = RacOptions {
        cluster_nodes: 256,
        ..Default::default()
    };
    check_same_bytes_in_1_2_3_threads(|threads| {
        let out = d.join(format!("t{threads}.rac"));
        streamed(&mesh, 700, 1, &o, &out).unwrap();
        std::fs::read(&out).unwrap()
    });
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_model_without_triangles_and_bad_options_are_handled_and_leave_nothing() {
    let d = dir("edge");
    // No triangles: a valid empty file.
    let empty = Mesh::new(vec![[0.0; 3], [1.0; 3]], Vec::new());
    let out = d.join("empty.rac");
    let r = streamed(&empty, 10, 1, &RacOptions::default(), &out).unwrap();
    assert_eq!(r.chunks, 0);
    let rac = RacBvh::open(&out, 1 << 20).unwrap();
    rac.verify().unwrap();
    assert_eq!(rac.decoded_mesh().triangles.len(), 0);
    std::fs::remove_file(&out).unwrap();
    // Options the codec refuses: an error, no output, no temporary file.
    let mesh = generate(Kind::Robot, 1000, 1, &mut |_, _| {}).unwrap();
    let bad = RacOptions {
        cluster_nodes: 100,
        ..Default::default()
    };
    let e = streamed(&mesh, 100, 1, &bad, &out).unwrap_err();
    assert!(e.to_string().contains("cluster_nodes"), "{e}");
    // A leaf size the builder refuses fails in the first chunk.
    let e = streamed(&mesh, 100, 0, &RacOptions::default(), &out).unwrap_err();
    assert!(e.to_string().contains("chunk 0"), "{e}");
    assert!(!out.exists());
    assert_no_file_left(&d);
    std::fs::remove_dir_all(&d).ok();
}

/// The command line: `cbvh build FILE --codec racbvh` goes out of core
/// when asked or when the model is over the budget; a truncated input
/// file is a clear error and leaves nothing.
#[cfg(feature = "app")]
#[test]
fn the_command_line_builds_racbvh_out_of_core() {
    let d = dir("cli");
    let (ply, v) = cli_builds_out_of_core(&d, "racbvh", &d.join("o.rac"));
    assert_eq!(v["codec"], "racbvh");
    let p = ply.to_str().unwrap();
    // A truncated input: the error names the face; no output, no
    // temporary directory.
    let full = std::fs::read(&ply).unwrap();
    std::fs::write(&ply, &full[..full.len() - 1000]).unwrap();
    let t = d.join("t.rac");
    let (ok, _, stderr) = cbvh(&[
        "build",
        p,
        "--codec",
        "racbvh",
        "--out-of-core",
        "-o",
        t.to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("face"), "{stderr}");
    assert!(!t.exists());
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".t.rac"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    std::fs::remove_dir_all(&d).ok();
}
