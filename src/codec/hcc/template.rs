//! The 26 tree templates of height 1 to 4 (HCCMesh §4.3).
//!
//! A template is the shape of a full binary tree (every node has 0 or 2
//! children) of height 1 to 4, written as a *breadth-first shape mask*: bit
//! `i` is set when the template's `i`-th node in breadth-first order has
//! two children inside the template. In breadth-first order the children of
//! the `k`-th node with children are nodes `2k + 1` and `2k + 2`, so a
//! node's children are found with one popcount ([`Template::children`]) and
//! siblings are always adjacent, which the pairwise box coding needs.
//!
//! There are `T(1) + T(2) + T(3) + T(4) = 1 + 1 + 3 + 21 = 26` shapes, as the
//! paper counts. Template ids are assigned by height, then by mask value;
//! the table is computed at compile time and checked by a const assertion.

/// Number of templates of height 1 to 4.
pub const TEMPLATE_COUNT: usize = 26;

/// The most nodes a template has (a complete tree of height 4).
pub const MAX_TEMPLATE_NODES: usize = 15;

/// Height of the tallest template; template leaves sit at depth
/// `MAX_HEIGHT - 1` within their template.
pub const MAX_HEIGHT: usize = 4;

/// One tree template.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Template {
    /// Breadth-first shape mask: bit `i` set when node `i` has children in
    /// the template.
    pub mask: u16,
    /// Number of nodes (`2 · popcount(mask) + 1`).
    pub nodes: u8,
    /// Height (a single node has height 1).
    pub height: u8,
}

impl Template {
    /// Local index of the left child of local node `i` (which must have
    /// children in the template); the right child follows it.
    #[inline(always)]
    pub fn children(&self, i: u32) -> u32 {
        2 * (self.mask as u32 & ((1u32 << i) - 1)).count_ones() + 1
    }

    /// Whether local node `i` has children inside the template.
    #[inline(always)]
    pub fn has_children(&self, i: u32) -> bool {
        self.mask >> i & 1 != 0
    }
}

/// Walks the breadth-first shape `mask`; returns `(nodes, height)` when it
/// is the canonical mask of a full binary tree of height at most 4.
const fn shape(mask: u16) -> Option<(u8, u8)> {
    let mut depth = [0u8; MAX_TEMPLATE_NODES];
    let mut n = 1usize;
    let mut i = 0usize;
    let mut height = 1u8;
    while i < n {
        let d = depth[i];
        if d + 1 > height {
            height = d + 1;
        }
        if mask >> i & 1 == 1 {
            if d as usize + 1 >= MAX_HEIGHT {
                return None;
            }
            depth[n] = d + 1;
            depth[n + 1] = d + 1;
            n += 2;
        }
        i += 1;
    }
    // Canonical: no bits beyond the last node.
    if n < 16 && (mask as u32) >> n != 0 {
        return None;
    }
    Some((n as u8, height))
}

/// The template table, computed at compile time (also for other compile-time
/// tables derived from it).
pub(super) const fn build_table() -> [Template; TEMPLATE_COUNT] {
    let mut out = [Template {
        mask: 0,
        nodes: 0,
        height: 0,
    }; TEMPLATE_COUNT];
    let mut count = 0;
    let mut h = 1u8;
    while h as usize <= MAX_HEIGHT {
        let mut mask = 0u32;
        while mask < 1 << MAX_TEMPLATE_NODES {
            if let Some((nodes, height)) = shape(mask as u16)
                && height == h
            {
                assert!(count < TEMPLATE_COUNT, "more templates than T(1..4)");
                out[count] = Template {
                    mask: mask as u16,
                    nodes,
                    height,
                };
                count += 1;
            }
            mask += 1;
        }
        h += 1;
    }
    assert!(count == TEMPLATE_COUNT, "fewer templates than T(1..4)");
    out
}

/// Every template, indexed by template id.
pub static TEMPLATES: [Template; TEMPLATE_COUNT] = build_table();

/// The id of the template with breadth-first shape `mask`, if any.
pub fn id_of_mask(mask: u16) -> Option<u8> {
    TEMPLATES
        .iter()
        .position(|t| t.mask == mask)
        .map(|i| i as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_by_height_match_the_paper() {
        let by_height = |h| TEMPLATES.iter().filter(|t| t.height == h).count();
        assert_eq!(
            [by_height(1), by_height(2), by_height(3), by_height(4)],
            [1, 1, 3, 21]
        );
        assert_eq!(TEMPLATES[0].nodes, 1);
        assert_eq!(TEMPLATES[1].mask, 1);
        assert!(
            TEMPLATES
                .iter()
                .all(|t| t.nodes as u32 == 2 * t.mask.count_ones() + 1)
        );
    }

    #[test]
    fn children_are_breadth_first() {
        // The complete tree of height 4: node i's children are 2i+1, 2i+2.
        let full = TEMPLATES[id_of_mask(0x7f).unwrap() as usize];
        for i in 0..7 {
            assert_eq!(full.children(i), 2 * i + 1);
        }
    }
}
