// Brute force: every ray against every primitive. Each acceleration mode defines these two functions.
// Mirrored by src/cpu/accel.rs.

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    var hit = best;
    // The cost of brute force: every primitive tested.
    box_tests += primitive_count();
    for (var i = 0u; i < globals.scene.sphere_count; i++) {
        let t = intersect_sphere(load_sphere(i), ray, hit.t);
        if (closer_primitive(t, i, hit)) {
            hit = Hit(t, HIT_PRIMITIVE, i);
        }
    }
    for (var i = 0u; i < globals.scene.triangle_count; i++) {
        let t = intersect_triangle(load_triangle(i), ray, hit.t);
        let index = globals.scene.sphere_count + i;
        if (closer_primitive(t, index, hit) && primitive_stops_ray(index, ray)) {
            hit = Hit(t, HIT_PRIMITIVE, index);
        }
    }
    return hit;
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    for (var i = 0u; i < globals.scene.sphere_count; i++) {
        let t = intersect_sphere(load_sphere(i), ray, t_max);
        if (t > 0.0 && t < t_max) {
            return true;
        }
    }
    for (var i = 0u; i < globals.scene.triangle_count; i++) {
        let t = intersect_triangle(load_triangle(i), ray, t_max);
        if (t > 0.0 && t < t_max && primitive_stops_ray(globals.scene.sphere_count + i, ray)) {
            return true;
        }
    }
    return false;
}
