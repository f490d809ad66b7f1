// The path integrator, one path per sample: at each vertex the light of the punctual lights and
// one sample of the environment (next-event estimation, weighted against the BSDF's own sampling
// by the power heuristic), then one direction drawn from the BSDF, until the path escapes, is
// absorbed, reaches MAX_DEPTH bounces or loses Russian roulette. No ambient term: light comes
// from lights, emitters, the environment and the background only. Mirrored by src/cpu/path.rs.

// Bounces before Russian roulette may end a path.
const ROULETTE_START: u32 = 3u;

// The punctual lights' and one environment sample's light at a vertex, leaving towards the view.
// `weighed`: the path goes on from here, so the environment's light that its BSDF sample could
// find is shared with it by the power heuristic.
fn path_direct_light(surface: Surface, frame: ShadingFrame, material: Material, s: GltfSurface, lobes: Lobes,
                     u: vec4<f32>, weighed: bool) -> vec3<f32> {
    var color = vec3<f32>(0.0);
    let origin = offset_origin(surface, frame.normal);
    for (var i = 0u; i < globals.scene.light_count; i++) {
        let light = load_light(i);
        let arrival = light_arrival(light, surface.position);
        let l = arrival.dir;
        if (dot(frame.shading, l) <= 0.0 || !lit(light, arrival)) {
            continue;
        }
        ray_count += 1u;
        if (occluded(make_ray(origin, l), arrival.distance)) {
            continue;
        }
        color += shadowed(arrival.irradiance) * punctual_response(material, s, frame, l);
    }
    let share = path_globals.environment_share;
    if (!HAS_ENVIRONMENT || path_globals.table_width == 0u || !(u.x < share)) {
        return color;
    }
    let drawn = sample_environment(u.yz);
    let l = drawn.xyz;
    let pdf = drawn.w * share;
    let n_dot_l = dot(frame.shading, l);
    if (!(pdf > 0.0) || n_dot_l <= 0.0 || dot(frame.normal, l) <= 0.0) {
        return color;
    }
    let f = reflection_brdf(material, s, lobes, frame.shading, frame.view, l);
    if (max3(f) <= 0.0) {
        return color;
    }
    ray_count += 1u;
    if (occluded(make_ray(origin, l), T_FAR)) {
        return color;
    }
    var weight = 1.0;
    if (weighed) {
        weight = power_heuristic(pdf, reflection_pdf(material, s, lobes, frame.shading, frame.view, l));
    }
    return color + shadowed(escaped_radiance(l, 0.0)) * f * (n_dot_l * weight / pdf);
}

// The sample's state before its camera ray: its pixel's seed for the epoch, its index among the
// pixel's samples, no blended layers yet.
fn start_sample(pixel: vec2<u32>, sample: u32) {
    path_seed = hash_u32(pixel.x ^ hash_u32(pixel.y ^ hash_u32(path_globals.epoch)));
    path_sample = sample;
    blend_layers = 0u;
}

// Zero for a NaN or an infinite sum: the last guard against a sample that would poison the
// accumulation.
fn finite_or_zero(color: vec3<f32>) -> vec3<f32> {
    let finite = all(color == color) && max3(abs(color)) <= 3.0e38;
    return select(vec3<f32>(0.0), color, finite);
}

fn trace_pixel(primary: Ray) -> PixelTrace {
    var result = PixelTrace(vec3<f32>(0.0), vec3<f32>(0.0), DEPTH_MISS);
    var ray = primary;
    var culls = true;
    var throughput = vec3<f32>(1.0);
    var cone = vec2<f32>(0.0, pixel_spread());
    // The density the last bounce drew the ray's direction with, where a light sample could have
    // found it too; 0 for the camera ray, mirrors and transmission.
    var bsdf_pdf = 0.0;
    var bounce = 0u;
    loop {
        ray_count += 1u;
        let hit = closest_hit(ray, T_FAR, culls);
        if (bounce == 0u && result.depth == DEPTH_MISS) {
            primary_cost = box_tests;
        }
        if (hit.kind == HIT_NONE) {
            var weight = 1.0;
            if (HAS_ENVIRONMENT && bsdf_pdf > 0.0) {
                weight = power_heuristic(bsdf_pdf, path_globals.environment_share * environment_pdf(ray.dir));
            }
            result.color += throughput * escaped_radiance(ray.dir, cone.y) * weight;
            break;
        }
        var surface = surface_at(ray, hit);
        cone = vec2<f32>(cone.x + cone.y * hit.t, cone.y);
        surface.attributes.footprint = abs(cone.x) / max(abs(dot(surface.normal, ray.dir)), MIN_FOOTPRINT_COSINE);
        let material = surface_material(surface);
        surface.shading = normal_mapped(surface, material);
        if (bounce == 0u && result.depth == DEPTH_MISS) {
            result.normal = surface.shading;
            result.depth = hit.t;
        }
        let entering = dot(surface.normal, ray.dir) < 0.0;
        let normal = select(-surface.normal, surface.normal, entering);
        let shading = select(-surface.shading, surface.shading, entering);
        let curvature = select(-surface.curvature, surface.curvature, entering);
        let frame = ShadingFrame(normal, shading, -ray.dir);
        if (HAS_VOLUMES && material.model == MODEL_GLTF && material.volume != 0u && !entering) {
            throughput *= exp(-material.absorption * hit.t);
        }
        // A blended surface stops the path with the chance of its alpha; else the path goes on
        // behind it, at the same bounce.
        if (HAS_ALPHA_BLEND && surface.blend && blend_layers < MAX_BLEND_LAYERS) {
            blend_layers += 1u;
            if (path_random(2u * (MAX_DEPTH + 1u) + blend_layers).x >= material.alpha) {
                ray = make_ray(offset_origin(surface, -normal), ray.dir);
                continue;
            }
        }
        if (HAS_GLTF_MATERIALS && material.model == MODEL_UNLIT) {
            result.color += throughput * material.color;
            break;
        }
        result.color += throughput * material.emission;
        let s = gltf_surface(material);
        let lobes = path_lobes(material, s, max(dot(shading, frame.view), 0.0));
        let goes_on = bounce < MAX_DEPTH;
        result.color += throughput * path_direct_light(surface, frame, material, s, lobes, light_numbers(bounce), goes_on);
        if (!goes_on) {
            break;
        }
        let u = bsdf_numbers(bounce);
        let sample = sample_bsdf(material, s, lobes, frame, entering, u.xyz);
        if (!(max3(sample.weight) > 0.0) || max3(sample.weight) > 3.0e38) {
            break;
        }
        throughput *= sample.weight;
        bsdf_pdf = sample.pdf;
        if (bounce >= ROULETTE_START) {
            let survival = min(max3(throughput), 1.0);
            if (!(u.w < survival)) {
                break;
            }
            throughput /= survival;
        }
        let side = select(normal, -normal, sample.through);
        ray = make_ray(offset_origin(surface, side), sample.dir);
        // Back faces hide from rays outside: reflected from outside or refracted out of a volume;
        // a thin wall's transmitted ray sees them, as the Whitted integrator's does.
        if (HAS_VOLUMES && material.model == MODEL_GLTF && material.volume != 0u) {
            culls = entering != sample.through;
        } else {
            culls = !sample.through;
        }
        cone = cone_reflected(cone, curvature);
        bounce += 1u;
    }
    result.color = finite_or_zero(result.color);
    return result;
}
