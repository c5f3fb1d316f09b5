//! The plain codec: the uncompressed reference every comparison is made
//! against (the papers' "Ori."). See [`node::PlainNode`] for the node
//! layout and [`file`](mod@file) for the self-contained file.
//!
//! Its nodes, vertices and triangles live in memory advised for
//! transparent huge pages ([`huge`](crate::codec::common::huge)), like
//! CLBVH's and Embree's, so that speed comparisons between them are about
//! layouts, not page sizes.

mod contract;
mod decode;
mod encode;
mod error;
pub mod file;
mod node;

pub use encode::PlainBvh;
pub use error::PlainError;
pub use node::PlainNode;
