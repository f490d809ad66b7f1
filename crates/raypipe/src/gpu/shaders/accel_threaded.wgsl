// Threaded BVH traversal (src/bvh/threaded.rs): nodes in depth-first order, left child first, so
// after a hit box or a leaf the walk goes on to the next node, and after a missed box it follows the
// node's link past the subtree. No stack, one fixed order. Mirrored by src/cpu/accel.rs.

fn traverse_threaded(ray: Ray, best: Hit, shadow: bool) -> Hit {
    var hit = best;
    let count = threaded_node_count();
    // The ray in the quantization frame, where box corners are whole quanta: t is unchanged.
    let origin = (ray.origin - globals.bvh_frame.origin) * globals.bvh_frame.inverse_quantum;
    let inv_dir = safe_inverse(ray.dir) * globals.bvh_frame.quantum;
    var index = 0u;
    while (index < count) {
        let node = load_threaded_node(index);
        if (is_leaf(node)) {
            // A leaf's primitive costs no more to test than its box: test it directly.
            if (hit_primitive(node.link & ~LEAF_BIT, ray, &hit) && shadow) {
                return hit;
            }
            index += 1u;
        } else if (intersect_box(quantized_min(node), quantized_max(node), origin, inv_dir, hit.t) < 0.0) {
            index = node.link;
        } else {
            index += 1u;
        }
    }
    return hit;
}

// 2n - 1 nodes for n primitives.
fn threaded_node_count() -> u32 {
    return max(2u * primitive_count(), 1u) - 1u;
}

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    return traverse_threaded(ray, best, false);
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_threaded(ray, Hit(t_max, HIT_NONE, 0u), true).kind != HIT_NONE;
}
