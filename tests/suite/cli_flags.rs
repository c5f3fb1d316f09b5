//! Issue 51, flags: the commands refuse, before any work and naming the
//! flag, the value and what the flag takes, what they used to accept: a
//! codec setting for a codec not in use (unknown key, value out of its
//! bounds).

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
