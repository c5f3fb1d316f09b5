//! Criterion benches for the builder, primary rays and BVTT pair
//! enumeration, each side by side with parry's `TriMesh` on the same mesh in
//! the same run.
//!
//! The statue size is `CBVH_BENCH_TRIS` (default 1 000 000 triangles). Bytes
//! per triangle of both structures are printed before the timings. Run with
//! `cargo bench --features sims --bench queries`; add `-- --quick` for a fast pass.

use std::hint::black_box;
use std::ops::ControlFlow;

use cbvh::build::{BuildOptions, Layout, build};
use cbvh::codec::ByteSize;
use cbvh::codec::plain::PlainBvh;
use cbvh::geom::{Pose, Ray};
use cbvh::parry::{parry_trimesh, trimesh_bytes_by_part};
use cbvh::scene::{Kind, generate};
use cbvh::{Mesh, TraversalStats, query};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3A;
use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::Vector;
use parry3d::query::{Ray as PRay, RayCast};

fn tris() -> usize {
    std::env::var("CBVH_BENCH_TRIS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000)
}

fn statue(n: usize) -> Mesh {
    generate(Kind::Statue, n, 0, &mut |_, _| {}).expect("generate statue")
}

/// Primary rays of a `w × h` pinhole camera looking at the mesh's centre
/// from the front, at 2.2 times its size.
fn camera_rays(mesh: &Mesh, w: usize, h: usize) -> Vec<Ray> {
    let (lo, hi) = mesh.bounds().unwrap();
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    let c = (lo + hi) * 0.5;
    let size = (hi - lo).max_element();
    let eye = c + Vec3A::new(0.3, 0.2, 1.0).normalize() * size * 2.2;
    let fwd = (c - eye).normalize();
    let right = fwd.cross(Vec3A::Y).normalize();
    let up = right.cross(fwd);
    let fov = 0.5f32;
    let mut rays = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
            let v = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
            let d = (fwd + right * u * fov + up * v * fov).normalize();
            rays.push(Ray::new(eye, d));
        }
    }
    rays
}

fn bench_build(c: &mut Criterion) {
    let n = tris();
    let mesh = statue(n);
    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.throughput(Throughput::Elements(mesh.triangle_count() as u64));
    for layout in Layout::ALL {
        let opts = BuildOptions {
            layout,
            ..Default::default()
        };
        g.bench_function(BenchmarkId::new("cbvh-plain", layout.name()), |b| {
            b.iter(|| PlainBvh::new(&build(&mesh, &opts, &|_, _| {}).unwrap(), &mesh))
        });
    }
    g.bench_function("parry-trimesh", |b| {
        b.iter(|| parry_trimesh(&mesh).unwrap())
    });
    g.finish();
}

fn bench_rays(c: &mut Criterion) {
    let n = tris();
    let mesh = statue(n);
    let plain = PlainBvh::new(
        &build(&mesh, &BuildOptions::default(), &|_, _| {}).unwrap(),
        &mesh,
    );
    let tm = parry_trimesh(&mesh).unwrap();
    let pb: usize = plain.bytes_total();
    let tb: usize = trimesh_bytes_by_part(&tm).iter().map(|p| p.1).sum();
    eprintln!(
        "rays: statue of {} triangles; plain {:.1} B/triangle, parry TriMesh {:.1} B/triangle",
        mesh.triangle_count(),
        pb as f64 / mesh.triangle_count() as f64,
        tb as f64 / mesh.triangle_count() as f64
    );
    let rays = camera_rays(&mesh, 128, 128);
    let prays: Vec<PRay> = rays
        .iter()
        .map(|r| PRay::new(Vector::from(r.origin), Vector::from(r.dir)))
        .collect();
    let mut g = c.benchmark_group("primary-rays");
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("cbvh-plain", |b| {
        b.iter(|| {
            let mut stats = TraversalStats::default();
            let mut hits = 0;
            for r in &rays {
                hits += query::closest_hit(&plain, r, f32::INFINITY, &mut stats).is_some() as u32;
            }
            black_box(hits)
        })
    });
    g.bench_function("parry-trimesh", |b| {
        b.iter(|| {
            let mut hits = 0;
            for r in &prays {
                hits += tm.cast_local_ray(r, f32::MAX, true).is_some() as u32;
            }
            black_box(hits)
        })
    });
    g.finish();
}

fn bench_bvtt(c: &mut Criterion) {
    let n = tris();
    let a = statue(n / 4);
    let b_mesh = generate(Kind::Turbine, n / 4, 0, &mut |_, _| {}).unwrap();
    let pa = PlainBvh::new(
        &build(&a, &BuildOptions::default(), &|_, _| {}).unwrap(),
        &a,
    );
    let pbv = PlainBvh::new(
        &build(&b_mesh, &BuildOptions::default(), &|_, _| {}).unwrap(),
        &b_mesh,
    );
    let ta = parry_trimesh(&a).unwrap();
    let tb = parry_trimesh(&b_mesh).unwrap();
    // The statue resting in the turbine's hub: shift B so that its top meets A's bottom.
    let (alo, _) = a.bounds().unwrap();
    let (_, bhi) = b_mesh.bounds().unwrap();
    let shift = glam::Vec3::new(0.0, alo[1] - bhi[1] + 0.05, 0.0);
    let pose = Pose::from_rotation_translation(glam::Quat::IDENTITY, shift);
    let prediction = 0.01;
    let mut stats = TraversalStats::default();
    let pairs = query::bvtt_pairs(&pa, &pbv, &pose, prediction, &mut stats).len();
    eprintln!(
        "bvtt: {} x {} triangles, {pairs} pairs",
        a.triangle_count(),
        b_mesh.triangle_count()
    );
    let mut g = c.benchmark_group("bvtt-pairs");
    g.sample_size(20);
    g.bench_function("cbvh-plain", |bch| {
        bch.iter(|| {
            let mut stats = TraversalStats::default();
            let mut count = 0u32;
            query::bvtt(&pa, &pbv, &pose, prediction, &mut stats, |_, _, _, _| {
                count += 1;
                ControlFlow::Continue(())
            });
            black_box(count)
        })
    });
    // parry's composite-composite strategy: each leaf of one tree inside the
    // other's box queries the other tree (contact_manifolds_composite_shape_composite_shape).
    g.bench_function("parry-trimesh", |bch| {
        let pos21 = parry3d::math::Pose::from_translation(Vector::from(-shift));
        bch.iter(|| {
            let mut count = 0u32;
            let b_in_a = tb
                .local_aabb()
                .transform_by(&pos21.inverse())
                .loosened(prediction);
            for i in ta.bvh().intersect_aabb(&b_in_a) {
                let tri = ta.triangle(i);
                let bb = parry3d::shape::Shape::compute_aabb(&tri, &pos21).loosened(prediction);
                for _ in tb.bvh().intersect_aabb(&bb) {
                    count += 1;
                }
            }
            black_box(count)
        })
    });
    g.finish();
}

criterion_group!(benches, bench_build, bench_rays, bench_bvtt);
criterion_main!(benches);
