//! Each thread's cache of decoded triangles, keyed by tree and triangle id.

use super::RacBvh;
use crate::geom::Triangle;

/// Decoded triangles per thread, direct-mapped by triangle id: (tree id,
/// triangle id, corners). A traversal of two trees meets the same leaf
/// again and again (once per leaf of the other tree it overlaps), and a
/// stored triangle costs twelve frame-of-reference look-ups to decode.
const TRI_CACHE: usize = 1024;

type TriSlot = (u64, u32, Triangle);

thread_local! {
    static TRIS: std::cell::RefCell<Box<[TriSlot]>> =
        std::cell::RefCell::new(vec![(0, 0, [glam::Vec3A::ZERO; 3]); TRI_CACHE].into_boxed_slice());
}

impl RacBvh {
    /// Triangle `id` of the stored mesh, through this thread's cache of
    /// decoded triangles (tree ids start at 1, so an empty slot never
    /// matches).
    #[inline]
    pub(super) fn cached_triangle(&self, id: u32) -> Triangle {
        let slot = id as usize % TRI_CACHE;
        let hit = TRIS.with(|c| {
            let c = c.try_borrow().ok()?;
            let (tree, tid, tri) = &c[slot];
            (*tree == self.id && *tid == id).then_some(*tri)
        });
        if let Some(t) = hit {
            return t;
        }
        self.expect_mesh();
        let t = self.mesh.triangle(id);
        TRIS.with(|c| {
            if let Ok(mut c) = c.try_borrow_mut() {
                c[slot] = (self.id, id, t);
            }
        });
        t
    }
}
