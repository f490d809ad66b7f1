//! Textures sampled through a material's maps: the twin of `shaders/maps.wgsl`, read by shading
//! and by the walks' alpha test (`admit`).

use super::intersect::v3;
use crate::bvh::layout::NONE;
use crate::records::{GpuTextureMap, PackedScene};
use crate::scene::Wrap;
use glam::{IVec2, Vec2, Vec4};

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

/// Texture map `index` at `uv`, or `None` where there is no map.
pub fn sample_map(scene: &PackedScene, index: u32, uv: Vec2) -> Option<Vec4> {
    (index != NONE).then(|| sample_texture(scene, &scene.texture_maps[index as usize], uv))
}
