//! The texture memory route: every record as rgba32float or rgba32uint texels, decoded by
//! `texels.wgsl`.

use super::{
    AttributeTexel, GpuLight, GpuMaterial, GpuPlane, GpuSphere, GpuTextureMap, GpuTriangle, GpuTriangleNormals,
};
use crate::bvh::layout::GpuNode;
use crate::bvh::threaded::GpuThreadedNode;
use crate::bvh::wide::GpuWideTexel;
use bytemuck::Pod;

/// What a record's texels hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelFormat {
    /// rgba32float. Integer fields travel as exact float values, not as reinterpreted bits: small
    /// integers would be denormal floats, which some drivers flush.
    Float,
    /// rgba32uint: the record's own bytes, 16 to a texel, as in a buffer. For records of integers
    /// only, which then take no more texels than bytes.
    Bits,
}

/// A record that can also travel as texels (the texture memory route). The WGSL decoders in
/// `texels.wgsl` read them back.
pub trait GpuRecord: Pod {
    /// The WGSL struct name in `types.wgsl`.
    const WGSL_TYPE: &'static str;
    /// How the record's texels are stored: floats, unless it packs integers.
    const TEXEL_FORMAT: TexelFormat = TexelFormat::Float;
    /// Texels per record: the record's size over 16 bytes.
    const TEXELS: usize = std::mem::size_of::<Self>() / 16;
    /// Appends the record's texels, as the bits of `TEXEL_FORMAT`'s values.
    fn push_texels(&self, out: &mut Vec<[u32; 4]>);
}

/// An rgba32float texel's bits.
fn floats(texel: [f32; 4]) -> [u32; 4] {
    texel.map(f32::to_bits)
}

/// Integers up to 2^24 are exact in f32; `PackedScene::new` keeps every index below this.
pub const MAX_TEXEL_INTEGER: u32 = 1 << 24;

impl GpuRecord for GpuSphere {
    const WGSL_TYPE: &'static str = "Sphere";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [x, y, z] = self.center;
        out.push(floats([x, y, z, self.radius]));
        out.push(floats([self.material as f32, 0.0, 0.0, 0.0]));
    }
}

impl GpuRecord for GpuTriangle {
    const WGSL_TYPE: &'static str = "Triangle";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [ax, ay, az] = self.v0;
        let [bx, by, bz] = self.v1;
        let [cx, cy, cz] = self.v2;
        out.push(floats([ax, ay, az, self.material as f32]));
        out.push(floats([bx, by, bz, link_texel(self.normals)]));
        out.push(floats([cx, cy, cz, link_texel(self.attributes)]));
    }
}

impl GpuRecord for AttributeTexel {
    const WGSL_TYPE: &'static str = "vec4<f32>";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        out.push(floats(self.0));
    }
}

/// One texel of the materials-and-texture-maps array (`PackedScene::shading`): rgba32float bits,
/// as `GpuRecord::push_texels` writes them, in every memory mode.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadingTexel(pub [u32; 4]);

impl GpuRecord for ShadingTexel {
    const WGSL_TYPE: &'static str = "vec4<f32>";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        out.push(self.0);
    }
}

/// Every texture's mip chain, one after another, as the GPU's rgba16float texture holds them (half
/// floats' bits): the pixels `GpuTextureMap::offset` points into.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TexturePixels(pub Vec<[u16; 4]>);

impl GpuRecord for GpuTriangleNormals {
    const WGSL_TYPE: &'static str = "TriangleNormals";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        for [x, y, z] in [self.n0, self.n1, self.n2] {
            out.push(floats([x, y, z, 0.0]));
        }
    }
}

impl GpuRecord for GpuPlane {
    const WGSL_TYPE: &'static str = "Plane";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [px, py, pz] = self.point;
        let [nx, ny, nz] = self.normal;
        let [tx, ty, tz] = self.tangent;
        let [bx, by, bz] = self.bitangent;
        out.push(floats([px, py, pz, self.material as f32]));
        out.push(floats([nx, ny, nz, self.checker_material as f32]));
        out.push(floats([tx, ty, tz, self.checker_size]));
        out.push(floats([bx, by, bz, 0.0]));
    }
}

impl GpuRecord for GpuLight {
    const WGSL_TYPE: &'static str = "Light";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [px, py, pz] = self.position;
        let [r, g, b] = self.color;
        let [dx, dy, dz] = self.direction;
        out.push(floats([px, py, pz, self.kind as f32]));
        out.push(floats([r, g, b, self.range]));
        out.push(floats([dx, dy, dz, self.spot_scale]));
        out.push(floats([self.spot_offset, 0.0, 0.0, 0.0]));
    }
}

impl GpuRecord for GpuMaterial {
    const WGSL_TYPE: &'static str = "Material";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [r, g, b] = self.color;
        let [er, eg, eb] = self.emission;
        let [sr, sg, sb] = self.specular_color;
        out.push(floats([r, g, b, self.specular]));
        out.push(floats([self.shininess, self.reflect, self.transmit, self.ior]));
        out.push(floats([er, eg, eb, self.model as f32]));
        out.push(floats([sr, sg, sb, self.metallic]));
        out.push(floats([
            self.roughness,
            self.specular_factor,
            self.occlusion_strength,
            link_texel(self.base_map),
        ]));
        out.push(floats([
            link_texel(self.metallic_roughness_map),
            link_texel(self.occlusion_map),
            link_texel(self.emissive_map),
            self.alpha,
        ]));
        out.push(floats([
            self.alpha_cutoff,
            link_texel(self.normal_map),
            self.normal_scale,
            0.0,
        ]));
        let [ar, ag, ab] = self.absorption;
        out.push(floats([ar, ag, ab, self.volume as f32]));
        out.push(floats([
            link_texel(self.specular_map),
            link_texel(self.specular_color_map),
            0.0,
            0.0,
        ]));
    }
}

impl GpuRecord for GpuTextureMap {
    const WGSL_TYPE: &'static str = "TextureMap";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [ua, ub, uc] = self.transform_u;
        let [va, vb, vc] = self.transform_v;
        // The offset stays below MAX_TEXEL_INTEGER (`scene::texture::MAX_TEXELS`), so it is exact.
        out.push(floats(
            [self.offset, self.width, self.height, self.wrap].map(|n| n as f32),
        ));
        out.push(floats([ua, ub, uc, self.tex_coord as f32]));
        out.push(floats([va, vb, vc, self.sampling as f32]));
    }
}

/// Links travel as exact floats, with `NONE` and `LEAF` (u32::MAX) as -1.
fn link_texel(link: u32) -> f32 {
    if link == u32::MAX { -1.0 } else { link as f32 }
}

impl GpuRecord for GpuThreadedNode {
    const WGSL_TYPE: &'static str = "ThreadedNode";
    // Its corners are 16-bit integers: the walk's node costs one texel fetch, not two.
    const TEXEL_FORMAT: TexelFormat = TexelFormat::Bits;
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [x, y, z] = self.bounds;
        out.push([x, y, z, self.link]);
    }
}

impl GpuRecord for GpuWideTexel {
    const WGSL_TYPE: &'static str = "WideTexel";
    // Texels of words already: the wide walk loads five for a node, one for four leaves.
    const TEXEL_FORMAT: TexelFormat = TexelFormat::Bits;
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        out.push(self.words);
    }
}

impl GpuRecord for GpuNode {
    const WGSL_TYPE: &'static str = "BvhNode";
    fn push_texels(&self, out: &mut Vec<[u32; 4]>) {
        let [ax, ay, az] = self.min;
        let [bx, by, bz] = self.max;
        out.push(floats([ax, ay, az, link_texel(self.left)]));
        out.push(floats([bx, by, bz, link_texel(self.right)]));
        out.push(floats([link_texel(self.parent), link_texel(self.escape), 0.0, 0.0]));
    }
}
