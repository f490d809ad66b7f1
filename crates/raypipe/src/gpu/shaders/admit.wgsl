// Which hits a ray takes: a triangle's sides and alpha (glTF's doubleSided and alphaMode) decide
// in the walks' hit test, so that a back face or a masked hole is never the closest hit and never
// blocks a shadow ray. Mirrored by src/cpu/admit.rs.

// What the ray being walked asks of the triangles it meets: set by closest_hit and occluded
// (trace.wgsl) before each walk.
var<private> ray_culls_back_faces: bool;
var<private> ray_is_shadow: bool;
// The share of a shadow ray's light that the blended triangles it passed let through.
var<private> shadow_light: f32;

// Whether the ray takes its hit of triangle i (among the triangles): not where it sees the back of
// a single-sided triangle and culls back faces, not where alpha MASK cuts the triangle away. A
// shadow ray passes a BLEND triangle, keeping (1 - alpha) of its light, until too little is left.
fn triangle_stops_ray(i: u32, ray: Ray) -> bool {
    let triangle = load_triangle(i);
    let flags = triangle.material & ~MATERIAL_INDEX_MASK;
    if (flags == 0u) {
        return true;
    }
    // The preamble's HAS_* constants keep what the scene does not use out of the walks: software
    // rasterizers (SwiftShader under WebGL2) pay for every line of a walk's inner loop.
    if (HAS_ONE_SIDED && (flags & TRIANGLE_SINGLE_SIDED) != 0u && ray_culls_back_faces) {
        let normal = normalize_scaled(cross(triangle.v1 - triangle.v0, triangle.v2 - triangle.v0));
        if (dot(normal, ray.dir) >= 0.0) {
            return false;
        }
    }
    if (!(HAS_ALPHA_MASK || HAS_ALPHA_BLEND) || (flags & (TRIANGLE_ALPHA_MASK | TRIANGLE_ALPHA_BLEND)) == 0u) {
        return true;
    }
    let material = load_material(triangle.material & MATERIAL_INDEX_MASK);
    let alpha = surface_alpha(material, triangle_attributes(triangle, ray));
    if (HAS_ALPHA_MASK && (flags & TRIANGLE_ALPHA_MASK) != 0u) {
        return alpha >= material.alpha_cutoff;
    }
    if (!HAS_ALPHA_BLEND || !ray_is_shadow) {
        return true;
    }
    shadow_light *= 1.0 - alpha;
    return shadow_light < MIN_WEIGHT;
}

// Whether the ray takes its hit of primitive `index` (spheres always). HAS_ONE_SIDED,
// HAS_ALPHA_MASK and HAS_ALPHA_BLEND (preamble) drop the test from scenes without such triangles.
fn primitive_stops_ray(index: u32, ray: Ray) -> bool {
    if (!(HAS_ONE_SIDED || HAS_ALPHA_MASK || HAS_ALPHA_BLEND) || is_sphere(index)) {
        return true;
    }
    return triangle_stops_ray(index - globals.scene.sphere_count, ray);
}

// Tests a primitive of the BVH; when it beats the best hit and the ray takes it, it becomes the
// best hit and this says so.
fn hit_primitive(index: u32, ray: Ray, hit: ptr<function, Hit>) -> bool {
    box_tests += 1u;
    let t = intersect_primitive(index, ray, (*hit).t);
    if (closer_primitive(t, index, *hit) && primitive_stops_ray(index, ray)) {
        *hit = Hit(t, HIT_PRIMITIVE, index);
        return true;
    }
    return false;
}
