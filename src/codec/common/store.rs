//! [`Store`]: a codec's bytes, owned (pre-loaded) or a range of a
//! memory-mapped file (out of core).

use std::ops::Range;
use std::sync::Arc;

/// Bytes of a section: owned (pre-loaded mode) or a range of a memory-mapped
/// file (out-of-core mode: the operating system reads pages on demand).
#[derive(Clone)]
pub enum Store {
    /// Bytes in memory.
    Owned(Vec<u8>),
    /// A range of a mapped file.
    Mapped(Arc<memmap2::Mmap>, Range<usize>),
}

impl std::ops::Deref for Store {
    type Target = [u8];
    #[inline]
    fn deref(&self) -> &[u8] {
        match self {
            Store::Owned(v) => v,
            Store::Mapped(m, r) => &m[r.clone()],
        }
    }
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = if matches!(self, Store::Owned(_)) {
            "owned"
        } else {
            "mapped"
        };
        write!(f, "Store({kind}, {} bytes)", self.len())
    }
}
