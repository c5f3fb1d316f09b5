//! The plain codec: the uncompressed reference every comparison is made
//! against (the papers' "Ori."). See [`node::PlainNode`] for the layout.

mod decode;
mod encode;
mod node;

pub use encode::PlainBvh;
pub use node::{LEAF_FLAG, PlainNode};
