// Ray-primitive intersection. Mirrored by src/cpu/intersect.rs.

struct Ray {
    origin: vec3<f32>,
    // Unit length: t is a distance.
    dir: vec3<f32>,
}

const HIT_NONE: u32 = 0u;
// A sphere or a triangle: the index is the primitive's (spheres first, then triangles).
const HIT_PRIMITIVE: u32 = 1u;
const HIT_PLANE: u32 = 2u;

// The closest hit found so far: t is t_max while kind is HIT_NONE.
struct Hit {
    t: f32,
    kind: u32,
    index: u32,
}

// What the intersect_* functions return for a miss: NO_HIT, from the preamble.

// The nearest t in (0, t_max] where the ray meets the sphere, or NO_HIT. t_max itself counts, so that
// a sphere as near as the best hit so far can still win the tie (see closer_primitive).
fn intersect_sphere(sphere: Sphere, ray: Ray, t_max: f32) -> f32 {
    let oc = ray.origin - sphere.center;
    let b = dot(oc, ray.dir);
    // Squared distance from the centre to the ray's line, without the cancellation in b*b - c.
    let off_axis = oc - b * ray.dir;
    let discriminant = sphere.radius * sphere.radius - dot(off_axis, off_axis);
    if (discriminant < 0.0) {
        return NO_HIT;
    }
    let root = sqrt(discriminant);
    let t_near = -b - root;
    if (t_near > 0.0 && t_near <= t_max) {
        return t_near;
    }
    let t_far = -b + root;
    if (t_far > 0.0 && t_far <= t_max) {
        return t_far;
    }
    return NO_HIT;
}

// Möller–Trumbore: (u, v, t) where v0 + u e1 + v e2 = origin + t dir. A ray in the triangle's plane
// (or a degenerate triangle) has det 0 and gets a u that fails every test.
fn triangle_uvt(triangle: Triangle, ray: Ray) -> vec3<f32> {
    let p = cross(ray.dir, triangle.e2);
    let det = dot(triangle.e1, p);
    if (det == 0.0) {
        return vec3<f32>(NO_HIT);
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - triangle.v0;
    let q = cross(s, triangle.e1);
    return vec3<f32>(dot(s, p) * inv_det, dot(ray.dir, q) * inv_det, dot(triangle.e2, q) * inv_det);
}

// The t in (0, t_max] where the ray meets the triangle, or NO_HIT; t_max counts, as for spheres.
fn intersect_triangle(triangle: Triangle, ray: Ray, t_max: f32) -> f32 {
    let uvt = triangle_uvt(triangle, ray);
    if (uvt.x >= 0.0 && uvt.y >= 0.0 && uvt.x + uvt.y <= 1.0 && uvt.z > 0.0 && uvt.z <= t_max) {
        return uvt.z;
    }
    return NO_HIT;
}

fn primitive_count() -> u32 {
    return globals.scene.sphere_count + globals.scene.triangle_count;
}

// Primitive `index` of the BVH's order: spheres, then triangles.
fn intersect_primitive(index: u32, ray: Ray, t_max: f32) -> f32 {
    if (index < globals.scene.sphere_count) {
        return intersect_sphere(load_sphere(index), ray, t_max);
    }
    return intersect_triangle(load_triangle(index - globals.scene.sphere_count), ray, t_max);
}

// Whether primitive `index`, met at t (or NO_HIT), beats the best hit: nearer, or as near with a
// lower index, so that coincident primitives resolve the same whatever order a traversal visits them in.
fn closer_primitive(t: f32, index: u32, best: Hit) -> bool {
    return t > 0.0 && (t < best.t || (t == best.t && best.kind == HIT_PRIMITIVE && index < best.index));
}

fn intersect_plane(plane: Plane, ray: Ray, t_max: f32) -> f32 {
    let denom = dot(plane.normal, ray.dir);
    if (abs(denom) < PARALLEL_EPSILON) {
        return t_max;
    }
    let t = dot(plane.point - ray.origin, plane.normal) / denom;
    if (t > 0.0 && t < t_max) {
        return t;
    }
    return t_max;
}

// 1 / dir, with near-zero components replaced so the slab test never computes 0 * inf.
fn safe_inverse(dir: vec3<f32>) -> vec3<f32> {
    return 1.0 / select(dir, vec3<f32>(TINY_DIRECTION), abs(dir) < vec3<f32>(TINY_DIRECTION));
}

// Where the ray enters the box (0 if it starts inside), if it does so by t_max; else NO_HIT.
fn intersect_box(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> f32 {
    box_tests += 1u;
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let t_enter = max(max(near.x, near.y), max(near.z, 0.0));
    let t_exit = min(min(far.x, far.y), min(far.z, t_max));
    if (t_enter <= t_exit) {
        return t_enter;
    }
    return NO_HIT;
}

// Tests a primitive of the BVH; when it beats the best hit, it becomes the best hit and this says so.
fn hit_primitive(index: u32, ray: Ray, hit: ptr<function, Hit>) -> bool {
    box_tests += 1u;
    let t = intersect_primitive(index, ray, (*hit).t);
    if (closer_primitive(t, index, *hit)) {
        *hit = Hit(t, HIT_PRIMITIVE, index);
        return true;
    }
    return false;
}

// Planes are unbounded, so they stay outside any acceleration structure and are always tested.
fn closest_plane(ray: Ray, best: Hit) -> Hit {
    var hit = best;
    for (var i = 0u; i < globals.scene.plane_count; i++) {
        let t = intersect_plane(load_plane(i), ray, hit.t);
        if (t < hit.t) {
            hit = Hit(t, HIT_PLANE, i);
        }
    }
    return hit;
}

fn any_plane(ray: Ray, t_max: f32) -> bool {
    for (var i = 0u; i < globals.scene.plane_count; i++) {
        if (intersect_plane(load_plane(i), ray, t_max) < t_max) {
            return true;
        }
    }
    return false;
}
