// Surfaces, their materials and maps, lights, and direct light with hard shadows: Whitted's
// (Lambert and Phong) and glTF's (brdf.wgsl). Mirrored by src/cpu/shade.rs.

// Secondary rays start RAY_BIAS (from the preamble) times the hit's reach off the surface, to escape
// it; the offset scales with the scene, so a scene renders alike at any size in the accepted range.

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
    // Texture coordinates at the hit, where the primitive has them (has_uv).
    uv: vec2<f32>,
    has_uv: bool,
}

fn max_abs(v: vec3<f32>) -> f32 {
    return max(abs(v.x), max(abs(v.y), abs(v.z)));
}

// normalize(v) for any nonzero v: the squares of a big or small v would overflow or underflow.
fn normalize_scaled(v: vec3<f32>) -> vec3<f32> {
    return normalize(v / max_abs(v));
}

// A smooth triangle's vertex normals interpolated at the hit, turned to the geometric normal's side;
// the geometric normal where they cancel out.
fn triangle_shading(triangle: Triangle, ray: Ray, normal: vec3<f32>) -> vec3<f32> {
    if (triangle.normals == NONE) {
        return normal;
    }
    let uvt = triangle_uvt(triangle, ray);
    let n = load_triangle_normals(triangle.normals);
    let blended = (1.0 - uvt.x - uvt.y) * n.n0 + uvt.x * n.n1 + uvt.y * n.n2;
    if (dot(blended, blended) == 0.0) {
        return normal;
    }
    let shading = normalize(blended);
    return select(shading, -shading, dot(shading, normal) < 0.0);
}

// A textured triangle's corner texture coordinates interpolated at the hit.
fn triangle_uv(triangle: Triangle, ray: Ray) -> vec2<f32> {
    let uvt = triangle_uvt(triangle, ray);
    let uvs = load_triangle_uvs(triangle.uvs);
    return (1.0 - uvt.x - uvt.y) * uvs.uv01.xy + uvt.x * uvs.uv01.zw + uvt.y * uvs.uv2;
}

fn surface_at(ray: Ray, hit: Hit) -> Surface {
    let position = ray.origin + hit.t * ray.dir;
    let reach = max(max_abs(ray.origin), max_abs(position));
    if (!HAS_PLANES || hit.kind == HIT_PRIMITIVE) {
        if (is_sphere(hit.index)) {
            let sphere = load_sphere(hit.index);
            let normal = normalize(position - sphere.center);
            return Surface(position, normal, normal, sphere.material, reach, vec2<f32>(0.0), false);
        }
        let triangle = load_triangle(hit.index - globals.scene.sphere_count);
        let normal = normalize_scaled(cross(triangle.v1 - triangle.v0, triangle.v2 - triangle.v0));
        let shading = triangle_shading(triangle, ray, normal);
        if (!HAS_TEXTURES || triangle.uvs == NONE) {
            return Surface(position, normal, shading, triangle.material, reach, vec2<f32>(0.0), false);
        }
        return Surface(position, normal, shading, triangle.material, reach, triangle_uv(triangle, ray), true);
    }
    let plane = load_plane(hit.index);
    let local = position - plane.point;
    let cell = floor(dot(local, plane.tangent) / plane.checker_size)
        + floor(dot(local, plane.bitangent) / plane.checker_size);
    var material = plane.material;
    if (cell - 2.0 * floor(cell * 0.5) != 0.0) {
        material = plane.checker_material;
    }
    return Surface(position, plane.normal, plane.normal, material, reach, vec2<f32>(0.0), false);
}

// A texture coordinate brought into the image's period by its wrap mode: [0, 1] for repeat and
// clamp, [0, 2] for mirror (the second copy mirrored). Done in floats, so that no coordinate is
// too big for an integer.
fn fold_coordinate(c: f32, wrap: u32) -> f32 {
    if (wrap == WRAP_REPEAT) {
        return c - floor(c);
    }
    if (wrap == WRAP_MIRROR) {
        return c - 2.0 * floor(c * 0.5);
    }
    return clamp(c, 0.0, 1.0);
}

// Column or row i of an axis of `size` texels, where i may lie one outside the folded period.
fn wrap_texel(i: i32, size: i32, wrap: u32) -> i32 {
    if (wrap == WRAP_REPEAT) {
        return (i + size) % size;
    }
    if (wrap == WRAP_MIRROR) {
        let period = 2 * size;
        let m = (i + period) % period;
        return select(m, period - 1 - m, m >= size);
    }
    return clamp(i, 0, size - 1);
}

// The materials' records and then the texture maps', texel by texel in one array (its binding is
// `shading`): MATERIAL_TEXELS and TEXTURE_MAP_TEXELS texels each.
const MATERIAL_TEXELS: u32 = 6u;
const TEXTURE_MAP_TEXELS: u32 = 3u;

fn load_material(i: u32) -> Material {
    let b = i * MATERIAL_TEXELS;
    return material_from_texels(load_shading(b), load_shading(b + 1u), load_shading(b + 2u), load_shading(b + 3u),
        load_shading(b + 4u), load_shading(b + 5u));
}

fn load_texture_map(i: u32) -> TextureMap {
    let b = globals.scene.material_count * MATERIAL_TEXELS + i * TEXTURE_MAP_TEXELS;
    return texture_map_from_texels(load_shading(b), load_shading(b + 1u), load_shading(b + 2u));
}

fn texture_texel(map: TextureMap, x: i32, y: i32) -> vec4<f32> {
    let index = map.offset + u32(y) * map.width + u32(x);
    return textureLoad(texture_pixels, texel_coord(index), 0);
}

fn lerp4(a: vec4<f32>, b: vec4<f32>, t: f32) -> vec4<f32> {
    return a * (1.0 - t) + b * t;
}

// The map's texture at uv, carried there by its transform. Bilinear filtering without mipmaps:
// the four texels around the point (texel centres at +0.5), weighted by its distance to them.
fn sample_texture(map: TextureMap, surface_uv: vec2<f32>) -> vec4<f32> {
    let point = vec3<f32>(surface_uv, 1.0);
    let uv = vec2<f32>(dot(map.transform_u, point), dot(map.transform_v, point));
    let wrap_u = map.wrap & 0xffu;
    let wrap_v = map.wrap >> 8u;
    let size = vec2<i32>(i32(map.width), i32(map.height));
    let p = vec2<f32>(fold_coordinate(uv.x, wrap_u), fold_coordinate(uv.y, wrap_v)) * vec2<f32>(size) - 0.5;
    let corner = floor(p);
    let f = p - corner;
    let i = vec2<i32>(corner);
    let x0 = wrap_texel(i.x, size.x, wrap_u);
    let x1 = wrap_texel(i.x + 1, size.x, wrap_u);
    let y0 = wrap_texel(i.y, size.y, wrap_v);
    let y1 = wrap_texel(i.y + 1, size.y, wrap_v);
    let near_row = lerp4(texture_texel(map, x0, y0), texture_texel(map, x1, y0), f.x);
    let far_row = lerp4(texture_texel(map, x0, y1), texture_texel(map, x1, y1), f.x);
    return lerp4(near_row, far_row, f.y);
}

fn sample_map(index: u32, uv: vec2<f32>) -> vec4<f32> {
    return sample_texture(load_texture_map(index), uv);
}

// The surface's material, its maps applied at the hit (where the primitive has texture
// coordinates): the base colour's, and a glTF material's metalness and roughness (blue and green)
// and emission.
fn surface_material(surface: Surface) -> Material {
    var material = load_material(surface.material);
    if (!HAS_TEXTURES || !surface.has_uv) {
        return material;
    }
    if (material.base_map != NONE) {
        material.color *= sample_map(material.base_map, surface.uv).rgb;
    }
    if (HAS_GLTF_MATERIALS && material.model == MODEL_GLTF) {
        if (material.metallic_roughness_map != NONE) {
            let texel = sample_map(material.metallic_roughness_map, surface.uv);
            material.roughness *= texel.y;
            material.metallic *= texel.z;
        }
        if (material.emissive_map != NONE) {
            material.emission *= sample_map(material.emissive_map, surface.uv).rgb;
        }
    }
    return material;
}

// The share of ambient light that reaches a glTF surface: 1 blended toward its occlusion map's red
// by the map's strength.
fn ambient_share(surface: Surface, material: Material) -> f32 {
    if (!HAS_TEXTURES || !surface.has_uv || material.occlusion_map == NONE) {
        return 1.0;
    }
    return 1.0 + material.occlusion_strength * (sample_map(material.occlusion_map, surface.uv).x - 1.0);
}

// `side` points to where the new ray goes: the facing normal for reflection and shadows, its
// opposite for refraction.
fn offset_origin(surface: Surface, side: vec3<f32>) -> vec3<f32> {
    return surface.position + side * (RAY_BIAS * surface.reach);
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

// Whether a light's shadow ray is worth casting: the paper's lights always are (their ray counts
// stay), a glTF light where it gives anything.
fn lit(light: Light, arrival: LightArrival) -> bool {
    return light.kind == LIGHT_CONSTANT || max3(arrival.irradiance) > 0.0;
}

// Ambient plus, for every light that the surface faces and that nothing blocks, Lambert and Phong
// times the light's E. `normal` (geometric) and `shading` face the viewer; `view` points from the
// surface to the viewer.
fn direct_light(surface: Surface, normal: vec3<f32>, shading: vec3<f32>, view: vec3<f32>, material: Material) -> vec3<f32> {
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
        var highlight = 0.0;
        let r_dot_v = dot(reflect(-l, shading), view);
        if (r_dot_v > 0.0 && material.specular > 0.0) {
            highlight = material.specular * pow(r_dot_v, material.shininess);
        }
        color += arrival.irradiance * (material.color * n_dot_l + vec3<f32>(highlight));
    }
    return color;
}

fn gltf_surface(material: Material) -> GltfSurface {
    return GltfSurface(material.color, material.metallic, material.roughness, material.transmit, material.ior,
        material.specular_factor, material.specular_color);
}

// A glTF surface's direct light: the ambient light on its diffuse share (times ambient_share),
// plus, for every light that it faces and that nothing blocks, E times the BRDF times the cosine.
fn gltf_direct_light(surface: Surface, normal: vec3<f32>, shading: vec3<f32>, view: vec3<f32>, material: Material, share: f32) -> vec3<f32> {
    let s = gltf_surface(material);
    let diffuse = s.base * ((1.0 - s.metallic) * (1.0 - s.transmission));
    var color = globals.scene.ambient * share * diffuse;
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
        color += arrival.irradiance * n_dot_l * gltf_brdf(s, shading, view, l);
    }
    return color;
}
