// BVH traversal with a per-pixel stack (the paper's local array), sized to the tree's depth, nearer
// child first, over the threaded walk's 16-byte depth-first nodes (src/bvh/threaded.rs): a node's
// left child is the next node, and its right child comes after the left subtree (the left child's
// link, or the node after a leaf). Mirrored by src/cpu/accel.rs.

// The closest primitive hit that beats `best`; with `shadow`, the first hit nearer than best.t.
fn traverse_stack(ray: Ray, best: Hit, shadow: bool) -> Hit {
    var hit = best;
    if (primitive_count() == 0u) {
        return hit;
    }
    // The ray in the quantization frame, where box corners are whole quanta: t is unchanged.
    let origin = (ray.origin - globals.bvh_frame.origin) * globals.bvh_frame.inverse_quantum;
    let inv_dir = safe_inverse(ray.dir) * globals.bvh_frame.quantum;
    // The node being visited, named by what its visit needs: an inner node by its position, a leaf
    // by its link (LEAF_BIT | primitive). Waiting nodes are named the same way, so resuming one
    // fetches nothing.
    let root = load_threaded_node(0u);
    var current = select(0u, root.link, is_leaf(root));
    if (!is_leaf(root) && intersect_box(quantized_min(root), quantized_max(root), origin, inv_dir, hit.t) < 0.0) {
        return hit;
    }
    // Nodes waiting to be visited, with the distance where the ray enters them.
    var stack: array<u32, BVH_STACK_SIZE>;
    var stack_t: array<f32, BVH_STACK_SIZE>;
    var size = 0u;
    var has_node = true;
    // Two loops (Aila and Laine's while-while): the inner one walks inner nodes down to the next
    // leaf, the outer one tests that leaf's primitive. SwiftShader and llvmpipe run a loop's whole
    // body for every step any of its lanes takes, so the primitive test is kept out of the
    // box-testing steps. The nodes tested, and their order, are those of one loop.
    loop {
        loop {
            if (!has_node) {
                // Resume at the next waiting node that the ray enters no farther than the best hit.
                if (size == 0u) {
                    break;
                }
                size -= 1u;
                if (stack_t[size] > hit.t) {
                    continue;
                }
                current = stack[size];
                has_node = true;
            }
            if ((current & LEAF_BIT) != 0u) {
                break;
            }
            let left_index = current + 1u;
            let left = load_threaded_node(left_index);
            let right_index = select(left.link, left_index + 1u, is_leaf(left));
            let right = load_threaded_node(right_index);
            let left_name = select(left_index, left.link, is_leaf(left));
            let right_name = select(right_index, right.link, is_leaf(right));
            // Leaf children are box-tested too and visited as nodes.
            let t_left = intersect_box(quantized_min(left), quantized_max(left), origin, inv_dir, hit.t);
            let t_right = intersect_box(quantized_min(right), quantized_max(right), origin, inv_dir, hit.t);
            let enters_left = t_left >= 0.0;
            let enters_right = t_right >= 0.0;
            // The nearer child is visited next (left on a tie); where the ray enters both, the
            // other waits.
            let right_first = enters_right && (!enters_left || t_right < t_left);
            if (enters_left && enters_right) {
                stack[size] = select(right_name, left_name, right_first);
                stack_t[size] = select(t_right, t_left, right_first);
                size += 1u;
            }
            current = select(left_name, right_name, right_first);
            has_node = enters_left || enters_right;
        }
        if (!has_node) {
            break;
        }
        if (hit_primitive(current & ~LEAF_BIT, ray, &hit) && shadow) {
            return hit;
        }
        has_node = false;
    }
    return hit;
}

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    return traverse_stack(ray, best, false);
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_stack(ray, Hit(t_max, HIT_NONE, 0u), true).kind != HIT_NONE;
}
