//! The threaded BVH that `--accel threaded` and `--accel stack` walk: the tree of
//! [`layout`](super::layout) renumbered in depth-first order, with boxes quantized to 16 bits, in 16
//! bytes a node.
//!
//! In depth-first (preorder) numbering the node after a hit box, and after a leaf, is always the
//! next one, so a node keeps a single link: where to go when the ray misses its box (Smits 1998's
//! skip link). The stack walk finds a node's children the same way: the next node, and the node
//! after the left subtree. On a software rasterizer every component a fragment reads is a separate
//! load, so a node of four words instead of nine is much of a walk's speed (docs/BENCHMARKS.md).
//!
//! Boxes are kept in a [`QuantizationFrame`] around the root: integer corners in units of a power
//! of two per axis, rounded outwards by one more unit. The walk moves the ray into the frame
//! instead of the boxes out of it, so the corners it tests are exact integers and every box holds
//! the one it stands for. `gpu/shaders/threaded.wgsl` lays out the same nodes on the GPU, bit for bit.

use super::aabb::Aabb;
use super::layout::{GpuNode, NONE};
use super::validate::InvalidTree;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use rayon::prelude::*;

/// Set in [`GpuThreadedNode::link`] for a leaf; the other bits are its primitive.
pub const LEAF_BIT: u32 = 1 << 31;
/// The largest quantized coordinate: corners are 16-bit.
pub const MAX_QUANTUM: u32 = 0xffff;
/// Extents below 2^-100 get a quantum of 1: any box is then one or two units wide, still a bound.
pub const TINY_EXTENT: f32 = power_of_two(-100);

/// A node of the threaded BVH; node i is the i-th in depth-first order, left child first.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuThreadedNode {
    /// The box in quanta of the frame, 16 bits a corner: `min.x | min.y << 16`,
    /// `min.z | max.x << 16`, `max.y | max.z << 16`.
    pub bounds: [u32; 3],
    /// Internal node: the node after its subtree, where a ray that misses the box goes on (the node
    /// count at the end of the tree). Leaf: [`LEAF_BIT`] | its primitive.
    pub link: u32,
}

impl GpuThreadedNode {
    /// Whether the node is a leaf: its link's top bit.
    pub fn is_leaf(&self) -> bool {
        self.link & LEAF_BIT != 0
    }

    /// A leaf's primitive.
    pub fn primitive(&self) -> u32 {
        self.link & !LEAF_BIT
    }

    /// The box's corners in quanta: exact integers.
    pub fn corners(&self) -> (Vec3, Vec3) {
        let [a, b, c] = self.bounds;
        let low = |w: u32| (w & MAX_QUANTUM) as f32;
        let high = |w: u32| (w >> 16) as f32;
        (Vec3::new(low(a), high(a), low(b)), Vec3::new(high(b), low(c), high(c)))
    }
}

/// A threaded BVH as the walks read it: its nodes, and the frame their boxes are in.
#[derive(Clone, Copy, Debug)]
pub struct ThreadedTree<'a> {
    /// The threaded nodes, root first.
    pub nodes: &'a [GpuThreadedNode],
    /// The frame the nodes' quantized boxes are in.
    pub frame: QuantizationFrame,
    /// The stack walk's stack size: the tree's depth in edges (at least 1), as the shader's
    /// `BVH_STACK_SIZE`. The CPU walk holds itself to it, so a stack too small fails there too.
    pub stack_size: u32,
}

/// Where quantized boxes live: corner q on an axis stands for `origin + q * quantum`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct QuantizationFrame {
    /// The root box's minimum corner.
    pub origin: Vec3,
    /// Per axis, the smallest power of two with 65534 of them spanning the root box: a power of
    /// two so that moving into the frame is exact where it matters, and 65534 so that the outward
    /// unit still fits.
    pub quantum: Vec3,
}

impl QuantizationFrame {
    /// The frame that quantizes boxes inside `root`, the tree's root box.
    pub fn around(root: Aabb) -> Self {
        let extent = root.max - root.min;
        Self {
            origin: root.min,
            quantum: Vec3::new(quantum_for(extent.x), quantum_for(extent.y), quantum_for(extent.z)),
        }
    }

    /// 1 / quantum: exact, as quantum is a power of two.
    pub fn inverse_quantum(&self) -> Vec3 {
        self.quantum.recip()
    }

    /// The box's corners in quanta, rounded outwards by one unit more than needed: the quantized
    /// box holds the box with room for the rounding of the walk's own arithmetic.
    pub fn quantize(&self, bounds: Aabb) -> [u32; 3] {
        let inverse = self.inverse_quantum();
        let lo = flush_subnormal(flush_subnormal(bounds.min - self.origin) * inverse).floor() - Vec3::ONE;
        let hi = flush_subnormal(flush_subnormal(bounds.max - self.origin) * inverse).ceil() + Vec3::ONE;
        let q = |v: f32| v.clamp(0.0, MAX_QUANTUM as f32) as u32;
        [
            q(lo.x) | q(lo.y) << 16,
            q(lo.z) | q(hi.x) << 16,
            q(hi.y) | q(hi.z) << 16,
        ]
    }

    /// The box a node's quantized corners stand for, in world space.
    pub fn world_box(&self, node: &GpuThreadedNode) -> Aabb {
        let (low, high) = node.corners();
        Aabb {
            min: self.origin + low * self.quantum,
            max: self.origin + high * self.quantum,
        }
    }
}

/// Subnormals as zero: GPUs may flush them, and the two devices must quantize alike.
pub(crate) fn flush_subnormal(v: Vec3) -> Vec3 {
    Vec3::select(v.cmplt(Vec3::splat(f32::MIN_POSITIVE)), Vec3::ZERO, v)
}

/// The smallest power of two q with 65534 q >= extent (1 for a flat or tiny extent). Computed from
/// the float's exponent bits, so the GPU finds the same one.
pub(crate) fn quantum_for(extent: f32) -> f32 {
    if extent.is_nan() || extent < TINY_EXTENT {
        return 1.0;
    }
    let floor_log2 = (extent.to_bits() >> 23) as i32 - 127;
    let mut exponent = floor_log2 - 15;
    if (MAX_QUANTUM - 1) as f32 * power_of_two(exponent) < extent {
        exponent += 1;
    }
    power_of_two(exponent)
}

pub(crate) const fn power_of_two(exponent: i32) -> f32 {
    f32::from_bits(((exponent + 127) as u32) << 23)
}

/// The threaded BVH of `nodes` (the root first, any numbering): its frame and its nodes in
/// depth-first order.
pub fn threaded_nodes(nodes: &[GpuNode]) -> (QuantizationFrame, Vec<GpuThreadedNode>) {
    let Some(root) = nodes.first() else {
        return (QuantizationFrame::default(), Vec::new());
    };
    let frame = QuantizationFrame::around(super::node_box(root));
    let order = depth_first_order(nodes);
    // Where each node lands: its escape link in the new numbering.
    let mut position = vec![0u32; nodes.len()];
    for (i, &node) in order.iter().enumerate() {
        position[node as usize] = i as u32;
    }
    let end = nodes.len() as u32;
    let threaded = order
        .par_iter()
        .with_min_len(4096)
        .map(|&index| {
            let node = &nodes[index as usize];
            let link = if node.is_leaf() {
                LEAF_BIT | node.left
            } else if node.escape == NONE {
                end
            } else {
                position[node.escape as usize]
            };
            GpuThreadedNode {
                bounds: frame.quantize(super::node_box(node)),
                link,
            }
        })
        .collect();
    (frame, threaded)
}

/// Checks a threaded BVH against the primitives' boxes: the links describe a depth-first order
/// (each internal node's link is the end of its subtree, the next node starts its left subtree, and
/// the end of that its right one), every primitive is in exactly one leaf, and every box, taken back
/// out of the frame exactly, holds the boxes of all primitives below it.
pub fn validate(
    frame: &QuantizationFrame,
    nodes: &[GpuThreadedNode],
    primitive_boxes: &[Aabb],
) -> Result<(), InvalidTree> {
    let n = primitive_boxes.len();
    if nodes.len() != (2 * n).saturating_sub(1) {
        return Err(format!("{} nodes for {n} primitives", nodes.len()).into());
    }
    if n == 0 {
        return Ok(());
    }
    let mut seen = vec![false; n];
    match check_subtree(frame, nodes, primitive_boxes, &mut seen, 0)? {
        (end, _) if end == nodes.len() => Ok(()),
        (end, _) => Err(format!("the tree ends at node {end} of {}", nodes.len()).into()),
    }
}

/// Checks the subtree at `index`; returns where it ends and its primitives' bounds.
fn check_subtree(
    frame: &QuantizationFrame,
    nodes: &[GpuThreadedNode],
    primitive_boxes: &[Aabb],
    seen: &mut [bool],
    index: usize,
) -> Result<(usize, Aabb), InvalidTree> {
    let node = nodes
        .get(index)
        .ok_or_else(|| format!("a subtree starts at node {index} of {}", nodes.len()))?;
    let (end, bounds) = if node.is_leaf() {
        let primitive = node.primitive() as usize;
        if primitive >= seen.len() || std::mem::replace(&mut seen[primitive], true) {
            return Err(format!("node {index}: primitive {primitive} is out of range or in two leaves").into());
        }
        (index + 1, primitive_boxes[primitive])
    } else {
        let (left_end, left) = check_subtree(frame, nodes, primitive_boxes, seen, index + 1)?;
        let (end, right) = check_subtree(frame, nodes, primitive_boxes, seen, left_end)?;
        if node.link as usize != end {
            return Err(format!("node {index}: link {} but its subtree ends at {end}", node.link).into());
        }
        (end, left.union(right))
    };
    // origin + q * quantum is exact in f64: q has 16 bits, quantum is a power of two.
    let (lo, hi) = node.corners();
    for axis in 0..3 {
        let exact = |q: Vec3| frame.origin[axis] as f64 + q[axis] as f64 * frame.quantum[axis] as f64;
        if exact(lo) > bounds.min[axis] as f64 || exact(hi) < bounds.max[axis] as f64 {
            return Err(format!("node {index}: its quantized box does not hold its primitives on axis {axis}").into());
        }
    }
    Ok((end, bounds))
}

/// Node indices in depth-first order, left child first.
fn depth_first_order(nodes: &[GpuNode]) -> Vec<u32> {
    let mut order = Vec::with_capacity(nodes.len());
    let mut pending = vec![0u32];
    while let Some(index) = pending.pop() {
        order.push(index);
        let node = &nodes[index as usize];
        if !node.is_leaf() {
            pending.push(node.right);
            pending.push(node.left);
        }
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantum_is_the_smallest_power_of_two_that_spans() {
        for extent in [1.0f32, 1.5, 2.0, 65534.0, 65535.0, 1e-20, 3.0e30, 0.1, 1.999_97] {
            let q = quantum_for(extent);
            assert!((MAX_QUANTUM - 1) as f32 * q >= extent, "{extent}: {q}");
            assert!(
                (MAX_QUANTUM - 1) as f32 * q / 2.0 < extent,
                "{extent}: {q} is not the smallest"
            );
            assert_eq!(q.to_bits() & 0x7f_ffff, 0, "{q} is a power of two");
        }
        assert_eq!(quantum_for(0.0), 1.0);
        assert_eq!(quantum_for(1e-35), 1.0);
    }

    #[test]
    fn quantized_boxes_hold_the_boxes() {
        let root = Aabb::new(Vec3::new(-3.0, 100.0, 1e-3), Vec3::new(5.0, 100.5, 1e-3));
        let frame = QuantizationFrame::around(root);
        let boxes = [
            root,
            Aabb::new(Vec3::new(-1.0, 100.2, 1e-3), Vec3::new(-0.999, 100.2001, 1e-3)),
            Aabb::new(Vec3::new(4.99, 100.49, 1e-3), Vec3::new(5.0, 100.5, 1e-3)),
        ];
        for bounds in boxes {
            let node = GpuThreadedNode {
                bounds: frame.quantize(bounds),
                link: 0,
            };
            let Aabb { min: lo, max: hi } = frame.world_box(&node);
            assert!(
                lo.cmple(bounds.min).all() && hi.cmpge(bounds.max).all(),
                "{bounds:?}: {lo} {hi}"
            );
        }
    }
}
