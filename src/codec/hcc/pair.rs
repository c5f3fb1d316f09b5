//! The box coding of one sibling pair (§4.2): which extents each child
//! inherits from the box its parent decodes to (the reuse mask) and which
//! vertices give the others. One function, used by the i-HCCMesh encoder
//! and by the o-HCCMesh decoder when it rebuilds the node words, so that
//! both make the same choice, tie for tie.

/// An extent `e` of a box as six numbers: 0–2 the minimum, 3–5 the maximum.
pub(super) type Extents = [f32; 6];

/// The empty box, ready to grow.
pub(super) const EMPTY: Extents = [
    f32::INFINITY,
    f32::INFINITY,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NEG_INFINITY,
    f32::NEG_INFINITY,
];

/// Whether extent `e`'s value `a` is farther out than `b`.
#[inline(always)]
pub(super) fn outer(e: usize, a: f32, b: f32) -> bool {
    if e < 3 { a < b } else { a > b }
}

/// What one sibling pair codes.
pub(super) struct PairCode {
    /// The six reuse-mask bits (bits 0–2 go to the left word, 3–5 to the
    /// right one).
    pub mask: u32,
    /// The vertex fields of the left and right word, in the callers' vertex
    /// numbering; only the first `used[side]` are set.
    pub fields: [[u32; 3]; 2],
    /// How many fields of each word the pair sets (0 for a leaf, whose
    /// fields hold its corners).
    pub used: [usize; 2],
    /// The boxes the two children decode to.
    pub boxes: [Extents; 2],
    /// Extents the inner child of a leaf–inner pair inherits although it
    /// does not attain them.
    pub loose: usize,
}

/// Codes the pair of children with tight boxes `tl`, `tr` attained by
/// vertices `vl`, `vr` (per extent), under a parent that decodes to `d`;
/// `ll`, `rl` say which children are leaves.
#[inline(always)]
pub(super) fn code_pair(
    d: &Extents,
    (tl, vl, ll): (&Extents, &[u32; 6], bool),
    (tr, vr, rl): (&Extents, &[u32; 6], bool),
) -> PairCode {
    // Each case builds its results in locals indexed by constants only, so
    // that the code stays in registers once inlined (a `PairCode` written
    // field by field through dynamic indices would go through memory).
    match (ll, rl) {
        (false, false) => {
            let (mut mask, mut fields, mut boxes) = (0, [[0; 3]; 2], [*tl, *tr]);
            // Without branches on the extents (whichever child attains an
            // extent is a coin toss): `|` and `&` rather than `||` and `&&`.
            for e in 0..6 {
                let left_inherits = (tl[e] == d[e])
                    | ((tr[e] != d[e])
                        // A parent decoded looser than tight: the child
                        // that loses less inherits.
                        & ((d[e] - tl[e]).abs() <= (d[e] - tr[e]).abs()));
                mask |= u32::from(left_inherits) << e;
                boxes[0][e] = if left_inherits { d[e] } else { tl[e] };
                boxes[1][e] = if left_inherits { tr[e] } else { d[e] };
                // Minima in the left word, maxima in the right one.
                fields[e / 3][e % 3] = if left_inherits { vr[e] } else { vl[e] };
            }
            PairCode {
                mask,
                fields,
                used: [3, 3],
                boxes,
                loose: 0,
            }
        }
        (true, true) => PairCode {
            mask: 0,
            fields: [[0; 3]; 2],
            used: [0; 2],
            boxes: [*tl, *tr],
            loose: 0,
        },
        (leaf_left, _) => {
            let (ti, vi) = if leaf_left { (tr, vr) } else { (tl, vl) };
            let axis = |e: usize| (d[e % 3 + 3] - d[e % 3]).max(f32::MIN_POSITIVE);
            let mut need = [0usize; 6];
            let mut n = 0;
            for e in 0..6 {
                need[n] = e;
                n += usize::from(ti[e] != d[e]);
            }
            let mut loose = 0;
            if n > 3 {
                // Three vertex fields: keep the three extents that shrink
                // the box most; the rest inherit (loose but conservative).
                need[..n].sort_by(|&a, &b| {
                    let la = (d[a] - ti[a]).abs() / axis(a);
                    let lb = (d[b] - ti[b]).abs() / axis(b);
                    lb.total_cmp(&la).then(a.cmp(&b))
                });
                loose = n - 3;
                n = 3;
                need[..n].sort_unstable();
            }
            let (mut mask, mut f) = (0b11_1111u32, [0u32; 3]);
            for (j, &e) in need[..n].iter().enumerate() {
                mask &= !(1 << e);
                f[j] = vi[e];
            }
            let inner: Extents =
                std::array::from_fn(|e| if mask >> e & 1 != 0 { d[e] } else { ti[e] });
            let (fields, used, boxes) = if leaf_left {
                ([[0; 3], f], [0, n], [*tl, inner])
            } else {
                ([f, [0; 3]], [n, 0], [inner, *tr])
            };
            PairCode {
                mask,
                fields,
                used,
                boxes,
                loose,
            }
        }
    }
}
