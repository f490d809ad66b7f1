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
    var index = 0u;
    var node = load_threaded_node(0u);
    if (!is_leaf(node) && intersect_box(quantized_min(node), quantized_max(node), origin, inv_dir, hit.t) < 0.0) {
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
                index = stack[size];
                node = load_threaded_node(index);
                has_node = true;
            }
            if (is_leaf(node)) {
                break;
            }
            let left_index = index + 1u;
            let left = load_threaded_node(left_index);
            let right_index = select(left.link, left_index + 1u, is_leaf(left));
            let right = load_threaded_node(right_index);
            // Leaf children are box-tested too and visited as nodes.
            let t_left = intersect_box(quantized_min(left), quantized_max(left), origin, inv_dir, hit.t);
            let t_right = intersect_box(quantized_min(right), quantized_max(right), origin, inv_dir, hit.t);
            if (t_left >= 0.0 && t_right >= 0.0) {
                // Both: go to the nearer (left on a tie), the other waits.
                if (t_right < t_left) {
                    stack[size] = left_index;
                    stack_t[size] = t_left;
                    index = right_index;
                    node = right;
                } else {
                    stack[size] = right_index;
                    stack_t[size] = t_right;
                    index = left_index;
                    node = left;
                }
                size += 1u;
            } else if (t_left >= 0.0) {
                index = left_index;
                node = left;
            } else if (t_right >= 0.0) {
                index = right_index;
                node = right;
            } else {
                has_node = false;
            }
        }
        if (!has_node) {
            break;
        }
        if (hit_primitive(node.link & ~LEAF_BIT, ray, &hit) && shadow) {
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
