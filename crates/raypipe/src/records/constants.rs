//! How the records encode a scene for the GPU (material models, triangle flags, attribute layouts,
//! light kinds, texture wrap and filter codes), and every constant the shaders share with the CPU
//! reference, emitted into each shader's preamble ([`wgsl`]) so that neither side can drift.

use crate::bvh::layout::{LEAF, NONE};
use crate::bvh::threaded::{LEAF_BIT, MAX_QUANTUM, TINY_EXTENT};
use crate::bvh::wide::{NODE_TEXELS, SPAN};
use crate::constants::{
    BLEND_STACK_ROOM, DEPTH_MISS, MAX_BLEND_LAYERS, MIN_FOOTPRINT_COSINE, MIN_WEIGHT, NO_HIT, PARALLEL_EPSILON,
    R2_STEP, RAY_BIAS, T_FAR, TINY_DIRECTION,
};
use crate::scene::{Filter, TexelFilter, Wrap};
use std::fmt::Write;

/// `GpuMaterial::model`: the paper's Whitted material.
pub(crate) const MODEL_WHITTED: u32 = 0;
/// `GpuMaterial::model`: glTF's metallic-roughness material.
pub(crate) const MODEL_GLTF: u32 = 1;
/// `GpuMaterial::model`: a glTF material with KHR_materials_unlit, its base colour its radiance.
pub(crate) const MODEL_UNLIT: u32 = 2;

/// `GpuTriangle::material`: the material's index is its low bits, at most this many; the flags
/// above them say what the walks' hit test must know of the material without loading it. All
/// stay below 2^24, exact in texture memory's float texels.
pub(crate) const MATERIAL_INDEX_MASK: u32 = (1 << 21) - 1;
/// The triangle's back (seen against its geometric normal) is invisible to camera and reflected
/// rays.
pub(crate) const TRIANGLE_SINGLE_SIDED: u32 = 1 << 21;
/// Alpha MASK: the triangle is cut away where its alpha is below the material's cutoff.
pub(crate) const TRIANGLE_ALPHA_MASK: u32 = 1 << 22;
/// Alpha BLEND: the triangle covers its alpha of a ray; shadow rays pass the rest.
pub(crate) const TRIANGLE_ALPHA_BLEND: u32 = 1 << 23;
/// The layout bits of a triangle's attribute block (`PackedScene::triangle_attributes`): which
/// attributes follow its first two texels.
pub(crate) const ATTRIBUTE_UV0: u32 = 1;
pub(crate) const ATTRIBUTE_UV1: u32 = 2;
pub(crate) const ATTRIBUTE_COLOR: u32 = 4;
pub(crate) const ATTRIBUTE_TANGENT: u32 = 8;

/// `GpuLight::kind` (by `scene::LightKind`, in `records/packed.rs`): the paper's light, E its colour
/// everywhere.
pub(crate) const LIGHT_CONSTANT: u32 = 0;
/// A KHR_lights_punctual point light: candela, inverse-square.
pub(crate) const LIGHT_POINT: u32 = 1;
/// A point light in a cone.
pub(crate) const LIGHT_SPOT: u32 = 2;
/// Parallel light in lux.
pub(crate) const LIGHT_DIRECTIONAL: u32 = 3;

/// `GpuTextureMap::wrap`: an axis's wrap mode (`wrap_code`), the u axis in the low byte and v
/// in the next.
pub const WRAP_REPEAT: u32 = 0;
/// Texture coordinates clamped to the edge.
pub const WRAP_CLAMP: u32 = 1;
/// Texture coordinates mirrored at every repeat.
pub const WRAP_MIRROR: u32 = 2;

/// `GpuTextureMap::sampling`: its low byte counts the texture's mip levels; these bits above it
/// are the sampler's filter ([`filter_code`]). Magnified and minified reads are linear unless
/// a NEAREST bit says otherwise; without a MIPMAP bit only the full-size image is read.
pub(crate) const MIP_LEVELS_MASK: u32 = 0xff;
pub(crate) const FILTER_MAGNIFY_NEAREST: u32 = 1 << 8;
pub(crate) const FILTER_MINIFY_NEAREST: u32 = 1 << 9;
pub(crate) const FILTER_MIPMAP_NEAREST: u32 = 1 << 10;
pub(crate) const FILTER_MIPMAP_LINEAR: u32 = 1 << 11;
/// The number the records carry for `wrap`.
pub(crate) fn wrap_code(wrap: Wrap) -> u32 {
    match wrap {
        Wrap::Repeat => WRAP_REPEAT,
        Wrap::Clamp => WRAP_CLAMP,
        Wrap::Mirror => WRAP_MIRROR,
    }
}

/// The `FILTER_*` bits the records carry for `filter`.
pub(crate) fn filter_code(filter: Filter) -> u32 {
    let nearest = |f: TexelFilter, bit: u32| if f == TexelFilter::Nearest { bit } else { 0 };
    nearest(filter.magnify, FILTER_MAGNIFY_NEAREST)
        | nearest(filter.minify, FILTER_MINIFY_NEAREST)
        | match filter.mipmaps {
            None => 0,
            Some(TexelFilter::Nearest) => FILTER_MIPMAP_NEAREST,
            Some(TexelFilter::Linear) => FILTER_MIPMAP_LINEAR,
        }
}

/// The constants above and the tracers' shared numbers ([`crate::constants`]) as WGSL
/// declarations. Floats print in Rust's shortest round-trip form, so the shader's literal is the
/// same f32.
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
        ("WRAP_REPEAT", WRAP_REPEAT),
        ("WRAP_CLAMP", WRAP_CLAMP),
        ("WRAP_MIRROR", WRAP_MIRROR),
    ] {
        writeln!(out, "const {name}: u32 = {value:#x}u;").unwrap();
    }
    out
}

/// A WGSL float literal that reads back as exactly `value`.
pub(crate) fn float_literal(value: f32) -> String {
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
    use crate::constants::{DEPTH_MISS, MIN_WEIGHT, PARALLEL_EPSILON, RAY_BIAS, T_FAR, TINY_DIRECTION};

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
