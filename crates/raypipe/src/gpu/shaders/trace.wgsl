// The tracer, one pixel per fragment. Shaders cannot recurse, so the tree of rays is walked
// depth-first by hand: a reflected branch is traced next, and its refracted sibling waits on an
// explicit stack of RAY_STACK_SIZE entries (MAX_DEPTH + 1: at most one waits per level; more where
// rays go on behind blended surfaces). Mirrored by src/cpu/trace.rs.

// T_FAR, MIN_WEIGHT (the weight below which a branch cannot change an 8-bit pixel) and DEPTH_MISS
// (the depth where the primary ray hits nothing; the host reads it as +inf) come from the preamble.

// Rays traced for the current pixel: primary, shadow and secondary, counted where they are cast.
var<private> ray_count: u32;
// Nodes tested so far (ray-box tests of internal nodes, ray-sphere tests of leaves; spheres tested for
// brute force), and their number for the primary ray: the pixel's cost, which a cost render
// (WRITE_COST) writes instead of the ray count.
var<private> box_tests: u32;
var<private> primary_cost: u32;
// The sample's random sequence (sampled glossy reflections): its seed and the draws so far.
var<private> sample_seed_value: u32;
var<private> random_draws: u32;
// Surfaces of blended triangles the pixel's rays went on behind, at most MAX_BLEND_LAYERS.
var<private> blend_layers: u32;

struct RayTask {
    origin: vec3<f32>,
    dir: vec3<f32>,
    weight: vec3<f32>,
    depth: u32,
    // Whether single-sided triangles hide their backs from the ray: camera and reflected rays,
    // not rays transmitted through a surface (which may be inside a volume).
    culls: bool,
    // The ray cone around it: its width where the ray starts, and its spread angle (radians).
    cone: vec2<f32>,
}

struct PixelTrace {
    color: vec3<f32>,
    // First-hit shading normal and distance; DEPTH_MISS where the primary ray escapes.
    normal: vec3<f32>,
    depth: f32,
}

// A 32-bit integer hash (PCG's output permutation, after Jarzynski and Olano 2020), for the per-pixel
// scramble of the sample sequence.
fn hash_u32(value: u32) -> u32 {
    let state = value * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The seed of a pixel's sample's random sequence.
fn sample_seed(pixel: vec2<u32>, sample: u32) -> u32 {
    return hash_u32(pixel.x ^ hash_u32(pixel.y ^ hash_u32(sample)));
}

// The next two uniform numbers in [0, 1) of the sample's sequence: a hash of its seed and the
// draw's number, integer arithmetic that every device computes alike.
fn random_pair() -> vec2<f32> {
    random_draws += 1u;
    let x = hash_u32(sample_seed_value ^ hash_u32(random_draws));
    let y = hash_u32(x);
    return vec2<f32>(vec2<u32>(x, y) >> vec2<u32>(8u)) * (1.0 / 16777216.0);
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

fn worth_tracing(weight: vec3<f32>) -> bool {
    return max(weight.x, max(weight.y, weight.z)) >= MIN_WEIGHT;
}

// The rays a hit sends on; a weight that is not worth_tracing means none. `through` goes on behind
// a blended surface: not a bounce, at the same depth.
struct Branches {
    reflected: RayTask,
    refracted: RayTask,
    through: RayTask,
}

// Traces one ray of the tree: adds its light to the pixel and says where it branches.
fn trace_task(task: RayTask, result: ptr<function, PixelTrace>) -> Branches {
    // Zero weights: no branches.
    var branches = Branches();
    let ray = make_ray(task.origin, task.dir);
    ray_count += 1u;
    let hit = closest_hit(ray, T_FAR, task.culls);
    if (task.depth == 0u) {
        primary_cost = box_tests;
    }
    if (hit.kind == HIT_NONE) {
        (*result).color += task.weight * escaped_radiance(ray.dir, task.cone.y);
        return branches;
    }
    var surface = surface_at(ray, hit);
    // The cone where it meets the surface: its width there, and its spread.
    let cone = vec2<f32>(task.cone.x + task.cone.y * hit.t, task.cone.y);
    surface.attributes.footprint = abs(cone.x) / max(abs(dot(surface.normal, ray.dir)), MIN_FOOTPRINT_COSINE);
    let material = surface_material(surface);
    surface.shading = normal_mapped(surface, material);
    // The first surface the camera ray meets, blended or not.
    if (task.depth == 0u && (*result).depth == DEPTH_MISS) {
        (*result).normal = surface.shading;
        (*result).depth = hit.t;
    }
    let entering = dot(surface.normal, ray.dir) < 0.0;
    // The geometric normal picks the side new rays start on; the shading normal bends them.
    let normal = select(-surface.normal, surface.normal, entering);
    let shading = select(-surface.shading, surface.shading, entering);
    let curvature = select(-surface.curvature, surface.curvature, entering);
    let view = -ray.dir;
    let frame = ShadingFrame(normal, shading, view);
    // A ray that leaves a volume lost light on its way through it (Beer-Lambert).
    var arrived = task;
    let volume = HAS_VOLUMES && material.model == MODEL_GLTF && material.volume != 0u;
    if (volume && !entering) {
        arrived.weight *= exp(-material.absorption * hit.t);
    }
    // A blended surface covers its alpha of the ray; the rest goes on behind it.
    var covered = arrived;
    if (HAS_ALPHA_BLEND && surface.blend) {
        covered.weight *= material.alpha;
        if (blend_layers < MAX_BLEND_LAYERS) {
            blend_layers += 1u;
            branches.through = RayTask(offset_origin(surface, -normal), ray.dir,
                arrived.weight * (1.0 - material.alpha), task.depth, task.culls, cone);
        }
    }
    // KHR_materials_unlit: the base colour is what the surface shows, and all it sends on.
    if (HAS_GLTF_MATERIALS && material.model == MODEL_UNLIT) {
        (*result).color += covered.weight * material.color;
        return branches;
    }
    let gltf = HAS_GLTF_MATERIALS && material.model == MODEL_GLTF;
    var light: vec3<f32>;
    if (gltf) {
        light = gltf_direct_light(surface, frame, material, ambient_share(surface, material));
    } else {
        light = direct_light(surface, frame, material);
    }
    (*result).color += covered.weight * (light + material.emission);
    if (!HAS_SECONDARY_RAYS || task.depth >= MAX_DEPTH) {
        return branches;
    }
    if (gltf) {
        let sent = gltf_branches(covered, surface, frame, material, entering, cone, curvature);
        branches.reflected = sent.reflected;
        branches.refracted = sent.refracted;
        return branches;
    }

    // Split the transmitted share by Fresnel; all of it reflects past the critical angle.
    var reflect_share = material.reflect;
    var transmit_share = material.transmit;
    var refracted = vec3<f32>(0.0);
    var refracted_cone = cone;
    if (transmit_share > 0.0) {
        let eta = select(material.ior, 1.0 / material.ior, entering);
        let cos_i = dot(view, shading);
        let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
        if (k < 0.0) {
            reflect_share += transmit_share;
            transmit_share = 0.0;
        } else {
            let cos_t = sqrt(k);
            refracted = normalize(eta * ray.dir + (eta * cos_i - cos_t) * shading);
            refracted_cone = cone_refracted(cone, curvature, eta, cos_i, cos_t);
            let fresnel = fresnel_schlick(select(cos_t, cos_i, entering), material.ior);
            reflect_share += transmit_share * fresnel;
            transmit_share *= 1.0 - fresnel;
        }
    }
    let depth = task.depth + 1u;
    branches.refracted = RayTask(offset_origin(surface, -normal), refracted, covered.weight * transmit_share, depth, false,
        refracted_cone);
    branches.reflected = RayTask(offset_origin(surface, normal), reflect(ray.dir, shading), covered.weight * reflect_share,
        depth, true, cone_reflected(cone, curvature));
    return branches;
}

// The twin of `Tracer::gltf_branches` in cpu/trace.rs, which says what it does.
fn gltf_branches(task: RayTask, surface: Surface, frame: ShadingFrame, material: Material, entering: bool, cone: vec2<f32>, curvature: f32) -> Branches {
    let normal = frame.normal;
    let shading = frame.shading;
    let view = frame.view;
    let s = gltf_surface(material);
    let sample = sample_specular(s, shading, view, random_pair());
    let depth = task.depth + 1u;
    var transmitted = sample.dir - 2.0 * dot(sample.dir, shading) * shading;
    var transmit_side = -normal;
    var transmit_culls = false;
    let reflected_cone = cone_reflected(cone, curvature);
    var transmitted_cone = cone;
    let volume = HAS_VOLUMES && material.volume != 0u;
    if (volume) {
        let eta = select(s.ior, 1.0 / s.ior, entering);
        let microfacet = normalize(sample.dir + view);
        let bent = refracted_direction(-view, microfacet, eta);
        transmitted = select(sample.dir, bent.xyz, bent.w > 0.0);
        transmitted_cone = reflected_cone;
        if (bent.w > 0.0) {
            transmitted_cone = cone_refracted(cone, curvature, eta, dot(view, microfacet), -dot(bent.xyz, microfacet));
        }
        transmit_side = select(normal, -normal, bent.w > 0.0);
        // Outside after it, where back faces hide again: leaving and refracted, or reflected
        // from outside.
        transmit_culls = entering != (bent.w > 0.0);
    }
    let transmit_share = (1.0 - s.metallic) * s.transmission * (1.0 - max3(sample.dielectric_fresnel)) * sample.share;
    var branches = Branches();
    branches.reflected = RayTask(offset_origin(surface, normal), sample.dir, task.weight * sample.weight, depth,
        !volume || entering, reflected_cone);
    branches.refracted = RayTask(offset_origin(surface, transmit_side), transmitted,
        task.weight * s.base * transmit_share, depth, transmit_culls, transmitted_cone);
    return branches;
}

fn trace_pixel(primary: Ray) -> PixelTrace {
    var result = PixelTrace(vec3<f32>(0.0), vec3<f32>(0.0), DEPTH_MISS);
    // The ray being traced stays out of the stack, which a scene without mirrors or glass never
    // touches.
    var task = RayTask(primary.origin, primary.dir, vec3<f32>(1.0), 0u, true, vec2<f32>(0.0, pixel_spread()));
    var waiting: array<RayTask, RAY_STACK_SIZE>;
    var top = 0u;
    loop {
        let branches = trace_task(task, &result);
        if (!HAS_SECONDARY_RAYS && !HAS_ALPHA_BLEND) {
            break;
        }
        let reflects = worth_tracing(branches.reflected.weight);
        if (HAS_ALPHA_BLEND && worth_tracing(branches.through.weight)) {
            // The ray goes on behind the blended surface; the surface's own branches wait.
            if (worth_tracing(branches.refracted.weight) && top < RAY_STACK_SIZE) {
                waiting[top] = branches.refracted;
                top += 1u;
            }
            if (reflects && top < RAY_STACK_SIZE) {
                waiting[top] = branches.reflected;
                top += 1u;
            }
            task = branches.through;
            continue;
        }
        if (worth_tracing(branches.refracted.weight)) {
            if (!reflects) {
                task = branches.refracted;
                continue;
            }
            if (top < RAY_STACK_SIZE) {
                waiting[top] = branches.refracted;
                top += 1u;
            }
        }
        if (reflects) {
            task = branches.reflected;
            continue;
        }
        if (top == 0u) {
            break;
        }
        top -= 1u;
        task = waiting[top];
    }
    return result;
}

// Both targets are rgba32uint holding f32 bits: integer targets are colour-renderable everywhere
// (float targets are not on GLES/WebGL2 without an extension), and bits read back exactly. They hold
// sums over the samples so far: each sample reads the previous pair and writes the other one.
struct PixelSums {
    // rgb: linear radiance; a: rays traced for this pixel (its cost, with WRITE_COST); summed.
    color: vec4<u32>,
    // xyz: first-hit normal; w: first-hit distance or DEPTH_MISS; the centre sample's.
    surface: vec4<u32>,
}

// The targets the previous sample wrote; unread by sample 0.
@group(1) @binding(0) var previous_color: texture_2d<u32>;
@group(1) @binding(1) var previous_surface: texture_2d<u32>;

// The pixel's next sample, added to the sums of those before it: what either entry point writes
// (fs_main in fullscreen.wgsl, cs_main in compute.wgsl).
fn sample_pixel(pixel: vec2<u32>) -> PixelSums {
    ray_count = 0u;
    box_tests = 0u;
    let sample = globals.camera.sample;
    sample_seed_value = sample_seed(pixel, sample);
    random_draws = 0u;
    blend_layers = 0u;
    let traced = trace_pixel(camera_ray(vec2<f32>(pixel) + sample_offset(pixel, sample)));
    let count = select(ray_count, primary_cost, WRITE_COST);
    return summed(pixel, vec4<f32>(traced.color, f32(count)), vec4<f32>(traced.normal, traced.depth));
}

// A sample's colour and count added to the pixel's sums so far; its surface kept only where it is
// the first (the centre sample's).
fn summed(pixel: vec2<u32>, sample_color: vec4<f32>, sample_surface: vec4<f32>) -> PixelSums {
    var color = sample_color;
    var surface = sample_surface;
    if (globals.camera.sample > 0u) {
        let texel = vec2<i32>(pixel);
        color = bitcast<vec4<f32>>(textureLoad(previous_color, texel, 0)) + color;
        surface = bitcast<vec4<f32>>(textureLoad(previous_surface, texel, 0));
    }
    return PixelSums(bitcast<vec4<u32>>(color), bitcast<vec4<u32>>(surface));
}

// The sums of a pixel whose primary ray misses the box around the scene's primitives (outside the
// rectangle it projects to, src/gpu/trace/region.rs; the tracer never runs there): what sample_pixel
// gives such a ray, what it escapes to and one ray, without tracing it.
fn miss_pixel(pixel: vec2<u32>) -> PixelSums {
    // Added to zero, as trace_task adds it to the pixel's colour.
    var color = vec3<f32>(0.0) + globals.scene.background;
    if (HAS_ENVIRONMENT) {
        let primary = camera_ray(vec2<f32>(pixel) + sample_offset(pixel, globals.camera.sample));
        color = vec3<f32>(0.0) + escaped_radiance(primary.dir, pixel_spread());
    }
    return summed(pixel, vec4<f32>(color, 1.0), vec4<f32>(vec3<f32>(0.0), DEPTH_MISS));
}
