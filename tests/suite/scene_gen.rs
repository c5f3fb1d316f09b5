//! Tests of the deterministic scene generators (`cbvh::scene`).

use cbvh::Mesh;
use cbvh::mesh::{boundary_edges, degenerate_triangles};
use cbvh::scene::{
    GenError, GenOptions, Kind, MAX_TRIS, MIN_TRIS, default_tris, generate, planned_triangles,
};

fn gen_quiet(kind: Kind, tris: usize, seed: u64) -> Mesh {
    generate(kind, tris, seed, &mut |_, _| {}).unwrap_or_else(|e| panic!("{kind} {tris}: {e}"))
}

fn within_5_percent(got: usize, want: usize) -> bool {
    (got as f64 / want as f64 - 1.0).abs() <= 0.05
}

/// Six times the signed volume (positive for outward-oriented closed meshes).
fn signed_volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize].map(f64::from));
            a[0] * (b[1] * c[2] - b[2] * c[1])
                + a[1] * (b[2] * c[0] - b[0] * c[2])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
        })
        .sum::<f64>()
        / 6.0
}

/// Checks everything a generated mesh promises; returns its triangle count.
fn check_mesh(kind: Kind, tris: usize, m: &Mesh) -> usize {
    let what = format!("{kind} {tris}");
    m.validate(&what).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        m.vertices.iter().flatten().all(|c| c.is_finite()),
        "{what}: non-finite vertex"
    );
    let n = m.vertices.len() as u32;
    assert!(
        m.triangles.iter().flatten().all(|&i| i < n),
        "{what}: index out of range"
    );
    let got = m.triangles.len();
    assert!(
        within_5_percent(got, tris),
        "{what}: produced {got} triangles"
    );
    // Every kind is closed: the statue and the isosurface as one surface,
    // the others part by part.
    assert_eq!(boundary_edges(m), 0, "{what}: open");
    assert!(signed_volume(m) > 0.0, "{what}: not outward-oriented");
    got
}

#[test]
fn counts_closedness_and_validity_at_several_sizes() {
    for kind in Kind::ALL {
        for tris in [1_000, 1_234, 9_999, 50_000] {
            let m = gen_quiet(kind, tris, 3);
            let got = check_mesh(kind, tris, &m);
            if kind != Kind::Isosurface || tris <= 50_000 {
                assert_eq!(
                    planned_triangles(kind, tris, 3).unwrap(),
                    got,
                    "{kind} {tris}: plan != result"
                );
            }
        }
    }
}

#[test]
fn counts_at_200k() {
    for kind in [Kind::Statue, Kind::Plant, Kind::Isosurface] {
        let m = gen_quiet(kind, 200_000, 11);
        check_mesh(kind, 200_000, &m);
        assert_eq!(degenerate_triangles(&m), 0, "{kind}");
    }
}

#[test]
fn statue_is_one_clean_surface_of_statue_size() {
    let m = gen_quiet(Kind::Statue, 20_000, 5);
    assert_eq!(degenerate_triangles(&m), 0);
    // Closed genus-0 surface: V = T/2 + 2, and no duplicated vertices.
    assert_eq!(m.vertices.len(), m.triangles.len() / 2 + 2);
    let mut v: Vec<[u32; 3]> = m.vertices.iter().map(|p| p.map(f32::to_bits)).collect();
    v.sort_unstable();
    v.dedup();
    assert_eq!(v.len(), m.vertices.len(), "duplicated vertices");
    let (lo, hi) = m.bounds().unwrap();
    let height = hi[1] - lo[1];
    assert!((1.8..2.4).contains(&height), "height {height}");
    assert!(lo[1].abs() < 0.05, "bottom at {}", lo[1]);
    assert!(hi[0] - lo[0] < height && hi[2] - lo[2] < height);
}

#[test]
fn turbine_plant_robot_sizes() {
    let (lo, hi) = gen_quiet(Kind::Turbine, 20_000, 0).bounds().unwrap();
    let width = hi[0] - lo[0];
    assert!(
        (3.5..4.6).contains(&width) && hi[1] - lo[1] < width / 2.0,
        "turbine {lo:?} {hi:?}"
    );
    let (lo, hi) = gen_quiet(Kind::Plant, 20_000, 0).bounds().unwrap();
    assert!(
        hi[0] - lo[0] > 3.0 * (hi[1] - lo[1]),
        "plant not flat: {lo:?} {hi:?}"
    );
    let (lo, hi) = gen_quiet(Kind::Robot, 16_000, 0).bounds().unwrap();
    assert!(
        lo[1].abs() < 1e-3 && (1.0..1.8).contains(&(hi[1] - lo[1])),
        "robot {lo:?} {hi:?}"
    );
}

#[test]
fn deterministic_per_seed_and_thread_count() {
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    for kind in Kind::ALL {
        let a = gen_quiet(kind, 30_000, 42);
        let b = gen_quiet(kind, 30_000, 42);
        assert!(a == b, "{kind}: same seed, different mesh");
        let one = pool(1).install(|| gen_quiet(kind, 30_000, 42));
        let three = pool(3).install(|| gen_quiet(kind, 30_000, 42));
        assert!(
            a == one && a == three,
            "{kind}: depends on the thread count"
        );
        let c = gen_quiet(kind, 30_000, 43);
        assert!(a != c, "{kind}: different seeds, same mesh");
    }
}

#[test]
fn progress_reaches_total() {
    for kind in Kind::ALL {
        let mut calls = Vec::new();
        gen_quiet(kind, 1_000, 0);
        generate(kind, 150_000, 0, &mut |done, total| {
            calls.push((done, total))
        })
        .unwrap();
        let &(done, total) = calls.last().expect("progress never called");
        assert!(
            total > 0 && done == total,
            "{kind}: ended at {done}/{total}"
        );
        assert!(calls.len() >= 3, "{kind}: only {} calls", calls.len());
        assert!(
            calls
                .windows(2)
                .all(|w| w[0].0 <= w[1].0 && w[0].1 == w[1].1),
            "{kind}: not monotone"
        );
    }
}

#[test]
fn count_formula_holds_up_to_the_maximum_without_generating() {
    // The part-based kinds are planned exactly by a closed formula; sweep
    // the whole range in 0.7 % steps.
    for kind in [Kind::Statue, Kind::Turbine, Kind::Plant, Kind::Robot] {
        let mut t = MIN_TRIS as f64;
        while t <= MAX_TRIS as f64 {
            let tris = t as usize;
            let got = planned_triangles(kind, tris, 1).unwrap();
            assert!(
                (got as f64 / tris as f64 - 1.0).abs() < 0.01,
                "{kind} {tris}: plans {got}"
            );
            t *= 1.007;
        }
        for tris in [
            1_000, 1_234, 9_999, 50_000, 1_000_000, 28_000_000, 50_000_000, MAX_TRIS,
        ] {
            let got = planned_triangles(kind, tris, 9).unwrap();
            assert!(within_5_percent(got, tris), "{kind} {tris}: plans {got}");
        }
    }
    // The isosurface plan at 50 M is an estimate from counting passes at
    // 128 and 256 cells; cheap enough to run here.
    let got = planned_triangles(Kind::Isosurface, 50_000_000, 0).unwrap();
    assert!(within_5_percent(got, 50_000_000));
}

#[test]
fn rejects_counts_out_of_range() {
    for kind in Kind::ALL {
        for tris in [0, MIN_TRIS - 1, MAX_TRIS + 1] {
            let err = generate(kind, tris, 0, &mut |_, _| {}).unwrap_err();
            assert_eq!(
                err,
                GenError::TrisOutOfRange {
                    kind,
                    requested: tris,
                    min: MIN_TRIS,
                    max: MAX_TRIS
                }
            );
            let msg = err.to_string();
            assert!(
                msg.contains(&MIN_TRIS.to_string()) && msg.contains(&MAX_TRIS.to_string()),
                "{msg}"
            );
            assert!(planned_triangles(kind, tris, 0).is_err());
        }
    }
}

#[test]
fn kinds_parse_and_print() {
    assert_eq!(Kind::ALL.len(), 5);
    for kind in Kind::ALL {
        assert_eq!(kind.to_string(), kind.name());
        assert_eq!(kind.name().parse::<Kind>().unwrap(), kind);
        assert_eq!(kind.name().to_uppercase().parse::<Kind>().unwrap(), kind);
        assert_eq!(GenOptions::for_kind(kind).tris, default_tris(kind));
    }
    assert!(matches!(
        "teapot".parse::<Kind>(),
        Err(GenError::UnknownKind(_))
    ));
    assert_eq!(default_tris(Kind::Robot), 16_000);
    assert_eq!(default_tris(Kind::Statue), 100_000);
    assert_eq!(default_tris(Kind::Turbine), 50_000);
    assert_eq!(default_tris(Kind::Plant), 100_000);
    assert_eq!(default_tris(Kind::Isosurface), 100_000);
    assert_eq!(GenOptions::default().seed, 0);
}

/// A fresh directory under the system temp dir for one test.
fn temp_dir(test: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("cbvh-scene-gen-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The bytes `mesh::save` writes for `mesh` as PLY.
fn saved_ply(mesh: &Mesh, dir: &std::path::Path) -> Vec<u8> {
    let path = dir.join("saved.ply");
    cbvh::mesh::save(mesh, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    bytes
}

#[test]
fn streamed_ply_is_the_saved_mesh_byte_for_byte() {
    use cbvh::scene::{Written, generate_to_ply};
    let dir = temp_dir("streamed");
    for kind in Kind::ALL {
        for (tris, seed) in [(2_000, 1), (5_000, 8)] {
            let mesh = gen_quiet(kind, tris, seed);
            let mut calls = Vec::new();
            let mut streamed = Vec::new();
            let written = generate_to_ply(kind, tris, seed, &mut streamed, &mut |d, t| {
                calls.push((d, t))
            })
            .unwrap();
            assert_eq!(
                written,
                Written {
                    vertices: mesh.vertices.len() as u64,
                    triangles: mesh.triangles.len() as u64,
                },
                "{kind} {tris} {seed}"
            );
            assert!(
                streamed == saved_ply(&mesh, &dir),
                "{kind} {tris} {seed}: the streamed PLY differs from mesh::save's"
            );
            let &(done, total) = calls.last().unwrap();
            assert!(
                total > 0 && done == total,
                "{kind}: ended at {done}/{total}"
            );
            assert!(calls.windows(2).all(|w| w[0].0 <= w[1].0));
            // Read back, it is the generated mesh.
            let path = dir.join("streamed.ply");
            std::fs::write(&path, &streamed).unwrap();
            let back = cbvh::mesh::load(&path).unwrap();
            assert_eq!(back.triangles, mesh.triangles, "{kind} {tris} {seed}");
            assert!(
                back.vertices
                    .iter()
                    .zip(&mesh.vertices)
                    .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits))
                    && back.vertices.len() == mesh.vertices.len(),
                "{kind} {tris} {seed}: vertices differ"
            );
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn streaming_accepts_more_than_generate_for_the_part_kinds() {
    use cbvh::scene::{GenWriteError, MAX_STREAMED_TRIS, generate_to_ply};
    assert!(
        Kind::ALL
            .iter()
            .all(|k| k.streams() == (*k != Kind::Isosurface))
    );
    let mut sink = Vec::new();
    for kind in Kind::ALL {
        let max = if kind.streams() {
            MAX_STREAMED_TRIS
        } else {
            MAX_TRIS
        };
        for tris in [MIN_TRIS - 1, max + 1] {
            let err = generate_to_ply(kind, tris, 0, &mut sink, &mut |_, _| {}).unwrap_err();
            let GenWriteError::Gen(err) = err else {
                panic!("{kind} {tris}: {err}")
            };
            assert_eq!(
                err,
                GenError::TrisOutOfRange {
                    kind,
                    requested: tris,
                    min: MIN_TRIS,
                    max
                }
            );
        }
    }
    assert!(sink.is_empty(), "wrote before checking the count");
}

#[cfg(feature = "app")]
#[test]
fn cbvh_gen_writes_ply_atomically() {
    let dir = temp_dir("cli");
    let names = |dir: &std::path::Path| -> Vec<String> {
        let mut n: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        n.sort();
        n
    };
    for (kind, name) in [(Kind::Statue, "s.ply"), (Kind::Isosurface, "i.ply")] {
        let out = dir.join(name);
        let (ok, _, err) = crate::common::cbvh(&[
            "gen",
            kind.name(),
            "--tris",
            "3000",
            "--seed",
            "4",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{kind}: {err}");
        assert!(err.contains("3000 requested"), "{err}");
        let mesh = gen_quiet(kind, 3000, 4);
        assert!(
            std::fs::read(&out).unwrap() == saved_ply(&mesh, &dir),
            "{kind}"
        );
    }
    // A failed run (a count out of range, refused naming the flag before
    // any work) leaves no file, temporary or not.
    let (ok, _, err) = crate::common::cbvh(&[
        "gen",
        "robot",
        "--tris",
        "10",
        "-o",
        dir.join("bad.ply").to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("--tris 10: the robot generator makes 1000 to"),
        "{err}"
    );
    assert_eq!(names(&dir), ["i.ply", "s.ply"]);
    let _ = std::fs::remove_dir_all(dir);
}
