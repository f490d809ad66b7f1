//! Acceleration modes: the twins of `shaders/accel_*.wgsl`. Each answers the closest primitive hit and
//! whether anything blocks a shadow ray.

use super::admit::{Primitives, hit_primitive};
use super::intersect::{
    Hit, HitKind, Ray, closer_primitive, count_box_tests, intersect_box, intersect_sphere, intersect_triangle,
    safe_inverse, v3,
};
use crate::bvh::layout::GpuNode;
use crate::bvh::threaded::{GpuThreadedNode, LEAF_BIT, QuantizationFrame, ThreadedTree};
use crate::bvh::wide::{NODE_TEXELS, WIDTH, WideTree};
use glam::Vec3;

/// Brute force: every ray against every primitive (`accel_brute.wgsl`).
pub fn brute_closest(primitives: &Primitives, ray: &Ray, best: Hit) -> Hit {
    let mut hit = best;
    // The cost of brute force: every primitive tested.
    count_box_tests(primitives.count() as u32);
    for (i, sphere) in primitives.spheres.iter().enumerate() {
        let t = intersect_sphere(sphere, ray, hit.t);
        if closer_primitive(t, i as u32, &hit) {
            hit = Hit {
                t,
                kind: HitKind::Primitive,
                index: i as u32,
            };
        }
    }
    for (i, triangle) in primitives.triangles.iter().enumerate() {
        let t = intersect_triangle(triangle, ray, hit.t);
        let index = (primitives.spheres.len() + i) as u32;
        if closer_primitive(t, index, &hit) && primitives.stops_ray(index, ray) {
            hit = Hit {
                t,
                kind: HitKind::Primitive,
                index,
            };
        }
    }
    hit
}

/// Whether any primitive blocks `ray` before `t_max`, testing every one (the brute-force walk's
/// shadow ray).
pub fn brute_occluded(primitives: &Primitives, ray: &Ray, t_max: f32) -> bool {
    let blocks = |t: f32| t > 0.0 && t < t_max;
    primitives
        .spheres
        .iter()
        .any(|s| blocks(intersect_sphere(s, ray, t_max)))
        || primitives.triangles.iter().enumerate().any(|(i, t)| {
            blocks(intersect_triangle(t, ray, t_max))
                && primitives.stops_ray((primitives.spheres.len() + i) as u32, ray)
        })
}

/// The closest primitive hit that beats `best`; with `shadow`, the first hit nearer than best.t
/// (`traverse_stack` in `accel_stack.wgsl`): a per-pixel stack, nearer child first, over the
/// depth-first nodes of [`threaded`], where a node's left child is the next node and its right child
/// follows the left subtree. The shader splits this loop in two (inner nodes down to a leaf, then the
/// leaf's primitive) for GPUs run on the CPU; the nodes and primitives tested, and their order, are
/// the same.
///
/// [`threaded`]: crate::bvh::threaded
pub fn traverse_stack(tree: ThreadedTree, primitives: &Primitives, ray: &Ray, best: Hit, shadow: bool) -> Hit {
    let nodes = tree.nodes;
    let mut hit = best;
    let Some(&root) = nodes.first() else {
        return hit;
    };
    let (origin, inv_dir) = ray_in_frame(&tree.frame, ray);
    let enter = |node: &GpuThreadedNode, t_max: f32| {
        let (lo, hi) = node.corners();
        intersect_box(lo, hi, origin, inv_dir, t_max)
    };
    // The node being visited, named by what its visit needs: an inner node by its position, a leaf
    // by its link (LEAF_BIT | primitive), as are the waiting ones.
    let name = |index: u32, node: &GpuThreadedNode| if node.is_leaf() { node.link } else { index };
    let mut current = name(0, &root);
    if !root.is_leaf() && enter(&root, hit.t) < 0.0 {
        return hit;
    }
    // Nodes waiting to be visited, with the distance where the ray enters them: no more than the
    // shader's stack holds.
    let capacity = tree.stack_size as usize;
    let mut stack: Vec<(u32, f32)> = Vec::with_capacity(capacity);
    loop {
        if current & LEAF_BIT != 0 {
            if hit_primitive(primitives, current & !LEAF_BIT, ray, &mut hit) && shadow {
                return hit;
            }
        } else {
            let left_index = current + 1;
            let left = nodes[left_index as usize];
            let right_index = if left.is_leaf() { left_index + 1 } else { left.link };
            let right = nodes[right_index as usize];
            let (left_name, right_name) = (name(left_index, &left), name(right_index, &right));
            // Leaf children are box-tested too and visited as nodes: one primitive test per step.
            let t_left = enter(&left, hit.t);
            let t_right = enter(&right, hit.t);
            let (enters_left, enters_right) = (t_left >= 0.0, t_right >= 0.0);
            // The nearer child is visited next (left on a tie); where the ray enters both, the
            // other waits.
            let right_first = enters_right && (!enters_left || t_right < t_left);
            if enters_left && enters_right {
                assert!(
                    stack.len() < capacity,
                    "the BVH stack of {capacity} overflowed: the tree is deeper than its stated depth"
                );
                stack.push(if right_first {
                    (left_name, t_left)
                } else {
                    (right_name, t_right)
                });
            }
            if enters_left || enters_right {
                current = if right_first { right_name } else { left_name };
                continue;
            }
        }
        // Resume at the next waiting node that the ray enters no farther than the best hit.
        match std::iter::from_fn(|| stack.pop()).find(|&(_, t)| t <= hit.t) {
            Some((waiting, _)) => current = waiting,
            None => break,
        }
    }
    hit
}

/// The ray's origin and inverse direction in the quantization frame, where box corners are whole
/// quanta: t along the ray is unchanged.
fn ray_in_frame(frame: &QuantizationFrame, ray: &Ray) -> (Vec3, Vec3) {
    let origin = (ray.origin - frame.origin) * frame.inverse_quantum();
    (origin, safe_inverse(ray.dir) * frame.quantum)
}

/// Threaded traversal (`accel_threaded.wgsl`) over the depth-first nodes of [`threaded`]: after a
/// hit box or a leaf the next node, after a missed box the node's link past its subtree.
///
/// [`threaded`]: crate::bvh::threaded
pub fn traverse_threaded(tree: ThreadedTree, primitives: &Primitives, ray: &Ray, best: Hit, shadow: bool) -> Hit {
    let nodes = tree.nodes;
    let mut hit = best;
    let (origin, inv_dir) = ray_in_frame(&tree.frame, ray);
    let mut index = 0;
    while let Some(node) = nodes.get(index as usize) {
        if node.is_leaf() {
            // A leaf's primitive costs no more to test than its box: test it directly.
            if hit_primitive(primitives, node.primitive(), ray, &mut hit) && shadow {
                return hit;
            }
            index += 1;
        } else {
            let (lo, hi) = node.corners();
            if intersect_box(lo, hi, origin, inv_dir, hit.t) < 0.0 {
                index = node.link;
            } else {
                index += 1;
            }
        }
    }
    hit
}

/// How the stackless walk reached the current node.
#[derive(Clone, Copy, PartialEq, Eq)]
enum From {
    Parent,
    Sibling,
    Child,
}

/// The near child of an internal node: the one whose box centre comes first along the ray.
fn near_child(nodes: &[GpuNode], node: &GpuNode, dir: Vec3) -> u32 {
    let (left, right) = (nodes[node.left as usize], nodes[node.right as usize]);
    let ahead = ((v3(left.min) + v3(left.max)) - (v3(right.min) + v3(right.max))).dot(dir);
    if ahead > 0.0 { node.right } else { node.left }
}

fn sibling(index: u32, parent: &GpuNode) -> u32 {
    if parent.left == index {
        parent.right
    } else {
        parent.left
    }
}

/// Stackless traversal (Hapala et al. 2011, `accel_stackless.wgsl`): parent links and a
/// three-state automaton, nearer child first.
pub fn traverse_stackless(nodes: &[GpuNode], primitives: &Primitives, ray: &Ray, best: Hit, shadow: bool) -> Hit {
    let mut hit = best;
    if primitives.count() == 0 {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    let root = nodes[0];
    if intersect_box(v3(root.min), v3(root.max), ray.origin, inv_dir, hit.t) < 0.0 {
        return hit;
    }
    if root.is_leaf() {
        hit_primitive(primitives, root.left, ray, &mut hit);
        return hit;
    }
    let mut index = near_child(nodes, &root, ray.dir);
    let mut state = From::Parent;
    loop {
        let node = nodes[index as usize];
        if state == From::Child {
            if index == 0 {
                break;
            }
            let parent = nodes[node.parent as usize];
            if index == near_child(nodes, &parent, ray.dir) {
                index = sibling(index, &parent);
                state = From::Sibling;
            } else {
                index = node.parent;
            }
            continue;
        }
        // From the parent or the sibling: a leaf's primitive (no dearer to test than its box), or the box.
        let mut descend = false;
        if node.is_leaf() {
            if hit_primitive(primitives, node.left, ray, &mut hit) && shadow {
                return hit;
            }
        } else {
            descend = intersect_box(v3(node.min), v3(node.max), ray.origin, inv_dir, hit.t) >= 0.0;
        }
        if descend {
            index = near_child(nodes, &node, ray.dir);
            state = From::Parent;
        } else if state == From::Parent {
            index = sibling(index, &nodes[node.parent as usize]);
            state = From::Sibling;
        } else {
            index = node.parent;
            state = From::Child;
        }
    }
    hit
}

/// A group of a wide node's children waiting to be visited (Ylitie et al.'s node and triangle
/// groups): where they are stored, the slots the ray hit as bits `slot ^ octant` (so the highest
/// bit is the nearest child), and the slots of the same kind that the node holds, to find a
/// child's place among them.
#[derive(Clone, Copy, Default)]
struct ChildGroup {
    base: u32,
    hits: u32,
    kind_mask: u32,
}

impl ChildGroup {
    /// Takes the nearest hit child: the texel of an internal child, the word of a leaf's primitive.
    fn take_nearest(&mut self, octant: u32, stride: u32) -> u32 {
        let bit = 31 - self.hits.leading_zeros();
        self.hits &= !(1 << bit);
        let slot = bit ^ octant;
        self.base + stride * (self.kind_mask & ((1 << slot) - 1)).count_ones()
    }
}

/// The closest primitive hit that beats `best`; with `shadow`, the first hit nearer than best.t
/// (`traverse_wide` in `accel_wide.wgsl`) over the compressed wide BVH of [`wide`]: each node's
/// eight boxes tested at once, its hit leaves tested at once, its hit internal children visited
/// nearest first in the order of the ray's octant, the rest waiting on a stack as one group.
///
/// [`wide`]: crate::bvh::wide
pub fn traverse_wide(tree: WideTree, primitives: &Primitives, ray: &Ray, best: Hit, shadow: bool) -> Hit {
    let mut hit = best;
    if primitives.count() == 0 {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    let octant = ray_octant(ray.dir);
    // The root, as a group of one internal child in slot 0.
    let mut nodes = ChildGroup {
        base: tree.root,
        hits: 1 << octant,
        kind_mask: 1,
    };
    let capacity = tree.stack_size as usize;
    let mut stack: Vec<ChildGroup> = Vec::with_capacity(capacity);
    loop {
        let mut leaves = ChildGroup::default();
        if nodes.hits != 0 {
            let texel = nodes.take_nearest(octant, NODE_TEXELS);
            if nodes.hits != 0 {
                assert!(
                    stack.len() < capacity,
                    "the BVH stack of {capacity} overflowed: the tree is deeper than its stated depth"
                );
                stack.push(nodes);
            }
            let node = tree.node(texel);
            // The ray in the node's frame, where its children's corners are whole quanta.
            let origin = (ray.origin - Vec3::from_array(node.origin)) * node.inverse_quantum();
            let node_inv_dir = inv_dir * node.quantum();
            let mut hit_slots = 0;
            for slot in 0..WIDTH {
                if node.slots & (1 << slot) != 0 {
                    let (lo, hi) = node.corners(slot);
                    if intersect_box(lo, hi, origin, node_inv_dir, hit.t) >= 0.0 {
                        hit_slots |= 1 << slot;
                    }
                }
            }
            nodes = ChildGroup {
                base: node.child_base,
                hits: octant_bits(hit_slots & node.imask(), octant),
                kind_mask: node.imask(),
            };
            leaves = ChildGroup {
                base: node.leaf_base,
                hits: octant_bits(hit_slots & node.leaf_mask(), octant),
                kind_mask: node.leaf_mask(),
            };
        } else if let Some(waiting) = stack.pop() {
            nodes = waiting;
        } else {
            break;
        }
        while leaves.hits != 0 {
            let word = leaves.take_nearest(octant, 1);
            if hit_primitive(primitives, tree.word(word), ray, &mut hit) && shadow {
                return hit;
            }
        }
    }
    hit
}

/// The ray's octant: bit k set where its direction's component k is not negative.
fn ray_octant(dir: Vec3) -> u32 {
    (dir.x >= 0.0) as u32 | ((dir.y >= 0.0) as u32) << 1 | ((dir.z >= 0.0) as u32) << 2
}

/// A mask of slots moved to the bits `slot ^ octant`: pairs, then pairs of pairs, then halves
/// swapped where the octant's bits say.
fn octant_bits(mask: u32, octant: u32) -> u32 {
    let mut bits = mask;
    if octant & 1 != 0 {
        bits = (bits & 0x55) << 1 | (bits >> 1) & 0x55;
    }
    if octant & 2 != 0 {
        bits = (bits & 0x33) << 2 | (bits >> 2) & 0x33;
    }
    if octant & 4 != 0 {
        bits = (bits & 0x0f) << 4 | (bits >> 4) & 0x0f;
    }
    bits
}
