//! Every host struct with a WGSL twin, as sizes and member offsets, for the test that holds them
//! to naga's layouts of the shaders' structs (the `internals` feature).

use super::{
    GpuBvhFrame, GpuCamera, GpuGlobals, GpuLight, GpuMaterial, GpuPlane, GpuSceneInfo, GpuSphere, GpuTextureMap,
    GpuTriangle, GpuTriangleNormals,
};
use crate::bvh::layout::GpuNode;
use crate::bvh::threaded::GpuThreadedNode;
use crate::bvh::wide::GpuWideTexel;

/// One host struct's layout, for the naga layout test.
pub struct StructLayout {
    /// The WGSL struct's name.
    pub wgsl_name: &'static str,
    /// Its size in bytes.
    pub size: usize,
    /// (member name, byte offset), padding excluded.
    pub members: &'static [(&'static str, usize)],
}

/// A [`StructLayout`] of `$ty` and its WGSL twin `$wgsl`, from the listed fields.
macro_rules! struct_layout {
    ($ty:ty, $wgsl:literal, [$($field:ident),* $(,)?]) => {
        $crate::records::layouts::StructLayout {
            wgsl_name: $wgsl,
            size: std::mem::size_of::<$ty>(),
            members: &[$((stringify!($field), std::mem::offset_of!($ty, $field))),*],
        }
    };
}
pub(crate) use struct_layout;

/// The fragment shader's records, with the WGSL name of each twin in `types.wgsl`. The compute
/// kernels' parameters have lists of their own beside their modules.
#[rustfmt::skip]
pub const LAYOUTS: &[StructLayout] = &[
    struct_layout!(GpuGlobals, "Globals", [camera, scene, bvh_frame]),
    struct_layout!(GpuCamera, "Camera", [eye, tan_half_fov, forward, aspect, right, width, up, height, sample]),
    struct_layout!(GpuSceneInfo, "SceneInfo", [
        background, ambient, sphere_count, plane_count, light_count, material_count, triangle_count,
        environment_map, irradiance_map, environment_intensity, environment_turn,
    ]),
    struct_layout!(GpuBvhFrame, "BvhFrame", [origin, quantum, inverse_quantum]),
    struct_layout!(GpuSphere, "Sphere", [center, radius, material]),
    struct_layout!(GpuTriangle, "Triangle", [v0, material, v1, normals, v2, attributes]),
    struct_layout!(GpuTriangleNormals, "TriangleNormals", [n0, n1, n2]),
    struct_layout!(GpuPlane, "Plane", [point, material, normal, checker_material, tangent, checker_size, bitangent]),
    struct_layout!(GpuLight, "Light", [position, kind, color, range, direction, spot_scale, spot_offset]),
    struct_layout!(GpuMaterial, "Material", [
        color, specular, shininess, reflect, transmit, ior, emission, model, specular_color, metallic, roughness,
        specular_factor, occlusion_strength, base_map, metallic_roughness_map, occlusion_map, emissive_map, alpha,
        alpha_cutoff, normal_map, normal_scale, absorption, volume, specular_map, specular_color_map,
    ]),
    struct_layout!(GpuTextureMap, "TextureMap", [offset, width, height, wrap, transform_u, tex_coord, transform_v, sampling]),
    struct_layout!(GpuNode, "BvhNode", [min, left, max, right, parent, escape]),
    struct_layout!(GpuThreadedNode, "ThreadedNode", [bounds, link]),
    struct_layout!(GpuWideTexel, "WideTexel", [words]),
];
