//! The random-access API of §5.1 on [`RacBvh`]: `root_index`, `bv`,
//! `is_leaf`, `left`, `right`, `triangle_index` and a leaf's triangles,
//! with `try_` variants that return errors instead of panicking.

use super::node::qbox_of;
use super::{RacBvh, RacError};
use crate::build::LEAF_FLAG;
use crate::geom::Aabb;

impl RacBvh {
    /// [`try_words`](Self::try_words), panicking with its error.
    #[inline]
    pub(super) fn words(&self, g: u32) -> [u32; 8] {
        self.try_words(g)
            .unwrap_or_else(|e| panic!("racbvh: {e} (run verify() to check the data)"))
    }

    /// The decoded box of complete words.
    #[inline]
    pub(super) fn box_of(&self, w: &[u32; 8]) -> Aabb {
        if self.header.empty {
            return Aabb::EMPTY;
        }
        self.header.grid.dequantize(&qbox_of(w))
    }

    /// `GetRootIndex`: the root's index (always 0).
    pub fn root_index(&self) -> u32 {
        0
    }

    /// `GetBV`: the conservative box of node `i`.
    ///
    /// # Panics
    /// If `i` does not exist or its data is corrupted (see [`try_bv`](Self::try_bv)).
    pub fn bv(&self, i: u32) -> Aabb {
        self.box_of(&self.words(i))
    }

    /// [`bv`](Self::bv) returning errors.
    pub fn try_bv(&self, i: u32) -> Result<Aabb, RacError> {
        Ok(self.box_of(&self.try_words(i)?))
    }

    /// `IsLeaf`: whether node `i` is a leaf. Panics like [`bv`](Self::bv).
    pub fn is_leaf(&self, i: u32) -> bool {
        self.words(i)[7] & LEAF_FLAG != 0
    }

    /// `GetLeftChildIdx`: the left child of inner node `i`. Panics like
    /// [`bv`](Self::bv), or if `i` is a leaf.
    pub fn left(&self, i: u32) -> u32 {
        let w = self.words(i);
        assert!(w[7] & LEAF_FLAG == 0, "racbvh: left({i}) of a leaf");
        w[6]
    }

    /// `GetRightChildIdx`: the right child of inner node `i`. Panics like
    /// [`left`](Self::left).
    pub fn right(&self, i: u32) -> u32 {
        let w = self.words(i);
        assert!(w[7] & LEAF_FLAG == 0, "racbvh: right({i}) of a leaf");
        w[7]
    }

    /// `GetTriangleIdx`: the (first) original triangle id of leaf `i`, or
    /// `None` for the empty tree's root. Panics like [`left`](Self::left)
    /// if `i` is not a leaf.
    pub fn triangle_index(&self, i: u32) -> Option<u32> {
        self.leaf_triangles(i).first().copied()
    }

    /// The original triangle ids of leaf `i`.
    pub fn leaf_triangles(&self, i: u32) -> Vec<u32> {
        let mut out = Vec::new();
        self.try_leaf_ids(i, &mut |id| out.push(id))
            .unwrap_or_else(|e| panic!("racbvh: {e}"));
        out
    }

    pub(super) fn try_leaf_ids(&self, i: u32, f: &mut dyn FnMut(u32)) -> Result<(), RacError> {
        let w = self.try_words(i)?;
        assert!(w[7] & LEAF_FLAG != 0, "racbvh: triangles of inner node {i}");
        let count = w[7] & !LEAF_FLAG;
        if count == 1 {
            f(w[6]);
        } else if count > 1 {
            if let Some(ids) = self
                .nodes
                .as_ref()
                .and_then(|n| n.get_ids(i, count as usize))
            {
                ids[..count as usize].iter().for_each(|&id| f(id));
                return Ok(());
            }
            let cl = self.cluster(i >> self.header.cluster_bits)?;
            let ids =
                cl.tris
                    .get(w[6] as usize..(w[6] + count) as usize)
                    .ok_or(RacError::Corrupt(
                        "a leaf's triangle slots are out of range",
                    ))?;
            ids.iter().for_each(|&id| f(id));
            self.remember(i, &w, &cl);
        }
        Ok(())
    }
}
