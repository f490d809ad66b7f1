//! The numbers the shader and the CPU reference must agree on, defined once here and emitted into
//! every shader's preamble ([`wgsl`]), so that neither side can drift from the other.

use crate::bvh::layout::{LEAF, NONE};
use crate::bvh::threaded::{LEAF_BIT, MAX_QUANTUM, TINY_EXTENT};
use crate::bvh::wide::{NODE_TEXELS, SPAN};
use std::fmt::Write;

/// Where a ray that hits nothing ends.
pub const T_FAR: f32 = 1e30;
/// A branch whose weight falls below this in every channel cannot change an 8-bit pixel; drop it.
pub const MIN_WEIGHT: f32 = 1e-3;
/// The depth channel's value where the primary ray hits nothing (the shader cannot write +inf).
pub const DEPTH_MISS: f32 = -1.0;
/// How far secondary rays start off the surface, along its normal.
pub const RAY_BIAS: f32 = 1e-4;
/// A ray closer to parallel with a plane than this misses it.
pub const PARALLEL_EPSILON: f32 = 1e-8;
/// Direction components smaller than this are replaced by it before inversion, so that the slab
/// test never computes 0 * inf.
pub const TINY_DIRECTION: f32 = 1e-20;
/// What an intersection returns for no hit.
pub const NO_HIT: f32 = -1.0;
/// The R2 sequence's steps per sample (Roberts 2018: 1/g and 1/g², g the plastic number) in 0.32
/// fixed point, so that sample positions are integer arithmetic: the same bits on every device.
pub const R2_STEP: [u32; 2] = [3_242_174_889, 2_447_445_414];

/// `GpuMaterial::model`: the paper's Whitted material.
pub const MODEL_WHITTED: u32 = 0;
/// `GpuMaterial::model`: glTF's metallic-roughness material.
pub const MODEL_GLTF: u32 = 1;
/// `GpuMaterial::model`: a glTF material with KHR_materials_unlit, its base colour its radiance.
pub const MODEL_UNLIT: u32 = 2;

/// `GpuTriangle::material`: the material's index is its low bits, at most this many; the flags
/// above them say what the walks' hit test must know of the material without loading it. All
/// stay below 2^24, exact in texture memory's float texels.
pub const MATERIAL_INDEX_MASK: u32 = (1 << 21) - 1;
/// The triangle's back (seen against its geometric normal) is invisible to camera and reflected
/// rays.
pub const TRIANGLE_SINGLE_SIDED: u32 = 1 << 21;
/// Alpha MASK: the triangle is cut away where its alpha is below the material's cutoff.
pub const TRIANGLE_ALPHA_MASK: u32 = 1 << 22;
/// Alpha BLEND: the triangle covers its alpha of a ray; shadow rays pass the rest.
pub const TRIANGLE_ALPHA_BLEND: u32 = 1 << 23;
/// The most surfaces a ray passes through for blended triangles before the rest of its weight is
/// dropped: what keeps a pixel's work bounded whatever the scene.
pub const MAX_BLEND_LAYERS: u32 = 32;
/// Room on the ray stack for branches that wait while a ray goes on through blended surfaces,
/// beyond the one per level of depth.
pub const BLEND_STACK_ROOM: u32 = 8;

/// The tracer's ray stack (`RAY_STACK_SIZE`): depth-first with two branches keeps at most one
/// waiting sibling per level, plus the pair just pushed; where a ray goes on behind blended
/// surfaces, their branches wait too, in BLEND_STACK_ROOM more (a branch that finds the stack full
/// is dropped, alike on both tracers).
pub fn ray_stack_size(max_depth: u32, blend: bool) -> u32 {
    max_depth + 1 + if blend { BLEND_STACK_ROOM } else { 0 }
}

/// The layout bits of a triangle's attribute block (`PackedScene::triangle_attributes`): which
/// attributes follow its first two texels.
pub const ATTRIBUTE_UV0: u32 = 1;
pub const ATTRIBUTE_UV1: u32 = 2;
pub const ATTRIBUTE_COLOR: u32 = 4;
pub const ATTRIBUTE_TANGENT: u32 = 8;

/// `GpuLight::kind` (`scene::LightKind::code`): the paper's light, E its colour everywhere.
pub const LIGHT_CONSTANT: u32 = 0;
/// A KHR_lights_punctual point light: candela, inverse-square.
pub const LIGHT_POINT: u32 = 1;
/// A point light in a cone.
pub const LIGHT_SPOT: u32 = 2;
/// Parallel light in lux.
pub const LIGHT_DIRECTIONAL: u32 = 3;

/// `GpuTextureMap::sampling`: its low byte counts the texture's mip levels; these bits above it
/// are the sampler's filter (`scene::Filter::code`). Magnified and minified reads are linear unless
/// a NEAREST bit says otherwise; without a MIPMAP bit only the full-size image is read.
pub const MIP_LEVELS_MASK: u32 = 0xff;
pub const FILTER_MAGNIFY_NEAREST: u32 = 1 << 8;
pub const FILTER_MINIFY_NEAREST: u32 = 1 << 9;
pub const FILTER_MIPMAP_NEAREST: u32 = 1 << 10;
pub const FILTER_MIPMAP_LINEAR: u32 = 1 << 11;
/// A footprint is its cone's width over the cosine between the ray and the surface, at least this:
/// at grazing angles the footprint is long, and reads the coarsest level.
pub const MIN_FOOTPRINT_COSINE: f32 = 1e-4;

/// The constants above as WGSL declarations. Floats print in Rust's shortest round-trip form, so
/// the shader's literal is the same f32.
pub fn wgsl() -> String {
    let mut out = String::from("// Generated: the constants shared with the CPU reference (records/constants.rs).\n");
    for (name, value) in [
        ("T_FAR", T_FAR),
        ("MIN_WEIGHT", MIN_WEIGHT),
        ("DEPTH_MISS", DEPTH_MISS),
        ("RAY_BIAS", RAY_BIAS),
        ("PARALLEL_EPSILON", PARALLEL_EPSILON),
        ("TINY_DIRECTION", TINY_DIRECTION),
        ("NO_HIT", NO_HIT),
        ("MAX_QUANTUM", MAX_QUANTUM as f32),
        ("TINY_EXTENT", TINY_EXTENT),
        ("WIDE_SPAN", SPAN),
        ("MIN_FOOTPRINT_COSINE", MIN_FOOTPRINT_COSINE),
    ] {
        writeln!(out, "const {name}: f32 = {};", float_literal(value)).unwrap();
    }
    for (name, value) in [
        ("LEAF", LEAF),
        ("NONE", NONE),
        ("LEAF_BIT", LEAF_BIT),
        ("WIDE_NODE_TEXELS", NODE_TEXELS),
        ("R2_STEP_X", R2_STEP[0]),
        ("R2_STEP_Y", R2_STEP[1]),
        ("MODEL_WHITTED", MODEL_WHITTED),
        ("MODEL_GLTF", MODEL_GLTF),
        ("MODEL_UNLIT", MODEL_UNLIT),
        ("LIGHT_CONSTANT", LIGHT_CONSTANT),
        ("LIGHT_POINT", LIGHT_POINT),
        ("LIGHT_SPOT", LIGHT_SPOT),
        ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
        ("MATERIAL_INDEX_MASK", MATERIAL_INDEX_MASK),
        ("ATTRIBUTE_UV0", ATTRIBUTE_UV0),
        ("ATTRIBUTE_UV1", ATTRIBUTE_UV1),
        ("ATTRIBUTE_COLOR", ATTRIBUTE_COLOR),
        ("ATTRIBUTE_TANGENT", ATTRIBUTE_TANGENT),
        ("TRIANGLE_SINGLE_SIDED", TRIANGLE_SINGLE_SIDED),
        ("TRIANGLE_ALPHA_MASK", TRIANGLE_ALPHA_MASK),
        ("TRIANGLE_ALPHA_BLEND", TRIANGLE_ALPHA_BLEND),
        ("MAX_BLEND_LAYERS", MAX_BLEND_LAYERS),
        ("BLEND_STACK_ROOM", BLEND_STACK_ROOM),
        ("MIP_LEVELS_MASK", MIP_LEVELS_MASK),
        ("FILTER_MAGNIFY_NEAREST", FILTER_MAGNIFY_NEAREST),
        ("FILTER_MINIFY_NEAREST", FILTER_MINIFY_NEAREST),
        ("FILTER_MIPMAP_NEAREST", FILTER_MIPMAP_NEAREST),
        ("FILTER_MIPMAP_LINEAR", FILTER_MIPMAP_LINEAR),
    ] {
        writeln!(out, "const {name}: u32 = {value:#x}u;").unwrap();
    }
    for wrap in crate::scene::Wrap::ALL {
        writeln!(out, "const {}: u32 = {}u;", wrap.wgsl_name(), wrap.code()).unwrap();
    }
    out
}

/// A WGSL float literal that reads back as exactly `value`.
pub fn float_literal(value: f32) -> String {
    let text = format!("{value:?}");
    if text.contains(['.', 'e']) {
        text
    } else {
        format!("{text}.0")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_read_back_exactly() {
        for value in [
            T_FAR,
            MIN_WEIGHT,
            DEPTH_MISS,
            RAY_BIAS,
            PARALLEL_EPSILON,
            TINY_DIRECTION,
            3.0,
            0.1,
        ] {
            assert_eq!(float_literal(value).parse::<f32>().unwrap(), value);
        }
    }
}
