//! [`HccError`].

/// What can stop an i-HCCMesh encode.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum HccError {
    /// The canonical tree was built with leaves too large for a
    /// multi-triangle leaf.
    #[error(
        "leaves of up to {got} triangles are more than hcc-multi stores (at most {limit}); build with a smaller leaf size"
    )]
    LeafSize {
        /// The tree's leaf size.
        got: usize,
        /// The largest supported.
        limit: usize,
    },
    /// The tree was not built over this mesh.
    #[error(
        "the tree holds {tree} triangles but the mesh has {mesh}: encode the tree with the mesh it was built from"
    )]
    MeshMismatch {
        /// Triangles in the tree.
        tree: usize,
        /// Triangles in the mesh.
        mesh: usize,
    },
    /// The canonical tree is not a tree over the mesh's triangles as the
    /// builder makes them (checked before the encoder reads it; see
    /// [`CanonicalBvh`](crate::build::CanonicalBvh)).
    #[error(
        "canonical node {node}: {what}; this is not a tree the builder makes over this mesh: build it again"
    )]
    BadTree {
        /// The canonical node where the walk from the root found it.
        node: u32,
        /// What is wrong.
        what: &'static str,
    },
    /// A single leaf has too many distinct vertices for a low-level tree.
    #[error(
        "leaf node {node} alone has {vertices} distinct vertices, more than a low-level tree indexes (511); build with a smaller leaf size"
    )]
    LeafTooBig {
        /// The canonical node.
        node: u32,
        /// Its distinct vertices.
        vertices: usize,
    },
    /// A low-level tree came out larger than its index fields address
    /// (the decomposition should have prevented this).
    #[error(
        "low-level tree {tree} has {nodes} nodes and {interconnections} inter-connections, more than 13-bit positions and 9-bit indices address"
    )]
    TreeLimits {
        /// The low-level tree.
        tree: u32,
        /// Its nodes.
        nodes: usize,
        /// Its inter-connections.
        interconnections: usize,
    },
    /// More low-level trees than a node handle numbers.
    #[error(
        "the mesh decomposes into {trees} low-level trees, more than hcc numbers ({limit}, about 600 M triangles); build with larger leaves or split the mesh"
    )]
    TooManyTrees {
        /// The low-level trees of the decomposition.
        trees: usize,
        /// The most supported.
        limit: usize,
    },
    /// Quantized vertices with a bit count the packing does not take.
    #[error(
        "{got} bits per quantized vertex coordinate: hcc takes 1 to {limit} (16 is the usual choice)"
    )]
    VertexBits {
        /// The bits asked for.
        got: u32,
        /// The most supported.
        limit: u32,
    },
    /// Quantized vertices over a mesh whose extent overflows `f32`.
    #[error(
        "the mesh's extent ({extent}) overflows f32, so no quantization grid spans it; keep f32 vertices or check the mesh's coordinates"
    )]
    Extent {
        /// The extent along the first axis found not finite.
        extent: f32,
    },
    /// A low-level tree's triangle blocks outgrew the leaf words' offset
    /// field (the decomposition's triangle limit should prevent this).
    #[error(
        "low-level tree {tree}'s triangle blocks reach bit {bits}, more than a leaf word addresses (2^21) or the blocks array holds (2^32 bytes)"
    )]
    BlockLimits {
        /// The low-level tree.
        tree: u32,
        /// The bit offset that did not fit.
        bits: u64,
    },
    /// Bytes that break the file frame (magic, truncation, checksums).
    #[error(transparent)]
    Format(#[from] crate::codec::common::FormatError),
    /// A version this build cannot read.
    #[error(
        "i-HCCMesh file version {found} is not supported (this build reads version {supported}); rebuild it with `cbvh build MESH --codec hcc -o FILE`"
    )]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// A structure that breaks what queries rely on.
    #[error("low-level tree {tree}, node word {node}: {what}; the file is damaged, rebuild it")]
    Corrupt {
        /// The low-level tree (0 for the high-level tree).
        tree: u32,
        /// The node word or high-level node.
        node: u32,
        /// What is wrong.
        what: &'static str,
    },
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] crate::files::IoError),
}
