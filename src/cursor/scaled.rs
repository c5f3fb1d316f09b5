//! [`Scaled`]: a cursor that shows another cursor's tree scaled axis by
//! axis, so that one compressed tree serves every scale of its shape
//! without being re-encoded (parry's `Shape::scale_dyn`).
//!
//! Boxes and triangle corners are multiplied by the scale as they are
//! handed out. A product rounds the same way for a box's bound as for a
//! corner's coordinate (rounding is monotonic), so the invariant every
//! cursor keeps (a node's box contains every triangle below it) holds for
//! the scaled tree exactly, mirrored axes included (a negative factor swaps
//! that axis's bounds). A scaled corner is the same `f32` as the corner of
//! a mesh whose vertices were scaled first, so a scaled view of an exact
//! codec answers as that mesh's tree does, up to ties between triangles.
//!
//! The unscaled view (every factor 1) is the same wrapper with a flag, so
//! that traversals are compiled once per codec, not twice: its only cost is
//! a branch that always goes the same way.

use glam::Vec3A;

use super::{Children, NodeCursor};
use crate::geom::{Aabb, Triangle};

/// `inner`'s tree scaled by a factor per axis (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct Scaled<'a, C> {
    inner: &'a C,
    scale: Vec3A,
    identity: bool,
}

impl<'a, C> Scaled<'a, C> {
    /// `inner` scaled by `scale`, whose components must be finite and
    /// non-zero (a negative one mirrors that axis).
    ///
    /// # Panics
    /// If a component is zero or not finite.
    #[inline]
    pub fn new(inner: &'a C, scale: Vec3A) -> Self {
        assert!(
            scale.is_finite() && scale.cmpne(Vec3A::ZERO).all(),
            "a scale needs finite, non-zero factors: {scale}"
        );
        Self {
            inner,
            scale,
            identity: scale == Vec3A::ONE,
        }
    }

    /// `inner` as it is (every factor 1).
    #[inline]
    pub fn unscaled(inner: &'a C) -> Self {
        Self {
            inner,
            scale: Vec3A::ONE,
            identity: true,
        }
    }

    /// The cursor underneath.
    #[inline]
    pub fn inner(&self) -> &'a C {
        self.inner
    }

    /// The factors.
    #[inline]
    pub fn scale(&self) -> Vec3A {
        self.scale
    }

    #[inline(always)]
    fn scale_box(&self, b: Aabb) -> Aabb {
        if self.identity {
            b
        } else {
            b.scaled(self.scale)
        }
    }

    #[inline(always)]
    fn scale_triangle(&self, t: &Triangle) -> Triangle {
        [t[0] * self.scale, t[1] * self.scale, t[2] * self.scale]
    }
}

impl<C: NodeCursor> NodeCursor for Scaled<'_, C> {
    type Node = C::Node;

    #[inline(always)]
    fn root(&self) -> (Self::Node, Aabb) {
        let (n, b) = self.inner.root();
        (n, self.scale_box(b))
    }

    #[inline(always)]
    fn is_leaf(&self, node: &Self::Node) -> bool {
        self.inner.is_leaf(node)
    }

    #[inline(always)]
    fn for_each_child(&self, node: &Self::Node, mut f: impl FnMut(Self::Node, Aabb)) {
        self.inner
            .for_each_child(node, |n, b| f(n, self.scale_box(b)));
    }

    #[inline(always)]
    fn children(&self, node: &Self::Node, out: &mut Children<Self::Node>) {
        self.inner.children(node, out);
        if !self.identity {
            out.scale_boxes(self.scale);
        }
    }

    #[inline(always)]
    fn for_each_triangle(&self, node: &Self::Node, mut f: impl FnMut(u32, &Triangle)) {
        if self.identity {
            self.inner.for_each_triangle(node, f)
        } else {
            self.inner
                .for_each_triangle(node, |id, t| f(id, &self.scale_triangle(t)))
        }
    }

    #[inline(always)]
    fn for_each_triangle_keyed(&self, node: &Self::Node, mut f: impl FnMut(u32, &Triangle)) {
        if self.identity {
            self.inner.for_each_triangle_keyed(node, f)
        } else {
            self.inner
                .for_each_triangle_keyed(node, |k, t| f(k, &self.scale_triangle(t)))
        }
    }

    #[inline(always)]
    fn id_of_key(&self, key: u32) -> u32 {
        self.inner.id_of_key(key)
    }

    #[inline(always)]
    fn triangle(&self, id: u32) -> Triangle {
        let t = self.inner.triangle(id);
        if self.identity {
            t
        } else {
            self.scale_triangle(&t)
        }
    }

    #[inline(always)]
    fn triangle_count(&self) -> usize {
        self.inner.triangle_count()
    }
}
