//! Karras's binary radix tree built bottom-up by merges (Apetrei 2014), with its boxes and links in
//! the same pass: the CPU's fast hierarchy. It gives the tree that Karras's per-node searches give
//! (`lbvh::internal_node`, and the GPU builder), numbered the same, bit for bit.
//!
//! Every node of the tree covers a run of sorted keys, and its parent is the node that extends the
//! run across the boundary, on either side, where the keys there share the longer prefix (the
//! smaller xor). So a finished subtree knows, from the keys on either side of it alone, which side
//! its sibling lies on, what its own number is, and its escape link. Leaves are taken in order with a
//! stack of finished subtrees that wait for a sibling on their right: a subtree whose sibling is
//! on its left merges with the top of the stack, which ends just before it, and the merge climbs
//! on. Each node is written whole, once, when its parent is made (the parent's number is the one
//! thing it lacks until then), and nothing is read back.
//!
//! In parallel: the leaves are cut into chunks, each merged on its own. What a chunk cannot finish
//! (subtrees whose sibling reaches into a neighbouring chunk: a few dozen) goes on, in order, to one
//! last serial merge of the same kind.

use super::aabb::Aabb;
use super::key::{Key, gather_leaf_boxes};
use super::layout::{GpuNode, LEAF, NONE};
use crate::parallel::DisjointWrites;
use glam::Vec3A;
use rayon::prelude::*;

/// Leaves merged by one task, by default.
pub(crate) const CHUNK: usize = 1 << 14;

/// Writes the tree over `keys` (sorted, each holding its primitive) into `nodes` (2n - 1 of them):
/// internal nodes in Karras's numbering, then the leaves in sorted order, each with its box, parent
/// and escape link. `leaf_boxes` keeps the leaves' boxes, in sorted order, for the next build.
/// `chunk` leaves are merged by one task ([`CHUNK`] unless a test wants more left to the last merge).
pub(crate) fn merge_bottom_up<K: Key>(
    keys: &[K],
    boxes: &[Aabb],
    leaf_boxes: &mut Vec<Aabb>,
    nodes: &mut [GpuNode],
    chunk: usize,
) {
    let n = keys.len();
    assert_eq!(nodes.len(), (2 * n).saturating_sub(1));
    assert!(chunk > 0);
    gather_leaf_boxes(keys, boxes, leaf_boxes);
    if n == 0 {
        return;
    }
    let leaf_boxes = &leaf_boxes[..];
    let nodes = DisjointWrites::new(nodes);
    // Merge each chunk's leaves
    let unfinished: Vec<Vec<Subtree>> = (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|task| {
            let positions = task * chunk..n.min((task + 1) * chunk);
            merge_leaves(keys, leaf_boxes, positions, &nodes)
        })
        .collect();
    // Merge what the chunks left, in order, up to the root
    let mut merger = Merger::new(&nodes, n);
    for subtree in unfinished.into_iter().flatten() {
        merger.add(subtree);
    }
    debug_assert!(merger.unfinished().is_empty(), "the merges end at the root");
}

/// Merges the leaves at `positions` and returns the subtrees whose sibling lies outside them, in
/// order.
#[inline(never)]
fn merge_leaves<K: Key>(
    keys: &[K],
    leaf_boxes: &[Aabb],
    positions: std::ops::Range<usize>,
    nodes: &DisjointWrites<GpuNode>,
) -> Vec<Subtree> {
    let mut merger = Merger::new(nodes, keys.len());
    let leaf_base = merger.leaf_base;
    let mut before = boundary(keys, positions.start as i64 - 1);
    let mut after = boundary(keys, positions.start as i64);
    for position in positions {
        // The escape link of every subtree that ends here: the right child of the split here.
        let after_next = boundary(keys, position as i64 + 1);
        let next = position as u32 + 1;
        let escape = if next > leaf_base {
            NONE
        } else if after < after_next {
            // Leaf `next` is that right child.
            leaf_base + next
        } else {
            next
        };
        let bounds = leaf_boxes[position];
        let primitive = keys[position].primitive();
        let leaf = Subtree::new(
            (bounds.min.into(), bounds.max.into()),
            [position as u32, position as u32],
            [before, after],
            [primitive, LEAF],
            escape,
            leaf_base,
        );
        merger.add(leaf);
        (before, after) = (after, after_next);
    }
    merger.unfinished()
}

/// How far down sorted keys `i` and `i + 1` agree, as the [`Key::xor_rank`] of their xor, each key
/// with its position below its code so that equal codes still differ (Karras, section 4): the
/// smaller it is, the longer their shared prefix. Only the two boundaries of one node are ever
/// compared, and their xors never have the same highest bit: the keys beyond both differ from the
/// node's keys within the node's prefix, and at different bits, or the node's first and last key
/// would differ there too. Outside the keys, [`NO_KEY`], above every boundary inside (codes leave
/// the keys' top bits zero).
#[inline(always)]
fn boundary<K: Key>(keys: &[K], i: i64) -> u64 {
    if i < 0 || i + 1 >= keys.len() as i64 {
        return NO_KEY;
    }
    let i = i as usize;
    (keys[i].at_position(i as u32) ^ keys[i + 1].at_position(i as u32 + 1)).xor_rank()
}

/// The boundary beyond the first or last key.
const NO_KEY: u64 = u64::MAX;

/// A finished subtree, waiting for its parent to be made: its box, the sorted positions it covers,
/// the boundaries on both sides, and what its node will hold.
#[derive(Clone, Copy)]
struct Subtree {
    min: Vec3A,
    max: Vec3A,
    /// The first and last sorted position it covers.
    range: [u32; 2],
    /// [`boundary`] before its first and after its last position.
    boundaries: [u64; 2],
    /// Its node's number, in Karras's numbering.
    node: u32,
    /// Its node's children, as the layout stores them (a leaf's primitive and [`LEAF`]).
    children: [u32; 2],
    escape: u32,
}

impl Subtree {
    /// Numbers the subtree as Karras does: a leaf by its position after the `leaf_base` (n - 1)
    /// internal nodes, the root 0, a left child by its last position, a right child by its first.
    #[inline(always)]
    fn new(
        bounds: (Vec3A, Vec3A),
        range: [u32; 2],
        boundaries: [u64; 2],
        children: [u32; 2],
        escape: u32,
        leaf_base: u32,
    ) -> Self {
        let mut subtree = Subtree {
            min: bounds.0,
            max: bounds.1,
            range,
            boundaries,
            node: 0,
            children,
            escape,
        };
        subtree.node = if range[0] == range[1] {
            leaf_base + range[0]
        } else if subtree.is_root() {
            0
        } else if subtree.is_left_child() {
            range[1]
        } else {
            range[0]
        };
        subtree
    }

    /// The root alone has no keys on either side.
    fn is_root(&self) -> bool {
        self.boundaries == [NO_KEY; 2]
    }

    /// Whether its parent extends it to the right: across the boundary whose keys share the longer
    /// prefix. Distinct keys never tie here.
    fn is_left_child(&self) -> bool {
        self.boundaries[1] < self.boundaries[0]
    }

    /// Writes its node, whole, now that its parent is known.
    #[inline(always)]
    fn write(&self, nodes: &DisjointWrites<GpuNode>, parent: u32) {
        let node = GpuNode {
            min: self.min.to_array(),
            left: self.children[0],
            max: self.max.to_array(),
            right: self.children[1],
            parent,
            escape: self.escape,
            _pad: [0; 2],
        };
        // SAFETY: every subtree is finished once, and written when its one parent is made (the
        // root when it is finished).
        unsafe { nodes.write(self.node as usize, node) };
    }
}

/// The merges over a run of subtrees taken in sorted order.
struct Merger<'a> {
    nodes: &'a DisjointWrites<GpuNode>,
    /// n - 1 for n keys: leaf p is node `leaf_base + p`.
    leaf_base: u32,
    /// Finished left children whose right sibling is not finished yet, each ending just before the
    /// next.
    waiting_for_right: Vec<Subtree>,
    /// Finished right children whose left sibling was not in this run, in order. All of them lie
    /// before every subtree in `waiting_for_right`.
    waiting_for_left: Vec<Subtree>,
}

impl<'a> Merger<'a> {
    /// Merges over `n` keys (at least one).
    fn new(nodes: &'a DisjointWrites<GpuNode>, n: usize) -> Self {
        Self {
            nodes,
            leaf_base: n as u32 - 1,
            waiting_for_right: Vec::with_capacity(64),
            waiting_for_left: Vec::new(),
        }
    }

    /// Takes the next subtree in order and makes every parent that it finishes.
    #[inline(always)]
    fn add(&mut self, mut subtree: Subtree) {
        loop {
            if subtree.is_root() {
                subtree.write(self.nodes, NONE);
                return;
            }
            if subtree.is_left_child() {
                self.waiting_for_right.push(subtree);
                return;
            }
            // A right child: its sibling is the subtree just before it, if that is finished.
            let Some(left) = self.waiting_for_right.pop() else {
                self.waiting_for_left.push(subtree);
                return;
            };
            debug_assert_eq!(left.range[1] + 1, subtree.range[0]);
            let parent = Subtree::new(
                (left.min.min(subtree.min), left.max.max(subtree.max)),
                [left.range[0], subtree.range[1]],
                [left.boundaries[0], subtree.boundaries[1]],
                [left.node, subtree.node],
                subtree.escape,
                self.leaf_base,
            );
            left.write(self.nodes, parent.node);
            subtree.write(self.nodes, parent.node);
            subtree = parent;
        }
    }

    /// What is left, in order.
    fn unfinished(mut self) -> Vec<Subtree> {
        self.waiting_for_left.append(&mut self.waiting_for_right);
        self.waiting_for_left
    }
}
