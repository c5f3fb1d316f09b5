//! `isosurface`: marching cubes of a seeded noise field, the stand-in for
//! the RACBVH paper's iso-surface model.
//!
//! The field is a four-octave value noise minus a steep radial falloff
//! (`∝ r⁸`), so the solid is a spongy blob, with some loose bits, inside
//! a ball of radius 0.95 centred in the domain `[0, 2]³` (it typically
//! spans 0.2 to 1.8 on each axis). Grid points on the domain's faces are
//! forced outside, so the surface is always fully closed.
//! Vertices are indexed by grid edge (one per crossed edge, shared by the
//! cells around it), and the case table ([`super::mc`]) is crack-free, so
//! the output is a closed, outward-oriented surface. Vertices are kept at
//! least 1/64 of an edge away from grid points, which avoids the zero-area
//! triangles marching cubes makes when the surface passes through one.
//!
//! The triangle count is steered through the cell size `h`, which is
//! continuous: the grid covers the domain with `⌈2/h⌉` cells from its
//! corner, so samples move continuously with `h`. Counting passes classify
//! cells without storing anything. Small grids (up to 220 cells a side,
//! about 400 k triangles) iterate on exact counts, Newton steps on
//! `count ∝ 1/h²` followed by a scan; large grids fit `count ≈ A/h² + B/h`
//! to counts at 128 and 256 cells and solve for `h` (observed error under
//! 1 % up to 20 M), and the generation pass is redone with a corrected `h`
//! in the rare case it misses by more than 4 %.
//!
//! Cells are classified with bit masks (64 cells per word), and a vertex's
//! index is the rank of its crossed edge among the crossed edges of its
//! plane or layer, so no per-edge index maps are stored.
//!
//! Work goes slab by slab: chunks of a few cell layers are processed in
//! parallel, each keeping two planes of samples and crossing masks, and their
//! outputs are appended in order. A chunk does not need the previous
//! chunk's output: the vertices on its bottom plane are the previous
//! chunk's last vertices, in an order it can recompute. So the output does
//! not depend on the thread count, and memory beyond the mesh itself is a
//! few planes per thread.

use glam::Vec3;
use rayon::prelude::*;

use super::mc::{McTable, table};
use super::noise::{fade, lattice};
use super::rng::Rng;
use crate::mesh::Mesh;

/// Side of the domain cube.
const SIZE: f32 = 2.0;
/// Radius of the ball that holds the solid.
const RADIUS: f32 = 0.95;
/// Strength of the radial falloff at `RADIUS` (beats the noise's maximum).
const FALLOFF: f32 = 2.5;
/// Constant added to the field: the solid's share of the ball.
const BIAS: f32 = 0.0;
/// Cell layers per parallel chunk.
const LAYERS: usize = 8;
/// Grids up to this many cells per axis are planned from exact counts.
const EXACT_MAX_N: f32 = 220.0;

struct Octave {
    seed: u32,
    freq: f32,
    amp: f32,
    shift: Vec3,
}

/// The seeded scalar field; inside where it is positive.
pub(crate) struct Field {
    octaves: Vec<Octave>,
    centre: Vec3,
}

impl Field {
    /// The field for `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        let mut rng = Rng::new(seed, 0x150);
        let mut freq = 2.4;
        let mut amp = 1.0;
        let octaves = (0..4)
            .map(|_| {
                let o = Octave {
                    seed: rng.next_u32(),
                    freq,
                    amp,
                    shift: Vec3::new(
                        rng.range(0.0, 64.0),
                        rng.range(0.0, 64.0),
                        rng.range(0.0, 64.0),
                    ),
                };
                freq *= 2.03;
                amp *= 0.5;
                o
            })
            .collect();
        Self {
            octaves,
            centre: Vec3::splat(0.5 * SIZE),
        }
    }
}

/// Per-axis sampling table of one octave: lattice cell (relative to `lo`)
/// and fade weight of each grid coordinate.
struct AxisTab {
    lo: i32,
    len: usize,
    cell: Vec<u32>,
    w: Vec<f32>,
}

impl AxisTab {
    fn new(origin: f32, h: f32, n: usize, freq: f32, shift: f32) -> Self {
        let coords: Vec<f32> = (0..=n)
            .map(|i| (origin + i as f32 * h) * freq + shift)
            .collect();
        let lo = coords[0].floor() as i32;
        let hi = coords[n].floor() as i32;
        let cell = coords
            .iter()
            .map(|c| (c.floor() as i32 - lo) as u32)
            .collect();
        let w = coords.iter().map(|c| fade(c - c.floor())).collect();
        Self {
            lo,
            len: (hi - lo + 2) as usize,
            cell,
            w,
        }
    }
}

/// A sampling grid of `n` cells of side `h` per axis from the origin.
struct Grid<'a> {
    field: &'a Field,
    n: usize,
    h: f32,
    origin: Vec3,
    tabs: Vec<[AxisTab; 3]>,
    /// Squared, scaled distance to the centre along each axis.
    d2: [Vec<f32>; 3],
    mc: &'static McTable,
}

/// One chunk's output: vertices, and triangles indexed relative to the
/// chunk's first vertex minus `prev` (the count of vertices on its bottom
/// plane, which the previous chunk emitted last).
struct ChunkOut {
    verts: Vec<[f32; 3]>,
    tris: Vec<[u32; 3]>,
    prev: u32,
}

/// One plane of samples with its inside bits and crossed edges. Edge
/// vertices are numbered by rank: `base`, then the crossed x-edges in
/// row-major order, then the crossed y-edges.
#[derive(Default)]
struct Plane {
    /// Field values, `(n+1)²`, row-major (y rows of x samples).
    f: Vec<f32>,
    /// Inside bits, `n+1` rows of `w` words.
    sign: Vec<u64>,
    /// Crossed x-edges (bit `i`: samples `i`, `i+1`), `n+1` rows.
    xb: Vec<u64>,
    /// Crossed y-edges (bit `i` of row `j`: rows `j`, `j+1`), `n` rows.
    yb: Vec<u64>,
    /// Vertex number of the first crossing of each word of `xb` / `yb`.
    xcum: Vec<u32>,
    ycum: Vec<u32>,
    /// Crossed edges in the plane.
    count: u32,
}

/// Crossed z-edges of a layer (between two planes), numbered from `base`.
#[derive(Default)]
struct Layer {
    zb: Vec<u64>,
    zcum: Vec<u32>,
    count: u32,
}

#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// Where the field crosses zero between samples `a` and `b` of opposite
/// sign, as a fraction of the edge, kept off the end points so that the
/// vertices of neighbouring edges do not coincide (no zero-area triangles
/// from vertices sitting on grid points).
#[inline]
fn cut(a: f32, b: f32) -> f32 {
    (a / (a - b)).clamp(1.0 / 64.0, 63.0 / 64.0)
}

/// Cells per axis for cell size `h`.
fn cells_for(h: f32) -> usize {
    ((SIZE / h).ceil() as usize).max(2)
}

/// Fills `cum` with the running popcount of `words` from `start`;
/// returns the total.
fn ranks(words: &[u64], cum: &mut Vec<u32>, start: u32) -> u32 {
    cum.clear();
    let mut c = start;
    for w in words {
        cum.push(c);
        c += w.count_ones();
    }
    c - start
}

/// The rank of bit `i` of row `row` among the set bits before it.
#[inline]
fn rank(bits: &[u64], cum: &[u32], w: usize, row: usize, i: usize) -> u32 {
    let k = row * w + i / 64;
    cum[k] + (bits[k] & ((1u64 << (i % 64)) - 1)).count_ones()
}

/// Calls `f(i)` for every set bit of a row, in increasing order.
#[inline]
fn for_bits(row: &[u64], mut f: impl FnMut(usize)) {
    for (wi, &word) in row.iter().enumerate() {
        let mut b = word;
        while b != 0 {
            f(wi * 64 + b.trailing_zeros() as usize);
            b &= b - 1;
        }
    }
}

impl<'a> Grid<'a> {
    fn new(field: &'a Field, h: f32) -> Self {
        let n = cells_for(h);
        // Anchored at the domain corner, so that samples move continuously
        // with h (a new layer appears far outside the solid).
        let origin = Vec3::ZERO;
        let tabs = field
            .octaves
            .iter()
            .map(|o| {
                let t = |a: usize| AxisTab::new(origin[a], h, n, o.freq, o.shift[a]);
                [t(0), t(1), t(2)]
            })
            .collect();
        let inv_r2 = 1.0 / (RADIUS * RADIUS);
        let d2 = [0, 1, 2].map(|a| {
            (0..=n)
                .map(|i| {
                    let d = origin[a] + i as f32 * h - field.centre[a];
                    d * d * inv_r2
                })
                .collect()
        });
        Self {
            field,
            n,
            h,
            origin,
            tabs,
            d2,
            mc: table(),
        }
    }

    /// Words per bit row.
    #[inline]
    fn w(&self) -> usize {
        (self.n + 1).div_ceil(64)
    }

    /// Samples plane `k` into `p.f` and its inside bits into `p.sign`.
    /// Points on the domain's faces, and points so far from the centre
    /// that the falloff beats any noise, are set to −1 without sampling.
    fn sample(&self, k: usize, p: &mut Plane, vz: &mut Vec<f32>, vy: &mut Vec<f32>) {
        let (n, n1, w) = (self.n, self.n + 1, self.w());
        // Every value and bit is rewritten below; no need to clear.
        p.f.resize(n1 * n1, -1.0);
        p.sign.resize(n1 * w, 0);
        if k == 0 || k == n {
            p.f.fill(-1.0);
            p.sign.fill(0);
            return;
        }
        let amp: f32 = self.field.octaves.iter().map(|o| o.amp).sum();
        // Beyond this scaled squared radius the field is negative.
        let cut = ((amp + BIAS) / FALLOFF).powf(0.25);
        let centre_i = (self.field.centre.x - self.origin.x) / self.h;
        let dz = self.d2[2][k];
        // Each octave's lattice values interpolated to this plane's z.
        vz.clear();
        let mut offsets = Vec::with_capacity(self.tabs.len());
        for (o, [tx, ty, tz]) in self.field.octaves.iter().zip(&self.tabs) {
            offsets.push(vz.len());
            let iz = tz.lo + tz.cell[k] as i32;
            let wz = tz.w[k];
            for iy in 0..ty.len as i32 {
                for ix in 0..tx.len as i32 {
                    let (x, y) = (tx.lo + ix, ty.lo + iy);
                    let (a, b) = (lattice(o.seed, x, y, iz), lattice(o.seed, x, y, iz + 1));
                    vz.push(o.amp * lerp(a, b, wz));
                }
            }
        }
        // Row by row, so that a row stays in cache while every octave is
        // added to it.
        for j in 0..n1 {
            let row = &mut p.f[j * n1..(j + 1) * n1];
            let bits = &mut p.sign[j * w..(j + 1) * w];
            bits.fill(0);
            let rem = cut - dz - self.d2[1][j];
            if j == 0 || j == n || rem <= 0.0 {
                row.fill(-1.0);
                continue;
            }
            // The sampled x-range of the row; the rest is outside.
            let half = rem.sqrt() * RADIUS / self.h;
            let i0 = ((centre_i - half).floor() as isize - 1).max(1) as usize;
            let i1 = ((centre_i + half).ceil() as isize + 1).min(n as isize - 1) as usize;
            if i0 > i1 {
                row.fill(-1.0);
                continue;
            }
            row[..i0].fill(-1.0);
            row[i1 + 1..].fill(-1.0);
            let row = &mut row[i0..=i1];
            let dy = self.d2[1][j] + dz;
            for (v, dx) in row.iter_mut().zip(&self.d2[0][i0..=i1]) {
                let r2 = dx + dy;
                let r4 = r2 * r2;
                *v = BIAS - FALLOFF * r4 * r4;
            }
            for ([tx, ty, _], &off) in self.tabs.iter().zip(&offsets) {
                let (cy, wy) = (ty.cell[j] as usize, ty.w[j]);
                let r0 = &vz[off + cy * tx.len..off + (cy + 1) * tx.len];
                let r1 = &vz[off + (cy + 1) * tx.len..off + (cy + 2) * tx.len];
                vy.clear();
                vy.extend(r0.iter().zip(r1).map(|(a, b)| lerp(*a, *b, wy)));
                for ((v, &cx), &wx) in row.iter_mut().zip(&tx.cell[i0..=i1]).zip(&tx.w[i0..=i1]) {
                    let cx = cx as usize;
                    *v += lerp(vy[cx], vy[cx + 1], wx);
                }
            }
            for (i, v) in (i0..).zip(row.iter()) {
                bits[i / 64] |= ((*v > 0.0) as u64) << (i % 64);
            }
        }
    }

    /// Finds and numbers (from `base`) the crossed x- and y-edges of a
    /// sampled plane.
    fn plane_edges(&self, p: &mut Plane, base: u32) {
        let (n, w) = (self.n, self.w());
        p.xb.clear();
        p.yb.clear();
        for j in 0..=n {
            let s = &p.sign[j * w..(j + 1) * w];
            for k in 0..w {
                let next = if k + 1 < w { s[k + 1] } else { 0 };
                // Samples beyond n are 0, like sample n: no false crossing.
                p.xb.push(s[k] ^ ((s[k] >> 1) | (next << 63)));
            }
            if j < n {
                let t = &p.sign[(j + 1) * w..(j + 2) * w];
                p.yb.extend(s.iter().zip(t).map(|(a, b)| a ^ b));
            }
        }
        let nx = ranks(&p.xb, &mut p.xcum, base);
        let ny = ranks(&p.yb, &mut p.ycum, base + nx);
        p.count = nx + ny;
    }

    /// Appends the vertices of a plane's crossed edges, in rank order.
    fn plane_vertices(&self, p: &Plane, k: usize, out: &mut Vec<[f32; 3]>) {
        let (n, n1, w, h) = (self.n, self.n + 1, self.w(), self.h);
        let z = self.origin.z + k as f32 * h;
        for j in 0..=n {
            let y = self.origin.y + j as f32 * h;
            for_bits(&p.xb[j * w..(j + 1) * w], |i| {
                let (a, b) = (p.f[j * n1 + i], p.f[j * n1 + i + 1]);
                out.push([self.origin.x + (i as f32 + cut(a, b)) * h, y, z]);
            });
        }
        for j in 0..n {
            for_bits(&p.yb[j * w..(j + 1) * w], |i| {
                let (a, b) = (p.f[j * n1 + i], p.f[(j + 1) * n1 + i]);
                out.push([
                    self.origin.x + i as f32 * h,
                    self.origin.y + (j as f32 + cut(a, b)) * h,
                    z,
                ]);
            });
        }
    }

    /// Finds, numbers from `base` and appends the crossed z-edges between
    /// planes `a` (at `k`) and `b`.
    fn layer(
        &self,
        a: &Plane,
        b: &Plane,
        k: usize,
        base: u32,
        l: &mut Layer,
        out: &mut Vec<[f32; 3]>,
    ) {
        let (n, n1, w, h) = (self.n, self.n + 1, self.w(), self.h);
        l.zb.clear();
        l.zb.extend(a.sign.iter().zip(&b.sign).map(|(x, y)| x ^ y));
        l.count = ranks(&l.zb, &mut l.zcum, base);
        let z = self.origin.z + k as f32 * h;
        for j in 0..=n {
            let y = self.origin.y + j as f32 * h;
            for_bits(&l.zb[j * w..(j + 1) * w], |i| {
                let (fa, fb) = (a.f[j * n1 + i], b.f[j * n1 + i]);
                out.push([self.origin.x + i as f32 * h, y, z + cut(fa, fb) * h]);
            });
        }
    }

    /// Bits of the cells of row `j` (between planes `a`, `b`) whose
    /// corners are not all on one side, into `out` (`w` words).
    fn active(&self, a: &[u64], b: &[u64], j: usize, out: &mut Vec<u64>) {
        let (n, w) = (self.n, self.w());
        out.clear();
        let word = |k: usize| -> (u64, u64) {
            if k >= w {
                return (0, 0);
            }
            let r = [
                a[j * w + k],
                a[(j + 1) * w + k],
                b[j * w + k],
                b[(j + 1) * w + k],
            ];
            (r[0] | r[1] | r[2] | r[3], r[0] & r[1] & r[2] & r[3])
        };
        let mut cur = word(0);
        for k in 0..w {
            let next = word(k + 1);
            let any = cur.0 | (cur.0 >> 1) | (next.0 << 63);
            let all = cur.1 & ((cur.1 >> 1) | (next.1 << 63));
            let mut act = any & !all;
            // Only cells 0..n exist.
            let lo = k * 64;
            if lo + 64 > n {
                act &= if n > lo { (1u64 << (n - lo)) - 1 } else { 0 };
            }
            out.push(act);
            cur = next;
        }
    }

    /// The marching-cubes case of the cell at sample index `c` (x, y
    /// corner) between planes `fa`, `fb`.
    #[inline]
    fn case(n1: usize, fa: &[f32], fb: &[f32], c: usize) -> usize {
        (fa[c] > 0.0) as usize
            | ((fa[c + 1] > 0.0) as usize) << 1
            | ((fa[c + n1] > 0.0) as usize) << 2
            | ((fa[c + n1 + 1] > 0.0) as usize) << 3
            | ((fb[c] > 0.0) as usize) << 4
            | ((fb[c + 1] > 0.0) as usize) << 5
            | ((fb[c + n1] > 0.0) as usize) << 6
            | ((fb[c + n1 + 1] > 0.0) as usize) << 7
    }

    /// Triangles of the cell layer between planes `a` and `b`.
    fn cells(&self, a: &Plane, b: &Plane, l: &Layer, act: &mut Vec<u64>, out: &mut Vec<[u32; 3]>) {
        let (n, n1, w) = (self.n, self.n + 1, self.w());
        for j in 0..n {
            self.active(&a.sign, &b.sign, j, act);
            for_bits(act, |i| {
                let case = Self::case(n1, &a.f, &b.f, j * n1 + i);
                let vertex = |e: u8| -> u32 {
                    let (lo, hi) = ((e & 1) as usize, (e >> 1 & 1) as usize);
                    match e >> 2 {
                        0 => {
                            let p = if hi == 0 { a } else { b };
                            rank(&p.xb, &p.xcum, w, j + lo, i)
                        }
                        1 => {
                            let p = if hi == 0 { a } else { b };
                            rank(&p.yb, &p.ycum, w, j, i + lo)
                        }
                        _ => rank(&l.zb, &l.zcum, w, j + hi, i + lo),
                    }
                };
                for t in self.mc.case(case) {
                    out.push(t.map(vertex));
                }
            });
        }
    }

    /// Generates cell layers `k0..k1`.
    fn chunk(&self, k0: usize, k1: usize) -> ChunkOut {
        let (mut vz, mut vy, mut act) = (Vec::new(), Vec::new(), Vec::new());
        let (mut a, mut b) = (Plane::default(), Plane::default());
        let mut layer = Layer::default();
        self.sample(k0, &mut a, &mut vz, &mut vy);
        self.plane_edges(&mut a, 0);
        let prev = a.count;
        let mut next = prev;
        let mut verts = Vec::new();
        let mut tris = Vec::new();
        for k in k0..k1 {
            self.sample(k + 1, &mut b, &mut vz, &mut vy);
            self.layer(&a, &b, k, next, &mut layer, &mut verts);
            next += layer.count;
            self.plane_edges(&mut b, next);
            self.plane_vertices(&b, k + 1, &mut verts);
            next += b.count;
            self.cells(&a, &b, &layer, &mut act, &mut tris);
            std::mem::swap(&mut a, &mut b);
        }
        ChunkOut { verts, tris, prev }
    }

    /// Counts the triangles of cell layers `k0..k1`.
    fn count_chunk(&self, k0: usize, k1: usize) -> u64 {
        let (mut vz, mut vy, mut act) = (Vec::new(), Vec::new(), Vec::new());
        let (mut a, mut b) = (Plane::default(), Plane::default());
        let n1 = self.n + 1;
        self.sample(k0, &mut a, &mut vz, &mut vy);
        let mut count = 0u64;
        for k in k0..k1 {
            self.sample(k + 1, &mut b, &mut vz, &mut vy);
            for j in 0..self.n {
                self.active(&a.sign, &b.sign, j, &mut act);
                for_bits(&act, |i| {
                    count += self.mc.count(Self::case(n1, &a.f, &b.f, j * n1 + i)) as u64
                });
            }
            std::mem::swap(&mut a, &mut b);
        }
        count
    }

    /// Cell-layer ranges processed as units: a fixed size, so the output
    /// does not depend on the thread count.
    fn chunks(&self) -> Vec<(usize, usize)> {
        (0..self.n)
            .step_by(LAYERS)
            .map(|k| (k, (k + LAYERS).min(self.n)))
            .collect()
    }

    /// Exact triangle count of this grid.
    fn count(&self) -> u64 {
        self.chunks()
            .par_iter()
            .map(|&(k0, k1)| self.count_chunk(k0, k1))
            .sum()
    }

    /// The mesh of this grid.
    fn mesh(&self, estimate: u64, progress: &mut dyn FnMut(u64, u64)) -> Mesh {
        let chunks = self.chunks();
        let total = self.n as u64;
        progress(0, total);
        let mut vertices: Vec<[f32; 3]> = Vec::with_capacity((estimate / 2 + 1024) as usize);
        let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(estimate as usize + 1024);
        let wave = (2 * rayon::current_num_threads()).max(1);
        for group in chunks.chunks(wave) {
            let outs: Vec<ChunkOut> = group
                .par_iter()
                .map(|&(k0, k1)| self.chunk(k0, k1))
                .collect();
            for out in outs {
                let base = vertices.len() as u32 - out.prev;
                vertices.extend_from_slice(&out.verts);
                triangles.extend(out.tris.iter().map(|t| t.map(|i| i + base)));
            }
            progress(group.last().map_or(0, |c| c.1) as u64, total);
        }
        if vertices.capacity() > vertices.len() + vertices.len() / 16 {
            vertices.shrink_to_fit();
        }
        if triangles.capacity() > triangles.len() + triangles.len() / 16 {
            triangles.shrink_to_fit();
        }
        Mesh::new(vertices, triangles)
    }
}

/// Exact triangle count with cell size `h`.
fn count_at(field: &Field, h: f32) -> u64 {
    Grid::new(field, h).count()
}

/// The planned cell size for `target` triangles, with the exact count when
/// it was measured.
pub(crate) fn plan(field: &Field, target: usize) -> (f32, Option<u64>) {
    let target = target as f64;
    // Work with x = 1/h (cells per unit length).
    let pilot = 64.0 / SIZE;
    let c = count_at(field, 1.0 / pilot).max(1) as f64;
    let mut x = pilot * (target / c).sqrt() as f32;
    if x * SIZE <= EXACT_MAX_N {
        let mut best = (f64::INFINITY, x, 0u64);
        let try_x = |x: f32, best: &mut (f64, f32, u64)| {
            let c = count_at(field, 1.0 / x);
            let err = (c as f64 / target - 1.0).abs();
            if err < best.0 {
                *best = (err, x, c);
            }
            c
        };
        // Newton steps on count ∝ x², damped in case the count is noisy.
        for it in 0..10 {
            let c = try_x(x, &mut best);
            if best.0 <= 0.01 {
                break;
            }
            let ratio = (target / c.max(1) as f64) as f32;
            x *= ratio.powf(if it < 5 { 0.5 } else { 0.25 });
        }
        // Small grids count in steps that Newton can jump over: scan.
        'scan: for step in [0.004f32, 0.001] {
            let centre = best.1;
            for k in 1..=40 {
                for sign in [1.0, -1.0] {
                    if best.0 <= 0.01 {
                        break 'scan;
                    }
                    try_x(centre * (1.0 + sign * step * k as f32), &mut best);
                }
            }
        }
        return (1.0 / best.1, Some(best.2));
    }
    let (x1, x2) = (128.0 / SIZE as f64, 256.0 / SIZE as f64);
    let c1 = count_at(field, (1.0 / x1) as f32) as f64;
    let c2 = count_at(field, (1.0 / x2) as f32) as f64;
    // count ≈ a·x² + b·x
    let a = (c2 / x2 - c1 / x1) / (x2 - x1);
    let b = c1 / x1 - a * x1;
    let x = if a > 0.0 {
        (-b + (b * b + 4.0 * a * target).sqrt()) / (2.0 * a)
    } else {
        x2 * (target / c2).sqrt()
    };
    (1.0 / x as f32, None)
}

/// The triangle count [`generate`] will produce: exact when the plan was
/// made from exact counts (small grids), otherwise the fitted model's
/// estimate (the request itself; the real count is checked, and the grid
/// corrected, after generation).
pub(crate) fn planned_triangles(tris: usize, seed: u64) -> u64 {
    match plan(&Field::new(seed), tris) {
        (_, Some(c)) => c,
        (_, None) => tris as u64,
    }
}

/// The isosurface mesh with about `tris` triangles.
pub(crate) fn generate(tris: usize, seed: u64, progress: &mut dyn FnMut(u64, u64)) -> Mesh {
    let field = Field::new(seed);
    let (mut h, exact) = plan(&field, tris);
    let mut estimate = exact.unwrap_or(tris as u64 + tris as u64 / 32);
    let mut attempt = 0;
    loop {
        let mesh = Grid::new(&field, h).mesh(estimate, progress);
        let got = mesh.triangles.len() as f64;
        attempt += 1;
        if exact.is_some() || attempt == 3 || (got / tris as f64 - 1.0).abs() <= 0.04 {
            return mesh;
        }
        h *= (got / tris as f64).sqrt() as f32;
        estimate = tris as u64 + tris as u64 / 32;
    }
}
