//! The marching-cubes case table, derived at first use rather than typed
//! in: for each of the 256 inside/outside patterns of a cube's corners,
//! the iso-contour is traced on each face as oriented segments, the
//! segments are chained into closed loops and each loop is fanned into
//! triangles.
//!
//! On a face with two crossings the segment is forced. On an ambiguous
//! face (inside and outside corners alternating) the rule is always the
//! same, "inside corners are cut off separately", and it depends only on
//! the face's four corners, so the two cubes sharing a face trace the same
//! segments (in opposite directions). Hence the surface has no cracks:
//! every segment is an edge of exactly two triangles, one in each cube,
//! and all triangles wind counter-clockwise seen from the outside (from
//! where the field is ≤ 0).
//!
//! Corner `c` of a cube sits at `(c & 1, c >> 1 & 1, c >> 2 & 1)` and is
//! inside when bit `c` of the case is set. Edge `4a + lo + 2·hi` runs along
//! axis `a`; `lo`, `hi` are the cube coordinates of its other two axes in
//! increasing axis order.

use std::sync::OnceLock;

/// Triangles for every case, as edge ids.
pub(crate) struct McTable {
    /// Triangles of case `c` are `tris[start[c]..start[c + 1]]`.
    pub start: [u16; 257],
    /// All triangles, as triples of edge ids.
    pub tris: Vec<[u8; 3]>,
}

impl McTable {
    /// Triangle count of `case`.
    #[inline]
    pub(crate) fn count(&self, case: usize) -> u32 {
        (self.start[case + 1] - self.start[case]) as u32
    }

    /// Triangles of `case`.
    #[inline]
    pub(crate) fn case(&self, case: usize) -> &[[u8; 3]] {
        &self.tris[self.start[case] as usize..self.start[case + 1] as usize]
    }
}

/// The edge joining corners `c0` and `c1` (which differ in one bit).
pub(crate) fn edge_between(c0: u8, c1: u8) -> u8 {
    let d = c0 ^ c1;
    debug_assert!(d.count_ones() == 1);
    let a = d.trailing_zeros() as u8;
    let (b0, b1) = match a {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    4 * a + (c0 >> b0 & 1) + 2 * (c0 >> b1 & 1)
}

/// Corners of the six faces, counter-clockwise seen from outside the cube.
fn faces() -> [[u8; 4]; 6] {
    let mut out = [[0u8; 4]; 6];
    for a in 0..3u8 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for s in 0..2u8 {
            let corner = |ub: u8, uc: u8| (s << a) | (ub << b) | (uc << c);
            // e_b × e_c = e_a: this order is counter-clockwise about +e_a.
            let mut f = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
            if s == 0 {
                f = [f[0], f[3], f[2], f[1]];
            }
            out[(2 * a + s) as usize] = f;
        }
    }
    out
}

fn build() -> McTable {
    let faces = faces();
    let mut start = [0u16; 257];
    let mut tris = Vec::new();
    for case in 0..256usize {
        let inside = |c: u8| case >> c & 1 == 1;
        // succ[e]: where the contour leaving crossing `e` goes next.
        let mut succ = [u8::MAX; 12];
        for f in &faces {
            for k in 0..4 {
                if inside(f[k]) || !inside(f[(k + 1) % 4]) {
                    continue;
                }
                // Entering the inside at edge k; leave at the first
                // inside→outside edge after it.
                let m = (1..4)
                    .map(|d| (k + d) % 4)
                    .find(|&m| inside(f[m]) && !inside(f[(m + 1) % 4]))
                    .expect("a face has as many entries as exits");
                let from = edge_between(f[k], f[(k + 1) % 4]);
                let to = edge_between(f[m], f[(m + 1) % 4]);
                assert_eq!(succ[from as usize], u8::MAX, "crossing entered twice");
                succ[from as usize] = to;
            }
        }
        let mut seen = [false; 12];
        for e in 0..12 {
            if succ[e] == u8::MAX || seen[e] {
                continue;
            }
            let mut lp = Vec::new();
            let mut cur = e;
            while !seen[cur] {
                seen[cur] = true;
                lp.push(cur as u8);
                cur = succ[cur] as usize;
                assert_ne!(cur, u8::MAX as usize, "open contour");
            }
            assert_eq!(cur, e, "contour does not close");
            for i in 1..lp.len() - 1 {
                tris.push([lp[0], lp[i], lp[i + 1]]);
            }
        }
        start[case + 1] = tris.len() as u16;
    }
    McTable { start, tris }
}

/// The table (built once).
pub(crate) fn table() -> &'static McTable {
    static TABLE: OnceLock<McTable> = OnceLock::new();
    TABLE.get_or_init(build)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_basics() {
        let t = table();
        assert_eq!(t.count(0), 0);
        assert_eq!(t.count(255), 0);
        for c in 0..8 {
            assert_eq!(t.count(1 << c), 1);
            assert_eq!(t.count(255 ^ (1 << c)), 1);
        }
        // A plane through the cube: a quad, two triangles.
        assert_eq!(t.count(0b0000_1111), 2);
        let max = (0..256).map(|c| t.count(c)).max().unwrap();
        assert!(max <= 8, "{max}");
    }
}
