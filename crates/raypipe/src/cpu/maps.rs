//! A triangle's attributes at a hit, and textures sampled through a material's maps: the twin of
//! `shaders/maps.wgsl`, read by shading and by the walks' alpha test (`admit`).

use super::intersect::{Ray, triangle_uvt, v3};
use crate::bvh::layout::NONE;
use crate::records::constants::{
    ATTRIBUTE_COLOR, ATTRIBUTE_TANGENT, ATTRIBUTE_UV0, ATTRIBUTE_UV1, FILTER_MAGNIFY_NEAREST, FILTER_MINIFY_NEAREST,
    FILTER_MIPMAP_LINEAR, FILTER_MIPMAP_NEAREST, MIP_LEVELS_MASK, WRAP_MIRROR, WRAP_REPEAT,
};
use crate::records::{AttributeTexel, GpuMaterial, GpuTextureMap, GpuTriangle, PackedScene};
use glam::{UVec2, Vec2, Vec3, Vec4};

/// A texture coordinate brought into the image's period by its wrap mode: [0, 1] for repeat and
/// clamp, [0, 2] for mirror (the second copy mirrored).
pub(crate) fn fold_coordinate(c: f32, wrap: u32) -> f32 {
    if wrap == WRAP_REPEAT {
        return c - c.floor();
    }
    if wrap == WRAP_MIRROR {
        return c - 2.0 * (c * 0.5).floor();
    }
    c.clamp(0.0, 1.0)
}

/// Column or row `i` of an axis of `size` texels, where `i` may lie one outside the folded period.
pub(crate) fn wrap_texel(i: i32, size: i32, wrap: u32) -> i32 {
    if wrap == WRAP_REPEAT {
        return (i + size) % size;
    }
    if wrap == WRAP_MIRROR {
        let period = 2 * size;
        let m = (i + period) % period;
        return if m >= size { period - 1 - m } else { m };
    }
    i.clamp(0, size - 1)
}

/// Where a mip level's texels start among all textures' texels, and its size.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MipLevel {
    pub offset: u32,
    pub size: UVec2,
}

/// Level `level` of the map's texture (`mip_level`): the levels follow the image one after another,
/// each side halved and rounded up (`scene::texture::mip_sizes`).
pub(crate) fn mip_level(map: &GpuTextureMap, level: u32) -> MipLevel {
    let mut offset = map.offset;
    let mut size = UVec2::new(map.width, map.height);
    for _ in 0..level {
        offset += size.x * size.y;
        size = (size + 1) / 2;
    }
    MipLevel { offset, size }
}

fn texture_texel(scene: &PackedScene, level: &MipLevel, x: i32, y: i32) -> Vec4 {
    let index = level.offset + y as u32 * level.size.x + x as u32;
    Vec4::from_array(scene.texture_pixels.0[index as usize].map(|b| half::f16::from_bits(b).to_f32()))
}

fn lerp4(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// Mip level `level` at `uv` (after the map's transform; `sample_level`): the texel nearest the
/// point, or the four around it (texel centres at +0.5) weighted by its distance to them. Nearest
/// reads the same four with all the weight on the first (the shader's one body for both).
fn sample_level(scene: &PackedScene, map: &GpuTextureMap, uv: Vec2, level: u32, nearest: bool) -> Vec4 {
    let level = mip_level(map, level);
    let (wrap_u, wrap_v) = (map.wrap & 0xff, map.wrap >> 8);
    let size = level.size.as_ivec2();
    let folded = Vec2::new(fold_coordinate(uv.x, wrap_u), fold_coordinate(uv.y, wrap_v)) * size.as_vec2();
    let p = if nearest { folded.floor() } else { folded - 0.5 };
    let corner = p.floor();
    let f = if nearest { Vec2::ZERO } else { p - corner };
    let i = corner.as_ivec2();
    let x0 = wrap_texel(i.x, size.x, wrap_u);
    let x1 = wrap_texel(i.x + 1, size.x, wrap_u);
    let y0 = wrap_texel(i.y, size.y, wrap_v);
    let y1 = wrap_texel(i.y + 1, size.y, wrap_v);
    let texel = |x, y| texture_texel(scene, &level, x, y);
    let near_row = lerp4(texel(x0, y0), texel(x1, y0), f.x);
    let far_row = lerp4(texel(x0, y1), texel(x1, y1), f.x);
    lerp4(near_row, far_row, f.y)
}

/// The map's texture at `surface_uv`, carried there by its transform, read at level of detail
/// `lod` (log2 of the texels a footprint spans; `sample_texture`). At or below 0 the image is
/// magnified and read at full size through the magnification filter; above, the minification
/// filter reads the level nearest `lod` or blends the two around it (trilinear), or reads the full
/// size where the sampler has no mipmaps.
pub(crate) fn sample_texture(scene: &PackedScene, map: &GpuTextureMap, surface_uv: Vec2, lod: f32) -> Vec4 {
    let point = surface_uv.extend(1.0);
    let uv = Vec2::new(v3(map.transform_u).dot(point), v3(map.transform_v).dot(point));
    let bits = map.sampling;
    let mut nearest = bits & FILTER_MAGNIFY_NEAREST != 0;
    let mut level = 0.0;
    if lod > 0.0 {
        nearest = bits & FILTER_MINIFY_NEAREST != 0;
        if bits & (FILTER_MIPMAP_NEAREST | FILTER_MIPMAP_LINEAR) != 0 {
            level = lod.min(((bits & MIP_LEVELS_MASK) - 1) as f32);
        }
        if bits & FILTER_MIPMAP_NEAREST != 0 {
            level = (level + 0.5).floor();
        }
    }
    let base = level.floor();
    let blend = level - base;
    // The shader's loop over the one or two levels read, weight by weight.
    let mut color = Vec4::ZERO;
    let mut weight = 1.0 - blend;
    for k in 0..if blend > 0.0 { 2 } else { 1 } {
        color += weight * sample_level(scene, map, uv, base as u32 + k, nearest);
        weight = blend;
    }
    color
}

/// The level of detail at which a map reads the hit (`texture_lod`): log2 of the texels the
/// footprint spans in the map's texture, through the triangle's texel scale for the map's
/// coordinate set and the map's transform (which scales areas by its determinant). -1 (full size)
/// where there is no footprint.
pub(crate) fn texture_lod(map: &GpuTextureMap, attributes: &Attributes) -> f32 {
    let scale = if map.tex_coord == 1 {
        attributes.texel_scale.y
    } else {
        attributes.texel_scale.x
    };
    let [a, b, _] = map.transform_u;
    let [c, d, _] = map.transform_v;
    let texel_area = (a * d - b * c).abs() * map.width as f32 * map.height as f32;
    lod_of(attributes.footprint * scale * texel_area.sqrt())
}

/// log2 of `texels`, -1 where it is not positive (`lod_of`).
pub(crate) fn lod_of(texels: f32) -> f32 {
    if texels > 0.0 { texels.min(1e30).log2() } else { -1.0 }
}

/// Whether the attributes hold the coordinate set the map reads (`has_coordinates`).
pub(crate) fn has_coordinates(map: &GpuTextureMap, attributes: &Attributes) -> bool {
    let set = if map.tex_coord == 1 {
        ATTRIBUTE_UV1
    } else {
        ATTRIBUTE_UV0
    };
    attributes.present & set != 0
}

/// The coordinates the map reads.
pub(crate) fn map_coordinates(map: &GpuTextureMap, attributes: &Attributes) -> Vec2 {
    if map.tex_coord == 1 {
        attributes.uv1
    } else {
        attributes.uv0
    }
}

/// Texture map `index` at the hit, through the coordinate set it reads; white where the triangle
/// lacks that set (`sample_map`), `None` where there is no map.
pub(crate) fn sample_map(scene: &PackedScene, index: u32, attributes: &Attributes) -> Option<Vec4> {
    if index == NONE {
        return None;
    }
    let map = &scene.texture_maps[index as usize];
    if !has_coordinates(map, attributes) {
        return Some(Vec4::ONE);
    }
    Some(sample_texture(
        scene,
        map,
        map_coordinates(map, attributes),
        texture_lod(map, attributes),
    ))
}

/// The alpha of a material's surface at the hit (`surface_alpha`): its own, times the vertex
/// colour's, times the base colour map's (`surface_material` multiplies them in this order).
pub(crate) fn surface_alpha(scene: &PackedScene, material: &GpuMaterial, attributes: &Attributes) -> f32 {
    let mut alpha = material.alpha;
    if attributes.present & ATTRIBUTE_COLOR != 0 {
        alpha *= attributes.color.w;
    }
    if attributes.present != 0
        && let Some(texel) = sample_map(scene, material.base_map, attributes)
    {
        alpha *= texel.w;
    }
    alpha
}

/// What a triangle carries at a hit besides its position and normals, from its attribute block:
/// `present` says which (`ATTRIBUTE_*` bits; 0 for none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attributes {
    /// The `ATTRIBUTE_*` bits of what the triangle has.
    pub present: u32,
    /// Texture coordinates of set 0.
    pub uv0: Vec2,
    /// Texture coordinates of set 1.
    pub uv1: Vec2,
    /// Linear RGBA; white without vertex colours.
    pub color: Vec4,
    /// Interpolated, not unit; w is the bitangent's sign.
    pub tangent: Vec4,
    /// The texture coordinates' units per unit of length on the triangle, for sets 0 and 1: the
    /// square root of their area over the triangle's.
    pub texel_scale: Vec2,
    /// The ray cone's width where it meets the surface, over the cosine between them: the length
    /// on the surface that the pixel sees (trace sets it; 0 reads textures at full size, as the
    /// walks' alpha test does).
    pub footprint: f32,
}

impl Attributes {
    /// No attributes: a triangle without texture coordinates, colours or tangents.
    pub const NONE: Attributes = Attributes {
        present: 0,
        uv0: Vec2::ZERO,
        uv1: Vec2::ZERO,
        color: Vec4::ONE,
        tangent: Vec4::ZERO,
        texel_scale: Vec2::ZERO,
        footprint: 0.0,
    };
}

/// A set of texture coordinates' units per unit of length on the triangle (`texel_scale`): the
/// square root of the ratio of the corners' area in texture space to the triangle's; 0 where
/// the triangle has no area.
fn texel_scale(triangle: &GpuTriangle, t0: [f32; 4], t1: [f32; 4]) -> f32 {
    let [v0, v1, v2] = triangle.corners();
    let (e1, e2) = (v1 - v0, v2 - v0);
    // Scaled by the longest edge's largest coordinate, so that no square overflows or underflows.
    let m = e1.abs().max_element().max(e2.abs().max_element());
    let world = (e1 / m).cross(e2 / m).length().sqrt() * m;
    let (a, b, c) = (
        Vec2::new(t0[0], t0[1]),
        Vec2::new(t0[2], t0[3]),
        Vec2::new(t1[0], t1[1]),
    );
    let texture = (b - a).perp_dot(c - a).abs().sqrt();
    if world > 0.0 { texture / world } else { 0.0 }
}

/// Three corners' coordinates (the first two in t0, the third in t1's x and y) blended by the
/// hit's barycentric weights (`blend_coordinates`).
fn blend_coordinates(uvt: Vec3, t0: [f32; 4], t1: [f32; 4]) -> Vec2 {
    (1.0 - uvt.x - uvt.y) * Vec2::new(t0[0], t0[1]) + uvt.x * Vec2::new(t0[2], t0[3]) + uvt.y * Vec2::new(t1[0], t1[1])
}

fn blend_corners(uvt: Vec3, corners: &[AttributeTexel]) -> Vec4 {
    let [a, b, c] = [0, 1, 2].map(|k| Vec4::from_array(corners[k].0));
    (1.0 - uvt.x - uvt.y) * a + uvt.x * b + uvt.y * c
}

/// The triangle's attributes where the ray meets it (`triangle_attributes`).
pub(crate) fn triangle_attributes(scene: &PackedScene, triangle: &GpuTriangle, ray: &Ray) -> Attributes {
    let mut a = Attributes::NONE;
    if triangle.attributes == NONE {
        return a;
    }
    let uvt = triangle_uvt(triangle, ray);
    let block = &scene.triangle_attributes[triangle.attributes as usize..];
    a.present = block[1].0[2] as u32;
    a.uv0 = blend_coordinates(uvt, block[0].0, block[1].0);
    a.texel_scale.x = texel_scale(triangle, block[0].0, block[1].0);
    let mut at = 2;
    if a.present & ATTRIBUTE_UV1 != 0 {
        a.uv1 = blend_coordinates(uvt, block[at].0, block[at + 1].0);
        a.texel_scale.y = texel_scale(triangle, block[at].0, block[at + 1].0);
        at += 2;
    }
    if a.present & ATTRIBUTE_COLOR != 0 {
        a.color = blend_corners(uvt, &block[at..]);
        at += 3;
    }
    if a.present & ATTRIBUTE_TANGENT != 0 {
        a.tangent = blend_corners(uvt, &block[at..]);
    }
    a
}
