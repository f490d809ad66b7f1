//! A triangle's attributes at a hit, and textures sampled through a material's maps: the twin of
//! `shaders/maps.wgsl`, read by shading and by the walks' alpha test (`admit`).

use super::intersect::{Ray, triangle_uvt, v3};
use crate::bvh::layout::NONE;
use crate::records::constants::{ATTRIBUTE_COLOR, ATTRIBUTE_TANGENT, ATTRIBUTE_UV0, ATTRIBUTE_UV1};
use crate::records::{AttributeTexel, GpuMaterial, GpuTextureMap, GpuTriangle, PackedScene};
use crate::scene::Wrap;
use glam::{IVec2, Vec2, Vec3, Vec4};

/// A texture coordinate brought into the image's period by its wrap mode: [0, 1] for repeat and
/// clamp, [0, 2] for mirror (the second copy mirrored).
pub fn fold_coordinate(c: f32, wrap: u32) -> f32 {
    if wrap == Wrap::Repeat.code() {
        return c - c.floor();
    }
    if wrap == Wrap::Mirror.code() {
        return c - 2.0 * (c * 0.5).floor();
    }
    c.clamp(0.0, 1.0)
}

/// Column or row `i` of an axis of `size` texels, where `i` may lie one outside the folded period.
pub fn wrap_texel(i: i32, size: i32, wrap: u32) -> i32 {
    if wrap == Wrap::Repeat.code() {
        return (i + size) % size;
    }
    if wrap == Wrap::Mirror.code() {
        let period = 2 * size;
        let m = (i + period) % period;
        return if m >= size { period - 1 - m } else { m };
    }
    i.clamp(0, size - 1)
}

fn texture_texel(scene: &PackedScene, map: &GpuTextureMap, x: i32, y: i32) -> Vec4 {
    let index = map.offset + y as u32 * map.width + x as u32;
    Vec4::from_array(scene.texture_pixels.0[index as usize].map(|b| half::f16::from_bits(b).to_f32()))
}

fn lerp4(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// The map's texture at `uv`, carried there by its transform. Bilinear filtering without
/// mipmaps: the four texels around the point (texel centres at +0.5), weighted by its distance to
/// them.
pub fn sample_texture(scene: &PackedScene, map: &GpuTextureMap, uv: Vec2) -> Vec4 {
    let point = uv.extend(1.0);
    let uv = Vec2::new(v3(map.transform_u).dot(point), v3(map.transform_v).dot(point));
    let (wrap_u, wrap_v) = (map.wrap & 0xff, map.wrap >> 8);
    let size = IVec2::new(map.width as i32, map.height as i32);
    let p = Vec2::new(fold_coordinate(uv.x, wrap_u), fold_coordinate(uv.y, wrap_v)) * size.as_vec2() - 0.5;
    let corner = p.floor();
    let f = p - corner;
    let i = corner.as_ivec2();
    let x0 = wrap_texel(i.x, size.x, wrap_u);
    let x1 = wrap_texel(i.x + 1, size.x, wrap_u);
    let y0 = wrap_texel(i.y, size.y, wrap_v);
    let y1 = wrap_texel(i.y + 1, size.y, wrap_v);
    let texel = |x, y| texture_texel(scene, map, x, y);
    let near_row = lerp4(texel(x0, y0), texel(x1, y0), f.x);
    let far_row = lerp4(texel(x0, y1), texel(x1, y1), f.x);
    lerp4(near_row, far_row, f.y)
}

/// Whether the attributes hold the coordinate set the map reads (`has_coordinates`).
pub fn has_coordinates(map: &GpuTextureMap, attributes: &Attributes) -> bool {
    let set = if map.tex_coord == 1 {
        ATTRIBUTE_UV1
    } else {
        ATTRIBUTE_UV0
    };
    attributes.present & set != 0
}

/// The coordinates the map reads.
pub fn map_coordinates(map: &GpuTextureMap, attributes: &Attributes) -> Vec2 {
    if map.tex_coord == 1 {
        attributes.uv1
    } else {
        attributes.uv0
    }
}

/// Texture map `index` at the hit, through the coordinate set it reads; white where the triangle
/// lacks that set (`sample_map`), `None` where there is no map.
pub fn sample_map(scene: &PackedScene, index: u32, attributes: &Attributes) -> Option<Vec4> {
    if index == NONE {
        return None;
    }
    let map = &scene.texture_maps[index as usize];
    if !has_coordinates(map, attributes) {
        return Some(Vec4::ONE);
    }
    Some(sample_texture(scene, map, map_coordinates(map, attributes)))
}

/// The alpha of a material's surface at the hit (`surface_alpha`): its own, times the vertex
/// colour's, times the base colour map's (`surface_material` multiplies them in this order).
pub fn surface_alpha(scene: &PackedScene, material: &GpuMaterial, attributes: &Attributes) -> f32 {
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
    pub present: u32,
    pub uv0: Vec2,
    pub uv1: Vec2,
    /// Linear RGBA; white without vertex colours.
    pub color: Vec4,
    /// Interpolated, not unit; w is the bitangent's sign.
    pub tangent: Vec4,
}

impl Attributes {
    pub const NONE: Attributes = Attributes {
        present: 0,
        uv0: Vec2::ZERO,
        uv1: Vec2::ZERO,
        color: Vec4::ONE,
        tangent: Vec4::ZERO,
    };
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
pub fn triangle_attributes(scene: &PackedScene, triangle: &GpuTriangle, ray: &Ray) -> Attributes {
    let mut a = Attributes::NONE;
    if triangle.attributes == NONE {
        return a;
    }
    let uvt = triangle_uvt(triangle, ray);
    let block = &scene.triangle_attributes[triangle.attributes as usize..];
    a.present = block[1].0[2] as u32;
    a.uv0 = blend_coordinates(uvt, block[0].0, block[1].0);
    let mut at = 2;
    if a.present & ATTRIBUTE_UV1 != 0 {
        a.uv1 = blend_coordinates(uvt, block[at].0, block[at + 1].0);
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
