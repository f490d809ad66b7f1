// Threaded BVH traversal: depth-first order, left child first, with no stack. A node whose box the
// ray misses (or a leaf, once its primitive is tested) hands over to its escape link, the next node
// after its subtree; a hit descends to the left child. Mirrored by src/cpu/accel.rs.

fn traverse_threaded(ray: Ray, best: Hit, shadow: bool) -> Hit {
    var hit = best;
    if (primitive_count() == 0u) {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    var index = 0u;
    while (index != NONE) {
        let node = load_node(index);
        // A leaf's primitive costs no more to test than its box: test it directly.
        if (node.right == LEAF) {
            if (hit_leaf(node, ray, &hit) && shadow) {
                return hit;
            }
            index = node.escape;
        } else if (intersect_box(node.min, node.max, ray.origin, inv_dir, hit.t) < 0.0) {
            index = node.escape;
        } else {
            index = node.left;
        }
    }
    return hit;
}

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    return traverse_threaded(ray, best, false);
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_threaded(ray, Hit(t_max, HIT_NONE, 0u), true).kind != HIT_NONE;
}
