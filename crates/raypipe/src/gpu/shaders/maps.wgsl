// The materials' and texture maps' records, a triangle's attributes at a hit, and textures sampled
// through a map: what shading and the walks' alpha test (admit.wgsl) read. Mirrored by
// src/cpu/maps.rs.

// What a triangle carries at a hit besides its position and normals, from its attribute block
// (src/records/packed.rs): `present` says which (ATTRIBUTE_* bits; 0 for none).
struct Attributes {
    present: u32,
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    // Linear RGBA; white without vertex colours.
    color: vec4<f32>,
    // Interpolated, not unit; w is the bitangent's sign.
    tangent: vec4<f32>,
    // The texture coordinates' units per unit of length on the triangle, for sets 0 and 1: the
    // square root of their area over the triangle's.
    texel_scale: vec2<f32>,
    // The ray cone's width where it meets the surface, over the cosine between them: the length on
    // the surface that the pixel sees (trace_task sets it; 0 reads textures at full size, as the
    // walks' alpha test does).
    footprint: f32,
}

fn no_attributes() -> Attributes {
    return Attributes(0u, vec2<f32>(0.0), vec2<f32>(0.0), vec4<f32>(1.0), vec4<f32>(0.0), vec2<f32>(0.0), 0.0);
}

// A set of texture coordinates' units per unit of length on the triangle: the square root of the
// ratio of the corners' area in texture space (the first two in t0, the third in t1.xy) to the
// triangle's; 0 where the triangle has no area.
fn texel_scale(triangle: Triangle, t0: vec4<f32>, t1: vec4<f32>) -> f32 {
    let e1 = triangle.v1 - triangle.v0;
    let e2 = triangle.v2 - triangle.v0;
    // Scaled by the longest edge's largest coordinate, so that no square overflows or underflows.
    let m = max(max(max(abs(e1.x), abs(e1.y)), abs(e1.z)), max(max(abs(e2.x), abs(e2.y)), abs(e2.z)));
    let world = sqrt(length(cross(e1 / m, e2 / m))) * m;
    let b = t0.zw - t0.xy;
    let c = t1.xy - t0.xy;
    let texture = sqrt(abs(b.x * c.y - b.y * c.x));
    return select(0.0, texture / world, world > 0.0);
}

// Three corners' coordinates (the first two in t0, the third in t1.xy) blended by the hit's
// barycentric weights.
fn blend_coordinates(uvt: vec3<f32>, t0: vec4<f32>, t1: vec4<f32>) -> vec2<f32> {
    return (1.0 - uvt.x - uvt.y) * t0.xy + uvt.x * t0.zw + uvt.y * t1.xy;
}

fn blend_corners(uvt: vec3<f32>, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> vec4<f32> {
    return (1.0 - uvt.x - uvt.y) * a + uvt.x * b + uvt.y * c;
}

// The triangle's attributes where the ray meets it.
fn triangle_attributes(triangle: Triangle, ray: Ray) -> Attributes {
    var a = no_attributes();
    if (!HAS_ATTRIBUTES || triangle.attributes == NONE) {
        return a;
    }
    let uvt = triangle_uvt(triangle, ray);
    var at = triangle.attributes;
    let set0_last = load_triangle_attributes(at + 1u);
    a.present = u32(set0_last.z);
    let set0_first = load_triangle_attributes(at);
    a.uv0 = blend_coordinates(uvt, set0_first, set0_last);
    a.texel_scale.x = texel_scale(triangle, set0_first, set0_last);
    at += 2u;
    if ((a.present & ATTRIBUTE_UV1) != 0u) {
        let set1_first = load_triangle_attributes(at);
        let set1_last = load_triangle_attributes(at + 1u);
        a.uv1 = blend_coordinates(uvt, set1_first, set1_last);
        a.texel_scale.y = texel_scale(triangle, set1_first, set1_last);
        at += 2u;
    }
    if ((a.present & ATTRIBUTE_COLOR) != 0u) {
        a.color = blend_corners(uvt, load_triangle_attributes(at), load_triangle_attributes(at + 1u),
            load_triangle_attributes(at + 2u));
        at += 3u;
    }
    if ((a.present & ATTRIBUTE_TANGENT) != 0u) {
        a.tangent = blend_corners(uvt, load_triangle_attributes(at), load_triangle_attributes(at + 1u),
            load_triangle_attributes(at + 2u));
    }
    return a;
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
const MATERIAL_TEXELS: u32 = 9u;
const TEXTURE_MAP_TEXELS: u32 = 3u;

fn load_material(i: u32) -> Material {
    let b = i * MATERIAL_TEXELS;
    return material_from_texels(load_shading(b), load_shading(b + 1u), load_shading(b + 2u), load_shading(b + 3u),
        load_shading(b + 4u), load_shading(b + 5u), load_shading(b + 6u), load_shading(b + 7u), load_shading(b + 8u));
}

fn load_texture_map(i: u32) -> TextureMap {
    let b = globals.scene.material_count * MATERIAL_TEXELS + i * TEXTURE_MAP_TEXELS;
    return texture_map_from_texels(load_shading(b), load_shading(b + 1u), load_shading(b + 2u));
}

// Where a mip level's texels start among all textures' texels, and its size.
struct MipLevel {
    offset: u32,
    size: vec2<u32>,
}

// Level `level` of the map's texture: the levels follow the image one after another, each side
// halved and rounded up (scene::texture::mip_sizes).
fn mip_level(map: TextureMap, level: u32) -> MipLevel {
    var offset = map.offset;
    var size = vec2<u32>(map.width, map.height);
    for (var i = 0u; i < level; i += 1u) {
        offset += size.x * size.y;
        size = (size + 1u) / 2u;
    }
    return MipLevel(offset, size);
}

fn texture_texel(level: MipLevel, x: i32, y: i32) -> vec4<f32> {
    let index = level.offset + u32(y) * level.size.x + u32(x);
    return textureLoad(texture_pixels, texel_coord(index), 0);
}

fn lerp4(a: vec4<f32>, b: vec4<f32>, t: f32) -> vec4<f32> {
    return a * (1.0 - t) + b * t;
}

// Mip level `level_index` at uv (after the map's transform): the texel nearest the point, or the
// four around it (texel centres at +0.5) weighted by its distance to them. Nearest reads the same
// four with all the weight on the first: one body for both keeps the shader small, as every
// texture read inlines it.
fn sample_level(map: TextureMap, uv: vec2<f32>, level_index: u32, nearest: bool) -> vec4<f32> {
    let level = mip_level(map, level_index);
    let wrap_u = map.wrap & 0xffu;
    let wrap_v = map.wrap >> 8u;
    let size = vec2<i32>(level.size);
    let folded = vec2<f32>(fold_coordinate(uv.x, wrap_u), fold_coordinate(uv.y, wrap_v)) * vec2<f32>(size);
    let p = select(folded - 0.5, floor(folded), nearest);
    let corner = floor(p);
    let f = select(p - corner, vec2<f32>(0.0), nearest);
    let i = vec2<i32>(corner);
    let x0 = wrap_texel(i.x, size.x, wrap_u);
    let x1 = wrap_texel(i.x + 1, size.x, wrap_u);
    let y0 = wrap_texel(i.y, size.y, wrap_v);
    let y1 = wrap_texel(i.y + 1, size.y, wrap_v);
    let near_row = lerp4(texture_texel(level, x0, y0), texture_texel(level, x1, y0), f.x);
    let far_row = lerp4(texture_texel(level, x0, y1), texture_texel(level, x1, y1), f.x);
    return lerp4(near_row, far_row, f.y);
}

// The map's texture at uv, carried there by its transform, read at level of detail `lod` (log2 of
// the texels a footprint spans). At or below 0 the image is magnified and read at full size through
// the magnification filter; above, the minification filter reads the level nearest `lod` or blends
// the two around it (trilinear), or reads the full size where the sampler has no mipmaps. The two
// levels are read in a loop, so that the shader holds one read.
fn sample_texture(map: TextureMap, surface_uv: vec2<f32>, lod: f32) -> vec4<f32> {
    let point = vec3<f32>(surface_uv, 1.0);
    let uv = vec2<f32>(dot(map.transform_u, point), dot(map.transform_v, point));
    let bits = map.sampling;
    var nearest = (bits & FILTER_MAGNIFY_NEAREST) != 0u;
    var level = 0.0;
    if (lod > 0.0) {
        nearest = (bits & FILTER_MINIFY_NEAREST) != 0u;
        if ((bits & (FILTER_MIPMAP_NEAREST | FILTER_MIPMAP_LINEAR)) != 0u) {
            level = min(lod, f32((bits & MIP_LEVELS_MASK) - 1u));
        }
        if ((bits & FILTER_MIPMAP_NEAREST) != 0u) {
            level = floor(level + 0.5);
        }
    }
    let base = floor(level);
    let blend = level - base;
    var color = vec4<f32>(0.0);
    var weight = 1.0 - blend;
    for (var k = 0u; k < select(1u, 2u, blend > 0.0); k += 1u) {
        color += weight * sample_level(map, uv, u32(base) + k, nearest);
        weight = blend;
    }
    return color;
}

// The level of detail at which a map reads the hit: log2 of the texels the footprint spans in the
// map's texture, through the triangle's texel scale for the map's coordinate set and the map's
// transform (which scales areas by its determinant). -1 (full size) where there is no footprint.
fn texture_lod(map: TextureMap, attributes: Attributes) -> f32 {
    let scale = select(attributes.texel_scale.x, attributes.texel_scale.y, map.tex_coord == 1u);
    let texel_area = abs(map.transform_u.x * map.transform_v.y - map.transform_u.y * map.transform_v.x)
        * f32(map.width) * f32(map.height);
    return lod_of(attributes.footprint * scale * sqrt(texel_area));
}

// log2 of `texels`, -1 where it is not positive.
fn lod_of(texels: f32) -> f32 {
    if (texels > 0.0) {
        return log2(min(texels, 1e30));
    }
    return -1.0;
}

// Whether the attributes hold the coordinate set the map reads.
fn has_coordinates(map: TextureMap, attributes: Attributes) -> bool {
    return (attributes.present & select(ATTRIBUTE_UV0, ATTRIBUTE_UV1, map.tex_coord == 1u)) != 0u;
}

// The map's texture at the hit, through the coordinate set it reads; white where the triangle
// lacks that set.
fn sample_map(index: u32, attributes: Attributes) -> vec4<f32> {
    let map = load_texture_map(index);
    if (!has_coordinates(map, attributes)) {
        return vec4<f32>(1.0);
    }
    return sample_texture(map, select(attributes.uv0, attributes.uv1, map.tex_coord == 1u), texture_lod(map, attributes));
}

// The alpha of a material's surface at the hit: its own, times the vertex colour's, times the base
// colour map's (surface_material multiplies them in this order).
fn surface_alpha(material: Material, attributes: Attributes) -> f32 {
    var alpha = material.alpha;
    if ((attributes.present & ATTRIBUTE_COLOR) != 0u) {
        alpha *= attributes.color.a;
    }
    if (HAS_TEXTURES && attributes.present != 0u && material.base_map != NONE) {
        alpha *= sample_map(material.base_map, attributes).a;
    }
    return alpha;
}
