//! Issue 51, flags: the commands refuse, before any work and naming the
//! flag, the value and what the flag takes, what they used to accept: a
//! codec setting for a codec not in use (unknown key, value out of its
//! bounds), a negative number (clap used to read it as a flag and suggest
//! `-- -5`, or report `-1` for `-10`), and a `--memory-mib` beyond the
//! machine's memory.

use crate::common::{cbvh_refuses_within, run_within};

/// A quick build of a small generated robot with `extra` flags.
fn plain_build<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "build", "--gen", "robot", "--tris", "1000", "--codec", "plain",
    ];
    args.extend_from_slice(extra);
    args
}

/// Every `--set` and every shorthand flag is checked against its codec's
/// declared settings whether or not that codec is built: a plain build
/// used to take all of these and exit 0.
#[test]
fn cli_checks_every_codecs_settings_whether_in_use_or_not() {
    for (extra, want) in [
        (
            &["--set", "hcc.nosuch=1"][..],
            "`hcc.nosuch`: hcc has no setting \"nosuch\"; its settings are vertex-ids, \
             triangle-ids, tree-order",
        ),
        (
            &["--bits", "99"],
            "invalid value '99' for '--bits <BITS>': racbvh.bits takes a whole number from 8 \
             to 24, not 99",
        ),
        (
            &["--set", "racbvh.bits=99"],
            "`racbvh.bits=99`: racbvh.bits takes a whole number from 8 to 24, not 99",
        ),
        (
            &["--cluster-nodes", "100"],
            "'--cluster-nodes <CLUSTER_NODES>': racbvh.cluster-nodes takes a power of two from \
             256 to 16384, not 100",
        ),
        (
            &["--clbvh-leaf-size", "0"],
            "'--clbvh-leaf-size <M>': clbvh.leaf-size takes a whole number from 1 to 10, not 0",
        ),
        (
            &["--set", "clbvh-compact.multi-leaf=maybe"],
            "clbvh-compact.multi-leaf takes true or false, not \"maybe\"",
        ),
        (
            &["--vertex-bits", "33"],
            "'--vertex-bits <VERTEX_BITS>': vertex bits 33: no codec quantizes to 33 bits \
             (racbvh takes a whole number from 8 to 24, hcc takes a whole number from 1 to 24",
        ),
    ] {
        let e = cbvh_refuses_within(&plain_build(extra), 20);
        assert!(e.contains(want), "{extra:?}: {e}");
    }
    // Values a codec not in use takes are still no error (hcc quantizes to
    // 4 bits; RACBVH to 12).
    for extra in [
        &["--vertex-bits", "4"][..],
        &["--bits", "12", "--set", "hcc.tree-order=true"],
    ] {
        let (ok, _, err) = crate::common::cbvh(&plain_build(extra));
        assert!(ok, "{extra:?}: {err}");
    }
    // `--set`'s help says what each setting takes, from the registry.
    let (ok, help, err) = crate::common::cbvh(&["build", "--help"]);
    assert!(ok, "{err}");
    for want in [
        "racbvh.cluster-nodes: a power of two from 256 to 16384",
        "clbvh.leaf-size: a whole number from 1 to 10",
        "hcc.tree-order: true or false",
        "hcc: a whole number from 1 to 24",
    ] {
        assert!(help.contains(want), "{want}: {help}");
    }
    // The drop tests, with only plain (and parry) running.
    let lucy = env!("CARGO_BIN_EXE_lucy-on-turbine");
    for (extra, want) in [
        (
            &["--vertex-bits", "33"][..],
            "no codec quantizes to 33 bits",
        ),
        (&["--set", "hcc.nosuch=1"], "hcc has no setting \"nosuch\""),
        (
            &["--bits", "99"],
            "racbvh.bits takes a whole number from 8 to 24",
        ),
    ] {
        let args = [&["--shapes", "plain,parry", "--steps", "1"][..], extra].concat();
        match run_within(lucy, &args, 20) {
            Some((false, _, e)) => assert!(e.contains(want), "{extra:?}: {e}"),
            other => panic!("{extra:?} was not refused before the run: {other:?}"),
        }
    }
}

/// A negative number given to a numeric flag is refused as such: the
/// message names the flag and says it takes a positive number, instead of
/// clap's "unexpected argument '-5'" with its `-- -5` tip (or `-1` for
/// `-10`, read as short flags).
#[test]
fn cli_refuses_negative_numbers_saying_the_flag_takes_a_positive_one() {
    let d = crate::common::temp_dir_for("cli-flags", "negative");
    let png = d.join("x.png");
    let png = png.to_str().unwrap();
    let ply = d.join("x.ply");
    let ply = ply.to_str().unwrap();
    for (args, flag) in [
        (vec!["build", "--gen", "robot", "--tris", "-5"], "--tris"),
        (
            vec!["render", "--gen", "robot", "--width", "-10", "-o", png],
            "--width",
        ),
        (
            vec!["render", "--gen", "robot", "--lights", "-1", "-o", png],
            "--lights",
        ),
        (vec!["gen", "robot", "--seed", "-1", "-o", ply], "--seed"),
        (vec!["gen", "robot", "--tris", "-1000", "-o", ply], "--tris"),
        (plain_build(&["--memory-mib", "-1"]), "--memory-mib"),
        (
            plain_build(&["--chunk-triangles", "-3"]),
            "--chunk-triangles",
        ),
        (plain_build(&["--leaf-size", "-2"]), "--leaf-size"),
        (plain_build(&["--vertex-bits", "-8"]), "--vertex-bits"),
        (plain_build(&["--bits", "-5"]), "--bits"),
        (plain_build(&["--cache-mib", "-5"]), "--cache-mib"),
        (vec!["lucy-on-turbine", "--steps", "-2"], "--steps"),
        (
            vec!["lucy-on-turbine", "--statue-tris", "-1"],
            "--statue-tris",
        ),
        (vec!["robot-in-plant", "--subdivide", "-1"], "--subdivide"),
        (vec!["robot-in-plant", "--threads", "-4"], "--threads"),
    ] {
        let e = cbvh_refuses_within(&args, 20);
        let value = args[args.iter().position(|a| *a == flag).unwrap() + 1];
        assert!(
            e.contains(&format!("invalid value '{value}' for '{flag}"))
                && e.contains(&format!("{value} is negative"))
                && e.contains("takes a positive")
                && !e.contains("tip:"),
            "{args:?}: {e}"
        );
    }
    // The codec setting's shorthand says the same as its `--set`.
    let e = cbvh_refuses_within(&plain_build(&["--set", "racbvh.cluster-nodes=-256"]), 20);
    assert!(
        e.contains("-256 is negative: racbvh.cluster-nodes takes a positive number"),
        "{e}"
    );
    std::fs::remove_dir_all(&d).ok();
}

/// The machine's memory, in MiB, as `MemTotal` in /proc/meminfo states it.
fn machine_mib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib >> 10)
}

/// `--memory-mib` is at most the machine's memory: 2^64 − 1 used to switch
/// the over-budget guard off.
#[test]
fn cli_memory_mib_is_at_most_the_machines_memory() {
    let e = cbvh_refuses_within(&plain_build(&["--memory-mib", "18446744073709551615"]), 20);
    assert!(e.contains("'--memory-mib <MIB>'"), "{e}");
    match machine_mib() {
        Some(mib) => {
            let want = format!(
                "18446744073709551615 MiB is more than the {mib} MiB this machine has (MemTotal \
                 in /proc/meminfo): --memory-mib takes a whole number from 1 to {mib}"
            );
            assert!(e.contains(&want), "{e}");
            let over = (mib + 1).to_string();
            let e = cbvh_refuses_within(&plain_build(&["--memory-mib", &over]), 20);
            assert!(e.contains(&format!("{over} MiB is more than")), "{e}");
            let all = mib.to_string();
            let (ok, _, err) = crate::common::cbvh(&plain_build(&["--memory-mib", &all]));
            assert!(ok, "--memory-mib {all}: {err}");
        }
        None => assert!(e.contains("16 TiB"), "{e}"),
    }
}
