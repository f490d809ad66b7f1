// Brute force: every ray against every sphere. Each acceleration mode defines these two functions.
// Mirrored by src/cpu/accel.rs.

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    var hit = best;
    // The cost of brute force: every sphere tested.
    box_tests += globals.sphere_count;
    for (var i = 0u; i < globals.sphere_count; i++) {
        let t = intersect_sphere(load_sphere(i), ray, hit.t);
        if (closer_sphere(t, i, hit)) {
            hit = Hit(t, HIT_SPHERE, i);
        }
    }
    return hit;
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    for (var i = 0u; i < globals.sphere_count; i++) {
        let t = intersect_sphere(load_sphere(i), ray, t_max);
        if (t > 0.0 && t < t_max) {
            return true;
        }
    }
    return false;
}
