// The Whitted integrator: shaders cannot recurse, so the tree of rays is walked depth-first by
// hand: a reflected branch is traced next, and its refracted sibling waits on an explicit stack of
// RAY_STACK_SIZE entries (MAX_DEPTH + 1: at most one waits per level; more where rays go on behind
// blended surfaces). Mirrored by src/cpu/trace.rs.

// MIN_WEIGHT, from the preamble, is the weight below which a branch cannot change an 8-bit pixel.

// The sample's random sequence (sampled glossy reflections): its seed and the draws so far.
var<private> sample_seed_value: u32;
var<private> random_draws: u32;

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

// The sample's state before its camera ray: its random sequence, no blended layers yet.
fn start_sample(pixel: vec2<u32>, sample: u32) {
    sample_seed_value = sample_seed(pixel, sample);
    random_draws = 0u;
    blend_layers = 0u;
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
