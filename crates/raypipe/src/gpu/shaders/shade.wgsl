// Surfaces, their materials and maps, lights, and direct light with hard shadows: Whitted's
// (Lambert and Phong) and glTF's (brdf.wgsl). Mirrored by src/cpu/shade.rs.

// Secondary rays start RAY_BIAS (from the preamble) times the hit's reach off the surface, to escape
// it; the offset scales with the scene, so a scene renders alike at any size in the accepted range.

// The twin of `ShadingFrame` in cpu/shade.rs, which says what it holds.
struct ShadingFrame {
    normal: vec3<f32>,
    shading: vec3<f32>,
    view: vec3<f32>,
}

struct Surface {
    position: vec3<f32>,
    // Geometric, unit, pointing out of the primitive: it decides inside and outside, and which side
    // new rays start on.
    normal: vec3<f32>,
    // Unit, on the geometric normal's side: the interpolated vertex normal of a smooth triangle, the
    // geometric normal otherwise. Lighting, reflection and refraction use it.
    shading: vec3<f32>,
    material: u32,
    // The largest coordinate of the ray's origin and of the hit: the position's rounding error is a
    // few float steps of it.
    reach: f32,
    // Texture coordinates, vertex colour and tangent at the hit, where the triangle has them.
    attributes: Attributes,
    // A triangle with alpha BLEND: it covers its alpha of the ray.
    blend: bool,
    // How fast the shading normal turns per unit of length across the surface, positive where it
    // turns away from the geometric normal's side (a sphere's 1 / radius seen from outside): what
    // widens or narrows a ray cone that the surface reflects or refracts.
    curvature: f32,
}

fn max_abs(v: vec3<f32>) -> f32 {
    return max(abs(v.x), max(abs(v.y), abs(v.z)));
}

// normalize(v) for any nonzero v: the squares of a big or small v would overflow or underflow.
fn normalize_scaled(v: vec3<f32>) -> vec3<f32> {
    return normalize(v / max_abs(v));
}

// A smooth triangle's vertex normals interpolated at the hit, turned to the geometric normal's side
// (the geometric normal where they cancel out), in xyz, and the triangle's curvature in w. A flat
// triangle has neither.
fn triangle_shading(triangle: Triangle, ray: Ray, normal: vec3<f32>) -> vec4<f32> {
    if (triangle.normals == NONE) {
        return vec4<f32>(normal, 0.0);
    }
    let uvt = triangle_uvt(triangle, ray);
    let n = load_triangle_normals(triangle.normals);
    let curvature = triangle_curvature(triangle, n, normal);
    let blended = (1.0 - uvt.x - uvt.y) * n.n0 + uvt.x * n.n1 + uvt.y * n.n2;
    if (dot(blended, blended) == 0.0) {
        return vec4<f32>(normal, curvature);
    }
    let shading = normalize(blended);
    return vec4<f32>(select(shading, -shading, dot(shading, normal) < 0.0), curvature);
}

fn facing(n: vec3<f32>, normal: vec3<f32>) -> vec3<f32> {
    return select(n, -n, dot(n, normal) < 0.0);
}

// The change of normal from corner a to corner b along their edge, over its length squared.
fn edge_turn(a: vec3<f32>, b: vec3<f32>, na: vec3<f32>, nb: vec3<f32>) -> f32 {
    let edge = b - a;
    let length_squared = dot(edge, edge);
    return select(0.0, dot(nb - na, edge) / length_squared, length_squared > 0.0);
}

// How fast a smooth triangle's vertex normals turn along its edges, averaged over the three. Normals
// on a sphere of radius r, seen from the geometric normal's side, give 1 / r outside and -1 / r
// inside.
fn triangle_curvature(triangle: Triangle, n: TriangleNormals, normal: vec3<f32>) -> f32 {
    // The vertex normals facing the geometric normal's side, as the shading normal does.
    let n0 = facing(n.n0, normal);
    let n1 = facing(n.n1, normal);
    let n2 = facing(n.n2, normal);
    let sum = edge_turn(triangle.v0, triangle.v1, n0, n1) + edge_turn(triangle.v1, triangle.v2, n1, n2)
        + edge_turn(triangle.v2, triangle.v0, n2, n0);
    return sum / 3.0;
}

fn surface_at(ray: Ray, hit: Hit) -> Surface {
    let position = ray.origin + hit.t * ray.dir;
    let reach = max(max_abs(ray.origin), max_abs(position));
    if (!HAS_PLANES || hit.kind == HIT_PRIMITIVE) {
        if (is_sphere(hit.index)) {
            let sphere = load_sphere(hit.index);
            let normal = normalize(position - sphere.center);
            return Surface(position, normal, normal, sphere.material, reach, no_attributes(), false, 1.0 / sphere.radius);
        }
        let triangle = load_triangle(hit.index - globals.scene.sphere_count);
        let normal = normalize_scaled(cross(triangle.v1 - triangle.v0, triangle.v2 - triangle.v0));
        let shading = triangle_shading(triangle, ray, normal);
        let material = triangle.material & MATERIAL_INDEX_MASK;
        let blend = HAS_ALPHA_BLEND && (triangle.material & TRIANGLE_ALPHA_BLEND) != 0u;
        return Surface(position, normal, shading.xyz, material, reach, triangle_attributes(triangle, ray), blend,
            shading.w);
    }
    let plane = load_plane(hit.index);
    let local = position - plane.point;
    let cell = floor(dot(local, plane.tangent) / plane.checker_size)
        + floor(dot(local, plane.bitangent) / plane.checker_size);
    var material = plane.material;
    if (cell - 2.0 * floor(cell * 0.5) != 0.0) {
        material = plane.checker_material;
    }
    return Surface(position, plane.normal, plane.normal, material, reach, no_attributes(), false, 0.0);
}

// The surface's material, its vertex colour and maps applied at the hit: the base colour's (alpha
// too, as surface_alpha computes it), and a glTF material's metalness and roughness (blue and
// green), emission, and specular strength (alpha) and colour.
fn surface_material(surface: Surface) -> Material {
    var material = load_material(surface.material);
    let a = surface.attributes;
    if ((a.present & ATTRIBUTE_COLOR) != 0u) {
        material.color *= a.color.rgb;
        material.alpha *= a.color.a;
    }
    if (!HAS_TEXTURES || a.present == 0u) {
        return material;
    }
    if (material.base_map != NONE) {
        let texel = sample_map(material.base_map, a);
        material.color *= texel.rgb;
        material.alpha *= texel.a;
    }
    if (HAS_GLTF_MATERIALS && material.model == MODEL_GLTF) {
        if (material.metallic_roughness_map != NONE) {
            let texel = sample_map(material.metallic_roughness_map, a);
            material.roughness *= texel.y;
            material.metallic *= texel.z;
        }
        if (material.emissive_map != NONE) {
            material.emission *= sample_map(material.emissive_map, a).rgb;
        }
        if (material.specular_map != NONE) {
            material.specular_factor *= sample_map(material.specular_map, a).a;
        }
        if (material.specular_color_map != NONE) {
            material.specular_color *= sample_map(material.specular_color_map, a).rgb;
        }
    }
    return material;
}

// The share of ambient light that reaches a glTF surface: 1 blended toward its occlusion map's red
// by the map's strength.
fn ambient_share(surface: Surface, material: Material) -> f32 {
    if (!HAS_TEXTURES || surface.attributes.present == 0u || material.occlusion_map == NONE) {
        return 1.0;
    }
    return 1.0 + material.occlusion_strength * (sample_map(material.occlusion_map, surface.attributes).x - 1.0);
}

// The shading normal bent by the material's normal map, in the frame of the triangle's tangent
// (made perpendicular to the shading normal n), its bitangent w cross(n, tangent) and n; n itself
// where the triangle lacks the map's coordinates or tangents, or where the bent normal would turn
// away from the geometric one.
fn normal_mapped(surface: Surface, material: Material) -> vec3<f32> {
    let n = surface.shading;
    let a = surface.attributes;
    if (!HAS_NORMAL_MAPS || material.normal_map == NONE || (a.present & ATTRIBUTE_TANGENT) == 0u) {
        return n;
    }
    let map = load_texture_map(material.normal_map);
    let along = a.tangent.xyz - dot(a.tangent.xyz, n) * n;
    if (!has_coordinates(map, a) || dot(along, along) == 0.0) {
        return n;
    }
    let tangent = normalize(along);
    let bitangent = select(-1.0, 1.0, a.tangent.w >= 0.0) * cross(n, tangent);
    let texel = sample_texture(map, select(a.uv0, a.uv1, map.tex_coord == 1u), texture_lod(map, a));
    let local = vec3<f32>((2.0 * texel.xy - 1.0) * material.normal_scale, 2.0 * texel.z - 1.0);
    let bent = local.x * tangent + local.y * bitangent + local.z * n;
    if (dot(bent, surface.normal) <= 0.0) {
        return n;
    }
    return normalize(bent);
}

// `side` points to where the new ray goes: the facing normal for reflection and shadows, its
// opposite for refraction.
fn offset_origin(surface: Surface, side: vec3<f32>) -> vec3<f32> {
    return surface.position + side * (RAY_BIAS * surface.reach);
}

// The unit direction of a ray along i refracted into the medium across n (unit, on i's side) with
// eta the ratio of indices (from over to), w = 1; w = 0 past the critical angle.
fn refracted_direction(i: vec3<f32>, n: vec3<f32>, eta: f32) -> vec4<f32> {
    let cos_i = -dot(n, i);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if (k < 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(normalize(eta * i + (eta * cos_i - sqrt(k)) * n), 1.0);
}

// Schlick's approximation of the Fresnel reflectance; cos_theta is taken on the less dense side.
fn fresnel_schlick(cos_theta: f32, ior: f32) -> f32 {
    let r = (1.0 - ior) / (1.0 + ior);
    let r0 = r * r;
    let x = 1.0 - cos_theta;
    let x2 = x * x;
    return r0 + (1.0 - r0) * x2 * x2 * x;
}

// How a light reaches a point: the unit direction to it, how far a shadow ray runs, and E, the
// irradiance on a surface facing it.
struct LightArrival {
    dir: vec3<f32>,
    distance: f32,
    irradiance: vec3<f32>,
}

// KHR_lights_punctual's recommended falloff: inverse-square, windowed smoothly to zero at range
// (none where it is 0).
fn range_attenuation(range: f32, distance: f32) -> f32 {
    let inverse_square = 1.0 / (distance * distance);
    if (range <= 0.0) {
        return inverse_square;
    }
    let ratio = distance / range;
    let ratio2 = ratio * ratio;
    return clamp(1.0 - ratio2 * ratio2, 0.0, 1.0) * inverse_square;
}

// What a light gives the point `position`, by its kind.
fn light_arrival(light: Light, position: vec3<f32>) -> LightArrival {
    if (light.kind == LIGHT_DIRECTIONAL) {
        return LightArrival(-light.direction, T_FAR, light.color);
    }
    let to_light = light.position - position;
    let distance = length(to_light);
    let dir = to_light / distance;
    var irradiance = light.color;
    if (light.kind != LIGHT_CONSTANT) {
        irradiance *= range_attenuation(light.range, distance);
    }
    if (light.kind == LIGHT_SPOT) {
        let cone = clamp(dot(light.direction, -dir) * light.spot_scale + light.spot_offset, 0.0, 1.0);
        irradiance *= cone * cone;
    }
    return LightArrival(dir, distance, irradiance);
}

// A light's irradiance past the blended triangles its shadow ray went through (occluded leaves
// their share in shadow_light).
fn shadowed(irradiance: vec3<f32>) -> vec3<f32> {
    if (!HAS_ALPHA_BLEND) {
        return irradiance;
    }
    return irradiance * shadow_light;
}

// Whether a light's shadow ray is worth casting: the paper's lights always are (their ray counts
// stay), a glTF light where it gives anything.
fn lit(light: Light, arrival: LightArrival) -> bool {
    return light.kind == LIGHT_CONSTANT || max3(arrival.irradiance) > 0.0;
}

// The twin of `direct_light` in cpu/shade.rs, which says what it does.
fn direct_light(surface: Surface, frame: ShadingFrame, material: Material) -> vec3<f32> {
    let normal = frame.normal;
    let shading = frame.shading;
    let view = frame.view;
    var color = globals.scene.ambient * material.color;
    let origin = offset_origin(surface, normal);
    for (var i = 0u; i < globals.scene.light_count; i++) {
        let light = load_light(i);
        let arrival = light_arrival(light, surface.position);
        let l = arrival.dir;
        let n_dot_l = dot(shading, l);
        if (n_dot_l <= 0.0 || !lit(light, arrival)) {
            continue;
        }
        ray_count += 1u;
        if (occluded(make_ray(origin, l), arrival.distance)) {
            continue;
        }
        let irradiance = shadowed(arrival.irradiance);
        var highlight = 0.0;
        let r_dot_v = dot(reflect(-l, shading), view);
        if (r_dot_v > 0.0 && material.specular > 0.0) {
            highlight = material.specular * pow(r_dot_v, material.shininess);
        }
        color += irradiance * (material.color * n_dot_l + vec3<f32>(highlight));
    }
    return color;
}

fn gltf_surface(material: Material) -> GltfSurface {
    return GltfSurface(material.color, material.metallic, material.roughness, material.transmit, material.ior,
        material.specular_factor, material.specular_color);
}

// The twin of `gltf_direct_light` in cpu/shade.rs, which says what it does.
fn gltf_direct_light(surface: Surface, frame: ShadingFrame, material: Material, share: f32) -> vec3<f32> {
    let normal = frame.normal;
    let shading = frame.shading;
    let view = frame.view;
    let s = gltf_surface(material);
    let diffuse = s.base * ((1.0 - s.metallic) * (1.0 - s.transmission));
    var ambient = vec3<f32>(globals.scene.ambient);
    if (HAS_ENVIRONMENT) {
        ambient = environment_irradiance(shading);
    }
    var color = ambient * share * diffuse;
    let origin = offset_origin(surface, normal);
    for (var i = 0u; i < globals.scene.light_count; i++) {
        let light = load_light(i);
        let arrival = light_arrival(light, surface.position);
        let l = arrival.dir;
        let n_dot_l = dot(shading, l);
        if (n_dot_l <= 0.0 || !lit(light, arrival)) {
            continue;
        }
        ray_count += 1u;
        if (occluded(make_ray(origin, l), arrival.distance)) {
            continue;
        }
        color += shadowed(arrival.irradiance) * n_dot_l * gltf_brdf(s, shading, view, l);
    }
    return color;
}
