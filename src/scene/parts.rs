//! Scenes made of parts: triangle budgeting across the parts, and the
//! parallel, deterministic computation of any range of the vertices and
//! triangles, into a mesh in memory or batch by batch into a PLY file.
//!
//! Every part is a [`BoxGrid`] bent by a [`Shape`] map and placed by a
//! rotation and a translation. The budget is split in proportion to each
//! part's area with error diffusion (each part absorbs the rounding error
//! of the ones before it, the largest part goes last), so the total lands
//! within a few triangles of the request once the request exceeds the sum
//! of the parts' minimum of 12 triangles each.

use std::io::{self, Write};

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::grid::BoxGrid;
use super::shapes::{Shape, area_half};
use crate::mesh::{Mesh, PlyWriter};

/// One closed component of a scene.
#[derive(Clone, Debug)]
pub(crate) struct Part {
    /// The shape in its own frame.
    pub shape: Shape,
    /// Rotation from the shape's frame to the scene (a proper rotation,
    /// possibly times a positive uniform scale).
    pub rot: Mat3,
    /// Translation from the shape's frame to the scene.
    pub pos: Vec3,
}

impl Part {
    /// A part at `pos` with no rotation.
    pub(crate) fn at(shape: Shape, pos: Vec3) -> Self {
        Self {
            shape,
            rot: Mat3::IDENTITY,
            pos,
        }
    }

    /// A part rotated by `rot`, then moved to `pos`.
    pub(crate) fn new(shape: Shape, rot: Mat3, pos: Vec3) -> Self {
        Self { shape, rot, pos }
    }

    /// A Y-axis shape (cylinder, capsule) spanning the segment `a`–`b`:
    /// the shape's y axis is turned onto `b − a` and centred between them.
    pub(crate) fn between(a: Vec3, b: Vec3, make: impl FnOnce(f32) -> Shape) -> Self {
        let d = b - a;
        let len = d.length();
        let rot = Mat3::from_quat(glam::Quat::from_rotation_arc(Vec3::Y, d / len));
        Self::new(make(0.5 * len), rot, 0.5 * (a + b))
    }
}

/// The best grid for a shape with axis lengths `lens` and `target`
/// triangles: cells close to square, count as close to the target as the
/// integers allow within `window` of the ideal cell counts on each axis.
pub(crate) fn choose_grid(lens: Vec3, target: f64, window: i64) -> BoxGrid {
    let l = [lens.x as f64, lens.y as f64, lens.z as f64];
    let area = area_half(lens).max(1e-30);
    let target = target.max(1.0);
    let h = (4.0 * area / target).sqrt();
    let ideal = l.map(|x| (x / h).max(1e-9));
    let range = |x: f64| {
        let r = x.round() as i64;
        ((r - window).max(1), (r + window).max(1))
    };
    let (rx, ry, rz) = (range(ideal[0]), range(ideal[1]), range(ideal[2]));
    let mut best = (f64::INFINITY, BoxGrid::new(1, 1, 1));
    for nx in rx.0..=rx.1 {
        for ny in ry.0..=ry.1 {
            for nz in rz.0..=rz.1 {
                let count = BoxGrid::triangles_of(nx as u64, ny as u64, nz as u64) as f64;
                let shape_err = (nx as f64 / ideal[0]).ln().abs()
                    + (ny as f64 / ideal[1]).ln().abs()
                    + (nz as f64 / ideal[2]).ln().abs();
                let cost = (count - target).abs() / target + 0.002 * shape_err;
                if cost < best.0 {
                    best = (cost, BoxGrid::new(nx as u32, ny as u32, nz as u32));
                }
            }
        }
    }
    best.1
}

/// Splits `tris` triangles over `parts` (see the module docs).
pub(crate) fn plan(parts: &[Part], tris: usize) -> Vec<BoxGrid> {
    let areas: Vec<f64> = parts.iter().map(|p| area_half(p.shape.lens())).collect();
    let total: f64 = areas.iter().sum();
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by(|&a, &b| areas[a].total_cmp(&areas[b]).then(a.cmp(&b)));
    let mut grids = vec![BoxGrid::new(1, 1, 1); parts.len()];
    let mut carry = 0.0;
    for (n, &i) in order.iter().enumerate() {
        let last = n + 1 == order.len();
        let target = tris as f64 * areas[i] / total + carry;
        let g = choose_grid(parts[i].shape.lens(), target, if last { 3 } else { 1 });
        carry = target - g.triangles() as f64;
        grids[i] = g;
    }
    grids
}

/// Total triangles of a plan.
pub(crate) fn plan_triangles(grids: &[BoxGrid]) -> u64 {
    grids.iter().map(BoxGrid::triangles).sum()
}

/// Elements per parallel task.
const CHUNK: usize = 4096;

/// Vertices or triangles per batch when streaming ([`Assembly::write_ply`]):
/// 3 MiB of either, so memory does not grow with the scene.
const STREAM_BATCH: usize = 1 << 18;

/// The parts of a scene with their grids, numbered: where each part's
/// vertices and triangles start in the whole mesh. Any range of vertices
/// or triangles can be computed on its own ([`fill_vertices`],
/// [`fill_triangles`]), which serves both the mesh in memory ([`build`])
/// and the mesh streamed to a file ([`write_ply`]).
///
/// [`fill_vertices`]: Self::fill_vertices
/// [`fill_triangles`]: Self::fill_triangles
/// [`build`]: Self::build
/// [`write_ply`]: Self::write_ply
pub(crate) struct Assembly {
    parts: Vec<Part>,
    grids: Vec<BoxGrid>,
    /// First vertex of each part, and the total at the end.
    voff: Vec<u64>,
    /// First triangle of each part, and the total at the end.
    toff: Vec<u64>,
}

impl Assembly {
    /// Numbers `parts` tessellated by `grids`.
    ///
    /// # Panics
    /// When the vertices do not fit `u32` indices (beyond about 8 billion
    /// triangles, far above what the generators accept).
    pub(crate) fn new(parts: Vec<Part>, grids: Vec<BoxGrid>) -> Self {
        let mut voff = Vec::with_capacity(parts.len() + 1);
        let mut toff = Vec::with_capacity(parts.len() + 1);
        let (mut v, mut t) = (0u64, 0u64);
        for g in &grids {
            voff.push(v);
            toff.push(t);
            v += g.vertices();
            t += g.triangles();
        }
        voff.push(v);
        toff.push(t);
        assert!(v <= u32::MAX as u64, "too many vertices for u32 indices");
        Self {
            parts,
            grids,
            voff,
            toff,
        }
    }

    /// Vertices of the whole mesh.
    pub(crate) fn vertices(&self) -> u64 {
        self.voff[self.voff.len() - 1]
    }

    /// Triangles of the whole mesh.
    pub(crate) fn triangles(&self) -> u64 {
        self.toff[self.toff.len() - 1]
    }

    /// Computes vertices `start..start + out.len()` into `out`, in
    /// parallel chunks.
    pub(crate) fn fill_vertices(&self, start: u64, out: &mut [[f32; 3]]) {
        let voff = &self.voff;
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
            let start = start + (c * CHUNK) as u64;
            let mut p = voff.partition_point(|&o| o <= start) - 1;
            for (e, slot) in out.iter_mut().enumerate() {
                let g = start + e as u64;
                while g >= voff[p + 1] {
                    p += 1;
                }
                let grid = &self.grids[p];
                let q = grid.unit(grid.vertex_ijk(g - voff[p]));
                let part = &self.parts[p];
                *slot = (part.rot * part.shape.map(q) + part.pos).to_array();
            }
        });
    }

    /// Computes triangles `start..start + out.len()` into `out`, in
    /// parallel chunks.
    pub(crate) fn fill_triangles(&self, start: u64, out: &mut [[u32; 3]]) {
        let (voff, toff) = (&self.voff, &self.toff);
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
            let start = start + (c * CHUNK) as u64;
            let mut p = toff.partition_point(|&o| o <= start) - 1;
            for (e, slot) in out.iter_mut().enumerate() {
                let g = start + e as u64;
                while g >= toff[p + 1] {
                    p += 1;
                }
                let o = voff[p] as u32;
                *slot = self.grids[p].triangle(g - toff[p]).map(|i| i + o);
            }
        });
    }

    /// Elements (vertices and triangles) between progress reports: about
    /// 1 % of the work, a whole number of chunks.
    fn step(&self) -> usize {
        let total = self.vertices() + self.triangles();
        ((total / 100) as usize).max(1 << 16).div_ceil(CHUNK) * CHUNK
    }

    /// Builds the mesh in memory, calling `progress(done, total)` about a
    /// hundred times.
    pub(crate) fn build(&self, progress: &mut dyn FnMut(u64, u64)) -> Mesh {
        let total = self.vertices() + self.triangles();
        let step = self.step();
        progress(0, total);
        let mut done = 0;
        let mut vertices = vec![[0f32; 3]; self.vertices() as usize];
        for (b, batch) in vertices.chunks_mut(step).enumerate() {
            self.fill_vertices((b * step) as u64, batch);
            done += batch.len() as u64;
            progress(done, total);
        }
        let mut triangles = vec![[0u32; 3]; self.triangles() as usize];
        for (b, batch) in triangles.chunks_mut(step).enumerate() {
            self.fill_triangles((b * step) as u64, batch);
            done += batch.len() as u64;
            progress(done, total);
        }
        Mesh::new(vertices, triangles)
    }

    /// Streams the mesh to `ply` (whose header must announce
    /// [`vertices`](Self::vertices) and [`triangles`](Self::triangles)) in
    /// batches of at most [`STREAM_BATCH`] elements, calling
    /// `progress(done, total)` after each batch written and at least every
    /// 1 % of the work. Each batch is written while the next is computed.
    /// Memory: two batch buffers, whatever the size of the mesh.
    pub(crate) fn write_ply<W: Write + Send>(
        &self,
        ply: &mut PlyWriter<W>,
        progress: &mut dyn FnMut(u64, u64),
    ) -> io::Result<()> {
        let (nv, nt) = (self.vertices(), self.triangles());
        let total = nv + nt;
        let batch = self.step().min(STREAM_BATCH) as u64;
        progress(0, total);
        pipeline(
            nv,
            batch,
            |start, out| self.fill_vertices(start, out),
            |out| ply.write_vertices(out),
            &mut |done| progress(done, total),
        )?;
        pipeline(
            nt,
            batch,
            |start, out| self.fill_triangles(start, out),
            |out| ply.write_triangles(out),
            &mut |done| progress(nv + done, total),
        )
    }
}

/// Computes elements `0..n` with `fill(start, out)` in batches of `batch`
/// and hands each batch to `write`, writing one batch while the next is
/// computed; `done(count)` after each batch written.
fn pipeline<T: Copy + Default + Send + Sync>(
    n: u64,
    batch: u64,
    fill: impl Fn(u64, &mut [T]) + Sync,
    mut write: impl FnMut(&[T]) -> io::Result<()> + Send,
    done: &mut dyn FnMut(u64),
) -> io::Result<()> {
    let len = |start: u64| (n - start).min(batch) as usize;
    let mut current = vec![T::default(); batch.min(n) as usize];
    let mut next = current.clone();
    if n > 0 {
        fill(0, &mut current[..len(0)]);
    }
    let mut start = 0;
    while start < n {
        let end = start + len(start) as u64;
        let (written, ()) = rayon::join(
            || write(&current[..len(start)]),
            || {
                if end < n {
                    fill(end, &mut next[..len(end)]);
                }
            },
        );
        written?;
        done(end);
        std::mem::swap(&mut current, &mut next);
        start = end;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choose_grid_hits_targets() {
        for target in [1000.0, 1234.0, 9999.0, 1e6, 5e7] {
            let g = choose_grid(Vec3::new(0.5, 1.5, 0.4), target, 3);
            let c = g.triangles() as f64;
            assert!((c / target - 1.0).abs() < 0.02, "{target}: {g:?} {c}");
        }
    }
}
