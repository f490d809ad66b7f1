//! The one BVH node layout: what the builders produce, the GPU reads and the CPU traversals walk.
//!
//! Nodes live in one array: the n - 1 internal nodes first (Karras's numbering: internal node i is
//! the one whose key range starts or ends at sorted position i), then the n leaves in sorted
//! order. The root is node 0 (for n = 1 it is the only leaf). The WGSL twin is `BvhNode` in
//! `shaders/types.wgsl`.

use bytemuck::{Pod, Zeroable};

/// "No node": the root's parent, and the escape link of the last subtree in depth-first order.
pub const NONE: u32 = u32::MAX;
/// The `right` field of a leaf.
pub const LEAF: u32 = u32::MAX;

/// A node of the build layout, as the stackless walk reads it: its box, its children (or its
/// primitive), its parent and its skip link.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuNode {
    /// Bounding box minimum corner.
    pub min: [f32; 3],
    /// Internal node: index of the left child. Leaf: index of its primitive (a sphere).
    pub left: u32,
    /// Bounding box maximum corner.
    pub max: [f32; 3],
    /// Internal node: index of the right child. Leaf: [`LEAF`].
    pub right: u32,
    /// Index of the parent node; [`NONE`] for the root.
    pub parent: u32,
    /// The node that follows this subtree in depth-first order, left child first (threaded
    /// traversal's skip link): the right sibling of the nearest ancestor-or-self that is a left
    /// child; [`NONE`] when the subtree ends the tree.
    pub escape: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
}

impl GpuNode {
    /// Whether the node is a leaf (it holds one primitive).
    pub fn is_leaf(&self) -> bool {
        self.right == LEAF
    }
}
