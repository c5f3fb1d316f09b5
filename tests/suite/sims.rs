//! The drop-test binaries as a user runs them: small generated meshes, a
//! few steps, every flag that changes the run, and the JSON they write.

use std::path::PathBuf;
use std::process::Command;

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("cbvh-sims-{}-{name}", std::process::id()))
}

fn run(bin: &str, args: &[&str]) -> (bool, String) {
    let out = Command::new(bin).args(args).output().expect("run the sim");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

const LUCY: &str = env!("CARGO_BIN_EXE_lucy-on-turbine");
const ROBOT: &str = env!("CARGO_BIN_EXE_robot-in-plant");

/// `lucy-on-turbine`'s meshes in the small runs: 1000 triangles each.
const SMALL_LUCY: [&str; 4] = ["--statue-tris", "1000", "--turbine-tris", "1000"];

/// `robot-in-plant`'s meshes in the small runs: a 1000-triangle robot in
/// a 2000-triangle plant.
const SMALL_ROBOT: [&str; 4] = ["--robot-tris", "1000", "--plant-tris", "2000"];

/// The flags `base`, then `extra`.
fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
    base.iter().chain(extra).copied().collect()
}

/// `lucy-on-turbine` with `tris`-triangle meshes (statue and turbine) for
/// `steps` steps, then `extra` flags.
fn lucy(tris: &str, steps: &str, extra: &[&str]) -> (bool, String) {
    let meshes = ["--statue-tris", tris, "--turbine-tris", tris];
    run(LUCY, &[&meshes[..], &["--steps", steps], extra].concat())
}

/// `lucy-on-turbine` on a small scene (1000-triangle meshes, one step)
/// with `extra` flags.
fn small_lucy(extra: &[&str]) -> (bool, String) {
    lucy("1000", "1", extra)
}

/// `robot-in-plant`'s flags for the small scene ([`SMALL_ROBOT`]) run for
/// one step, then `extra`.
fn small_robot<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    [&SMALL_ROBOT[..], &["--steps", "1"], extra].concat()
}

/// The JSON report a sim wrote to `json` after it succeeded (`ok`, else
/// the test fails with its `stderr`); the file is removed.
fn report(ok: bool, stderr: &str, json: &std::path::Path) -> serde_json::Value {
    assert!(ok, "{stderr}");
    let v = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    std::fs::remove_file(json).ok();
    v
}

#[test]
fn lucy_on_turbine_runs_with_threads_and_cluster_size_and_writes_json() {
    let json = temp("lucy.json");
    let (ok, stderr) = lucy(
        "3000",
        "40",
        &[
            "--shapes",
            "plain,racbvh",
            "--threads",
            "1",
            "--cluster-nodes",
            "256",
            "--json",
            json.to_str().unwrap(),
        ],
    );
    let v = report(ok, &stderr, &json);
    assert_eq!(v["scene"]["threads"], 1);
    // Each codec's options as used, by its name (plain has none).
    let options = v["scene"]["codec_options"].as_object().unwrap();
    assert_eq!(options.keys().collect::<Vec<_>>(), ["plain", "racbvh"]);
    let racbvh = options["racbvh"].as_str().unwrap();
    assert!(racbvh.contains("cluster_nodes: 256"), "{racbvh}");
    let runs = v["runs"].as_array().unwrap();
    let shapes: Vec<&str> = runs.iter().map(|r| r["shape"].as_str().unwrap()).collect();
    // Bare cbvh names run in both contact modes by default.
    assert_eq!(shapes, ["plain", "plain-pairs", "racbvh", "racbvh-pairs"]);
    let size = v["scene"]["dropped_size"].as_f64().unwrap();
    let get = |name: &str| runs.iter().find(|r| r["shape"] == name).unwrap();
    let y = |name: &str| get(name)["final_translation"][1].as_f64().unwrap();
    let u = |r: &serde_json::Value, k: &str| r[k].as_u64().unwrap();
    for r in runs {
        for key in ["median", "mean", "p95", "max"] {
            assert!(r["narrow_phase_ms"][key].as_f64().unwrap() > 0.0, "{r}");
            assert!(r["interference_ms"][key].as_f64().unwrap() > 0.0, "{r}");
        }
        assert_eq!(r["fallback_bvh_built"], false);
        assert!(r["bytes_per_triangle"].as_f64().unwrap() > 0.0);
        // 40 steps from just above the turbine: the statue lands.
        assert!(r["steps_in_contact"].as_u64().unwrap() > 0, "{r}");
        assert!(u(r, "max_contact_pairs") > 0);
        let state = r["final_state"].as_str().unwrap();
        assert!(
            [
                "resting",
                "moving",
                "fell off the base",
                "tunnelled through the base"
            ]
            .contains(&state),
            "{state}"
        );
        // 40 steps: still on the turbine.
        assert!(!state.contains("base"), "{r}");
        if r["contact_mode"] == "patches" {
            // Patches: fewer manifolds than triangle pairs, at most four
            // points each.
            assert!(u(r, "max_manifolds") < u(r, "max_contact_pairs"), "{r}");
            assert!(
                u(r, "max_contact_points") <= 4 * u(r, "max_manifolds"),
                "{r}"
            );
        } else {
            assert_eq!(r["contact_mode"], "pairs");
            assert_eq!(u(r, "max_manifolds"), u(r, "max_contact_pairs"), "{r}");
        }
    }
    // The modes and the codecs land the statue at about the same height.
    for (a, b) in [
        ("plain", "plain-pairs"),
        ("racbvh", "racbvh-pairs"),
        ("plain", "racbvh"),
    ] {
        assert!(
            (y(a) - y(b)).abs() < 0.05 * size,
            "{a} at {}, {b} at {} (size {size})",
            y(a),
            y(b)
        );
    }
    // Patches give the solver far fewer points than the pairs mode.
    assert!(u(get("plain"), "max_contact_points") < u(get("plain-pairs"), "max_contact_points"));
}

#[test]
fn contact_modes_follow_the_flag_and_the_shape_names() {
    let json = temp("modes.json");
    let (ok, stderr) = lucy(
        "1000",
        "2",
        &[
            "--contacts",
            "patches",
            "--shapes",
            "parry,plain,racbvh-pairs",
            "--json",
            json.to_str().unwrap(),
        ],
    );
    let v = report(ok, &stderr, &json);
    let modes: Vec<(&str, &str)> = v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["shape"].as_str().unwrap(),
                r["contact_mode"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        modes,
        [
            ("parry", "parry"),
            ("plain", "patches"),
            ("racbvh-pairs", "pairs")
        ]
    );
    // Both modes for `plain` already include `plain-pairs`: named again, it
    // runs once.
    let json = temp("modes_dedup.json");
    let (ok, stderr) = small_lucy(&[
        "--shapes",
        "plain,plain-pairs",
        "--json",
        json.to_str().unwrap(),
    ]);
    let v = report(ok, &stderr, &json);
    let names: Vec<&str> = v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["shape"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["plain", "plain-pairs"]);
    let (ok, stderr) = run(LUCY, &["--steps", "1", "--shapes", "parry-pairs"]);
    assert!(!ok);
    assert!(stderr.contains("no contact modes"), "{stderr}");
}

#[test]
fn sims_reject_bad_flags_with_a_message() {
    let (ok, stderr) = run(ROBOT, &["--threads", "0", "--steps", "1"]);
    assert!(!ok);
    assert!(stderr.contains("--threads must be at least 1"), "{stderr}");
    // Bounded before any work: neither a capacity overflow nor a pool of
    // a hundred thousand threads.
    for (flag, value) in [("--steps", "18446744073709551615"), ("--threads", "100000")] {
        let (ok, stderr) = run(LUCY, &with(&SMALL_LUCY, &[flag, value]));
        assert!(!ok, "{flag} {value} accepted");
        assert!(
            stderr.contains(&format!("{flag} {value} is more than")),
            "{stderr}"
        );
    }
    let (ok, stderr) = small_lucy(&["--shapes", "racbvh", "--cluster-nodes", "100"]);
    assert!(!ok);
    assert!(stderr.contains("power of two"), "{stderr}");
}

/// Every flag is checked before the first shape runs: each of these used to
/// fail late (after the runs), run with nonsense, or be impossible to give.
#[test]
fn sims_check_every_flag_before_the_first_run() {
    let reject = |extra: &[&str], want: &str| {
        let (ok, stderr) = run(ROBOT, &small_robot(extra));
        assert!(!ok, "{extra:?} was accepted");
        assert!(stderr.contains(want), "{extra:?}: {stderr}");
        // Rejected before any mesh was made or any shape ran.
        assert!(
            !stderr.contains("dropping"),
            "{extra:?} ran first: {stderr}"
        );
    };
    reject(&["--width-fraction", "0"], "--width-fraction 0 must be");
    reject(&["--width-fraction", "NaN"], "--width-fraction NaN must be");
    reject(&["--width-fraction", "1e30"], "at most 1000 (0.5");
    reject(&["--gap", "-1"], "--gap -1 must be");
    reject(&["--gap", "1e30"], "must be 0 to 1000");
    reject(
        &["--offset", "1e30,0"],
        "must be two numbers from -1000 to 1000",
    );
    reject(&["--cluster-nodes", "3"], "power of two");
    reject(&["--offset", "0.1"], "is not X,Z");
    reject(&["--offset", "nan,0"], "not a finite number");
    reject(
        &["--plot", "/nonexistent-dir/x.png"],
        "--plot /nonexistent-dir/x.png",
    );
    reject(&["--json", "/nonexistent-dir/x.json"], "cannot write there");
    reject(&["--subdivide", "7"], "--subdivide 7 multiplies");
    let json = temp("offset.json");
    // The small scene with `extra` flags, running `shapes`: its report.
    let report_of = |extra: &[&str], shapes: &str| {
        let out = ["--shapes", shapes, "--json", json.to_str().unwrap()];
        let (ok, stderr) = run(ROBOT, &small_robot(&[extra, &out].concat()));
        report(ok, &stderr, &json)
    };
    // The documented X,Z form, with a negative value, runs.
    let v = report_of(&["--offset", "-0.2,0.1"], "plain");
    // plain in both contact modes.
    assert_eq!(v["runs"].as_array().unwrap().len(), 2);
    let robot_tris = v["scene"]["dropped_triangles"].as_u64().unwrap();
    // --subdivide 2 drops the same robot with 16 times the triangles.
    let v = report_of(&["--subdivide", "2"], "plain-patches");
    assert_eq!(
        v["scene"]["dropped_triangles"].as_u64().unwrap(),
        16 * robot_tris
    );
    assert!(
        v["scene"]["dropped"]
            .as_str()
            .unwrap()
            .ends_with("subdivided 2×"),
        "{}",
        v["scene"]
    );
}

/// `--leaf-size N` builds every cbvh shape's tree with leaves of up to N
/// triangles: plain's nodes shrink, hcc runs with multi-triangle leaves,
/// and CLBVH's leaves grow to hold the tree's (its 4 would be an error
/// under leaves of 5).
#[test]
fn leaf_size_sets_the_cbvh_shapes_leaves() {
    let json = temp("leaves.json");
    let run_with = |leaf: &str| {
        let (ok, stderr) = lucy(
            "3000",
            "30",
            &[
                "--shapes",
                "plain,hcc,clbvh,clbvh-compact",
                "--contacts",
                "patches",
                "--leaf-size",
                leaf,
                "--json",
                json.to_str().unwrap(),
            ],
        );
        let v = report(ok, &stderr, &json);
        assert_eq!(v["scene"]["leaf_size"], leaf.parse::<u64>().unwrap());
        let runs = v["runs"].as_array().unwrap().clone();
        let bytes = |name: &str| {
            let r = runs.iter().find(|r| r["shape"] == name).unwrap();
            assert!(r["steps_in_contact"].as_u64().unwrap() > 0, "{r}");
            r["bytes_per_triangle"].as_f64().unwrap()
        };
        (bytes("plain"), bytes("hcc"), bytes("clbvh"))
    };
    let one = run_with("1");
    let five = run_with("5");
    // Fewer nodes for plain (32 bytes each); hcc's nodes shrink too.
    assert!(five.0 < 0.8 * one.0, "plain {} → {}", one.0, five.0);
    assert!(five.1 < one.1, "hcc {} → {}", one.1, five.1);
    assert!(five.2 > 0.0);
    let (ok, stderr) = run(LUCY, &["--leaf-size", "0", "--steps", "1"]);
    assert!(!ok);
    assert!(stderr.contains("--leaf-size"), "{stderr}");
    assert!(!stderr.contains("dropping"), "{stderr}");
}

/// `bin` with `args` refused within 20 s (a bad flag checked before any
/// mesh is made): its stderr. Fails if it runs or succeeds.
fn refused_within(bin: &str, args: &[&str]) -> String {
    match crate::common::run_within(bin, args, 20) {
        Some((false, _, stderr)) => {
            assert!(!stderr.contains("dropping"), "{args:?} ran first: {stderr}");
            stderr
        }
        Some((true, _, stderr)) => panic!("{args:?} was accepted: {stderr}"),
        None => panic!("{args:?} still ran after 20 s: not refused before the work"),
    }
}

/// Issue 33: every mesh's count flag is checked before any mesh is made
/// and named (`--turbine-tris 0` used to fail after the statue was
/// generated, with the generator's message); so is the product of a
/// count and `--subdivide`, from the generator's plan or a file's header
/// (a 200 M-triangle robot subdivided three times is more triangles than
/// a mesh can number: it used to be generated, then hit an assert).
#[test]
fn sims_check_mesh_counts_and_subdivide_before_any_mesh() {
    // The other mesh is large: were it made first, 20 s would not do.
    let cases: [(&str, &[&str], &str); 6] = [
        (
            LUCY,
            &["--statue-tris", "30000000", "--turbine-tris", "0"],
            "--turbine-tris 0: the turbine generator makes 1000 to 200000000 triangles",
        ),
        (
            LUCY,
            &["--statue-tris", "999", "--turbine-tris", "30000000"],
            "--statue-tris 999: the statue generator",
        ),
        (
            ROBOT,
            &["--robot-tris", "30000000", "--plant-tris", "0"],
            "--plant-tris 0: the plant generator",
        ),
        (
            ROBOT,
            &["--robot-tris", "300000000"],
            "--robot-tris 300000000: the robot generator makes 1000 to 200000000",
        ),
        (
            ROBOT,
            &["--robot-tris", "200000000", "--subdivide", "3"],
            "--subdivide 3: the robot of --robot-tris 200000000 has",
        ),
        (
            LUCY,
            &[
                "--statue-tris",
                "200000000",
                "--subdivide",
                "3",
                "--turbine-tris",
                "1000",
            ],
            "more than the 4294967295 a mesh can number",
        ),
    ];
    for (bin, args, want) in cases {
        let e = refused_within(bin, args);
        assert!(e.contains(want), "{args:?}: {e}");
    }
    // A file's header: a PLY stating 1.1 G faces (and holding none, so
    // that loading it would fail otherwise) times 4.
    let ply = temp("huge-header.ply");
    std::fs::write(
        &ply,
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
         property float y\nproperty float z\nelement face 1100000000\n\
         property list uchar int vertex_indices\nend_header\n",
    )
    .unwrap();
    let e = refused_within(
        ROBOT,
        &["--robot", ply.to_str().unwrap(), "--subdivide", "1"],
    );
    assert!(
        e.contains("--subdivide 1:") && e.contains("has 1100000000 triangles"),
        "{e}"
    );
    // A missing file is named with its flag before the other mesh is made.
    let e = refused_within(
        LUCY,
        &[
            "--statue-tris",
            "30000000",
            "--turbine",
            temp("none.off").to_str().unwrap(),
        ],
    );
    assert!(e.contains("--turbine") && e.contains("none.off"), "{e}");
    std::fs::remove_file(&ply).ok();
}

/// Issue 33: `--replay-rounds` is 1 to 1000 (each round costs about a
/// run's narrow phase); the outputs' directories are checked, named and
/// never made, and the plot and frame are PNG files.
#[test]
fn sims_bound_replay_rounds_and_check_outputs() {
    let refused = |extra: &[&str]| refused_within(ROBOT, &small_robot(extra));
    let e = refused(&["--replay", "--replay-rounds", "1001"]);
    assert!(e.contains("--replay-rounds") && e.contains("1001"), "{e}");
    let e = refused(&["--replay", "--replay-rounds", "0"]);
    assert!(e.contains("--replay-rounds"), "{e}");
    let json = temp("rounds.json");
    let (ok, stderr) = run(
        ROBOT,
        &small_robot(&[
            "--replay",
            "--replay-rounds",
            "1000",
            "--shapes",
            "plain-patches",
            "--json",
            json.to_str().unwrap(),
        ]),
    );
    report(ok, &stderr, &json);
    let missing = temp("no-such-dir");
    for flag in ["--json", "--plot", "--render"] {
        let p = missing.join("sub").join("x.png");
        let e = refused(&[flag, p.to_str().unwrap()]);
        assert!(
            e.contains(&format!("{flag} {}", p.display())) && e.contains("does not exist"),
            "{flag}: {e}"
        );
        assert!(!missing.exists());
    }
    for flag in ["--plot", "--render"] {
        let p = temp("x.txt");
        let e = refused(&[flag, p.to_str().unwrap()]);
        assert!(e.contains(flag) && e.contains(".png"), "{flag}: {e}");
        assert!(!p.exists());
    }
}

/// Issue 33: the thread count is checked by one function for `cbvh render`
/// and the sims: the same words for the same value.
#[test]
fn render_and_sims_check_threads_alike() {
    let sim = |t: &str| refused_within(ROBOT, &with(&SMALL_ROBOT, &["--threads", t]));
    let render = |t: &str| {
        crate::common::cbvh_refuses_within(
            &[
                "render",
                "--gen",
                "robot",
                "--tris",
                "1000",
                "-o",
                "x.png",
                "--threads",
                t,
            ],
            20,
        )
    };
    let line = |e: String| {
        e.lines()
            .find(|l| l.starts_with("error: "))
            .map(str::to_string)
            .unwrap_or(e)
    };
    let (s, r) = (line(sim("100000")), line(render("100000")));
    assert!(s.contains("--threads 100000 is more than 4 ×"), "{s}");
    assert_eq!(s, r);
}
