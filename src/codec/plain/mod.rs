//! The plain codec: the uncompressed reference every comparison is made
//! against (the papers' "Ori."). See [`node::PlainNode`] for the node
//! layout and [`file`](mod@file) for the self-contained file.

mod contract;
mod decode;
mod encode;
mod error;
pub mod file;
mod node;

pub use encode::PlainBvh;
pub use error::PlainError;
pub use node::PlainNode;
