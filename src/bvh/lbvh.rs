//! Karras (2012): the binary radix tree over sorted Morton codes, every internal node found
//! independently, then bounds bottom-up and the traversal links. Each step is parallel over nodes;
//! `lbvh_*.wgsl` runs the same steps on the GPU.

use super::aabb::Aabb;
use super::layout::{GpuNode, LEAF, NONE};
use super::sort::DisjointWrites;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Rayon splits below this many nodes cost more than they save.
const MIN_TASK: usize = 4096;

/// The hierarchy of n sorted keys: children and key ranges of the n - 1 internal nodes, parents of
/// all 2n - 1 nodes.
pub struct Hierarchy {
    pub left: Vec<u32>,
    pub right: Vec<u32>,
    /// First and last sorted position that internal node i covers; one of them is i.
    pub first: Vec<u32>,
    pub last: Vec<u32>,
    pub parent: Vec<u32>,
}

/// Length of the common prefix of sorted keys i and j; -1 outside the array. Equal keys compare
/// their positions instead, so every key is distinct (Karras, section 4).
pub fn delta(codes: &[u64], i: usize, j: i64) -> i32 {
    if j < 0 || j >= codes.len() as i64 {
        return -1;
    }
    let (a, b) = (codes[i], codes[j as usize]);
    if a != b {
        (a ^ b).leading_zeros() as i32
    } else {
        64 + ((i as u32) ^ (j as u32)).leading_zeros() as i32
    }
}

/// Internal node i: (left child, right child, first, last), children as node indices.
pub fn internal_node(codes: &[u64], i: usize) -> (u32, u32, u32, u32) {
    let n = codes.len();
    let leaf_base = (n - 1) as u32;
    let ii = i as i64;
    // Direction of the range: towards the neighbour that shares the longer prefix.
    let d: i64 = if delta(codes, i, ii + 1) > delta(codes, i, ii - 1) {
        1
    } else {
        -1
    };
    // Upper bound of the range's length by doubling, then its exact length by binary search.
    let delta_min = delta(codes, i, ii - d);
    let mut l_max: i64 = 2;
    while delta(codes, i, ii + l_max * d) > delta_min {
        l_max *= 2;
    }
    let mut l: i64 = 0;
    let mut t = l_max / 2;
    while t >= 1 {
        if delta(codes, i, ii + (l + t) * d) > delta_min {
            l += t;
        }
        t /= 2;
    }
    let j = ii + l * d;
    // The split: the last position that shares more than the node's prefix with i.
    let delta_node = delta(codes, i, j);
    let mut s: i64 = 0;
    let mut divisor: i64 = 2;
    loop {
        let t = (l + divisor - 1) / divisor;
        if delta(codes, i, ii + (s + t) * d) > delta_node {
            s += t;
        }
        if t == 1 {
            break;
        }
        divisor *= 2;
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

/// Builds the radix tree over sorted codes (at least two).
pub fn hierarchy(codes: &[u64]) -> Hierarchy {
    let n = codes.len();
    debug_assert!(n >= 2);
    let internal: Vec<(u32, u32, u32, u32)> = (0..n - 1)
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|i| internal_node(codes, i))
        .collect();
    let mut parent = vec![NONE; 2 * n - 1];
    let writes = DisjointWrites::new(&mut parent);
    internal
        .par_iter()
        .enumerate()
        .with_min_len(MIN_TASK)
        .for_each(|(i, &(l, r, _, _))| {
            // SAFETY: every node is the child of exactly one internal node.
            unsafe {
                writes.write(l as usize, i as u32);
                writes.write(r as usize, i as u32);
            }
        });
    Hierarchy {
        left: internal.iter().map(|x| x.0).collect(),
        right: internal.iter().map(|x| x.1).collect(),
        first: internal.iter().map(|x| x.2).collect(),
        last: internal.iter().map(|x| x.3).collect(),
        parent,
    }
}

/// Bounds of every node: leaves from their primitives, internal nodes bottom-up. Each leaf climbs
/// towards the root; at each internal node an atomic visit counter stops the first child to arrive,
/// and the second, which then knows both children's boxes, writes the union and climbs on.
pub fn bounds(h: &Hierarchy, sorted_boxes: &[Aabb]) -> Vec<Aabb> {
    let n = sorted_boxes.len();
    let leaf_base = n - 1;
    let mut boxes = vec![Aabb::EMPTY; 2 * n - 1];
    boxes[leaf_base..].copy_from_slice(sorted_boxes);
    let visits: Vec<AtomicU32> = (0..n - 1).map(|_| AtomicU32::new(0)).collect();
    let out = DisjointWrites::new(&mut boxes);
    (0..n).into_par_iter().with_min_len(MIN_TASK).for_each(|k| {
        let mut node = h.parent[leaf_base + k];
        while node != NONE {
            let i = node as usize;
            // AcqRel: the second arrival sees the box its sibling's climber wrote before arriving.
            if visits[i].fetch_add(1, Ordering::AcqRel) == 0 {
                return;
            }
            // SAFETY: the counter admits exactly one task per internal node, after both children
            // were written; children are read only after their own single writer finished.
            unsafe {
                let union = out.read(h.left[i] as usize).union(out.read(h.right[i] as usize));
                out.write(i, union);
            }
            node = h.parent[i];
        }
    });
    boxes
}

/// The escape link of every node, each found on its own: a node that covers sorted positions
/// [.., b] is followed in depth-first order by the right child of the internal node that splits at
/// b. That child starts at b + 1: it is internal node b + 1 when that node's range starts there,
/// and otherwise leaf b + 1. Nothing follows a subtree that ends at n - 1.
pub fn escapes(h: &Hierarchy, n: usize) -> Vec<u32> {
    let leaf_base = (n - 1) as u32;
    (0..2 * n - 1)
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|node| {
            let last = if node < n - 1 {
                h.last[node]
            } else {
                node as u32 - leaf_base
            };
            let next = last + 1;
            if next as usize == n {
                NONE
            } else if (next as usize) < n - 1 && h.first[next as usize] == next {
                next
            } else {
                leaf_base + next
            }
        })
        .collect()
}

/// Assembles the node array from the build's parts.
pub fn assemble(h: &Hierarchy, boxes: &[Aabb], escapes: &[u32], sorted_primitives: &[u32]) -> Vec<GpuNode> {
    let n = sorted_primitives.len();
    (0..2 * n - 1)
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|node| {
            let (left, right) = if node < n - 1 {
                (h.left[node], h.right[node])
            } else {
                (sorted_primitives[node - (n - 1)], LEAF)
            };
            GpuNode {
                min: boxes[node].min.to_array(),
                left,
                max: boxes[node].max.to_array(),
                right,
                parent: h.parent[node],
                escape: escapes[node],
                _pad: [0; 2],
            }
        })
        .collect()
}
