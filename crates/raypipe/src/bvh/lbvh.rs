//! Karras (2012): the binary radix tree over sorted Morton codes, then bounds bottom-up and the
//! traversal links. The CPU finds the tree one of two ways ([`Hierarchy`]): every internal node by
//! Karras's own searches, then bounds and links in a climb; or by bottom-up merges
//! ([`super::merge`]) that write bounds and links in the same pass, as the GPU does. Each phase runs
//! in parallel, and the last writes each node of the final array once, whole; `LbvhBuilder` keeps
//! its buffers from one build to the next, as a per-frame rebuild wants.

use super::aabb::Aabb;
use super::key::{Key, gather_leaf_boxes};
use super::layout::{GpuNode, LEAF, NONE};
use super::merge::{self, merge_bottom_up};
use super::morton::{Grid, MortonBits};
use super::sort::radix_sort_by_key_then;
use super::{BuildTimings, Bvh};
use crate::parallel::{DisjointWrites, MIN_TASK};
use glam::{Vec3A, Vec4};
use rayon::prelude::*;
use web_time::Instant;

/// Whether sorted key j shares more leading bits with key i than `limit` allows (see
/// [`Key::below_top_bit`]); no key outside the array does. Karras (section 4) makes every key
/// distinct by comparing positions where codes are equal: keys that hold their sorted position below
/// the code do exactly that in one xor. Comparing xors with a limit ranks common-prefix lengths
/// without counting them: the searches below compare with one length at a time.
#[inline(always)]
fn shares_more<K: Key>(keys: &[K], i: usize, j: i64, limit: K) -> bool {
    j >= 0 && j < keys.len() as i64 && (keys[i] ^ keys[j as usize]) <= limit
}

/// Internal node i over n sorted keys: its left and right child, as node indices (internal nodes
/// 0..n-1, then leaves).
#[inline(always)]
pub(crate) fn internal_node<K: Key>(keys: &[K], i: usize) -> [u32; 2] {
    // Direction of the range: towards the neighbour that shares the longer prefix, which is the one
    // with the smaller xor (sorted distinct keys never differ from i first at the same bit on both
    // sides). The other neighbour's prefix bounds the range: every key in it shares more with i.
    let key = keys[i];
    let to_right = key ^ keys[i + 1];
    if i == 0 {
        // No left neighbour: the root spans everything.
        let everything = !K::default();
        return search_range::<K, true>(keys, i, everything);
    }
    let to_left = key ^ keys[i - 1];
    if to_right < to_left {
        search_range::<K, true>(keys, i, to_left.below_top_bit())
    } else {
        search_range::<K, false>(keys, i, to_right.below_top_bit())
    }
}

/// The rest of [`internal_node`], for a range that grows from i to the right (`RIGHT`) or to the
/// left; a constant direction spares the searches a multiply on every step. `in_range` is the xor
/// limit of the keys in the range.
#[inline(always)]
fn search_range<K: Key, const RIGHT: bool>(keys: &[K], i: usize, in_range: K) -> [u32; 2] {
    let leaf_base = (keys.len() - 1) as u32;
    let ii = i as i64;
    let at = |offset: i64| if RIGHT { ii + offset } else { ii - offset };
    // Upper bound of the range's length by doubling, then its exact length by binary search. The
    // binary search starts at l_max / 2, which the doubling passed (for l_max = 2, the neighbour at
    // 1 passes by the choice of direction). Its steps add 0 or t without a branch: which way they
    // go is data, and unpredictable.
    let mut l_max: i64 = 2;
    while shares_more(keys, i, at(l_max), in_range) {
        l_max *= 2;
    }
    let mut l = l_max / 2;
    let mut t = l_max / 4;
    while t >= 1 {
        l += t * shares_more(keys, i, at(l + t), in_range) as i64;
        t /= 2;
    }
    let j = at(l);
    if l == 1 {
        // Two leaves, the commonest node: the split is between them.
        let split = if RIGHT { i } else { i - 1 } as u32;
        return [leaf_base + split, leaf_base + split + 1];
    }
    // The split: the last position that shares more than the node's prefix with i, in steps of
    // ceil(l / 2), ceil(l / 4), ..., 1 (shifts: the divisors are powers of two).
    let in_child = (keys[i] ^ keys[j as usize]).below_top_bit();
    let mut s: i64 = 0;
    let mut shift = 1;
    loop {
        let t = (l + (1 << shift) - 1) >> shift;
        s += t * shares_more(keys, i, at(s + t), in_child) as i64;
        if t == 1 {
            break;
        }
        shift += 1;
    }
    // The split position is the last key of the left child.
    let split = if RIGHT { at(s) } else { at(s) - 1 } as u32;
    let (first, last) = (ii.min(j) as u32, ii.max(j) as u32);
    let left = if first == split { leaf_base + split } else { split };
    let right = if last == split + 1 {
        leaf_base + split + 1
    } else {
        split + 1
    };
    [left, right]
}

/// The escape link of a node whose range ends at sorted position `last`: the node after its subtree
/// in depth-first order. That is the right child of the internal node that splits at `last`, and it
/// starts at `last + 1`: internal node `last + 1` when that node's range starts there (its split then
/// lies at or after it), otherwise leaf `last + 1`. Nothing follows a subtree that ends at n - 1.
#[inline(always)]
pub fn escape(children: &[[u32; 2]], last: u32) -> u32 {
    let leaf_base = children.len() as u32;
    let next = last + 1;
    if next == leaf_base + 1 {
        NONE
    } else if next < leaf_base && split(children, next) >= next {
        next
    } else {
        leaf_base + next
    }
}

/// Where internal node `node` splits its range: the last position of its left child, which is the
/// child's number when it is internal (a left child is numbered by its last position).
#[inline(always)]
fn split(children: &[[u32; 2]], node: u32) -> u32 {
    let leaf_base = children.len() as u32;
    let left = children[node as usize][0];
    if left >= leaf_base { left - leaf_base } else { left }
}

/// How the CPU builder finds the binary radix tree. Both find the same tree and write the same node
/// array, bit for bit. The merges live in [`super::merge`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Hierarchy {
    /// Bottom-up merges (Apetrei 2014), which write the boxes and links in the same pass over the
    /// leaves.
    #[default]
    Merges,
    /// Karras's searches: every internal node found on its own, then the boxes and links in a climb
    /// of their own.
    Searches,
}

crate::choice::impl_choice!(
    Hierarchy,
    [
        (
            Merges,
            "merges",
            "bottom-up merges (Apetrei 2014), which write the boxes and links in the same pass over the leaves"
        ),
        (
            Searches,
            "searches",
            "Karras's searches: every internal node found on its own, then the boxes and links in a climb of their own"
        ),
    ]
);

/// A bound on the depth of any LBVH over `count` primitives with codes of `bits`: each level of the
/// radix tree consumes at least one bit of the (code, position) key, which has bits + ceil(log2 n)
/// bits. Renderers size their traversal stack with it where the tree is rebuilt as the scene moves.
pub fn depth_bound(count: usize, bits: MortonBits) -> u32 {
    bits.total_bits() + (count.max(1) as u64).next_power_of_two().trailing_zeros()
}

/// A reusable LBVH builder: build after build, its buffers keep their capacity. `K` is `u64` for
/// 30-bit Morton codes and `u128` for 63-bit ones.
#[derive(Default)]
pub struct LbvhBuilder<K: Key> {
    hierarchy: Hierarchy,
    /// Leaves merged by one task ([`Hierarchy::Merges`]); [`merge::CHUNK`] unless set.
    merge_chunk: Option<usize>,
    keys: Vec<K>,
    scratch: Vec<K>,
    /// The sorted keys with their positions in place of their primitives: what the hierarchy
    /// search compares.
    positioned: Vec<K>,
    /// Left and right child of each internal node.
    children: Vec<[u32; 2]>,
    /// Parent of each node.
    parents: Vec<u32>,
    /// The primitives' boxes in sorted order: the leaves' boxes.
    leaf_boxes: Vec<Aabb>,
    nodes: Vec<GpuNode>,
}

impl<K: Key> LbvhBuilder<K> {
    /// A builder with Karras's hierarchy and empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// A builder that makes its hierarchy by `hierarchy`.
    pub fn with_hierarchy(hierarchy: Hierarchy) -> Self {
        Self {
            hierarchy,
            ..Self::default()
        }
    }

    /// A key too narrow for the codes would shift their top bits away and build a wrong tree
    /// without a word: refused, as the caller's mistake it is.
    fn check_width(bits: MortonBits) {
        assert!(
            bits.total_bits() <= K::CODE_BITS,
            "{}-bit Morton codes do not fit a key of {} code bits: use LbvhBuilder::<u128>",
            bits.total_bits(),
            K::CODE_BITS
        );
    }

    /// Merges `leaves` leaves per task ([`Hierarchy::Merges`]): small chunks leave more of the tree
    /// to the serial merge that joins them, which tests want.
    pub fn with_merge_chunk(mut self, leaves: usize) -> Self {
        assert!(leaves > 0);
        self.merge_chunk = Some(leaves);
        self
    }

    /// Builds over `boxes`, computing Morton codes of their centroids; [`Self::to_bvh`] and
    /// [`Self::into_bvh`] give the tree.
    /// The key must hold codes of `bits` (`u64` for 30-bit codes, `u128` for 63-bit ones).
    pub fn build(&mut self, boxes: &[Aabb], bits: MortonBits) -> BuildTimings {
        Self::check_width(bits);
        let start = Instant::now();
        self.morton_keys(boxes, bits, None);
        let morton = ms_since(start);
        let mut timings = self.build_from_keys(boxes, bits);
        timings.morton = morton;
        timings
    }

    /// Builds over `boxes` with the given Morton codes (so devices can be compared on identical input).
    pub fn build_with_codes(&mut self, boxes: &[Aabb], codes: &[u64], bits: MortonBits) -> BuildTimings {
        Self::check_width(bits);
        assert_eq!(boxes.len(), codes.len());
        self.morton_keys(boxes, bits, Some(codes));
        self.build_from_keys(boxes, bits)
    }

    /// Builds once and hands the tree over.
    pub fn build_into(mut self, boxes: &[Aabb], bits: MortonBits) -> (Bvh, BuildTimings) {
        let timings = self.build(boxes, bits);
        (self.into_bvh(), timings)
    }

    /// The tree of the last build, taking the node array.
    pub fn into_bvh(self) -> Bvh {
        Bvh {
            primitive_count: self.keys.len(),
            nodes: self.nodes,
        }
    }

    /// The tree of the last build, copied.
    pub fn to_bvh(&self) -> Bvh {
        Bvh {
            primitive_count: self.keys.len(),
            nodes: self.nodes.clone(),
        }
    }

    // Compute Morton codes of primitive centroids (or take the given ones), paired with primitive
    // indices
    fn morton_keys(&mut self, boxes: &[Aabb], bits: MortonBits, codes: Option<&[u64]>) {
        match codes {
            Some(codes) => self.fill_keys(boxes, |i, _| codes[i]),
            None => {
                let grid = Grid::around_centroids(boxes, bits);
                self.fill_keys(boxes, |_, b| grid.code(b));
            }
        }
    }

    fn fill_keys(&mut self, boxes: &[Aabb], code: impl Fn(usize, &Aabb) -> u64 + Sync) {
        self.keys.resize(boxes.len(), K::default());
        self.keys
            .par_chunks_mut(MIN_TASK)
            .zip(boxes.par_chunks(MIN_TASK))
            .enumerate()
            .for_each(|(chunk, (keys, boxes))| {
                for ((i, key), b) in (chunk * MIN_TASK..).zip(keys).zip(boxes) {
                    *key = K::new(code(i, b), i as u32);
                }
            });
    }

    fn build_from_keys(&mut self, boxes: &[Aabb], bits: MortonBits) -> BuildTimings {
        let n = boxes.len();
        let mut timings = BuildTimings::default();

        // Sort the keys by code; the index below keeps equal codes in primitive order
        let start = Instant::now();
        // Each sorted stretch, while in cache, also gives the searches their positioned keys.
        let searches = self.hierarchy == Hierarchy::Searches;
        self.positioned.resize(if searches { n } else { 0 }, K::default());
        let positioned = DisjointWrites::new(&mut self.positioned);
        let position_keys = |start: usize, keys: &[K]| {
            if !searches {
                return;
            }
            for (position, key) in (start..).zip(keys) {
                // SAFETY: the sorted stretches are disjoint.
                unsafe { positioned.write(position, key.at_position(position as u32)) };
            }
        };
        radix_sort_by_key_then(
            &mut self.keys,
            &mut self.scratch,
            bits.total_bits(),
            |k| k.code(),
            position_keys,
        );
        timings.sort = ms_since(start);

        self.nodes.resize((2 * n).saturating_sub(1), GpuNode::default());
        if n == 0 {
            return timings;
        }
        match self.hierarchy {
            Hierarchy::Merges => {
                let start = Instant::now();
                let chunk = self.merge_chunk.unwrap_or(merge::CHUNK);
                merge_bottom_up(&self.keys, boxes, &mut self.leaf_boxes, &mut self.nodes, chunk);
                timings.hierarchy = ms_since(start);
            }
            Hierarchy::Searches => {
                let start = Instant::now();
                self.hierarchy();
                timings.hierarchy = ms_since(start);
                let start = Instant::now();
                self.bounds_and_links(boxes);
                timings.bounds = ms_since(start);
            }
        }
        timings
    }

    // Find every internal node's children, and so every node's parent
    fn hierarchy(&mut self) {
        let n = self.keys.len();
        let positioned = &self.positioned;
        self.children.resize(n - 1, [0, 0]);
        self.parents.resize(2 * n - 1, NONE);
        self.parents[0] = NONE;
        let parents = DisjointWrites::new(&mut self.parents);
        self.children
            .par_chunks_mut(MIN_TASK)
            .enumerate()
            .for_each(|(chunk, children)| {
                for (i, children) in (chunk * MIN_TASK..).zip(children) {
                    *children = internal_node(positioned, i);
                    // SAFETY: every node but the root is the child of exactly one internal node.
                    unsafe {
                        parents.write(children[0] as usize, i as u32);
                        parents.write(children[1] as usize, i as u32);
                    }
                }
            });
    }

    // Write every node whole: its box (leaves from their primitives, internal nodes bottom-up), its
    // children, its parent and its escape link
    //
    // On the CPU, a walk that forks into both subtrees while they are large, then climbs from each
    // leaf of a small subtree in order: each node is written once, after its children, with no
    // atomics and no second pass over the array. (The GPU, with a thread per leaf, climbs with
    // atomic visit counters and writes the links in a pass of its own.) Unions never round, so both
    // give identical boxes; each escape link comes from the end of its node's range alone, by the
    // rule of the GPU's pass.
    fn bounds_and_links(&mut self, boxes: &[Aabb]) {
        let n = self.keys.len();
        let keys = &self.keys;
        gather_leaf_boxes(keys, boxes, &mut self.leaf_boxes);
        let walk = Walk {
            nodes: DisjointWrites::new(&mut self.nodes),
            keys,
            children: &self.children,
            parents: &self.parents,
            leaf_boxes: &self.leaf_boxes,
            leaf_base: n as u32 - 1,
        };
        walk.visit(0, 0, n as u32 - 1);
    }
}

/// Subtrees with fewer leaves than this are walked on one thread.
const SERIAL_LEAVES: u32 = 4096;

struct Walk<'a, K: Key> {
    nodes: DisjointWrites<GpuNode>,
    keys: &'a [K],
    children: &'a [[u32; 2]],
    parents: &'a [u32],
    leaf_boxes: &'a [Aabb],
    leaf_base: u32,
}

impl<K: Key> Walk<'_, K> {
    /// Writes `node`, which covers sorted positions `first..=last`, and every node below it, and
    /// returns its box: forks into both subtrees while they are large, then hands each to
    /// [`Self::climb`].
    fn visit(&self, node: u32, first: u32, last: u32) -> Aabb {
        if last - first < SERIAL_LEAVES {
            return self.climb(node, first, last);
        }
        let [left, right] = self.children[node as usize];
        let split = split(self.children, node);
        let (left_box, right_box) =
            rayon::join(|| self.visit(left, first, split), || self.visit(right, split + 1, last));
        let bounds = left_box.union(right_box);
        let parent = self.parents[node as usize];
        let (min, max) = (bounds.min.into(), bounds.max.into());
        self.write_node(node, [left, right], min, max, parent, escape(self.children, last));
        bounds
    }

    /// Writes the subtree of `root`, which covers sorted positions `first..=last`, on this thread
    /// and returns its box: leaves in order, each followed by the climb through the nodes that it
    /// ends (those it is the last leaf of: a node is done when its right child is). A node's left
    /// child was written before it, and its box is read back from the array. Every node that a
    /// leaf ends shares the leaf's escape link.
    fn climb(&self, root: u32, first: u32, last: u32) -> Aabb {
        let (mut min, mut max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        for position in first..=last {
            let escape = escape(self.children, position);
            let mut node = self.leaf_base + position;
            let mut parent = self.parents[node as usize];
            let primitive = self.keys[position as usize].primitive();
            let leaf = self.leaf_boxes[position as usize];
            (min, max) = (Vec3A::from(leaf.min), Vec3A::from(leaf.max));
            self.write_node(node, [primitive, LEAF], min, max, parent, escape);
            while node != root {
                let children @ [left, right] = self.children[parent as usize];
                if right != node {
                    break;
                }
                // SAFETY: the left child ends before `position`: this thread wrote it already.
                let sibling = unsafe { self.nodes.read(left as usize) };
                // The node's first two 16-byte rows are its min and max corners in SIMD lanes (the
                // fourth lane holds a child link and is never written back).
                let rows: [[f32; 4]; 3] = bytemuck::cast(sibling);
                min = Vec3A::from_vec4(Vec4::from_array(rows[0])).min(min);
                max = Vec3A::from_vec4(Vec4::from_array(rows[1])).max(max);
                let grandparent = self.parents[parent as usize];
                self.write_node(parent, children, min, max, grandparent, escape);
                (node, parent) = (parent, grandparent);
            }
        }
        // The last leaf's climb ends at the root.
        Aabb::new(min.into(), max.into())
    }

    /// Writes `node`: `children` as the layout has them (a leaf's primitive and [`LEAF`]), its box,
    /// parent and escape link.
    #[inline(always)]
    fn write_node(&self, node: u32, children: [u32; 2], min: Vec3A, max: Vec3A, parent: u32, escape: u32) {
        let [left, right] = children;
        let written = GpuNode {
            min: min.to_array(),
            left,
            max: max.to_array(),
            right,
            parent,
            escape,
            _pad: [0; 2],
        };
        // SAFETY: the walk reaches each node once; the subtrees of a fork are disjoint.
        unsafe { self.nodes.write(node as usize, written) };
    }
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
