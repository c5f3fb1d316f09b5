//! Coder contexts and the symbol mappings shared by the encoder and the
//! decoder (see the module docs of [`super`] for what each codes).

use super::Header;
use crate::codec::common::packed::bits_for;

/// Coder context: the structure symbol.
pub(super) const CTX_STRUCT: usize = 0;
/// Coder context: a local root's parent cluster index.
pub(super) const CTX_PCLUSTER: usize = 1;
/// Coder context: triangle-id deltas.
pub(super) const CTX_TRI: usize = 2;
/// Coder context: leaf triangle counts.
pub(super) const CTX_COUNT: usize = 3;
/// Coder context: local-leaf child index deltas.
pub(super) const CTX_CHILD: usize = 4;
/// Coder context: the bit length of a triangle-id delta too large for
/// [`CTX_TRI`].
pub(super) const CTX_TRI_FAR: usize = 5;
/// First of the 24 box-residual contexts (see [`mask_context`] and
/// [`value_context`]).
pub(super) const CTX_BV: usize = 6;
/// Number of contexts.
pub(super) const NCTX: usize = CTX_BV + 24;

/// The mask of a node's zero residuals, as sent: XORed with the mask
/// predicted from the sibling (when the sibling is earlier in the same
/// cluster). A face one sibling leaves is a face the other touches, so the
/// sibling's non-zero residuals predict this node's zero ones.
#[inline]
pub(super) fn zero_mask(r: &[u32; 6], sibling: Option<&[u32; 6]>) -> u32 {
    let mut m = 0;
    for k in 0..6 {
        let predicted = sibling.is_some_and(|s| s[k] != 0);
        m |= u32::from((r[k] == 0) != predicted) << k;
    }
    m
}

/// Context of the zero mask: by leaf, side, sibling known.
#[inline]
pub(super) fn mask_context(leaf: bool, right: bool, sibling: bool) -> usize {
    CTX_BV + ((usize::from(leaf) << 2) | (usize::from(right) << 1) | usize::from(sibling))
}

/// Context of non-zero residual `k` (0..6): by leaf, side, min-or-max
/// half, sibling known.
#[inline]
pub(super) fn value_context(leaf: bool, right: bool, k: usize, sibling: bool) -> usize {
    CTX_BV
        + 8
        + (((usize::from(leaf) << 3) | (usize::from(right) << 2) | ((k / 3) << 1))
            | usize::from(sibling))
}

/// A box residual (or a far triangle-id delta) is sent as its bit length
/// (the symbol) followed by its bits below the leading one, raw.
#[inline]
pub(super) fn bucket(r: u64) -> u32 {
    64 - r.leading_zeros()
}

/// Raw bits of a new symbol in context `ctx`.
pub(super) fn raw_bits(ctx: usize, h: &Header) -> u32 {
    match ctx {
        CTX_STRUCT => h.cluster_bits + 3,
        CTX_PCLUSTER => h.cluster_bits + 1,
        CTX_TRI => bits_for(2 * u64::from(h.tri_threshold)),
        CTX_COUNT => 17,
        CTX_CHILD => bits_for(u64::from(h.node_count)) + 1,
        CTX_TRI_FAR => 6,
        c if c < CTX_BV + 8 => 6,
        _ => 5,
    }
}

/// Number of bit streams in a cluster: the tree (structure, pair indices,
/// triangle ids, local-leaf children), the zero masks, and one per box
/// residual component (min x, y, z, max x, y, z). Decoding reads them side
/// by side, so each stream's chain of dependent reads (a code's length
/// depends on the previous code) is a sixth of a node's, and the processor
/// overlaps them.
pub(super) const STREAMS: usize = 8;
/// The stream of the boxes' zero masks.
pub(super) const STREAM_MASK: usize = 1;
/// The stream of residual component 0 (component `k` is `STREAM_RES + k`).
pub(super) const STREAM_RES: usize = 2;
