//! Multi-triangle leaves: each leaf's triangles as one bit-packed block of
//! local vertex indices.
//!
//! # Layout
//!
//! A low-level tree's blocks are one bit stream (least-significant bit
//! first) starting on a byte of the `blocks` array (the tree's
//! `block_start`); a leaf word holds its block's bit offset in that stream
//! and its triangle count (see [`node`](super::node)). A block is
//!
//! | bits | field |
//! |---|---|
//! | `S` | the leaf's first *slot*: its triangles' position among the tree's, in node-word order (`S` = bits of the tree's triangle count − 1) |
//! | 9 | `base`: the smallest local vertex index of the leaf's corners |
//! | 4 | `w`: bits per corner offset, 0 to 9 |
//! | `3 · w` per triangle | each corner's local index − `base`, corner 0 first |
//!
//! The tree's vertex array is ordered by first use, leaf by leaf in block
//! order, so a leaf's corners sit in a narrow window of it (its own new
//! vertices and its neighbours' recent ones) and `w` is usually 4–6 bits
//! instead of 9. A triangle's slot plus the tree's first rank is its
//! storage rank, which the id map turns into the input id.

use super::node::INDEX_BITS;
use super::vertices::{bits_at, width_of};
use crate::codec::common::bits::BitWriter;

/// Bits of a block's corner-width field.
pub const WIDTH_BITS: u32 = 4;

/// Bits of the slot field for a tree of `triangles` triangles.
#[inline(always)]
pub fn slot_bits(triangles: u32) -> u32 {
    width_of(triangles.saturating_sub(1))
}

/// A block's header, read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// The leaf's first slot in its tree.
    pub slot: u32,
    /// The smallest local vertex index.
    pub base: u32,
    /// Bits per corner offset.
    pub width: u32,
    /// Bit position (in the blocks array) of the first triangle.
    pub at: u64,
}

impl Block {
    /// Reads the block header at bit `at` of `blocks`.
    #[inline(always)]
    pub fn read(blocks: &[u8], at: u64, slot_bits: u32) -> Self {
        let head = bits_at(blocks, at, slot_bits + INDEX_BITS + WIDTH_BITS);
        let slot = head & ((1u32 << slot_bits) - 1);
        let rest = head >> slot_bits;
        Self {
            slot,
            base: rest & ((1 << INDEX_BITS) - 1),
            width: rest >> INDEX_BITS,
            at: at + u64::from(slot_bits + INDEX_BITS + WIDTH_BITS),
        }
    }

    /// The local corners of the block's triangle `j`.
    #[inline(always)]
    pub fn corners(&self, blocks: &[u8], j: u32) -> [u32; 3] {
        let w = self.width;
        let bits = bits_at(blocks, self.at + u64::from(3 * w * j), 3 * w);
        let m = (1u32 << w) - 1;
        [
            self.base + (bits & m),
            self.base + (bits >> w & m),
            self.base + (bits >> (2 * w) & m),
        ]
    }

    /// Bit position just past a block of `count` triangles.
    pub fn end(&self, count: u32) -> u64 {
        self.at + u64::from(3 * self.width * count)
    }
}

/// Appends the block of the leaf whose first slot is `slot` and whose
/// triangles have local corners `corners` (each below 512); returns the
/// block's bit offset in `w`.
pub fn write(w: &mut BitWriter, slot: u32, slot_bits: u32, corners: &[[u32; 3]]) -> u64 {
    let at = w.bit_len();
    let base = corners.iter().flatten().copied().min().unwrap_or(0);
    let top = corners.iter().flatten().copied().max().unwrap_or(0);
    let width = width_of(top - base);
    debug_assert!(top < 1 << INDEX_BITS && slot < 1 << slot_bits.max(1));
    w.put(u64::from(slot), slot_bits);
    w.put(u64::from(base), INDEX_BITS);
    w.put(u64::from(width), WIDTH_BITS);
    for c in corners {
        for &v in c {
            w.put(u64::from(v - base), width);
        }
    }
    at
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_round_trip() {
        let leaves: Vec<Vec<[u32; 3]>> = vec![
            vec![[7, 8, 9], [9, 8, 10]],
            vec![[511, 0, 3]],
            vec![[4, 4, 4]; 5],
            (0..64).map(|k| [k, k + 1, k + 2]).collect(),
        ];
        let sb = slot_bits(80);
        let mut w = BitWriter::default();
        w.put(1, 3); // not at bit 0
        let mut slot = 0;
        let mut at = Vec::new();
        for l in &leaves {
            at.push(write(&mut w, slot, sb, l));
            slot += l.len() as u32;
        }
        let bytes = w.finish();
        let mut slot = 0;
        for (l, &a) in leaves.iter().zip(&at) {
            let b = Block::read(&bytes, a, sb);
            assert_eq!(b.slot, slot);
            for (j, c) in l.iter().enumerate() {
                assert_eq!(b.corners(&bytes, j as u32), *c);
            }
            slot += l.len() as u32;
        }
        assert_eq!(Block::read(&bytes, at[2], sb).width, 0);
        assert_eq!(slot_bits(1), 0);
        assert_eq!(slot_bits(2), 1);
        assert_eq!(slot_bits(80), 7);
    }
}
