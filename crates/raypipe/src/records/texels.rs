//! The texture memory route: every record as rgba32float texels, decoded by `texels.wgsl`.

use super::{GpuLight, GpuMaterial, GpuPlane, GpuSphere, GpuTriangle, GpuTriangleNormals, GpuTriangleUvs};
use crate::bvh::layout::GpuNode;
use crate::bvh::threaded::GpuThreadedNode;
use bytemuck::Pod;

/// A record that can also travel as rgba32float texels (the texture memory route).
///
/// Integer fields travel as exact float values, not as reinterpreted bits: small integers would be
/// denormal floats, which some drivers flush. The WGSL decoders in `texels.wgsl` undo this.
pub trait GpuRecord: Pod {
    /// The WGSL struct name in `types.wgsl`.
    const WGSL_TYPE: &'static str;
    /// Texels per record: the record's size over 16 bytes.
    const TEXELS: usize = std::mem::size_of::<Self>() / 16;
    fn push_texels(&self, out: &mut Vec<[f32; 4]>);
}

/// Integers up to 2^24 are exact in f32; `PackedScene::new` keeps every index below this.
pub const MAX_TEXEL_INTEGER: u32 = 1 << 24;

impl GpuRecord for GpuSphere {
    const WGSL_TYPE: &'static str = "Sphere";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let [x, y, z] = self.center;
        out.push([x, y, z, self.radius]);
        out.push([self.material as f32, 0.0, 0.0, 0.0]);
    }
}

impl GpuRecord for GpuTriangle {
    const WGSL_TYPE: &'static str = "Triangle";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let [ax, ay, az] = self.v0;
        let [bx, by, bz] = self.v1;
        let [cx, cy, cz] = self.v2;
        out.push([ax, ay, az, self.material as f32]);
        out.push([bx, by, bz, link_texel(self.normals)]);
        out.push([cx, cy, cz, link_texel(self.uvs)]);
    }
}

impl GpuRecord for GpuTriangleUvs {
    const WGSL_TYPE: &'static str = "TriangleUvs";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let [u2, v2] = self.uv2;
        out.push(self.uv01);
        out.push([u2, v2, 0.0, 0.0]);
    }
}

/// Every texture's texels, one after another, as the GPU's rgba16float texture holds them (half
/// floats' bits): the pixels `GpuMaterial::texture_offset` points into.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TexturePixels(pub Vec<[u16; 4]>);

impl GpuRecord for GpuTriangleNormals {
    const WGSL_TYPE: &'static str = "TriangleNormals";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        for [x, y, z] in [self.n0, self.n1, self.n2] {
            out.push([x, y, z, 0.0]);
        }
    }
}

impl GpuRecord for GpuPlane {
    const WGSL_TYPE: &'static str = "Plane";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let [px, py, pz] = self.point;
        let [nx, ny, nz] = self.normal;
        let [tx, ty, tz] = self.tangent;
        let [bx, by, bz] = self.bitangent;
        out.push([px, py, pz, self.material as f32]);
        out.push([nx, ny, nz, self.checker_material as f32]);
        out.push([tx, ty, tz, self.checker_size]);
        out.push([bx, by, bz, 0.0]);
    }
}

impl GpuRecord for GpuLight {
    const WGSL_TYPE: &'static str = "Light";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let [px, py, pz] = self.position;
        let [r, g, b] = self.color;
        out.push([px, py, pz, 0.0]);
        out.push([r, g, b, 0.0]);
    }
}

impl GpuRecord for GpuMaterial {
    const WGSL_TYPE: &'static str = "Material";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let [r, g, b] = self.color;
        let [er, eg, eb] = self.emission;
        out.push([r, g, b, self.specular]);
        out.push([self.shininess, self.reflect, self.transmit, self.ior]);
        out.push([er, eg, eb, link_texel(self.texture_offset)]);
        // The offset stays below MAX_TEXEL_INTEGER (`scene::texture::MAX_TEXELS`), so it is exact.
        out.push([self.texture_width, self.texture_height, self.texture_wrap, 0].map(|n| n as f32));
    }
}

/// Links travel as exact floats, with `NONE` and `LEAF` (u32::MAX) as -1.
fn link_texel(link: u32) -> f32 {
    if link == u32::MAX { -1.0 } else { link as f32 }
}

impl GpuRecord for GpuThreadedNode {
    const WGSL_TYPE: &'static str = "ThreadedNode";
    // Quantized corners are exact floats, so the six take two texels.
    const TEXELS: usize = 2;
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let (lo, hi) = self.corners();
        // A leaf travels as -(primitive + 1).
        let link = if self.is_leaf() {
            -(self.primitive() as f32) - 1.0
        } else {
            self.link as f32
        };
        out.push([lo.x, lo.y, lo.z, link]);
        out.push([hi.x, hi.y, hi.z, 0.0]);
    }
}

impl GpuRecord for GpuNode {
    const WGSL_TYPE: &'static str = "BvhNode";
    fn push_texels(&self, out: &mut Vec<[f32; 4]>) {
        let [ax, ay, az] = self.min;
        let [bx, by, bz] = self.max;
        out.push([ax, ay, az, link_texel(self.left)]);
        out.push([bx, by, bz, link_texel(self.right)]);
        out.push([link_texel(self.parent), link_texel(self.escape), 0.0, 0.0]);
    }
}
