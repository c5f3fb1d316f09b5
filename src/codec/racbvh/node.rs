//! The median-split prediction of a child's quantized box from its
//! parent's (§4.2) and the in-core node a cluster decompresses into (§5).
//! Boxes are quantized on one
//! [`Grid`](crate::codec::common::quant::Grid) over the root box.

use std::sync::atomic::{AtomicU32, Ordering};

use glam::UVec3;

use crate::codec::common::bits::{unzigzag, zigzag};
use crate::codec::common::quant::QBox;

/// Flag in [`CoreNode`] word 0 marking an *incomplete* node (§5.2): its
/// box words still hold the coded residuals.
pub const INCOMPLETE: u32 = 0x8000_0000;

/// The median-split prediction: the parent's longest quantized axis (the
/// lowest on ties) and its middle.
#[inline]
pub fn split(parent: &QBox) -> (usize, u32) {
    let e = parent.max - parent.min;
    let a = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    (a, parent.min[a] + (parent.max[a] - parent.min[a]) / 2)
}

/// The six residuals of `child` against the prediction from `parent` for
/// side `right`, in component order min x,y,z, max x,y,z. Outer faces are
/// coded as inward distances (≥ 0), the split face as a zig-zagged signed
/// offset from the middle. (Which component is the split face depends on the
/// parent's box, which an incomplete node does not know yet; so the coder's
/// contexts are chosen from the side and the min/max half only.)
pub fn residuals(parent: &QBox, right: bool, child: &QBox) -> [u64; 6] {
    let (axis, mid) = split(parent);
    let mut out = [0; 6];
    for a in 0..3 {
        out[a] = if right && a == axis {
            zigzag(i64::from(child.min[a]) - i64::from(mid))
        } else {
            u64::from(child.min[a] - parent.min[a])
        };
        out[3 + a] = if !right && a == axis {
            zigzag(i64::from(child.max[a]) - i64::from(mid))
        } else {
            u64::from(parent.max[a] - child.max[a])
        };
    }
    out
}

/// Rebuilds a child box from its parent and residuals; `None` if the result
/// leaves the grid or is inverted (corrupted data).
#[inline]
pub fn apply(parent: &QBox, right: bool, r: &[u32; 6], max_q: u32) -> Option<QBox> {
    let (axis, mid) = split(parent);
    let mut q = QBox::default();
    let mut ok = true;
    for a in 0..3 {
        // Both candidates computed, one selected: no data-dependent branch.
        let split_min = i64::from(mid) + unzigzag(u64::from(r[a]));
        let outer_min = i64::from(parent.min[a]) + i64::from(r[a]);
        let split_max = i64::from(mid) + unzigzag(u64::from(r[3 + a]));
        let outer_max = i64::from(parent.max[a]) - i64::from(r[3 + a]);
        let on_axis = a == axis;
        let lo = if right & on_axis {
            split_min
        } else {
            outer_min
        };
        let hi = if !right & on_axis {
            split_max
        } else {
            outer_max
        };
        ok &= (lo >= 0) & (hi >= lo) & (hi <= i64::from(max_q));
        q.min[a] = lo as u32;
        q.max[a] = hi as u32;
    }
    ok.then_some(q)
}

/// The in-core node of §5: the 32 bytes of Listing 1, with the box held as
/// quantized integers so that children can be predicted from it.
///
/// # Layout
/// | word | complete node | incomplete node (§5.2) |
/// |---|---|---|
/// | 0–2 | quantized min x, y, z | residuals 0–2, word 0 ORed with [`INCOMPLETE`] |
/// | 3–5 | quantized max x, y, z | residuals 3–5 |
/// | 6 | inner: left child (global index); leaf with one triangle: its id; leaf with several: first slot in the cluster's triangle list | same |
/// | 7 | inner: right child; leaf: [`LEAF_FLAG`] \| triangle count | same |
///
/// [`LEAF_FLAG`] is the canonical tree's leaf flag. These words live in
/// core only: no flag value is part of the file format.
///
/// Words are atomics so that a completion (which rewrites words 0–5 under the
/// cluster's lock, word 0 last with release ordering) can run while other
/// threads read the same cluster.
///
/// [`LEAF_FLAG`]: crate::build::LEAF_FLAG
#[derive(Default)]
#[repr(C)]
pub struct CoreNode(pub [AtomicU32; 8]);

const _: () = assert!(std::mem::size_of::<CoreNode>() == 32);

impl CoreNode {
    /// A node from its words.
    pub fn new(words: [u32; 8]) -> Self {
        Self(words.map(AtomicU32::new))
    }

    /// Whether the box words hold the final box.
    #[inline]
    pub fn is_complete(&self) -> bool {
        self.0[0].load(Ordering::Acquire) & INCOMPLETE == 0
    }

    /// The words (word 0 read with acquire ordering first).
    #[inline]
    pub fn words(&self) -> [u32; 8] {
        let w0 = self.0[0].load(Ordering::Acquire);
        let mut w = [w0, 0, 0, 0, 0, 0, 0, 0];
        for (k, slot) in w.iter_mut().enumerate().skip(1) {
            *slot = self.0[k].load(Ordering::Relaxed);
        }
        w
    }

    /// Stores a completed box (word 0 last, with release ordering).
    pub fn set_box(&self, q: &QBox) {
        self.0[1].store(q.min.y, Ordering::Relaxed);
        self.0[2].store(q.min.z, Ordering::Relaxed);
        self.0[3].store(q.max.x, Ordering::Relaxed);
        self.0[4].store(q.max.y, Ordering::Relaxed);
        self.0[5].store(q.max.z, Ordering::Relaxed);
        self.0[0].store(q.min.x, Ordering::Release);
    }
}

/// The quantized box held in complete node words.
#[inline]
pub fn qbox_of(w: &[u32; 8]) -> QBox {
    QBox {
        min: UVec3::new(w[0], w[1], w[2]),
        max: UVec3::new(w[3], w[4], w[5]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residuals_invert() {
        let p = QBox {
            min: UVec3::new(3, 10, 0),
            max: UVec3::new(40, 20, 9),
        };
        let c = QBox {
            min: UVec3::new(25, 11, 0),
            max: UVec3::new(40, 19, 5),
        };
        for right in [false, true] {
            let r = residuals(&p, right, &c).map(|x| x as u32);
            assert_eq!(apply(&p, right, &r, 65535), Some(c));
        }
    }
}
