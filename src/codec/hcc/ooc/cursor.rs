//! [`NodeCursor`] over an [`HccOocBvh`], and its [`RayCursor`]: both
//! delegate to the decoded i-HCCMesh, or to the paged trees out of core
//! (through i-HCCMesh's own ray traversal, module `hcc::trace`).

use super::super::HccNode;
use super::super::trace::{self, Pairs};
use super::paged::Paged;
use super::{HccOocBvh, Mode};
use crate::cursor::{Children, NodeCursor, TraversalStats};
use crate::geom::{Aabb, Ray, Triangle};
use crate::query::{RayCursor, RayHit};

impl NodeCursor for HccOocBvh {
    type Node = HccNode;

    #[inline(always)]
    fn root(&self) -> (HccNode, Aabb) {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.root(),
            Mode::Paged(p) => p.root(),
        }
    }

    #[inline(always)]
    fn is_leaf(&self, node: &HccNode) -> bool {
        match &self.mode {
            Mode::Paged(p) if node.is_unopened() => p.open(node).is_leaf(),
            _ => node.is_leaf(),
        }
    }

    #[inline]
    fn for_each_child(&self, node: &HccNode, mut f: impl FnMut(HccNode, Aabb)) {
        let kids = match &self.mode {
            Mode::Whole { hcc, .. } => hcc.children_of(node),
            Mode::Paged(p) => p.children_of(node),
        };
        for (c, b) in kids {
            f(c, b);
        }
    }

    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn children(&self, node: &HccNode, out: &mut Children<HccNode>) {
        match &self.mode {
            Mode::Whole { hcc, .. } => out.set(&hcc.children_of(node)),
            Mode::Paged(p) => out.set(&p.children_of(node)),
        }
    }

    #[inline]
    fn for_each_triangle(&self, node: &HccNode, mut f: impl FnMut(u32, &Triangle)) {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.for_each_triangle(node, f),
            Mode::Paged(p) => p.for_each_triangle(node, &mut f),
        }
    }

    /// Keys are storage ranks, as the pre-loaded i-HCCMesh's.
    #[inline]
    fn for_each_triangle_keyed(&self, node: &HccNode, mut f: impl FnMut(u32, &Triangle)) {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.for_each_triangle_keyed(node, f),
            Mode::Paged(p) => p.for_each_ranked_triangle(node, &mut f),
        }
    }

    #[inline(always)]
    fn id_of_key(&self, key: u32) -> u32 {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.id_of_key(key),
            Mode::Paged(p) => p.id_of(key),
        }
    }

    fn triangle(&self, id: u32) -> Triangle {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.triangle(id),
            Mode::Paged(p) => p.triangle(id),
        }
    }

    fn triangle_count(&self) -> usize {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.triangle_count(),
            Mode::Paged(p) => p.triangle_count(),
        }
    }
}

impl RayCursor for HccOocBvh {
    /// The i-HCCMesh's own traversal (module `hcc::trace`), over the
    /// decoded mesh or the paged trees.
    #[inline]
    fn closest_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> Option<RayHit> {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.closest_hit(ray, t_max, stats),
            Mode::Paged(p) => trace::closest_hit(self, p, ray, t_max, stats),
        }
    }

    /// As [`closest_hit`](Self::closest_hit).
    #[inline]
    fn any_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.any_hit(ray, t_max, stats),
            Mode::Paged(p) => trace::any_hit(self, p, ray, t_max, stats),
        }
    }
}

impl Pairs for Paged {
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn pair(&self, node: &HccNode) -> [(HccNode, Aabb); 2] {
        self.children_of(node)
    }
}
