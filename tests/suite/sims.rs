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
    let (ok, stderr) = run(
        env!("CARGO_BIN_EXE_lucy-on-turbine"),
        &[
            "--statue-tris",
            "3000",
            "--turbine-tris",
            "3000",
            "--steps",
            "40",
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
    assert_eq!(v["scene"]["racbvh_cluster_nodes"], 256);
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
    let (ok, stderr) = run(
        env!("CARGO_BIN_EXE_lucy-on-turbine"),
        &[
            "--statue-tris",
            "1000",
            "--turbine-tris",
            "1000",
            "--steps",
            "2",
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
    let (ok, stderr) = run(
        env!("CARGO_BIN_EXE_lucy-on-turbine"),
        &[
            "--statue-tris",
            "1000",
            "--turbine-tris",
            "1000",
            "--steps",
            "1",
            "--shapes",
            "plain,plain-pairs",
            "--json",
            json.to_str().unwrap(),
        ],
    );
    let v = report(ok, &stderr, &json);
    let names: Vec<&str> = v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["shape"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["plain", "plain-pairs"]);
    let (ok, stderr) = run(
        env!("CARGO_BIN_EXE_lucy-on-turbine"),
        &["--steps", "1", "--shapes", "parry-pairs"],
    );
    assert!(!ok);
    assert!(stderr.contains("no contact modes"), "{stderr}");
}

#[test]
fn sims_reject_bad_flags_with_a_message() {
    let (ok, stderr) = run(
        env!("CARGO_BIN_EXE_robot-in-plant"),
        &["--threads", "0", "--steps", "1"],
    );
    assert!(!ok);
    assert!(stderr.contains("--threads must be at least 1"), "{stderr}");
    // Bounded before any work: neither a capacity overflow nor a pool of
    // a hundred thousand threads.
    for (flag, value) in [("--steps", "18446744073709551615"), ("--threads", "100000")] {
        let small = ["--statue-tris", "1000", "--turbine-tris", "1000"];
        let args = [&small[..], &[flag, value]].concat();
        let (ok, stderr) = run(env!("CARGO_BIN_EXE_lucy-on-turbine"), &args);
        assert!(!ok, "{flag} {value} accepted");
        assert!(
            stderr.contains(&format!("{flag} {value} is more than")),
            "{stderr}"
        );
    }
    let (ok, stderr) = run(
        env!("CARGO_BIN_EXE_lucy-on-turbine"),
        &[
            "--statue-tris",
            "1000",
            "--turbine-tris",
            "1000",
            "--steps",
            "1",
            "--shapes",
            "racbvh",
            "--cluster-nodes",
            "100",
        ],
    );
    assert!(!ok);
    assert!(stderr.contains("power of two"), "{stderr}");
}

/// Every flag is checked before the first shape runs: each of these used to
/// fail late (after the runs), run with nonsense, or be impossible to give.
#[test]
fn sims_check_every_flag_before_the_first_run() {
    let small = [
        "--robot-tris",
        "1000",
        "--plant-tris",
        "2000",
        "--steps",
        "1",
    ];
    let bin = env!("CARGO_BIN_EXE_robot-in-plant");
    let reject = |extra: &[&str], want: &str| {
        let args: Vec<&str> = small.iter().chain(extra).copied().collect();
        let (ok, stderr) = run(bin, &args);
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
    // The documented X,Z form, with a negative value, runs.
    let json = temp("offset.json");
    let args: Vec<&str> = small
        .iter()
        .copied()
        .chain([
            "--offset",
            "-0.2,0.1",
            "--shapes",
            "plain",
            "--json",
            json.to_str().unwrap(),
        ])
        .collect();
    let (ok, stderr) = run(bin, &args);
    let v = report(ok, &stderr, &json);
    // plain in both contact modes.
    assert_eq!(v["runs"].as_array().unwrap().len(), 2);
    let robot_tris = v["scene"]["dropped_triangles"].as_u64().unwrap();
    // --subdivide 2 drops the same robot with 16 times the triangles.
    let args: Vec<&str> = small
        .iter()
        .copied()
        .chain([
            "--subdivide",
            "2",
            "--shapes",
            "plain-patches",
            "--json",
            json.to_str().unwrap(),
        ])
        .collect();
    let (ok, stderr) = run(bin, &args);
    let v = report(ok, &stderr, &json);
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
    let bin = env!("CARGO_BIN_EXE_lucy-on-turbine");
    let json = temp("leaves.json");
    let run_with = |leaf: &str| {
        let (ok, stderr) = run(
            bin,
            &[
                "--statue-tris",
                "3000",
                "--turbine-tris",
                "3000",
                "--steps",
                "30",
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
    let (ok, stderr) = run(bin, &["--leaf-size", "0", "--steps", "1"]);
    assert!(!ok);
    assert!(stderr.contains("--leaf-size"), "{stderr}");
    assert!(!stderr.contains("dropping"), "{stderr}");
}
