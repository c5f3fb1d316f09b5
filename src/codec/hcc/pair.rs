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
    let mut out = PairCode {
        mask: 0,
        fields: [[0; 3]; 2],
        used: [0; 2],
        boxes: [*tl, *tr],
        loose: 0,
    };
    match (ll, rl) {
        (false, false) => {
            for e in 0..6 {
                let left_inherits = if tl[e] == d[e] {
                    true
                } else if tr[e] == d[e] {
                    false
                } else {
                    // A parent decoded looser than tight: the child that
                    // loses less inherits.
                    (d[e] - tl[e]).abs() <= (d[e] - tr[e]).abs()
                };
                let v = if left_inherits {
                    out.mask |= 1 << e;
                    out.boxes[0][e] = d[e];
                    vr[e]
                } else {
                    out.boxes[1][e] = d[e];
                    vl[e]
                };
                // Minima in the left word, maxima in the right one.
                out.fields[e / 3][e % 3] = v;
            }
            out.used = [3, 3];
        }
        (true, true) => {}
        (leaf_left, _) => {
            let (side, ti, vi) = if leaf_left { (1, tr, vr) } else { (0, tl, vl) };
            let axis = |e: usize| (d[e % 3 + 3] - d[e % 3]).max(f32::MIN_POSITIVE);
            let mut need = [0usize; 6];
            let mut n = 0;
            for e in 0..6 {
                if ti[e] != d[e] {
                    need[n] = e;
                    n += 1;
                }
            }
            if n > 3 {
                // Three vertex fields: keep the three extents that shrink
                // the box most; the rest inherit (loose but conservative).
                need[..n].sort_by(|&a, &b| {
                    let la = (d[a] - ti[a]).abs() / axis(a);
                    let lb = (d[b] - ti[b]).abs() / axis(b);
                    lb.total_cmp(&la).then(a.cmp(&b))
                });
                out.loose = n - 3;
                n = 3;
                need[..n].sort_unstable();
            }
            out.mask = 0b11_1111;
            for (j, &e) in need[..n].iter().enumerate() {
                out.mask &= !(1 << e);
                out.fields[side][j] = vi[e];
            }
            out.used[side] = n;
            for (e, b) in out.boxes[side].iter_mut().enumerate() {
                if out.mask >> e & 1 != 0 {
                    *b = d[e];
                }
            }
        }
    }
    out
}
