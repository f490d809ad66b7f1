// BVH traversal with a per-pixel stack (the paper's local array), sized to the tree's depth, nearer
// child first. Mirrored by src/cpu/accel.rs.

// The closest primitive hit that beats `best`; with `shadow`, the first hit nearer than best.t.
fn traverse_stack(ray: Ray, best: Hit, shadow: bool) -> Hit {
    var hit = best;
    if (primitive_count() == 0u) {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    var node = load_node(0u);
    if (intersect_box(node.min, node.max, ray.origin, inv_dir, hit.t) < 0.0) {
        return hit;
    }
    // Nodes waiting to be visited, with the distance where the ray enters them.
    var stack: array<u32, BVH_STACK_SIZE>;
    var stack_t: array<f32, BVH_STACK_SIZE>;
    var size = 0u;
    loop {
        if (node.right == LEAF) {
            if (hit_leaf(node, ray, &hit) && shadow) {
                return hit;
            }
        } else {
            let left = load_node(node.left);
            let right = load_node(node.right);
            // Leaf children: test their primitives now (no dearer than their boxes); box-test the others.
            var t_left = NO_HIT;
            if (left.right == LEAF) {
                if (hit_leaf(left, ray, &hit) && shadow) {
                    return hit;
                }
            } else {
                t_left = intersect_box(left.min, left.max, ray.origin, inv_dir, hit.t);
            }
            var t_right = NO_HIT;
            if (right.right == LEAF) {
                if (hit_leaf(right, ray, &hit) && shadow) {
                    return hit;
                }
            } else {
                t_right = intersect_box(right.min, right.max, ray.origin, inv_dir, hit.t);
            }
            if (t_left >= 0.0 && t_right >= 0.0) {
                // Both: go to the nearer (left on a tie), the other waits.
                if (t_right < t_left) {
                    stack[size] = node.left;
                    stack_t[size] = t_left;
                    node = right;
                } else {
                    stack[size] = node.right;
                    stack_t[size] = t_right;
                    node = left;
                }
                size += 1u;
                continue;
            }
            if (t_left >= 0.0) {
                node = left;
                continue;
            }
            if (t_right >= 0.0) {
                node = right;
                continue;
            }
        }
        // Resume at the next waiting node that the ray enters no farther than the best hit.
        var resumed = false;
        while (size > 0u && !resumed) {
            size -= 1u;
            if (stack_t[size] <= hit.t) {
                node = load_node(stack[size]);
                resumed = true;
            }
        }
        if (!resumed) {
            break;
        }
    }
    return hit;
}

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    return traverse_stack(ray, best, false);
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_stack(ray, Hit(t_max, HIT_NONE, 0u), true).kind != HIT_NONE;
}
