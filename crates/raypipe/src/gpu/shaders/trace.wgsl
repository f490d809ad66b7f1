// What the integrators' tracers share, one pixel per fragment: the pixel's counters, the camera
// ray and where in its pixel a sample looks, closest hits and shadow rays, and the ray cones that
// filter textures. The bounce loops are whitted.wgsl's and path.wgsl's, the accumulation
// pixel.wgsl's. Mirrored by src/cpu/trace.rs.

// T_FAR and DEPTH_MISS (the depth where the primary ray hits nothing; the host reads it as +inf)
// come from the preamble.

// Rays traced for the current pixel: primary, shadow and secondary, counted where they are cast.
var<private> ray_count: u32;
// Nodes tested so far (ray-box tests of internal nodes, ray-sphere tests of leaves; spheres tested for
// brute force), and their number for the primary ray: the pixel's cost, which a cost render
// (WRITE_COST) writes instead of the ray count.
var<private> box_tests: u32;
var<private> primary_cost: u32;
// Surfaces of blended triangles the pixel's rays went on behind, at most MAX_BLEND_LAYERS.
var<private> blend_layers: u32;

struct PixelTrace {
    color: vec3<f32>,
    // First-hit shading normal and distance; DEPTH_MISS where the primary ray escapes.
    normal: vec3<f32>,
    depth: f32,
}

// A 32-bit integer hash (PCG's output permutation, after Jarzynski and Olano 2020), for the per-pixel
// scrambles of the samples.
fn hash_u32(value: u32) -> u32 {
    let state = value * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Where in its pixel sample `index` looks, in [0, 1)^2. Sample 0 is the centre, so one sample is the
// unjittered image; later samples follow the R2 sequence, shifted per pixel by a hash (a
// Cranley-Patterson rotation) so that neighbouring pixels do not repeat one pattern. Integer
// arithmetic in 0.32 fixed point, so every device computes the same bits.
fn sample_offset(pixel: vec2<u32>, index: u32) -> vec2<f32> {
    if (index == 0u) {
        return vec2<f32>(0.5);
    }
    let scramble_x = hash_u32(pixel.x ^ hash_u32(pixel.y));
    let scramble_y = hash_u32(scramble_x);
    let fixed = vec2<u32>(scramble_x + index * R2_STEP_X, scramble_y + index * R2_STEP_Y);
    return vec2<f32>(fixed >> vec2<u32>(8u)) * (1.0 / 16777216.0);
}

// The ray through a pixel position (pixel centres at +0.5, row 0 at the top).
fn camera_ray(pixel: vec2<f32>) -> Ray {
    let x = (2.0 * pixel.x / globals.camera.width - 1.0) * globals.camera.tan_half_fov * globals.camera.aspect;
    let y = (1.0 - 2.0 * pixel.y / globals.camera.height) * globals.camera.tan_half_fov;
    let dir = normalize(globals.camera.forward + x * globals.camera.right + y * globals.camera.up);
    return make_ray(globals.camera.eye, dir);
}

fn closest_hit(ray: Ray, t_max: f32, culls: bool) -> Hit {
    ray_culls_back_faces = culls;
    let planes = closest_plane(ray, Hit(t_max, HIT_NONE, 0u));
    return accel_closest(ray, planes);
}

// Whether something blocks the shadow ray before t_max; where nothing does, shadow_light holds the
// share of light that its blended triangles let through. Shadow rays see both sides of triangles.
fn occluded(ray: Ray, t_max: f32) -> bool {
    ray_culls_back_faces = false;
    ray_is_shadow = true;
    shadow_light = 1.0;
    let blocked = any_plane(ray, t_max) || accel_occluded(ray, t_max);
    ray_is_shadow = false;
    return blocked;
}

// The spread angle of the ray cone through a pixel: the angle one pixel of the image subtends at the
// eye, at its centre.
fn pixel_spread() -> f32 {
    return atan(2.0 * globals.camera.tan_half_fov / globals.camera.height);
}

// A ray cone (width at the surface, spread) reflected by a surface of `curvature` (seen from the
// ray's side): across the cone's width the normal turns by curvature × width, and the reflected
// rays by twice that (Akenine-Möller et al., "Improved Shader and Texture Level of Detail Using Ray
// Cones", 2021).
fn cone_reflected(cone: vec2<f32>, curvature: f32) -> vec2<f32> {
    return vec2<f32>(cone.x, cone.y + 2.0 * curvature * cone.x);
}

// A ray cone refracted by a surface of `curvature`, with `eta` the ratio of indices and the cosines
// of the incident and refracted rays to the normal. Snell's law differentiated: a change of the
// incident angle changes the refracted one ratio = η cos θi / cos θt times as much, so the incoming
// spread scales by it, and the normal's turn across the width bends the refracted rays by
// (ratio - 1) times that turn (a convex surface entering glass focuses).
fn cone_refracted(cone: vec2<f32>, curvature: f32, eta: f32, cos_i: f32, cos_t: f32) -> vec2<f32> {
    let ratio = eta * cos_i / max(cos_t, MIN_FOOTPRINT_COSINE);
    return vec2<f32>(cone.x, ratio * cone.y + (ratio - 1.0) * curvature * cone.x);
}
