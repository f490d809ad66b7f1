// Ray queries over the driver's acceleration structures (src/gpu/builders/rayquery.rs). The driver walks its
// own tree and tests the opaque triangles itself; the triangles whose hits the shader decides
// (single-sided, alpha MASK or BLEND) and the spheres' boxes come back as candidates, which the
// walks' own hit test (hit_primitive, admit.wgsl) takes or leaves. Its CPU twin is brute force
// (src/cpu/trace.rs): the same closest hit. The cost it counts (WRITE_COST) is the driver's steps
// that reached the shader: one per rayQueryProceed, and one per candidate tested; the driver's own
// box and triangle tests are hidden from the shader.

// The scene primitive (spheres first, then triangles) that a BLAS primitive stands for: an
// instance's custom index is where its BLAS's names start in blas_primitives.
fn query_primitive(found: RayIntersection) -> u32 {
    return blas_primitives[found.instance_custom_data + found.primitive_index];
}

// The closest primitive hit that beats `best`; with `shadow`, the first hit nearer than best.t.
fn walk_query(ray: Ray, best: Hit, shadow: bool) -> Hit {
    var hit = best;
    if (primitive_count() == 0u) {
        return hit;
    }
    let flags = select(RAY_FLAG_NONE, RAY_FLAG_TERMINATE_ON_FIRST_HIT, shadow);
    var query: ray_query;
    rayQueryInitialize(&query, scene_tlas, RayDesc(flags, 0xffu, 0.0, hit.t, ray.origin, ray.dir));
    loop {
        box_tests += 1u;
        if (!rayQueryProceed(&query)) {
            break;
        }
        // An opaque triangle the driver took alone bounds the test, so that a box's hit is never
        // generated beyond it.
        hit = with_driver_triangle(rayQueryGetCommittedIntersection(&query), ray, hit);
        let candidate = rayQueryGetCandidateIntersection(&query);
        if (hit_primitive(query_primitive(candidate), ray, &hit)) {
            // Read before the branch: naga 30 emits an argument computed in the call's own block
            // only after the call.
            let t = hit.t;
            if (candidate.kind == RAY_QUERY_INTERSECTION_AABB) {
                rayQueryGenerateIntersection(&query, t);
            } else {
                rayQueryConfirmIntersection(&query);
            }
            if (shadow) {
                rayQueryTerminate(&query);
            }
        }
    }
    return with_driver_triangle(rayQueryGetCommittedIntersection(&query), ray, hit);
}

// `hit`, or the triangle the driver holds (`committed`) where it is nearer: an opaque triangle it
// took alone (or one the shader confirmed). The shader keeps the hits it takes itself rather than
// read them back as the committed intersection: after rayQueryGenerateIntersection, lavapipe's
// committed intersection did not always name the box's primitive (hundreds of wrong pixels among
// 2000 spheres). The distance is the walks' own, as the BVH walks find it; the driver's where their
// test misses the triangle (an edge the two tests round differently).
fn with_driver_triangle(committed: RayIntersection, ray: Ray, hit: Hit) -> Hit {
    if (committed.kind != RAY_QUERY_INTERSECTION_TRIANGLE || committed.t >= hit.t) {
        return hit;
    }
    let index = query_primitive(committed);
    let t = intersect_primitive(index, ray, T_FAR);
    return Hit(select(committed.t, t, t > 0.0), HIT_PRIMITIVE, index);
}

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    return walk_query(ray, best, false);
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    return walk_query(ray, Hit(t_max, HIT_NONE, 0u), true).kind != HIT_NONE;
}
