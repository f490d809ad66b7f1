//! Karras (2012): the binary radix tree over sorted Morton codes, every internal node found
//! independently, then bounds bottom-up and the traversal links. Each phase runs in parallel over
//! nodes and writes the final node array in place; `LbvhBuilder` keeps its buffers from one build to
//! the next, as a per-frame rebuild wants.

use super::aabb::Aabb;
use super::layout::{GpuNode, LEAF, NONE};
use super::morton::{self, MortonBits};
use super::sort::radix_sort_by_key;
use super::{BuildTimings, Bvh};
use rayon::prelude::*;
use std::time::Instant;

/// Rayon splits below this many items cost more than they save.
const MIN_TASK: usize = 4096;

/// A sort key: the Morton code above the primitive index, so that one stable radix sort of the code
/// bits orders primitives by code and keeps equal codes in primitive order. 30-bit codes fit a u64
/// with the index (half the sort's memory traffic); 63-bit codes need a u128.
pub trait Key: Copy + Default + Send + Sync + 'static {
    fn new(code: u64, primitive: u32) -> Self;
    fn code(self) -> u64;
    fn primitive(self) -> u32;
}

impl Key for u64 {
    fn new(code: u64, primitive: u32) -> Self {
        (code << 32) | primitive as u64
    }
    fn code(self) -> u64 {
        self >> 32
    }
    fn primitive(self) -> u32 {
        self as u32
    }
}

impl Key for u128 {
    fn new(code: u64, primitive: u32) -> Self {
        ((code as u128) << 32) | primitive as u128
    }
    fn code(self) -> u64 {
        (self >> 32) as u64
    }
    fn primitive(self) -> u32 {
        self as u32
    }
}

/// Length of the common prefix of sorted keys i and j; -1 outside the array. Equal codes compare
/// their positions instead, so every key is distinct (Karras, section 4).
pub fn delta<K: Key>(keys: &[K], i: usize, j: i64) -> i32 {
    if j < 0 || j >= keys.len() as i64 {
        return -1;
    }
    let (a, b) = (keys[i].code(), keys[j as usize].code());
    if a != b {
        (a ^ b).leading_zeros() as i32
    } else {
        64 + ((i as u32) ^ (j as u32)).leading_zeros() as i32
    }
}

/// Internal node i over n sorted keys: (left child, right child, first, last), children as node
/// indices (internal nodes 0..n-1, then leaves).
pub fn internal_node<K: Key>(keys: &[K], i: usize) -> (u32, u32, u32, u32) {
    let n = keys.len();
    let leaf_base = (n - 1) as u32;
    let ii = i as i64;
    // Direction of the range: towards the neighbour that shares the longer prefix.
    let d: i64 = if delta(keys, i, ii + 1) > delta(keys, i, ii - 1) {
        1
    } else {
        -1
    };
    // Upper bound of the range's length by doubling, then its exact length by binary search.
    let delta_min = delta(keys, i, ii - d);
    let mut l_max: i64 = 2;
    while delta(keys, i, ii + l_max * d) > delta_min {
        l_max *= 2;
    }
    let mut l: i64 = 0;
    let mut t = l_max / 2;
    while t >= 1 {
        if delta(keys, i, ii + (l + t) * d) > delta_min {
            l += t;
        }
        t /= 2;
    }
    let j = ii + l * d;
    // The split: the last position that shares more than the node's prefix with i.
    let delta_node = delta(keys, i, j);
    // Steps of ceil(l / 2), ceil(l / 4), ..., 1 (shifts: the divisors are powers of two).
    let mut s: i64 = 0;
    let mut shift = 1;
    loop {
        let t = (l + (1 << shift) - 1) >> shift;
        if delta(keys, i, ii + (s + t) * d) > delta_node {
            s += t;
        }
        if t == 1 {
            break;
        }
        shift += 1;
    }
    let split = (ii + s * d + d.min(0)) as u32;
    let (first, last) = (ii.min(j) as u32, ii.max(j) as u32);
    let left = if first == split { leaf_base + split } else { split };
    let right = if last == split + 1 {
        leaf_base + split + 1
    } else {
        split + 1
    };
    (left, right, first, last)
}

/// The node array, written field by field from many tasks: each phase writes every field of its
/// own nodes, and reads only fields written in an earlier phase or ordered by an atomic.
#[derive(Clone, Copy)]
struct Nodes(*mut GpuNode, usize);

// SAFETY: tasks write disjoint fields; see each use.
unsafe impl Send for Nodes {}
unsafe impl Sync for Nodes {}

impl Nodes {
    fn at(&self, i: usize) -> *mut GpuNode {
        assert!(i < self.1, "node {i} out of bounds {}", self.1);
        // SAFETY: in bounds.
        unsafe { self.0.add(i) }
    }
}

/// A reusable LBVH builder: build after build, its buffers keep their capacity. `K` is `u64` for
/// 30-bit Morton codes and `u128` for 63-bit ones.
#[derive(Default)]
pub struct LbvhBuilder<K: Key> {
    keys: Vec<K>,
    scratch: Vec<K>,
    /// First and last sorted position covered by each internal node; one of them is its index.
    ranges: Vec<[u32; 2]>,
    nodes: Vec<GpuNode>,
}

impl<K: Key> LbvhBuilder<K> {
    pub fn new() -> Self {
        Self::default()
    }

    /// Builds over `boxes`, computing Morton codes of their centroids; the tree is in [`Self::nodes`].
    pub fn build(&mut self, boxes: &[Aabb], bits: MortonBits) -> BuildTimings {
        let start = Instant::now();
        self.morton_keys(boxes, bits, None);
        let morton = ms_since(start);
        let mut timings = self.build_from_keys(boxes, bits);
        timings.morton = morton;
        timings
    }

    /// Builds over `boxes` with the given Morton codes (so devices can be compared on identical input).
    pub fn build_with_codes(&mut self, boxes: &[Aabb], codes: &[u64], bits: MortonBits) -> BuildTimings {
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

    // Compute Morton codes of primitive centroids, paired with primitive indices
    fn morton_keys(&mut self, boxes: &[Aabb], bits: MortonBits, codes: Option<&[u64]>) {
        let n = boxes.len();
        self.keys.resize(n, K::default());
        if let Some(codes) = codes {
            self.keys
                .par_iter_mut()
                .with_min_len(MIN_TASK)
                .zip(codes)
                .enumerate()
                .for_each(|(i, (key, &code))| *key = K::new(code, i as u32));
            return;
        }
        let bounds = morton::centroid_bounds(boxes);
        let scale = morton::scales(bounds, 1 << bits.bits_per_axis());
        self.keys
            .par_iter_mut()
            .with_min_len(MIN_TASK)
            .zip(boxes)
            .enumerate()
            .for_each(|(i, (key, b))| {
                let code = morton::morton_code(b.centroid(), bounds, scale, bits);
                *key = K::new(code, i as u32);
            });
    }

    fn build_from_keys(&mut self, boxes: &[Aabb], bits: MortonBits) -> BuildTimings {
        let n = boxes.len();
        let mut timings = BuildTimings::default();

        // Sort the keys by code; the index below keeps equal codes in primitive order
        let start = Instant::now();
        radix_sort_by_key(&mut self.keys, &mut self.scratch, bits.total_bits(), |k| k.code());
        timings.sort = ms_since(start);

        self.nodes.resize((2 * n).saturating_sub(1), GpuNode::default());
        if n == 0 {
            return timings;
        }
        if n == 1 {
            self.nodes[0] = GpuNode {
                min: boxes[0].min.to_array(),
                left: 0,
                max: boxes[0].max.to_array(),
                right: LEAF,
                parent: NONE,
                escape: NONE,
                _pad: [0; 2],
            };
            return timings;
        }

        let start = Instant::now();
        self.hierarchy();
        timings.hierarchy = ms_since(start);
        let start = Instant::now();
        self.bounds(boxes);
        timings.bounds = ms_since(start);
        let start = Instant::now();
        self.links();
        timings.links = ms_since(start);
        timings
    }

    // Find every internal node's children and range, and every node's parent
    fn hierarchy(&mut self) {
        let n = self.keys.len();
        let keys = &self.keys;
        self.ranges.resize(n - 1, [0, 0]);
        let nodes = Nodes(self.nodes.as_mut_ptr(), self.nodes.len());
        // SAFETY (field writes below): task i alone writes node i's children and the parent field
        // of those two children; every node is the child of exactly one internal node.
        unsafe { (*nodes.at(0)).parent = NONE };
        self.ranges
            .par_iter_mut()
            .with_min_len(MIN_TASK)
            .enumerate()
            .for_each(|(i, range)| {
                let (left, right, first, last) = internal_node(keys, i);
                *range = [first, last];
                unsafe {
                    let node = nodes.at(i);
                    (*node).left = left;
                    (*node).right = right;
                    (*nodes.at(left as usize)).parent = i as u32;
                    (*nodes.at(right as usize)).parent = i as u32;
                }
            });
    }

    // Bound leaves by their primitives, then internal nodes bottom-up
    //
    // On the CPU, a post-order walk that forks into both subtrees while they are large: each node
    // is bounded after its children, with no atomics. (The GPU, with a thread per leaf, climbs with
    // atomic visit counters instead.) Unions never round, so both give identical boxes.
    fn bounds(&mut self, boxes: &[Aabb]) {
        let n = self.keys.len();
        let leaf_base = n - 1;
        // Leaves first, in sorted order: their primitives are scattered through `boxes`, so fetch
        // ahead of use to overlap the cache misses instead of waiting on each.
        let keys = &self.keys;
        self.nodes[leaf_base..]
            .par_chunks_mut(MIN_TASK)
            .enumerate()
            .for_each(|(chunk, leaves)| {
                let base = chunk * MIN_TASK;
                for (k, leaf) in leaves.iter_mut().enumerate() {
                    if let Some(ahead) = keys.get(base + k + PREFETCH_DISTANCE) {
                        prefetch(&boxes[ahead.primitive() as usize]);
                    }
                    let primitive = keys[base + k].primitive();
                    let b = boxes[primitive as usize];
                    leaf.min = b.min.to_array();
                    leaf.max = b.max.to_array();
                    leaf.left = primitive;
                    leaf.right = LEAF;
                }
            });
        let nodes = Nodes(self.nodes.as_mut_ptr(), self.nodes.len());
        let walk = BoundsWalk {
            nodes,
            ranges: &self.ranges,
            leaf_base,
        };
        walk.bound(0);
    }

    // Link every node to the node after its subtree in depth-first order (the escape link)
    //
    // A node that covers sorted positions [.., b] is followed by the right child of the internal
    // node that splits at b. That child starts at b + 1: it is internal node b + 1 when that node's
    // range starts there, and otherwise leaf b + 1. Nothing follows a subtree that ends at n - 1.
    fn links(&mut self) {
        let n = self.keys.len();
        let leaf_base = (n - 1) as u32;
        let ranges = &self.ranges;
        self.nodes
            .par_iter_mut()
            .with_min_len(MIN_TASK)
            .enumerate()
            .for_each(|(node, out)| {
                let last = if node < n - 1 {
                    ranges[node][1]
                } else {
                    node as u32 - leaf_base
                };
                let next = last + 1;
                out.escape = if next as usize == n {
                    NONE
                } else if (next as usize) < n - 1 && ranges[next as usize][0] == next {
                    next
                } else {
                    leaf_base + next
                };
                out._pad = [0; 2];
            });
    }
}

/// Subtrees with fewer leaves than this are bounded on one thread.
const SERIAL_LEAVES: u32 = 4096;

/// How many leaves ahead the leaf pass fetches its primitives' boxes.
const PREFETCH_DISTANCE: usize = 32;

fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint; it reads nothing and cannot fault.
    unsafe {
        std::arch::x86_64::_mm_prefetch(value as *const T as *const i8, std::arch::x86_64::_MM_HINT_T0);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

struct BoundsWalk<'a> {
    nodes: Nodes,
    ranges: &'a [[u32; 2]],
    leaf_base: usize,
}

impl BoundsWalk<'_> {
    /// Writes the box of internal `node` and of every internal node below it (leaves are bounded
    /// already), and returns it.
    fn bound(&self, node: usize) -> ([f32; 3], [f32; 3]) {
        let out = self.nodes.at(node);
        // SAFETY: the walk reaches each node once, from its parent's call; the two subtrees of a
        // fork are disjoint. Links were written in the hierarchy phase and are only read here.
        unsafe {
            if node >= self.leaf_base {
                return ((*out).min, (*out).max);
            }
            let (left, right) = ((*out).left as usize, (*out).right as usize);
            let [first, last] = self.ranges[node];
            let ((lmin, lmax), (rmin, rmax)) = if last - first >= SERIAL_LEAVES {
                rayon::join(|| self.bound(left), || self.bound(right))
            } else {
                (self.bound(left), self.bound(right))
            };
            let min = [lmin[0].min(rmin[0]), lmin[1].min(rmin[1]), lmin[2].min(rmin[2])];
            let max = [lmax[0].max(rmax[0]), lmax[1].max(rmax[1]), lmax[2].max(rmax[2])];
            (*out).min = min;
            (*out).max = max;
            (min, max)
        }
    }
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
