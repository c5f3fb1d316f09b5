//! Every codec's self-contained file: saved atomically, opened by content
//! (not extension) into a shape that needs no mesh, verified, giving the
//! same answers and mass properties as the codec built from the mesh; and
//! the CLI and sims using such files as a new user would.

use crate::common::{self, cbvh};

use std::path::PathBuf;
use std::process::Command;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::codec::{AnyCodec, AnyOptions, Codec, CodecFileError, CodecKind, OpenOptions};
use cbvh::parry::CbvhShape;
use cbvh::query::{self, RayCursor};
use cbvh::{Mesh, TraversalStats};
use common::*;
use parry3d::mass_properties::MassProperties;
use parry3d::math::Vector;
use parry3d::shape::Shape;

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("cbvh-files-{}-{name}", std::process::id()))
}

fn statue(tris: usize) -> Mesh {
    cbvh::scene::generate(cbvh::scene::Kind::Statue, tris, 3, &mut |_, _| {}).unwrap()
}

/// Every codec of the registry over `mesh`.
fn codecs(mesh: &Mesh) -> Vec<AnyCodec> {
    let bvh = build(mesh, &BuildOptions::default(), &|_, _| {}).unwrap();
    let options = AnyOptions {
        racbvh: RacOptions {
            cluster_nodes: 256,
            ..Default::default()
        },
        ..Default::default()
    };
    CodecKind::ALL
        .iter()
        .map(|&k| AnyCodec::encode(k, &bvh, mesh, &options).unwrap())
        .collect()
}

fn hits<C: RayCursor>(c: &C, mesh: &Mesh) -> Vec<Option<(u32, u32)>> {
    let mut stats = TraversalStats::default();
    test_rays(mesh, 5, 200)
        .iter()
        .map(|r| {
            query::closest_hit(c, r, f32::INFINITY, &mut stats).map(|h| (h.triangle, h.t.to_bits()))
        })
        .collect()
}

fn codec_hits(c: &AnyCodec, mesh: &Mesh) -> Vec<Option<(u32, u32)>> {
    cbvh::with_codec!(c, |c| hits(c, mesh))
}

/// `cbvh render FILE -o PNG` at 64 × 48, then `extra`: (success, stdout,
/// stderr).
fn render_small(file: &str, png: &std::path::Path, extra: &[&str]) -> (bool, String, String) {
    let size = ["--width", "64", "--height", "48"];
    let args = ["render", file, "-o", png.to_str().unwrap()];
    cbvh(&[&args[..], &size, extra].concat())
}

#[test]
fn every_codec_file_opens_by_content_into_a_shape_without_the_mesh() {
    let mesh = statue(3000);
    let parry = MassProperties::from_trimesh(
        1.0,
        &mesh
            .vertices
            .iter()
            .map(|v| Vector::from_array(*v))
            .collect::<Vec<_>>(),
        &mesh.triangles,
    );
    for codec in codecs(&mesh) {
        // A name that says nothing: the content decides.
        let path = temp(&format!("{}.bin", codec.name()));
        codec.save(&path).unwrap();
        let opened = AnyCodec::open(&path, &OpenOptions::default()).unwrap();
        assert_eq!(opened.name(), codec.name());
        let dm = codec.decoded_mesh();
        assert_eq!(opened.decoded_mesh(), dm);
        let want = codec_hits(&codec, &dm);
        assert_eq!(codec_hits(&opened, &dm), want);
        // Mass properties come from the file, equal to parry's own
        // integration of the original mesh (cbvh sums in f64, parry in
        // f32).
        let shape = CbvhShape::open(&path).unwrap();
        let m = shape.mass_properties(1.0);
        assert!(
            (m.mass() - parry.mass()).abs() <= 1e-5 * parry.mass()
                && (m.local_com - parry.local_com).length() <= 1e-6,
            "{}: {m:?} vs {parry:?}",
            codec.name()
        );
        assert_eq!(shape.triangle_count(), mesh.triangles.len());
        std::fs::remove_file(&path).unwrap();
    }
}

#[test]
fn opening_a_non_codec_file_or_a_missing_one_says_what_to_give() {
    let path = temp("mesh.rac");
    std::fs::write(&path, b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    let e = AnyCodec::open(&path, &OpenOptions::default()).unwrap_err();
    assert!(matches!(e, CodecFileError::NotACodecFile { .. }), "{e}");
    assert!(e.to_string().contains("cbvh build"), "{e}");
    std::fs::remove_file(&path).unwrap();
    let e = AnyCodec::open(&path, &OpenOptions::default()).unwrap_err();
    assert!(matches!(e, CodecFileError::Io(_)), "{e}");
}

#[test]
fn saving_over_a_mapped_file_is_atomic() {
    // The old file stays intact for whoever has it mapped: no SIGBUS, the
    // old tree still answers as before, and the new file is the new tree.
    let (a, b) = (statue(2000), soup(9, 1500, 3.0));
    let path = temp("mapped.rac");
    let opts = RacOptions {
        cluster_nodes: 256,
        ..Default::default()
    };
    let ra = RacBvh::encode(
        &build(&a, &BuildOptions::default(), &|_, _| {}).unwrap(),
        &a,
        &opts,
    )
    .unwrap();
    let rb = RacBvh::encode(
        &build(&b, &BuildOptions::default(), &|_, _| {}).unwrap(),
        &b,
        &opts,
    )
    .unwrap();
    ra.save(&path).unwrap();
    let mapped = RacBvh::open(&path, 1 << 12).unwrap();
    let da = ra.decoded_mesh();
    let before = hits(&mapped, &da);
    rb.save(&path).unwrap();
    mapped.clear_cache();
    mapped.verify().unwrap();
    assert_eq!(hits(&mapped, &da), before);
    assert_eq!(hits(&ra, &da), before);
    let now = RacBvh::open(&path, 1 << 20).unwrap();
    assert_eq!(now.decoded_mesh(), rb.decoded_mesh());
    drop(mapped);
    std::fs::remove_file(&path).unwrap();
}

/// The new user's path: build a file, then info, render, re-encode and a
/// sim, with no mesh file anywhere.
#[test]
fn cli_and_sims_use_codec_files_with_no_mesh_anywhere() {
    for codec in ["racbvh", "plain"] {
        let file = temp(&format!("cli-{codec}.rac"));
        let f = file.to_str().unwrap();
        let (ok, _, err) = cbvh(&[
            "build", "--gen", "statue", "--tris", "3000", "--codec", codec, "-o", f,
        ]);
        assert!(ok, "{err}");
        let (ok, out, err) = cbvh(&["info", f]);
        assert!(ok, "{err}");
        for want in [
            &format!("codec                 {codec}"),
            "B/triangle",
            "verify                ok",
        ] {
            assert!(out.contains(want), "{want:?} not in {out}");
        }
        let png = temp(&format!("cli-{codec}.png"));
        let (ok, out, err) = render_small(f, &png, &[]);
        assert!(ok, "{err}");
        assert!(out.contains(&format!("codec             {codec}")), "{out}");
        assert!(std::fs::metadata(&png).unwrap().len() > 100);
        // Re-encode into the other codec.
        let other = temp(&format!("cli-{codec}-other.bin"));
        let to = if codec == "plain" { "racbvh" } else { "plain" };
        let (ok, _, err) = cbvh(&["build", f, "--codec", to, "-o", other.to_str().unwrap()]);
        assert!(ok, "{err}");
        let (ok, out, err) = cbvh(&["info", other.to_str().unwrap(), "--json"]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["codec"], to);
        assert_eq!(v["verified"], true);
        let sim = Command::new(env!("CARGO_BIN_EXE_lucy-on-turbine"))
            .args([
                "--statue",
                f,
                "--turbine-tris",
                "2000",
                "--steps",
                "2",
                "--shapes",
                "plain",
            ])
            .output()
            .unwrap();
        assert!(
            sim.status.success(),
            "{}",
            String::from_utf8_lossy(&sim.stderr)
        );
        for p in [&file, &png, &other] {
            std::fs::remove_file(p).ok();
        }
    }
    // parry has no file; a damaged file is refused with a clear message.
    let (ok, _, err) = cbvh(&[
        "build", "--gen", "robot", "--codec", "parry", "-o", "/tmp/x",
    ]);
    assert!(!ok && err.contains("no cbvh file"), "{err}");
    let bad = temp("damaged.rac");
    let (ok, _, err) = cbvh(&[
        "build",
        "--gen",
        "statue",
        "--tris",
        "2000",
        "--codec",
        "racbvh",
        "-o",
        bad.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let mut bytes = std::fs::read(&bad).unwrap();
    // In the mesh sections (checked by verify): the triangles section's
    // last bytes, before the edge flags (section table at 184, entry 4).
    let flags_at = u64::from_le_bytes(bytes[280..288].try_into().unwrap()) as usize;
    bytes[flags_at - 100] ^= 4;
    std::fs::write(&bad, &bytes).unwrap();
    let (ok, _, err) = cbvh(&["info", bad.to_str().unwrap()]);
    assert!(!ok && err.contains("verify failed"), "{err}");
    let (ok, _, _) = cbvh(&["info", bad.to_str().unwrap(), "--no-verify"]);
    assert!(ok);
    std::fs::remove_file(&bad).ok();
}

/// `cbvh render` of an o-HCCMesh file reports its decode cache: with a
/// budget far below the model the trees are decoded as rays reach them
/// (decodes and hits counted, the budget as given); with the default
/// budget the whole file is decoded up front and there is no cache.
#[test]
fn cli_render_reports_the_decode_cache_of_an_out_of_core_file() {
    let file = temp("cli-render-cache.hccz");
    let f = file.to_str().unwrap();
    let (ok, _, err) = cbvh(&[
        "build", "--gen", "statue", "--tris", "20000", "--codec", "hcc-ooc", "-o", f,
    ]);
    assert!(ok, "{err}");
    let png = temp("cli-render-cache.png");
    // The render's output with `extra` arguments after the common ones.
    let render = |extra: &[&str]| {
        let (ok, out, err) = render_small(f, &png, extra);
        assert!(ok, "{err}");
        out
    };
    let json = |extra: &[&str]| {
        let out = render(&[extra, &["--json"]].concat());
        serde_json::from_str::<serde_json::Value>(&out).unwrap()
    };
    let small = json(&["--cache-mib", "0"]);
    let cache = &small["cache"];
    assert_eq!(cache["budget_bytes"], 0, "{small}");
    assert!(cache["decodes"].as_u64().unwrap() > 0, "{small}");
    assert!(
        cache["hits"].as_u64().unwrap() + cache["decodes"].as_u64().unwrap()
            >= small["primary_rays"].as_u64().unwrap() / 64,
        "{small}"
    );
    let whole = json(&[]);
    assert!(whole["cache"].is_null(), "{whole}");
    assert_eq!(whole["rays"], small["rays"]);
    let out = render(&["--cache-mib", "0"]);
    assert!(out.contains("decode cache      0.0 MiB budget"), "{out}");
    for p in [&file, &png] {
        std::fs::remove_file(p).ok();
    }
}

/// Bit flips in the mesh sections used to give silently wrong answers to a
/// caller who did not call `verify`: the first triangle a query reads now
/// checks the mesh sections once, so such a caller gets the original
/// answers or a panic that names the damage, never other triangles.
/// `cbvh build --clbvh-leaf-size M` reaches the CLBVH encoder (the file
/// records `M`, and a larger `M` makes fewer, fuller multi-leaf nodes and
/// a different file) and every `M` stays lossless: the files answer rays
/// exactly as plain over the same mesh.
/// Codec settings reach the codec through `--set CODEC.KEY=VALUE` and the
/// shorthand flags, the codec checks them before any work, and `--help`
/// lists every codec's keys from the registry.
#[test]
fn cli_codec_settings_come_from_set_and_the_shorthands() {
    let build = |extra: &[&str]| {
        let mut args = vec![
            "build", "--gen", "robot", "--tris", "2000", "--codec", "racbvh", "--json",
        ];
        args.extend_from_slice(extra);
        cbvh(&args)
    };
    let nodes = |out: &str| {
        let v: serde_json::Value = serde_json::from_str(out).unwrap();
        v["cluster_nodes"].as_u64().unwrap()
    };
    let (ok, out, err) = build(&["--set", "racbvh.cluster-nodes=1024"]);
    assert!(ok, "{err}");
    assert_eq!(nodes(&out), 1024);
    // A later setting wins over a shorthand.
    let (ok, out, err) = build(&[
        "--cluster-nodes",
        "512",
        "--set",
        "racbvh.cluster-nodes=256",
    ]);
    assert!(ok, "{err}");
    assert_eq!(nodes(&out), 256);
    let (ok, out, err) = build(&["--cluster-nodes", "512"]);
    assert!(ok, "{err}");
    assert_eq!(nodes(&out), 512);
    for (extra, want) in [
        (&["--set", "racbvh.cluster-nodes=100"][..], "power of two"),
        (
            &["--set", "racbvh.cluster-size=1024"],
            "racbvh has no setting",
        ),
        (&["--set", "zip.level=9"], "no codec named \"zip\""),
        (&["--set", "racbvh"], "is not CODEC.KEY=VALUE"),
    ] {
        let (ok, _, err) = build(extra);
        assert!(!ok && err.contains(want), "{extra:?}: {err}");
        assert!(!err.contains("generating"), "{extra:?} ran first: {err}");
    }
    // Settings of a codec not being built are not its business: hcc takes
    // 4-bit vertices although RACBVH could not.
    let (ok, _, err) = cbvh(&[
        "build",
        "--gen",
        "robot",
        "--tris",
        "2000",
        "--codec",
        "hcc",
        "--vertex-bits",
        "4",
    ]);
    assert!(ok, "{err}");
    let (ok, help, err) = cbvh(&["build", "--help"]);
    assert!(ok, "{err}");
    assert!(
        help.contains("racbvh: cluster-nodes, bits, tri-delta-threshold")
            && help.contains("clbvh: leaf-size, multi-leaf"),
        "{help}"
    );
}

/// The drop tests are subcommands of `cbvh` too, with the sims' flags.
#[test]
fn cbvh_runs_the_drop_tests_as_subcommands() {
    let (ok, help, err) = cbvh(&["--help"]);
    assert!(ok, "{err}");
    assert!(
        help.contains("lucy-on-turbine") && help.contains("robot-in-plant"),
        "{help}"
    );
    let json = temp("cbvh-drop.json");
    let (ok, _, err) = cbvh(&[
        "lucy-on-turbine",
        "--statue-tris",
        "1000",
        "--turbine-tris",
        "1000",
        "--steps",
        "2",
        "--shapes",
        "plain,racbvh",
        "--contacts",
        "patches",
        "--set",
        "racbvh.cluster-nodes=512",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    std::fs::remove_file(&json).ok();
    assert_eq!(v["runs"].as_array().unwrap().len(), 2, "{v}");
    let racbvh = v["scene"]["codec_options"]["racbvh"].as_str().unwrap();
    assert!(racbvh.contains("cluster_nodes: 512"), "{v}");
    let (ok, _, err) = cbvh(&["robot-in-plant", "--steps", "0"]);
    assert!(!ok && err.contains("--steps must be at least 1"), "{err}");
}

#[test]
fn cli_clbvh_leaf_size_changes_the_encoding_and_stays_lossless() {
    let mut files = Vec::new();
    for (codec, m) in [
        ("clbvh", "1"),
        ("clbvh", "8"),
        ("clbvh-compact", "1"),
        ("clbvh-compact", "8"),
    ] {
        let file = temp(&format!("cli-leaf-{codec}-{m}.clb"));
        let f = file.to_str().unwrap();
        let (ok, out, err) = cbvh(&[
            "build",
            "--gen",
            "statue",
            "--tris",
            "4000",
            "--codec",
            codec,
            "--clbvh-leaf-size",
            m,
            "--json",
            "-o",
            f,
        ]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["leaf_size"].to_string(), m, "{out}");
        files.push((file, v));
    }
    for pair in files.chunks(2) {
        let (small, large) = (&pair[0].1, &pair[1].1);
        assert!(
            large["multi_leaf_nodes"].as_u64() < small["multi_leaf_nodes"].as_u64(),
            "M=8 should make fewer multi-leaf nodes than M=1: {small} {large}"
        );
        assert_ne!(
            std::fs::read(&pair[0].0).unwrap(),
            std::fs::read(&pair[1].0).unwrap()
        );
    }
    let first = AnyCodec::open(&files[0].0, &OpenOptions::default()).unwrap();
    let mesh = first.decoded_mesh();
    let plain = cbvh::codec::plain::PlainBvh::new(
        &build(&mesh, &BuildOptions::default(), &|_, _| {}).unwrap(),
        &mesh,
    );
    let want = hits(&plain, &mesh);
    assert!(want.iter().any(Option::is_some));
    for (file, _) in &files {
        let c = AnyCodec::open(file, &OpenOptions::default()).unwrap();
        assert_eq!(codec_hits(&c, &mesh), want, "{}", file.display());
        std::fs::remove_file(file).unwrap();
    }
    // A canonical leaf larger than M is refused, not truncated.
    let (ok, _, err) = cbvh(&[
        "build",
        "--gen",
        "statue",
        "--tris",
        "4000",
        "--codec",
        "clbvh",
        "--leaf-size",
        "4",
        "--clbvh-leaf-size",
        "2",
    ]);
    assert!(!ok && err.contains("leaf size 2"), "{err}");
}

#[test]
fn skipping_verify_never_gives_triangles_from_damaged_mesh_bytes() {
    let mesh = statue(2000);
    let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).unwrap();
    let rac = RacBvh::encode(&bvh, &mesh, &RacOptions::default()).unwrap();
    let bytes = rac.to_bytes();
    let dm = rac.decoded_mesh();
    let want = hits(&rac, &dm);
    // The mesh sections come before the edge flags, which end the file;
    // their offsets are in the section table (bytes 184 + k × 24 of the
    // header).
    let mesh_at = u64::from_le_bytes(bytes[232..240].try_into().unwrap()) as usize;
    let flags_at = u64::from_le_bytes(bytes[280..288].try_into().unwrap()) as usize;
    let mut rng = Rng(17);
    let mut panics = 0;
    for _ in 0..60 {
        let mut bad = bytes.clone();
        let at = mesh_at + rng.below(flags_at - mesh_at);
        bad[at] ^= 1 << rng.below(8);
        let Ok(t) = RacBvh::from_bytes(&bad, 1 << 20) else {
            continue;
        };
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| hits(&t, &dm))) {
            Ok(got) => assert_eq!(got, want, "flip at {at} changed answers silently"),
            Err(e) => {
                let msg = e.downcast_ref::<String>().cloned().unwrap_or_default();
                assert!(msg.contains("damaged"), "{msg}");
                assert!(t.verify().is_err());
                panics += 1;
            }
        }
    }
    assert!(panics > 0);
}

/// A caterpillar tree (each inner node's right child is the next inner
/// node) makes the chain of local roots' parents as long as the tree has
/// clusters. Completing its deepest leaf from a cold cache used to recurse
/// once per cluster (a crafted 3.2 M-node chain overflowed the stack); it
/// is a loop now, and the whole chain decodes, verifies and answers.
#[test]
fn a_deep_chain_of_clusters_completes_without_recursion() {
    use cbvh::build::{CanonicalBvh, CanonicalNode, LEAF_FLAG, Layout};
    let n = 40_000usize; // triangles; 2n - 1 nodes, ~310 clusters of 256
    let vertices: Vec<[f32; 3]> = (0..n)
        .flat_map(|i| {
            let x = i as f32;
            [[x, 0.0, 0.0], [x + 0.5, 0.0, 0.0], [x, 1.0, 0.0]]
        })
        .collect();
    let triangles: Vec<[u32; 3]> = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mesh = Mesh::new(vertices, triangles);
    let leaf = |t: usize| CanonicalNode {
        min: [t as f32, 0.0, 0.0],
        max: [t as f32 + 0.5, 1.0, 0.0],
        a: t as u32,
        b: LEAF_FLAG | 1,
    };
    // Node 2k is inner k (covering triangles k..n), node 2k + 1 its left
    // leaf (triangle k); the last inner node's right child is the leaf of
    // triangle n - 1, at index 2n - 2.
    let mut nodes = Vec::with_capacity(2 * n - 1);
    let mut parents = Vec::with_capacity(2 * n - 1);
    for k in 0..n - 1 {
        let right = if k + 1 < n - 1 { 2 * k + 2 } else { 2 * n - 2 };
        nodes.push(CanonicalNode {
            min: [k as f32, 0.0, 0.0],
            max: [n as f32 - 0.5, 1.0, 0.0],
            a: (2 * k + 1) as u32,
            b: right as u32,
        });
        parents.push(if k == 0 { u32::MAX } else { (2 * k - 2) as u32 });
        nodes.push(leaf(k));
        parents.push((2 * k) as u32);
    }
    nodes.push(leaf(n - 1));
    parents.push((2 * n - 4) as u32);
    let bvh = CanonicalBvh {
        nodes,
        parents,
        leaf_triangles: (0..n as u32).collect(),
        layout: Layout::DepthFirst,
        max_leaf_triangles: 1,
    };
    let opts = RacOptions {
        cluster_nodes: 256,
        vertex_bits: None,
        ..Default::default()
    };
    let rac = RacBvh::encode(&bvh, &mesh, &opts).unwrap();
    let cold = RacBvh::from_bytes(&rac.to_bytes(), 1 << 30).unwrap();
    // Run on a thread with a small stack: one frame per cluster would not fit.
    std::thread::Builder::new()
        .stack_size(64 << 10)
        .spawn(move || {
            let last = (2 * n - 2) as u32;
            let b = cold.try_bv(last).unwrap();
            assert!(b.min.x <= (n - 1) as f32 && b.max.x >= n as f32 - 0.5);
            cold.verify().unwrap();
        })
        .unwrap()
        .join()
        .unwrap();
}

/// Issue 33: `cbvh gen`, `build` and `render` check a generator's
/// `--tris` and the output's place before any work, naming the flag; a
/// refused output's missing directory is not created, in memory or out of
/// core; and `--chunk-triangles` is bounded.
#[test]
fn cli_checks_counts_outputs_and_chunks_before_any_work() {
    let d = temp_dir_for("files", "flags");
    let at = |name: &str| d.join(name).to_str().unwrap().to_string();
    let (ply, obj, png) = (at("g.ply"), at("g.obj"), at("g.png"));
    // A generator's count out of its range, named with the range.
    for (args, want) in [
        (
            vec!["gen", "statue", "--tris", "0", "-o", &ply],
            "--tris 0: the statue generator makes 1000 to 1000000000 triangles",
        ),
        (
            vec!["gen", "statue", "--tris", "1500000000", "-o", &ply],
            "--tris 1500000000: the statue generator makes 1000 to 1000000000",
        ),
        (
            vec!["gen", "statue", "--tris", "300000000", "-o", &obj],
            "--tris 300000000: the statue generator makes 1000 to 200000000",
        ),
        (
            vec!["gen", "isosurface", "--tris", "300000000", "-o", &ply],
            "--tris 300000000: the isosurface generator makes 1000 to 200000000",
        ),
        (
            vec!["build", "--gen", "robot", "--tris", "999"],
            "--tris 999: the robot generator",
        ),
        (
            vec!["render", "--gen", "plant", "--tris", "0", "-o", &png],
            "--tris 0: the plant generator",
        ),
        (vec!["gen", "robot", "-o", &at("g.stl")], "--output"),
        (
            vec![
                "build",
                "--gen",
                "robot",
                "--tris",
                "1000",
                "-o",
                d.to_str().unwrap(),
            ],
            "it is a directory",
        ),
    ] {
        let e = cbvh_refuses_within(&args, 20);
        assert!(e.contains(want), "{args:?}: {e}");
    }
    // An output in a missing directory: refused before generating (a
    // 3 M-triangle statue would take a while), naming -o's flag, and the
    // directory is not made.
    let missing = d.join("no");
    let inside = |name: &str| {
        missing
            .join("such")
            .join(name)
            .to_str()
            .unwrap()
            .to_string()
    };
    let mut refused: Vec<Vec<String>> = vec![
        vec!["gen", "statue", "--tris", "3000000", "-o", &inside("s.ply")],
        vec![
            "build",
            "--gen",
            "statue",
            "--tris",
            "3000000",
            "-o",
            &inside("s.plain"),
        ],
        vec![
            "render",
            "--gen",
            "statue",
            "--tris",
            "3000000",
            "-o",
            &inside("s.png"),
        ],
    ]
    .into_iter()
    .map(|a| a.into_iter().map(String::from).collect())
    .collect();
    // Out of core (every codec that builds so), which used to make the
    // output's directories and report success.
    cbvh::mesh::save(&statue(100_000), &ply).unwrap();
    let cbvh_out = inside("s.cbvh");
    for codec in CodecKind::ALL.iter().filter(|k| k.builds_out_of_core()) {
        let args = out_of_core_build(&ply, codec.name(), &cbvh_out);
        refused.push(args.into_iter().map(String::from).collect());
    }
    for args in &refused {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let e = cbvh_refuses_within(&args, 20);
        assert!(
            e.contains("--output") && e.contains("does not exist"),
            "{args:?}: {e}"
        );
        assert!(!missing.exists(), "{args:?} made {}", missing.display());
    }
    // --chunk-triangles: at least 1, numbered by u32, and a chunk that fits
    // the memory budget.
    let out = at("c.hcc");
    for (extra, want) in [
        (&["--chunk-triangles", "0"][..], "'--chunk-triangles <N>'"),
        (
            &["--chunk-triangles", "4294967296"],
            "'--chunk-triangles <N>'",
        ),
        (
            &["--chunk-triangles", "1000000", "--memory-mib", "23"],
            "--chunk-triangles 1000000: building a chunk of",
        ),
    ] {
        let mut args = vec![
            "build",
            &ply,
            "--codec",
            "hcc-ooc",
            "--out-of-core",
            "-o",
            &out,
        ];
        args.extend_from_slice(extra);
        let e = cbvh_refuses_within(&args, 20);
        assert!(e.contains(want), "{extra:?}: {e}");
        assert!(!std::path::Path::new(&out).exists());
    }
    // A build that is not chunked: --chunk-triangles is refused, not
    // ignored.
    let args = [
        "build",
        &ply,
        "--codec",
        "racbvh",
        "--chunk-triangles",
        "500",
        "-o",
        &out,
    ];
    let e = cbvh_refuses_within(&args, 20);
    assert!(
        e.contains("--chunk-triangles 500 sizes an out-of-core build's chunks")
            && e.contains("add --out-of-core"),
        "{e}"
    );
    assert!(!std::path::Path::new(&out).exists());
    std::fs::remove_dir_all(&d).ok();
}
