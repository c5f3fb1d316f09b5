//! Throughput of the triangle-pair contact kernel ([`cbvh::contact::PairKernel`])
//! on near-touching pairs: nanoseconds per pair for the separating-axis
//! test plus contact points, with the runtime-selected SIMD path and the
//! portable one. Pairs are small triangles (1 mm) placed within a few
//! millimetres of each other, as at the contact of two fine meshes; about
//! half of them are within the prediction distance.
//!
//! `cargo run --release --example kernel_bench -- [pairs] [auto|scalar]`

use std::time::Instant;

use cbvh::contact::{PairKernel, kernel::Simd};
use cbvh::geom::Triangle;
use glam::Vec3A;

/// A small deterministic generator (xorshift), so runs are comparable.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn v(&mut self, s: f32) -> Vec3A {
        Vec3A::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * s
    }
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("pairs: a number"))
        .unwrap_or(2_000_000);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let size = 1e-3;
    let pairs: Vec<(Triangle, Triangle)> = (0..n)
        .map(|_| {
            let c = rng.v(1.0);
            let a: Triangle = [c + rng.v(size), c + rng.v(size), c + rng.v(size)];
            let d = c + rng.v(4.0 * size);
            let b: Triangle = [d + rng.v(size), d + rng.v(size), d + rng.v(size)];
            (a, b)
        })
        .collect();
    let only = std::env::args().nth(2);
    let prediction = 2e-3;
    for (name, simd) in [("auto", Simd::Auto), ("scalar", Simd::Scalar)] {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let mut best = f64::MAX;
        let mut contacts = 0u64;
        for _ in 0..5 {
            let mut kernel = PairKernel::with_simd(prediction, simd).exact_separation(false);
            let mut points = 0usize;
            let t = Instant::now();
            for (k, (a, b)) in pairs.iter().enumerate() {
                kernel.push(k as u32, a, k as u32, b, &mut |c| {
                    points += c.points().len()
                });
            }
            kernel.flush(&mut |c| points += c.points().len());
            best = best.min(t.elapsed().as_secs_f64());
            contacts = kernel.stats.contacts;
            std::hint::black_box(points);
        }
        println!(
            "{name:>6}: {:.1} ns per pair (best of 5, {n} pairs, {contacts} within the prediction)",
            best * 1e9 / n as f64
        );
    }
}
