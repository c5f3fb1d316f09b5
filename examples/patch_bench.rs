//! Time of one body pair's contact patches at a fixed pose: a generated
//! statue pressed onto a generated turbine (axis along x, as in
//! `lucy-on-turbine`) at a pose the sim reaches (`--pose`), then [`cbvh::parry::cbvh_cbvh::patches`] timed
//! `--reps` times. Unlike the sim, the pose (and so the work) is the same in
//! every run, so two builds can be compared on a noisy machine. Both orders
//! of the pair are timed: the statue as tree A and as tree B.
//!
//! `cargo run --release --features sims --example patch_bench -- [--statue-tris N]
//! [--turbine-tris M] [--codec C] [--pose tx,ty,tz,qx,qy,qz,qw] [--prediction P] [--reps R]
//! [--threads T]`; `--codec` names the codec of both shapes (`plain` by
//! default, with the registry's default options, e.g. RACBVH's 64 MiB cluster
//! cache).

use std::time::Instant;

use cbvh::build::BuildOptions;
use cbvh::codec::{AnyOptions, CodecKind};
use cbvh::contact::PatchOptions;
use cbvh::parry::cbvh_cbvh::patches;
use cbvh::parry::{CbvhShape, ContactCounters};
use cbvh::scene::Kind;
use cbvh::sim::droptest::{Placement, place};
use parry3d::math::{Pose, Rotation, Vector};

/// The value after `name` on the command line, or `default`.
fn arg<T: std::str::FromStr>(name: &str, default: T) -> T {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1))
        .map(|v| {
            v.parse()
                .unwrap_or_else(|_| panic!("{name}: cannot parse {v:?}"))
        })
        .unwrap_or(default)
}

/// `--pose tx,ty,tz,qx,qy,qz,qw`: the statue's pose on the turbine. The
/// default is where `lucy-on-turbine --statue-tris 6000000 --turbine-tris
/// 600000 --threads 1 --steps 54` leaves it (its `final_translation` and
/// `final_rotation`): resting across blades, about 51 k pairs in contact.
fn pose_arg() -> [f32; 7] {
    let args: Vec<String> = std::env::args().collect();
    let given = args.iter().position(|a| a == "--pose").map(|k| {
        let v: Vec<f32> = args[k + 1]
            .split(',')
            .map(|x| x.parse().expect("--pose: seven numbers"))
            .collect();
        v.try_into().expect("--pose: seven numbers")
    });
    given.unwrap_or([
        0.420_819_6,
        -0.426_254_27,
        -0.076_808_89,
        0.014_679_676,
        -0.004_143_114,
        0.088_642_46,
        0.995_946_7,
    ])
}

/// Contact pairs at `pos12` (turbine is shape 1).
fn contacts(pos12: &Pose, turbine: &CbvhShape, statue: &CbvhShape, prediction: f32) -> u64 {
    let c = ContactCounters::default();
    patches(
        pos12,
        turbine,
        statue,
        &prediction,
        &PatchOptions::default(),
        false,
        Some(&c),
    );
    c.take()[1]
}

fn main() {
    let statue_tris: usize = arg("--statue-tris", 6_000_000);
    let turbine_tris: usize = arg("--turbine-tris", 600_000);
    let reps: usize = arg("--reps", 15);
    let threads: usize = arg("--threads", 1);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("the global pool is set once");
    let no_progress = &mut |_: u64, _: u64| {};
    let mut statue = cbvh::scene::generate(Kind::Statue, statue_tris, 1, no_progress)
        .expect("statue generation");
    let mut turbine = cbvh::scene::generate(Kind::Turbine, turbine_tris, 1, no_progress)
        .expect("turbine generation");
    for v in &mut turbine.vertices {
        *v = [v[1], -v[0], v[2]];
    }
    // Placed as the sim places it (its defaults).
    place(&mut statue, &turbine, &Placement::default());
    let codec: CodecKind = arg("--codec", CodecKind::Plain);
    let build = |m| {
        CbvhShape::build(m, &BuildOptions::default(), codec, &AnyOptions::default()).expect("shape")
    };
    let t = Instant::now();
    let (s_statue, s_turbine) = (build(&statue), build(&turbine));
    eprintln!(
        "built {} + {} triangles in {:.1} s",
        statue.triangles.len(),
        turbine.triangles.len(),
        t.elapsed().as_secs_f64()
    );
    // rapier's default prediction distance (0.02 × the length unit); the
    // sim bounds it by the motion since the last step.
    let prediction = arg("--prediction", 0.02f32);
    // The statue body's pose relative to the fixed turbine (both colliders
    // sit at their bodies' origins, so this is pos12).
    let p = pose_arg();
    let at = Pose::from_parts(
        Vector::new(p[0], p[1], p[2]),
        Rotation::from_xyzw(p[3], p[4], p[5], p[6]).normalize(),
    );
    let inv = at.inverse();
    let time = |f: &dyn Fn() -> u64| {
        let mut ms: Vec<f64> = (0..reps)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(f());
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        ms[ms.len() / 2]
    };
    let run = |a: &CbvhShape, b: &CbvhShape, p: &Pose| {
        let c = ContactCounters::default();
        let set = patches(
            p,
            a,
            b,
            &prediction,
            &PatchOptions::default(),
            false,
            Some(&c),
        );
        let [cand, cont, n] = c.take();
        (cand, cont, n, set.patches.len())
    };
    println!(
        "{} contacts at the pose, prediction {prediction}, {threads} thread(s), median of {reps}",
        contacts(&at, &s_turbine, &s_statue, prediction)
    );
    for (name, a, b, p) in [
        ("turbine as A", &s_turbine, &s_statue, at),
        ("statue as A", &s_statue, &s_turbine, inv),
    ] {
        let (cand, cont, _, np) = run(a, b, &p);
        let ms = time(&|| run(a, b, &p).1);
        println!(
            "{name:13} {ms:8.3} ms  candidates {cand:8}  contacts {cont:8}  patches {np:4}  {:6.1} ns/contact",
            ms * 1e6 / cont.max(1) as f64
        );
    }
}
