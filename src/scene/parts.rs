//! Scenes made of parts: triangle budgeting across the parts, and the
//! parallel, deterministic fill of pre-sized vertex and triangle buffers.
//!
//! Every part is a [`BoxGrid`] bent by a [`Shape`] map and placed by a
//! rotation and a translation. The budget is split in proportion to each
//! part's area with error diffusion (each part absorbs the rounding error
//! of the ones before it, the largest part goes last), so the total lands
//! within a few triangles of the request once the request exceeds the sum
//! of the parts' minimum of 12 triangles each.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::grid::BoxGrid;
use super::shapes::{Shape, area_half};
use crate::mesh::Mesh;

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

/// Builds the mesh of `parts` tessellated by `grids`, calling
/// `progress(done, total)` about a hundred times.
pub(crate) fn build(parts: &[Part], grids: &[BoxGrid], progress: &mut dyn FnMut(u64, u64)) -> Mesh {
    let mut voff = Vec::with_capacity(parts.len() + 1);
    let mut toff = Vec::with_capacity(parts.len() + 1);
    let (mut v, mut t) = (0u64, 0u64);
    for g in grids {
        voff.push(v);
        toff.push(t);
        v += g.vertices();
        t += g.triangles();
    }
    voff.push(v);
    toff.push(t);
    assert!(v <= u32::MAX as u64, "too many vertices for u32 indices");
    let total = v + t;
    let step = ((total / 100) as usize).max(1 << 16).div_ceil(CHUNK) * CHUNK;
    progress(0, total);

    let mut vertices = vec![[0f32; 3]; v as usize];
    let mut done = 0;
    for (b, batch) in vertices.chunks_mut(step).enumerate() {
        let base = (b * step) as u64;
        batch
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, out)| {
                let start = base + (c * CHUNK) as u64;
                let mut p = voff.partition_point(|&o| o <= start) - 1;
                for (e, slot) in out.iter_mut().enumerate() {
                    let g = start + e as u64;
                    while g >= voff[p + 1] {
                        p += 1;
                    }
                    let grid = &grids[p];
                    let q = grid.unit(grid.vertex_ijk(g - voff[p]));
                    let part = &parts[p];
                    *slot = (part.rot * part.shape.map(q) + part.pos).to_array();
                }
            });
        done += batch.len() as u64;
        progress(done, total);
    }

    let mut triangles = vec![[0u32; 3]; t as usize];
    for (b, batch) in triangles.chunks_mut(step).enumerate() {
        let base = (b * step) as u64;
        batch
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, out)| {
                let start = base + (c * CHUNK) as u64;
                let mut p = toff.partition_point(|&o| o <= start) - 1;
                for (e, slot) in out.iter_mut().enumerate() {
                    let g = start + e as u64;
                    while g >= toff[p + 1] {
                        p += 1;
                    }
                    let o = voff[p] as u32;
                    *slot = grids[p].triangle(g - toff[p]).map(|i| i + o);
                }
            });
        done += batch.len() as u64;
        progress(done, total);
    }
    Mesh::new(vertices, triangles)
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
