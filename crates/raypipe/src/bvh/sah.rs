//! The surface area heuristic: the cost of a tree, and a binned-SAH builder as the quality reference.

use super::aabb::Aabb;
use super::layout::{GpuNode, LEAF, NONE};
use super::{Bvh, node_box};

/// Expected cost of a random ray through the tree (traversal and intersection cost 1, one primitive
/// per leaf), relative to the root: Σ internal SA / SA(root) + Σ leaf SA / SA(root).
pub fn sah_cost(bvh: &Bvh) -> f64 {
    let Some(root) = bvh.nodes.first() else { return 0.0 };
    let root_area = node_box(root).surface_area() as f64;
    if root_area == 0.0 {
        return bvh.nodes.len() as f64;
    }
    bvh.nodes.iter().map(|n| node_box(n).surface_area() as f64).sum::<f64>() / root_area
}

const BINS: usize = 16;

/// Top-down binned SAH (16 bins per axis over the centroid bounds), down to one primitive per leaf,
/// into the same node layout. Node order is depth-first, so escape links are the next subtree.
pub fn build_binned_sah(boxes: &[Aabb]) -> Bvh {
    let n = boxes.len();
    let mut nodes: Vec<GpuNode> = Vec::with_capacity((2 * n).saturating_sub(1));
    if n == 0 {
        return Bvh {
            nodes,
            primitive_count: 0,
        };
    }
    let mut primitives: Vec<u32> = (0..n as u32).collect();
    let centroids: Vec<glam::Vec3> = boxes.iter().map(|b| b.centroid()).collect();
    // Ranges of `primitives` still to split, with the node that points to each and from which side,
    // on a stack of their own rather than the thread's (wasm's is 1 MiB): the right half under the
    // left, so that nodes come out in depth-first order.
    let mut pending = vec![Pending {
        range: 0..n,
        parent: NONE,
        is_right: false,
    }];
    while let Some(Pending {
        range,
        parent,
        is_right,
    }) = pending.pop()
    {
        let index = nodes.len() as u32;
        if parent != NONE {
            let parent = &mut nodes[parent as usize];
            *(if is_right { &mut parent.right } else { &mut parent.left }) = index;
        }
        let prims = &mut primitives[range.clone()];
        let bounds = prims.iter().fold(Aabb::EMPTY, |b, &p| b.union(boxes[p as usize]));
        nodes.push(GpuNode {
            min: bounds.min.to_array(),
            max: bounds.max.to_array(),
            parent,
            ..GpuNode::default()
        });
        if let [only] = prims {
            nodes[index as usize].left = *only;
            nodes[index as usize].right = LEAF;
            continue;
        }
        let mid = range.start + split(prims, boxes, &centroids);
        pending.push(Pending {
            range: mid..range.end,
            parent: index,
            is_right: true,
        });
        pending.push(Pending {
            range: range.start..mid,
            parent: index,
            is_right: false,
        });
    }
    // Depth-first numbering makes the escape of a node the index just past its subtree.
    let mut ends = vec![0u32; nodes.len()];
    for i in (0..nodes.len()).rev() {
        ends[i] = if nodes[i].is_leaf() {
            i as u32 + 1
        } else {
            ends[nodes[i].right as usize]
        };
    }
    for (i, node) in nodes.iter_mut().enumerate() {
        node.escape = if ends[i] as usize == n * 2 - 1 { NONE } else { ends[i] };
    }
    Bvh {
        nodes,
        primitive_count: n,
    }
}

/// A range of primitives waiting to become a subtree under `parent` (NONE for the root).
struct Pending {
    range: std::ops::Range<usize>,
    parent: u32,
    is_right: bool,
}

/// Orders two or more primitives so that the cheapest binned split puts the first ones left, and
/// says how many: at least one a side.
fn split(prims: &mut [u32], boxes: &[Aabb], centroids: &[glam::Vec3]) -> usize {
    let centroid_bounds = prims.iter().fold(Aabb::EMPTY, |b, &p| b.grow(centroids[p as usize]));
    let extent = centroid_bounds.max - centroid_bounds.min;
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, bins left of the split)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let bin_of = |p: u32| {
            let t = (centroids[p as usize][axis] - centroid_bounds.min[axis]) / extent[axis];
            ((t * BINS as f32) as usize).min(BINS - 1)
        };
        let mut bin_boxes = [Aabb::EMPTY; BINS];
        let mut counts = [0usize; BINS];
        for &p in prims.iter() {
            let b = bin_of(p);
            bin_boxes[b] = bin_boxes[b].union(boxes[p as usize]);
            counts[b] += 1;
        }
        let mut right_area = [0f64; BINS];
        let mut right_count = [0usize; BINS];
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            acc = acc.union(bin_boxes[b]);
            cnt += counts[b];
            right_area[b] = acc.surface_area() as f64;
            right_count[b] = cnt;
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for b in 1..BINS {
            acc = acc.union(bin_boxes[b - 1]);
            cnt += counts[b - 1];
            if cnt == 0 || right_count[b] == 0 {
                continue;
            }
            // In f64: areas times counts overflow f32 for wide scenes of many primitives.
            let cost = acc.surface_area() as f64 * cnt as f64 + right_area[b] * right_count[b] as f64;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    match best {
        Some((_, axis, bin)) => {
            let (mut i, mut j) = (0, prims.len());
            while i < j {
                let t = (centroids[prims[i] as usize][axis] - centroid_bounds.min[axis]) / extent[axis];
                let goes_left = ((t * BINS as f32) as usize).min(BINS - 1) < bin;
                if goes_left {
                    i += 1;
                } else {
                    j -= 1;
                    prims.swap(i, j);
                }
            }
            i
        }
        // All centroids coincide: split the list in half.
        None => prims.len() / 2,
    }
}
