// The path integrator, one path per sample: at each vertex the light of the punctual lights and
// one sample of an area light, the environment or an emitting triangle (next-event estimation,
// weighted against the BSDF's own sampling by the power heuristic), then one direction drawn from
// the BSDF, until the path escapes, is absorbed, reaches MAX_DEPTH bounces or loses Russian
// roulette. No ambient term: light comes from lights, emitters, the environment and the
// background only. Mirrored by src/cpu/path.rs.

// Bounces before Russian roulette may end a path.
const ROULETTE_START: u32 = 3u;

// The punctual lights' and one area light sample's light at a vertex, leaving towards the view.
// `weighed`: the path goes on from here, so the area light that its BSDF sample could find is
// shared with it by the power heuristic.
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
    var drawn = LightSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0);
    if (HAS_ENVIRONMENT && u.x < share) {
        drawn = environment_sample(u.yz, share);
    } else if (HAS_TRIANGLES && path_globals.emitter_count > 0u) {
        drawn = emitter_light(origin, vec3<f32>((u.x - share) / (1.0 - share), u.y, u.z), 1.0 - share);
    }
    let l = drawn.dir;
    let n_dot_l = dot(frame.shading, l);
    if (!(drawn.pdf > 0.0) || n_dot_l <= 0.0 || dot(frame.normal, l) <= 0.0 || max3(drawn.radiance) <= 0.0) {
        return color;
    }
    let f = reflection_brdf(material, s, lobes, frame.shading, frame.view, l);
    if (max3(f) <= 0.0) {
        return color;
    }
    ray_count += 1u;
    if (occluded(make_ray(origin, l), drawn.distance)) {
        return color;
    }
    var weight = 1.0;
    if (weighed) {
        weight = power_heuristic(drawn.pdf, reflection_pdf(material, s, lobes, frame.shading, frame.view, l));
    }
    return color + shadowed(drawn.radiance) * f * (n_dot_l * weight / drawn.pdf);
}

// A direction to an area light, the radiance it brings, how far its shadow ray runs, and its
// density in solid angle (the light's chance among the lights included); pdf 0 for none.
struct LightSample {
    dir: vec3<f32>,
    radiance: vec3<f32>,
    distance: f32,
    pdf: f32,
}

// The environment's light along a direction drawn from its table with u, drawn with `chance`.
fn environment_sample(u: vec2<f32>, chance: f32) -> LightSample {
    let drawn = sample_environment(u);
    return LightSample(drawn.xyz, escaped_radiance(drawn.xyz, 0.0), T_FAR, drawn.w * chance);
}

// Shadow rays to an emitter stop this much short of it, so as not to hit it (relative to the
// distance).
const EMITTER_SHADOW_SHORTENING: f32 = 1e-4;

// The light of a point drawn on an emitter with u, seen from `origin` (offset from the surface, as
// the shadow ray and a BSDF sample's ray start), the emitters drawn with `chance`: its emission
// there (its emissive map read), none where it shows the point its back (single-sided) or a hole
// (alpha MASK).
fn emitter_light(origin: vec3<f32>, u: vec3<f32>, chance: f32) -> LightSample {
    var none = LightSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0);
    let drawn = sample_emitter(u);
    let to_light = drawn.point - origin;
    let distance = length(to_light);
    if (!(distance > 0.0)) {
        return none;
    }
    let l = to_light / distance;
    let towards = make_ray(origin, l);
    ray_culls_back_faces = true;
    ray_is_shadow = false;
    if (!triangle_stops_ray(drawn.index, towards)) {
        return none;
    }
    let emitter = surface_at(towards, Hit(distance, HIT_PRIMITIVE, globals.scene.sphere_count + drawn.index));
    let cos_light = abs(dot(emitter.normal, l));
    let pdf = chance * emitter_pdf(drawn.index, drawn.chance, distance, cos_light);
    let emission = surface_material(emitter).emission;
    return LightSample(l, emission, distance * (1.0 - EMITTER_SHADOW_SHORTENING), pdf);
}

// How much of an emitter's light that a BSDF sample of density `bsdf_pdf` found at `hit` counts,
// beside the emitter's own sampling: the power heuristic's weight, 1 where no light sample could
// have found it (a sphere's or a plane's emission, a mirror's or transmission's direction).
fn emission_weight(hit: Hit, surface: Surface, ray: Ray, bsdf_pdf: f32) -> f32 {
    if (!HAS_TRIANGLES || !(bsdf_pdf > 0.0) || path_globals.emitter_count == 0u || hit.kind != HIT_PRIMITIVE
        || is_sphere(hit.index)) {
        return 1.0;
    }
    let index = hit.index - globals.scene.sphere_count;
    let chance = emitter_chance(index);
    if (!(chance > 0.0)) {
        return 1.0;
    }
    let share = 1.0 - path_globals.environment_share;
    let light_pdf = share * emitter_pdf(index, chance, hit.t, abs(dot(surface.normal, ray.dir)));
    return power_heuristic(bsdf_pdf, light_pdf);
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
            if (HAS_ENVIRONMENT && bsdf_pdf > 0.0 && path_globals.table_width > 0u) {
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
        let volume = HAS_VOLUMES && material.model == MODEL_GLTF && material.volume != 0u;
        if (volume && !entering) {
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
        if (max3(material.emission) > 0.0) {
            result.color += throughput * material.emission * emission_weight(hit, surface, ray, bsdf_pdf);
        }
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
        if (volume) {
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
