// Ray-primitive intersection. Mirrored by src/cpu/intersect.rs.

// The shear that takes a ray to the frame where it starts at the origin and runs along +z (Woop,
// Benthin and Wald 2013): the frame's z is the direction's dominant axis, its x and y the other two
// (swapped where the ray points down that axis, which keeps the triangles' winding); s holds
// (dir.x / dir.z, dir.y / dir.z, 1 / dir.z) in the frame's axes. The axes are kept as choices
// between swizzles, not as indices: a vector indexed by a per-pixel value costs a trip through
// memory on some compilers (SwiftShader's, under every browser without a GPU), in every corner of
// every triangle test.
struct RayShear {
    // The frame's z is world x (z_is_x), world y (z_is_y), or world z.
    z_is_x: bool,
    z_is_y: bool,
    // The frame's x and y are the remaining axes in reverse cyclic order.
    swap_xy: bool,
    s: vec3<f32>,
}

// v's components in the frame's axis order: exact, a permutation.
fn shear_axes(v: vec3<f32>, shear: RayShear) -> vec3<f32> {
    let cyclic = select(select(v, v.zxy, shear.z_is_y), v.yzx, shear.z_is_x);
    return select(cyclic, cyclic.yxz, shear.swap_xy);
}

fn ray_shear(dir: vec3<f32>) -> RayShear {
    let a = abs(dir);
    var shear = RayShear(a.x > a.y && a.x > a.z, false, false, vec3<f32>(0.0));
    shear.z_is_y = !shear.z_is_x && a.y > a.z;
    // The swap leaves z where it is.
    shear.swap_xy = shear_axes(dir, shear).z < 0.0;
    let d = shear_axes(dir, shear);
    let sz = 1.0 / d.z;
    shear.s = vec3<f32>(d.x * sz, d.y * sz, sz);
    return shear;
}

struct Ray {
    origin: vec3<f32>,
    // Unit length: t is a distance.
    dir: vec3<f32>,
    // For the triangle test, worked out once per ray.
    shear: RayShear,
}

fn make_ray(origin: vec3<f32>, dir: vec3<f32>) -> Ray {
    return Ray(origin, dir, ray_shear(dir));
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

// A corner in the ray's sheared frame: xy where the ray passes through (0, 0), z scaled so that the
// hit's t comes out of the barycentric blend of the corners' z.
fn sheared(corner: vec3<f32>, ray: Ray) -> vec3<f32> {
    let p = shear_axes(corner - ray.origin, ray.shear);
    let s = ray.shear.s;
    return vec3<f32>(p.x - s.x * p.z, p.y - s.y * p.z, s.z * p.z);
}

// p.x q.y - p.y q.x, with the pair taken in one fixed order: the triangle across an edge meets it
// as (q, p) and gets exactly the negated value, even where the compiler fuses multiply-adds.
fn edge_function(p: vec2<f32>, q: vec2<f32>) -> f32 {
    if (p.x < q.x || (p.x == q.x && p.y < q.y)) {
        return p.x * q.y - p.y * q.x;
    }
    return -(q.x * p.y - q.y * p.x);
}

// The watertight ray-triangle test (Woop, Benthin and Wald 2013): (u, v, t) where
// (1 - u - v) v0 + u v1 + v v2 = origin + t dir, or NO_HIT in every component where the ray passes
// outside. Two triangles sharing an edge compute that edge's function from the same sheared corners,
// so a ray through the edge hits one of them (or both), never neither. A ray in the triangle's
// plane (or a degenerate triangle) has det 0 and misses.
fn triangle_uvt(triangle: Triangle, ray: Ray) -> vec3<f32> {
    let a = sheared(triangle.v0, ray);
    let b = sheared(triangle.v1, ray);
    let c = sheared(triangle.v2, ray);
    let u = edge_function(c.xy, b.xy);
    let v = edge_function(a.xy, c.xy);
    let w = edge_function(b.xy, a.xy);
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return vec3<f32>(NO_HIT);
    }
    let det = u + v + w;
    if (det == 0.0) {
        return vec3<f32>(NO_HIT);
    }
    // Weights first, then depths: an edge function is already a product of two coordinates, and
    // times a depth it would overflow near the accepted range's end (MAX_COORDINATE).
    let inv_det = 1.0 / det;
    let weights = vec3<f32>(u, v, w) * inv_det;
    return vec3<f32>(weights.y, weights.z, weights.x * a.z + weights.y * b.z + weights.z * c.z);
}

// The t in (0, t_max] where the ray meets the triangle, or NO_HIT; t_max counts, as for spheres.
fn intersect_triangle(triangle: Triangle, ray: Ray, t_max: f32) -> f32 {
    let t = triangle_uvt(triangle, ray).z;
    if (t > 0.0 && t <= t_max) {
        return t;
    }
    return NO_HIT;
}

fn primitive_count() -> u32 {
    return globals.scene.sphere_count + globals.scene.triangle_count;
}

// Whether primitive `index` of the BVH's order (spheres, then triangles) is a sphere. HAS_SPHERES
// and HAS_TRIANGLES (preamble) make it a constant where the scene holds one kind, so the code for
// the other drops out.
fn is_sphere(index: u32) -> bool {
    return !HAS_TRIANGLES || (HAS_SPHERES && index < globals.scene.sphere_count);
}

fn intersect_primitive(index: u32, ray: Ray, t_max: f32) -> f32 {
    if (is_sphere(index)) {
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

// min and max of numbers that are not NaN, as a compare and a select: a box test's are, and the
// software rasterizers pay for min's and max's NaN rules with a compare and a blend more each.
fn larger(a: f32, b: f32) -> f32 {
    return select(a, b, b > a);
}

fn smaller(a: f32, b: f32) -> f32 {
    return select(a, b, b < a);
}

// Where the ray enters the box (0 if it starts inside), if it does so by t_max; else NO_HIT.
fn intersect_box(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> f32 {
    box_tests += 1u;
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let swap = t1 < t0;
    let near = select(t0, t1, swap);
    let far = select(t1, t0, swap);
    let t_enter = larger(larger(near.x, near.y), larger(near.z, 0.0));
    let t_exit = smaller(smaller(far.x, far.y), smaller(far.z, t_max));
    if (t_enter <= t_exit) {
        return t_enter;
    }
    return NO_HIT;
}

// Planes are unbounded, so they stay outside any acceleration structure and are always tested.
fn closest_plane(ray: Ray, best: Hit) -> Hit {
    var hit = best;
    if (!HAS_PLANES) {
        return hit;
    }
    for (var i = 0u; i < globals.scene.plane_count; i++) {
        let t = intersect_plane(load_plane(i), ray, hit.t);
        if (t < hit.t) {
            hit = Hit(t, HIT_PLANE, i);
        }
    }
    return hit;
}

fn any_plane(ray: Ray, t_max: f32) -> bool {
    if (!HAS_PLANES) {
        return false;
    }
    for (var i = 0u; i < globals.scene.plane_count; i++) {
        if (intersect_plane(load_plane(i), ray, t_max) < t_max) {
            return true;
        }
    }
    return false;
}
