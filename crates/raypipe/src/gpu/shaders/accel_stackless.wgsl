// Stackless BVH traversal (Hapala, Davidovič, Wald, Havran and Slusallek 2011): parent links and a
// three-state automaton instead of a stack, nearer child first. The state says how the walk reached
// the current node: from its parent (descending), from its sibling (the near child is done), or from
// a child (climbing back). Mirrored by src/cpu/accel.rs.

const FROM_PARENT: u32 = 0u;
const FROM_SIBLING: u32 = 1u;
const FROM_CHILD: u32 = 2u;

// The near child of an internal node: the one whose box centre comes first along the ray. It
// depends on the node and the ray only, so the walk decides alike going down and coming back up.
fn near_child(node: BvhNode, dir: vec3<f32>) -> u32 {
    let left = load_node(node.left);
    let right = load_node(node.right);
    let ahead = dot((left.min + left.max) - (right.min + right.max), dir);
    return select(node.left, node.right, ahead > 0.0);
}

fn sibling(index: u32, parent: BvhNode) -> u32 {
    return select(parent.left, parent.right, parent.left == index);
}

fn traverse_stackless(ray: Ray, best: Hit, shadow: bool) -> Hit {
    var hit = best;
    if (primitive_count() == 0u) {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    let root = load_node(0u);
    if (intersect_box(root.min, root.max, ray.origin, inv_dir, hit.t) < 0.0) {
        return hit;
    }
    if (root.right == LEAF) {
        hit_primitive(root.left, ray, &hit);
        return hit;
    }
    var index = near_child(root, ray.dir);
    var state = FROM_PARENT;
    loop {
        let node = load_node(index);
        if (state == FROM_CHILD) {
            if (index == 0u) {
                break;
            }
            let parent = load_node(node.parent);
            if (index == near_child(parent, ray.dir)) {
                index = sibling(index, parent);
                state = FROM_SIBLING;
            } else {
                index = node.parent;
            }
            continue;
        }
        // From the parent or the sibling: a leaf's primitive (no dearer to test than its box), or the box.
        var descend = false;
        if (node.right == LEAF) {
            if (hit_primitive(node.left, ray, &hit) && shadow) {
                return hit;
            }
        } else {
            descend = intersect_box(node.min, node.max, ray.origin, inv_dir, hit.t) >= 0.0;
        }
        if (descend) {
            index = near_child(node, ray.dir);
            state = FROM_PARENT;
        } else if (state == FROM_PARENT) {
            index = sibling(index, load_node(node.parent));
            state = FROM_SIBLING;
        } else {
            index = node.parent;
            state = FROM_CHILD;
        }
    }
    return hit;
}

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    return traverse_stackless(ray, best, false);
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_stackless(ray, Hit(t_max, HIT_NONE, 0u), true).kind != HIT_NONE;
}
