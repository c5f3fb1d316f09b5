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
use cbvh::codec::hcc::HccBvh;
use cbvh::codec::hcc::ooc::{HccOocBvh, OocError, OocOptions, StreamedBuild, encode_streamed};
use cbvh::codec::{AnyCodec, OpenOptions};
use cbvh::scene::{Kind, generate};
use common::*;

fn dir(name: &str) -> PathBuf {
    temp_dir_for("stream", name)
}

/// Builds `mesh` out of core in chunks of `chunk` triangles into `out`.
fn streamed(
    mesh: &Mesh,
    chunk: u64,
    leaf: usize,
    o: &OocOptions,
    out: &Path,
) -> Result<StreamedBuild, OocError> {
    through_chunks(mesh, chunk, leaf, out, |input, b| {
        encode_streamed(input, b, o, out, &|_, _, _| {})
    })
}

#[test]
fn streamed_files_answer_like_brute_force_and_hold_the_in_memory_triangles() {
    let d = dir("answers");
    let o = OocOptions::default();
    for (name, mesh) in streamed_meshes() {
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
            assert_eq!(hcc.vertex_error(), direct.vertex_error());
            let what = format!("{name} chunk {chunk}");
            let same = matches!(name, "same" | "flat");
            check_streamed_like_direct(&what, &ooc, &direct, &out, &mesh, chunk, r.chunks, same);
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn streamed_bytes_do_not_depend_on_threads() {
    let d = dir("threads");
    let mesh = generate(Kind::Statue, 6000, 4, &mut |_, _| {}).unwrap();
    check_same_bytes_in_1_2_3_threads(|threads| {
        let out = d.join(format!("t{threads}.hco"));
        streamed(&mesh, 700, 1, &OocOptions::default(), &out).unwrap();
        std::fs::read(&out).unwrap()
    });
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
    assert_no_file_left(&d);
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

/// The command line: `cbvh build FILE --codec hcc-ooc` goes out of core
/// when asked or when the model is over the budget, refuses other codecs
/// then, and a build killed half way leaves nothing under the output's
/// name; the next build removes what it left.
#[cfg(feature = "app")]
#[test]
fn the_command_line_builds_out_of_core_and_a_killed_build_leaves_no_file() {
    let d = dir("cli");
    let (ply, _) = cli_builds_out_of_core(&d, "hcc-ooc", &d.join("o.hco"));
    let p = ply.to_str().unwrap();
    // Over the budget, the other codecs refuse before any work, naming
    // the way out.
    let plain = d.join("p.bin");
    let (ok, _, stderr) = cbvh(&[
        "build",
        p,
        "--codec",
        "plain",
        "--memory-mib",
        "1",
        "-o",
        plain.to_str().unwrap(),
    ]);
    assert!(
        !ok && stderr.contains("only racbvh and hcc-ooc build out of core"),
        "{stderr}"
    );
    assert!(!plain.exists());
    let (ok, _, stderr) = cbvh(&["build", p, "--codec", "hcc-ooc", "--out-of-core"]);
    assert!(!ok && stderr.contains("-o"), "{stderr}");
    // Killed half way: no file under the name; the next build says what
    // it removed.
    let k = d.join("k.hco");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_cbvh"))
        .args([
            "build",
            p,
            "--codec",
            "hcc-ooc",
            "--out-of-core",
            "--chunk-triangles",
            "500",
            "-o",
        ])
        .arg(&k)
        .stderr(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let temp_of = |d: &Path| {
        std::fs::read_dir(d)
            .unwrap()
            .flatten()
            .any(|e| e.file_name().to_string_lossy().starts_with(".k.hco."))
    };
    let t0 = std::time::Instant::now();
    while !temp_of(&d) && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!k.exists(), "a killed build left its output");
    assert!(
        temp_of(&d),
        "the killed build's temporary directory is there to be found"
    );
    let (ok, _, stderr) = cbvh(&[
        "build",
        p,
        "--codec",
        "hcc-ooc",
        "--out-of-core",
        "-o",
        k.to_str().unwrap(),
    ]);
    assert!(
        ok && stderr.contains("left by a run that was stopped"),
        "{stderr}"
    );
    assert!(k.exists() && !temp_of(&d));
    // `cbvh gen` clears what a killed run of it left, too (a process id
    // no process has).
    let stale = d.join(".g.ply.tmp-4000000000-0");
    std::fs::write(&stale, b"half").unwrap();
    let g = d.join("g.ply");
    let (ok, _, stderr) = cbvh(&["gen", "robot", "--tris", "1000", "-o", g.to_str().unwrap()]);
    assert!(
        ok && stderr.contains("left by a run that was stopped"),
        "{stderr}"
    );
    assert!(g.exists() && !stale.exists());
    std::fs::remove_dir_all(&d).ok();
}

/// A drop test whose statue is a codec file built out of core uses the
/// file as stored for the runs of its codec (whole cache and a tenth),
/// builds the other runs from its decoded mesh, and places the base
/// around it: the same geometry in every run, so the same fall.
#[cfg(feature = "app")]
#[test]
fn a_drop_test_uses_an_out_of_core_file_as_stored() {
    let d = dir("drop");
    let mesh = generate(Kind::Statue, 6000, 2, &mut |_, _| {}).unwrap();
    let out = d.join("s.hco");
    let r = streamed(&mesh, 1500, 1, &OocOptions::default(), &out).unwrap();
    assert!(r.chunks >= 4);
    let json = d.join("drop.json");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_lucy-on-turbine"))
        .args([
            "--statue",
            out.to_str().unwrap(),
            "--turbine-tris",
            "2000",
            "--steps",
            "40",
        ])
        .args([
            "--shapes",
            "hcc-ooc,hcc-ooc-10pct,plain",
            "--contacts",
            "patches",
            "--json",
        ])
        .arg(&json)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("used as stored"), "{stderr}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["scene"]["dropped_triangles"], mesh.triangles.len() as u64);
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 3);
    let y = |r: &serde_json::Value| r["final_translation"][1].as_f64().unwrap();
    let size = v["scene"]["dropped_size"].as_f64().unwrap();
    assert!(size > 0.0);
    for r in runs {
        // It fell (the body starts where its mesh is) and the three
        // agree.
        assert!(y(r) < 0.0, "{}: did not fall", r["shape"]);
        assert!(
            (y(r) - y(&runs[2])).abs() < 0.02 * size,
            "{} ends at {} against plain's {}",
            r["shape"],
            y(r),
            y(&runs[2])
        );
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The registry's out-of-core hook: every codec that says it builds out
/// of core writes a file of its own kind that verifies, through
/// `AnyOptions::encode_streamed` (what `cbvh build --out-of-core` calls);
/// every other codec declines, writing nothing. At least the two streamed
/// encoders are there.
#[test]
fn the_registry_builds_out_of_core_exactly_the_codecs_that_say_so() {
    use cbvh::codec::{AnyOptions, CodecKind};
    let d = dir("registry");
    let mesh = generate(Kind::Statue, 2000, 3, &mut |_, _| {}).unwrap();
    let options = AnyOptions::default();
    let mut built = Vec::new();
    for &kind in CodecKind::ALL {
        let out = d.join(format!("{kind}.bin"));
        let made = through_chunks(&mesh, 300, 1, &out, |input, b| {
            options.encode_streamed(kind, input, b, &out, &|_, _, _| {})
        });
        match made {
            None => {
                assert!(!kind.builds_out_of_core(), "{kind} declined");
                assert!(!out.exists(), "{kind} wrote a file");
            }
            Some(r) => {
                let r = r.unwrap_or_else(|e| panic!("{kind}: {e}"));
                assert!(kind.builds_out_of_core(), "{kind} built but says it cannot");
                assert!(r.chunks > 1 && r.largest_chunk <= 300, "{kind}: {r:?}");
                let total: f64 = r.parts.iter().map(|p| p.1).sum();
                let bytes = std::fs::metadata(&out).unwrap().len() as f64;
                if kind == CodecKind::HccOoc {
                    // The o-HCCMesh's parts sum to its file.
                    assert_eq!(total, bytes, "{kind}");
                }
                assert!(total > 0.0 && total <= bytes, "{kind}: {total} of {bytes}");
                let codec = AnyCodec::open(&out, &OpenOptions::default())
                    .unwrap_or_else(|e| panic!("{kind}: {e}"));
                assert_eq!(codec.kind(), kind);
                assert_eq!(codec.triangle_count(), mesh.triangles.len());
                built.push(kind);
            }
        }
    }
    assert!(
        built.contains(&CodecKind::Racbvh) && built.contains(&CodecKind::HccOoc),
        "{built:?}"
    );
    std::fs::remove_dir_all(&d).ok();
}
