//! Ray sets shared by the benchmarks (`examples/racbvh_stats.rs`,
//! `examples/packet_bench.rs`, `benches/cluster_cache.rs` and the `peers`
//! crate include this file with `#[path]`), so that they all shoot the
//! same rays.

#![allow(dead_code)] // each includer uses what it needs

use glam::Vec3A;

/// Incoherent rays: from points on a sphere around the box `lo..hi`
/// (radius its diagonal) towards random points of the box; fixed seed.
pub fn random_rays(lo: Vec3A, hi: Vec3A, n: usize) -> Vec<cbvh::geom::Ray> {
    let mut s = 0x1234_5678_u64;
    let mut f = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length();
    (0..n)
        .map(|_| {
            let d = Vec3A::new(f() - 0.5, f() - 0.5, f() - 0.5).normalize_or(Vec3A::X);
            let origin = c + d * r;
            let target = lo + (hi - lo) * Vec3A::new(f(), f(), f());
            cbvh::geom::Ray::new(origin, (target - origin).normalize_or(Vec3A::Z))
        })
        .collect()
}

/// A pinhole camera in front of the box `lo..hi` (+Z side, Y up), at 2.2
/// times its largest extent from its centre, 30° field of view, one ray
/// per pixel centre of a `width × width` image (`width` a multiple of 8),
/// in 8×8 tiles (row-major tiles, row-major pixels in a tile) so that a
/// packet is a tile. Returns the eye and the unit directions.
pub fn camera_tiles(lo: Vec3A, hi: Vec3A, width: usize) -> (Vec3A, Vec<Vec3A>) {
    assert!(width.is_multiple_of(8), "width must be a multiple of 8");
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).max_element();
    let eye = centre + Vec3A::new(0.0, 0.0, 2.2 * size);
    let half = 15f32.to_radians().tan();
    let mut dirs = Vec::with_capacity(width * width);
    for ty in (0..width).step_by(8) {
        for tx in (0..width).step_by(8) {
            for y in ty..ty + 8 {
                for x in tx..tx + 8 {
                    let u = ((x as f32 + 0.5) / width as f32 * 2.0 - 1.0) * half;
                    let v = (1.0 - (y as f32 + 0.5) / width as f32 * 2.0) * half;
                    dirs.push(Vec3A::new(u, v, -1.0).normalize());
                }
            }
        }
    }
    (eye, dirs)
}
