//! The compressed wide BVH that `--accel wide` walks, after Ylitie, Karras and Laine 2017
//! ("Efficient incoherent ray traversal on GPUs through compressed wide BVHs"): the binary tree of
//! [`layout`](super::layout) collapsed into nodes of up to eight children, whose boxes are kept in
//! 8 bits an axis in the node's own frame, so that one 80-byte node tests eight boxes.
//!
//! **The array.** One array of texels (four u32 words each), as every memory mode reads it, the
//! texture route's rgba32uint texels included. First the leaf words: primitive indices, four a
//! texel, [`leaf_texels`] texels for n primitives. Then the nodes, five texels each, the root first:
//!
//! | texel | words |
//! |---|---|
//! | 0 | origin.x, origin.y, origin.z (f32 bits): the node box's minimum corner; `exponents`: the biased exponent (an f32's exponent bits) of each axis's quantum in bits 0-7, 8-15, 16-23, and `imask` in bits 24-31 |
//! | 1 | `child_base`: the texel of the first internal child; `leaf_base`: the word of the first leaf child's primitive; `slots`: the occupied slots, bit s for slot s; 0 |
//! | 2 | low x of slots 0-3, 4-7 (a byte each, slot 0 lowest); low y of slots 0-3, 4-7 |
//! | 3 | low z; high x |
//! | 4 | high y; high z |
//!
//! A slot's box is `origin + q * quantum` per axis, q its two corners; `imask` says which occupied
//! slots hold internal children, the others holding one primitive each (the LBVH's leaves hold one).
//! Children are stored in slot order: the internal child in slot s at `child_base + 5 r`, r the
//! internal slots below s; the leaf in slot s at word `leaf_base + r`, r the leaf slots below s.
//!
//! **Slots face octants** (Ylitie et al. §3.1): slot s stands for the direction whose component on
//! axis k is positive where bit k of s is set, and each child takes, in the collapse's order, the
//! free slot whose direction its centre lies furthest along from the node's centre. A ray whose
//! octant is o (bit k set where its direction is not negative) then meets the children nearly
//! front to back in decreasing order of `s ^ o`, with no sort.
//!
//! **The collapse** is top-down and greedy, as H-PLOC's conversion kernel: a node starts from the
//! binary node's two children and opens its largest internal child until it has eight or only
//! leaves. "Largest" is the box's extent summed over the axes (half its perimeter), not its area:
//! sums of differences come out bit for bit alike on every device, where a product's fused or
//! unfused rounding may not, and the GPU's collapse (`gpu/shaders/wide.wgsl`) must choose the
//! children the CPU chooses. Level by level, so that each level's nodes collapse in parallel.

use super::aabb::Aabb;
use super::layout::{GpuNode, LEAF};
use super::threaded::{TINY_EXTENT, flush_subnormal, power_of_two};
use super::validate::InvalidTree;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use rayon::prelude::*;

/// Children a node holds at most.
pub const WIDTH: usize = 8;
/// Texels a node takes.
pub const NODE_TEXELS: u32 = 5;
/// The quanta that span a node's box on an axis: 254, so that rounding outwards by one unit
/// more keeps every corner within a byte.
pub const SPAN: f32 = 254.0;
/// The largest quantized coordinate.
pub const MAX_QUANTUM: u32 = 0xff;

/// One texel of the wide BVH's array: four words.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuWideTexel {
    /// The texel's four words.
    pub words: [u32; 4],
}

/// A node as its five texels hold it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WideNode {
    /// The low corner of the quantization grid.
    pub origin: [f32; 3],
    /// Biased exponents of the quanta (bits 0-7 x, 8-15 y, 16-23 z) and the internal slots (24-31).
    pub exponents: u32,
    /// The first texel of the node's internal children.
    pub child_base: u32,
    /// The first of the node's leaf words.
    pub leaf_base: u32,
    /// Bit s: slot s holds a child.
    pub slots: u32,
    /// Padding to 16 bytes.
    pub _pad: u32,
    /// Low corners per axis, a byte a slot: slots 0-3 in the first word, 4-7 in the second.
    pub lo: [[u32; 2]; 3],
    /// High corners per axis, as `lo` holds the low ones.
    pub hi: [[u32; 2]; 3],
}

const _: () = assert!(std::mem::size_of::<WideNode>() == NODE_TEXELS as usize * 16);

impl WideNode {
    /// Slots holding internal children.
    pub fn imask(&self) -> u32 {
        self.exponents >> 24
    }

    /// Slots holding a leaf's primitive.
    pub fn leaf_mask(&self) -> u32 {
        self.slots & !self.imask()
    }

    /// The quantum on each axis: a power of two.
    pub fn quantum(&self) -> Vec3 {
        let e = |axis: u32| f32::from_bits(((self.exponents >> (8 * axis)) & 0xff) << 23);
        Vec3::new(e(0), e(1), e(2))
    }

    /// 1 / quantum, exact.
    pub fn inverse_quantum(&self) -> Vec3 {
        let e = |axis: u32| f32::from_bits((254 - ((self.exponents >> (8 * axis)) & 0xff)) << 23);
        Vec3::new(e(0), e(1), e(2))
    }

    /// Slot s's box corners in quanta: exact integers.
    pub fn corners(&self, slot: usize) -> (Vec3, Vec3) {
        let byte = |words: [u32; 2]| ((words[slot / 4] >> (8 * (slot % 4))) & 0xff) as f32;
        let [lx, ly, lz] = self.lo;
        let [hx, hy, hz] = self.hi;
        (
            Vec3::new(byte(lx), byte(ly), byte(lz)),
            Vec3::new(byte(hx), byte(hy), byte(hz)),
        )
    }

    /// Where slot s's child is: the texel of an internal child, the word of a leaf's primitive.
    pub fn child(&self, slot: usize) -> u32 {
        let below = (1u32 << slot) - 1;
        if self.imask() & (1 << slot) != 0 {
            self.child_base + NODE_TEXELS * (self.imask() & below).count_ones()
        } else {
            self.leaf_base + (self.leaf_mask() & below).count_ones()
        }
    }
}

/// A wide BVH as the walks read it.
#[derive(Clone, Copy, Debug)]
pub struct WideTree<'a> {
    /// The tree's texels: the leaf words, then the nodes.
    pub texels: &'a [GpuWideTexel],
    /// Where the root starts: after the leaf words.
    pub root: u32,
    /// The walk's stack of waiting node groups holds this many: the binary tree's depth (at least
    /// 1), as the shader's `BVH_STACK_SIZE`; the wide tree is no deeper.
    pub stack_size: u32,
}

impl WideTree<'_> {
    /// The wide node whose first texel is `texel`.
    pub fn node(&self, texel: u32) -> WideNode {
        let at = texel as usize;
        bytemuck::pod_read_unaligned(bytemuck::cast_slice(&self.texels[at..at + NODE_TEXELS as usize]))
    }

    /// The 32-bit word `word` of the texels, counted from the first.
    pub fn word(&self, word: u32) -> u32 {
        self.texels[word as usize / 4].words[word as usize % 4]
    }
}

/// Texels of leaf words for `primitive_count` primitives: where the root starts.
pub fn leaf_texels(primitive_count: usize) -> u32 {
    primitive_count.div_ceil(4) as u32
}

/// Texels the array may need for `primitive_count` primitives: the leaf words and as many nodes as
/// a greedy collapse can make. Every node that is not all leaves has eight children, so with F
/// such nodes and L all-leaf ones (two leaves or more each) there are at most n / 2 + F nodes and
/// F is at most (n / 2 - 1) / 7: 4n / 7 in all.
pub(crate) fn capacity_texels(primitive_count: usize) -> u32 {
    leaf_texels(primitive_count) + NODE_TEXELS * node_capacity(primitive_count)
}

pub(crate) fn node_capacity(primitive_count: usize) -> u32 {
    (4 * primitive_count).div_ceil(7).max(1) as u32
}

/// The smallest power of two q with SPAN q >= extent (1 for a flat or tiny extent), as its biased
/// exponent; from the float's exponent bits, so the GPU finds the same one.
pub(crate) fn quantum_exponent(extent: f32) -> u32 {
    if extent.is_nan() || extent < TINY_EXTENT {
        return 127;
    }
    let floor_log2 = (extent.to_bits() >> 23) as i32 - 127;
    let mut exponent = floor_log2 - 7;
    if SPAN * power_of_two(exponent) < extent {
        exponent += 1;
    }
    (exponent + 127) as u32
}

/// A child of a node being collapsed: its binary node's box and children, read once.
#[derive(Clone, Copy, Default)]
struct Child {
    /// The binary node.
    index: u32,
    /// Internal: the binary node's children. Leaf: its primitive, and [`LEAF`].
    left: u32,
    right: u32,
    min: Vec3,
    max: Vec3,
    /// The box's extent summed over the axes (half its perimeter): the collapse's measure of a
    /// child's size. Sums of differences come out bit for bit alike on every device.
    extent: f32,
}

impl Child {
    fn read(nodes: &[GpuNode], index: u32) -> Self {
        let node = &nodes[index as usize];
        let (min, max) = (Vec3::from_array(node.min), Vec3::from_array(node.max));
        let size = max - min;
        Self {
            index,
            left: node.left,
            right: node.right,
            min,
            max,
            extent: (size.x + size.y) + size.z,
        }
    }

    fn is_leaf(&self) -> bool {
        self.right == LEAF
    }
}

/// The wide node made from binary node `index`, but for where its children are stored, and below
/// each slot an internal child's binary node or a leaf's primitive. Each binary node it reaches is
/// read once.
fn collapse(nodes: &[GpuNode], index: u32) -> (WideNode, [u32; WIDTH]) {
    let node = Child::read(nodes, index);
    let mut children = [Child::default(); WIDTH];
    let mut count = 1;
    children[0] = node;
    if !node.is_leaf() {
        (children[0], children[1], count) = (Child::read(nodes, node.left), Child::read(nodes, node.right), 2);
    }
    // The largest internal child (the first of equals) gives way to its two, until there are eight
    // or only leaves.
    while count < WIDTH {
        let mut widest: Option<usize> = None;
        for (i, c) in children[..count].iter().enumerate() {
            if !c.is_leaf() && widest.is_none_or(|w| c.extent > children[w].extent) {
                widest = Some(i);
            }
        }
        let Some(i) = widest else { break };
        let opened = children[i];
        (children[i], children[count]) = (Child::read(nodes, opened.left), Child::read(nodes, opened.right));
        count += 1;
    }
    // Each child in turn takes the free slot whose octant its centre lies furthest into (the first
    // of equals).
    let centre = node.min + node.max;
    let mut slot_child = [usize::MAX; WIDTH];
    let mut free = (1u32 << WIDTH) - 1;
    for (i, c) in children[..count].iter().enumerate() {
        let costs = octant_costs((c.min + c.max) - centre);
        let mut best = free.trailing_zeros() as usize;
        let mut best_cost = costs[best];
        // Without branches: which slot wins is a coin toss to a branch predictor.
        for (slot, &cost) in costs.iter().enumerate() {
            let better = free & (1 << slot) != 0 && cost > best_cost;
            best = if better { slot } else { best };
            best_cost = if better { cost } else { best_cost };
        }
        free &= !(1 << best);
        slot_child[best] = i;
    }
    // The children's boxes in the node's frame.
    let extent = node.max - node.min;
    let exponents = [extent.x, extent.y, extent.z].map(quantum_exponent);
    let mut wide = WideNode {
        origin: node.min.to_array(),
        ..WideNode::default()
    };
    let mut imask = 0;
    let mut below = [0; WIDTH];
    for (slot, &i) in slot_child.iter().enumerate() {
        let Some(c) = children.get(i) else { continue };
        wide.slots |= 1 << slot;
        below[slot] = if c.is_leaf() {
            c.left
        } else {
            imask |= 1 << slot;
            c.index
        };
        let (lo, hi) = quantize(node.min, exponents, Aabb::new(c.min, c.max));
        let (word, shift) = (slot / 4, 8 * (slot % 4));
        for axis in 0..3 {
            wide.lo[axis][word] |= lo[axis] << shift;
            wide.hi[axis][word] |= hi[axis] << shift;
        }
    }
    wide.exponents = exponents[0] | exponents[1] << 8 | exponents[2] << 16 | imask << 24;
    (wide, below)
}

/// How far `offset` lies along each slot's diagonal: slot s's cost is the sum of the components,
/// each signed by s's bit for its axis, added x, y, then z.
fn octant_costs(offset: Vec3) -> [f32; WIDTH] {
    std::array::from_fn(|slot| {
        let signed = |v: f32, bit: usize| if slot & (1 << bit) != 0 { v } else { -v };
        (signed(offset.x, 0) + signed(offset.y, 1)) + signed(offset.z, 2)
    })
}

/// A child box's corners in quanta of a node's frame, rounded outwards by one unit more than
/// needed, as [`super::threaded::QuantizationFrame::quantize`] does: `clamp(floor(lo) - 1, 0,
/// 255)` and `clamp(ceil(hi) + 1, 0, 255)`, as the GPU computes them, in integers (the quanta are
/// never negative once subnormals are flushed, and floor and ceil are library calls on x86-64's
/// baseline).
fn quantize(origin: Vec3, exponents: [u32; 3], bounds: Aabb) -> ([u32; 3], [u32; 3]) {
    let inverse = Vec3::from_array(exponents.map(|e| f32::from_bits((254 - e) << 23)));
    let lo = flush_subnormal(flush_subnormal(bounds.min - origin) * inverse).to_array();
    let hi = flush_subnormal(flush_subnormal(bounds.max - origin) * inverse).to_array();
    let below = |q: f32| if q >= 1.0 { (q as u32 - 1).min(MAX_QUANTUM) } else { 0 };
    let above = |q: f32| {
        let whole = q.min(2.0 * MAX_QUANTUM as f32) as u32;
        (whole + u32::from((whole as f32) < q) + 1).min(MAX_QUANTUM)
    };
    (lo.map(below), hi.map(above))
}

/// The wide BVH of `nodes` (the root first) over `primitive_count` primitives, as its texels,
/// `capacity_texels` of them: as many as any tree over as many primitives may need, as the
/// GPU's, so that a renderer whose scene moves rewrites its array in place each frame.
pub fn wide_texels(nodes: &[GpuNode], primitive_count: usize) -> Vec<GpuWideTexel> {
    let root = leaf_texels(primitive_count) as usize;
    let mut texels: Vec<GpuWideTexel> = bytemuck::zeroed_vec(capacity_texels(primitive_count) as usize);
    if nodes.is_empty() {
        return texels;
    }
    let (leaf_words, node_texels) = texels.split_at_mut(root);
    let node_words: &mut [WideNode] = bytemuck::cast_slice_mut(node_texels);
    let mut leaves = Vec::with_capacity(primitive_count);
    // The binary node of each wide node, in the order they are placed: level after level.
    let mut queue = Vec::with_capacity(node_capacity(primitive_count) as usize);
    queue.push(0u32);
    let mut level = 0..1;
    while !level.is_empty() {
        let made = &mut node_words[level.clone()];
        let mut below = vec![[0u32; WIDTH]; made.len()];
        made.par_iter_mut()
            .zip(&mut below)
            .zip(&queue[level.clone()])
            .with_min_len(512)
            .for_each(|((wide, below), &binary)| (*wide, *below) = collapse(nodes, binary));
        // In order, each node's children after those of the nodes before it.
        for (wide, below) in made.iter_mut().zip(&below) {
            wide.child_base = (root + NODE_TEXELS as usize * queue.len()) as u32;
            wide.leaf_base = leaves.len() as u32;
            for (slot, &child) in below.iter().enumerate() {
                if wide.imask() & (1 << slot) != 0 {
                    queue.push(child);
                } else if wide.slots & (1 << slot) != 0 {
                    leaves.push(child);
                }
            }
        }
        level = level.end..queue.len();
    }
    for (texel, words) in leaf_words.iter_mut().zip(leaves.chunks(4)) {
        texel.words[..words.len()].copy_from_slice(words);
    }
    texels
}

/// Checks a wide BVH against the primitives' boxes: every node is reached once from the root, its
/// children stored where its masks say, every primitive in exactly one leaf, and every slot's box,
/// taken back out of its node's frame exactly, holds the boxes of all primitives below it.
pub fn validate(tree: &WideTree, primitive_boxes: &[Aabb]) -> Result<(), InvalidTree> {
    let n = primitive_boxes.len();
    if tree.root != leaf_texels(n) {
        return Err(InvalidTree(format!(
            "the root is at texel {} for {n} primitives",
            tree.root
        )));
    }
    if n == 0 {
        return Ok(());
    }
    let mut seen = vec![false; n];
    check_node(tree, primitive_boxes, &mut seen, tree.root, 0)?;
    match seen.iter().position(|&s| !s) {
        Some(missing) => Err(InvalidTree(format!("primitive {missing} is in no leaf"))),
        None => Ok(()),
    }
}

/// Checks the subtree of the node at `texel`; returns its primitives' bounds.
fn check_node(
    tree: &WideTree,
    primitive_boxes: &[Aabb],
    seen: &mut [bool],
    texel: u32,
    depth: u32,
) -> Result<Aabb, InvalidTree> {
    if texel < tree.root
        || !(texel - tree.root).is_multiple_of(NODE_TEXELS)
        || texel as usize + NODE_TEXELS as usize > tree.texels.len()
    {
        return Err(format!("a child at texel {texel}, which starts no node").into());
    }
    // Visiting a node at depth d leaves at most d groups waiting (one for each node above it).
    if depth > tree.stack_size.max(1) {
        return Err(format!("node at texel {texel}: deeper than the stack of {}", tree.stack_size).into());
    }
    let node = tree.node(texel);
    if node.slots == 0 || node.slots > 0xff || node.imask() & !node.slots != 0 {
        return Err(format!(
            "node at texel {texel}: slots {:#x}, imask {:#x}",
            node.slots,
            node.imask()
        )
        .into());
    }
    let mut bounds: Option<Aabb> = None;
    for slot in 0..WIDTH {
        if node.slots & (1 << slot) == 0 {
            continue;
        }
        let child = node.child(slot);
        let below = if node.imask() & (1 << slot) != 0 {
            check_node(tree, primitive_boxes, seen, child, depth + 1)?
        } else {
            let words = tree.texels.len() as u32 * 4;
            if child >= tree.root * 4 || child >= words {
                return Err(format!("node at texel {texel}: leaf word {child} is past the leaf words").into());
            }
            let primitive = tree.word(child) as usize;
            if primitive >= seen.len() || std::mem::replace(&mut seen[primitive], true) {
                return Err(
                    format!("node at texel {texel}: primitive {primitive} is out of range or in two leaves").into(),
                );
            }
            primitive_boxes[primitive]
        };
        // origin + q * quantum is exact in f64: q has 8 bits, quantum is a power of two.
        let (lo, hi) = node.corners(slot);
        let quantum = node.quantum();
        for axis in 0..3 {
            let exact = |q: Vec3| node.origin[axis] as f64 + q[axis] as f64 * quantum[axis] as f64;
            if exact(lo) > below.min[axis] as f64 || exact(hi) < below.max[axis] as f64 {
                return Err(format!(
                    "node at texel {texel}: slot {slot}'s box does not hold its primitives on axis {axis}"
                )
                .into());
            }
        }
        bounds = Some(bounds.map_or(below, |b| b.union(below)));
    }
    Ok(bounds.expect("a node with a slot"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantum_is_the_smallest_power_of_two_that_spans() {
        for extent in [1.0f32, 1.5, 2.0, 254.0, 255.0, 1e-20, 3.0e30, 0.1, 1.999_97] {
            let q = f32::from_bits(quantum_exponent(extent) << 23);
            assert!(SPAN * q >= extent, "{extent}: {q}");
            assert!(SPAN * q / 2.0 < extent, "{extent}: {q} is not the smallest");
        }
        assert_eq!(quantum_exponent(0.0), 127);
    }

    #[test]
    fn capacity_holds_the_worst_collapse() {
        // n / 2 all-leaf nodes of two leaves under full nodes of eight: about 4n / 7.
        for n in [1usize, 2, 3, 16, 17, 100, 1000] {
            assert!(
                node_capacity(n) as usize >= n / 2 + (n / 2).saturating_sub(1) / 7,
                "{n}"
            );
        }
    }
}
