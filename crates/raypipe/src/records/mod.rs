//! What crosses to the GPU: the scene as flat records that the fragment shader reads, and that the
//! CPU reference reads too, so both tracers see the same f32 numbers.
//!
//! Every record is `repr(C)` + `Pod`, a multiple of 16 bytes, with its WGSL twin in
//! `src/gpu/shaders/types.wgsl`; the layout test checks sizes and member offsets against naga's for
//! every struct in `layouts::LAYOUTS`, the build kernels' parameters among them. Fields named `_pad*` are
//! padding the WGSL struct gets implicitly.

#[cfg(feature = "internals")]
pub mod constants;
#[cfg(not(feature = "internals"))]
pub(crate) mod constants;
#[cfg(feature = "internals")]
pub mod layouts;
pub mod packed;
pub mod path;
pub mod posed;
pub mod texels;

pub use packed::{PackedBvh, PackedScene};
pub use path::{GpuPathGlobals, PathTables};
pub use posed::{PoseOn, PoseStep, PosedScene, Poses};
pub use texels::{GpuRecord, MAX_TEXEL_INTEGER, ShadingTexel, TexelFormat, TexturePixels};

use crate::bvh::aabb::Aabb;
use crate::bvh::threaded::QuantizationFrame;
use crate::scene::Camera;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// The pinhole camera as `camera_ray` reads it: its basis and the image size in pixels. Moving the
/// camera or resizing the image rewrites this record alone.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    /// The eye's position.
    pub eye: [f32; 3],
    /// tan(fov / 2), fov vertical.
    pub tan_half_fov: f32,
    /// normalize(target - eye).
    pub forward: [f32; 3],
    /// width / height.
    pub aspect: f32,
    /// normalize(cross(forward, up)).
    pub right: [f32; 3],
    /// The image width, in pixels.
    pub width: f32,
    /// cross(right, forward): the true up.
    pub up: [f32; 3],
    /// The image height, in pixels.
    pub height: f32,
    /// Which of each pixel's samples this draw traces: 0 is the pixel centre, later ones are
    /// jittered (`sample_offset`). The renderer writes it before every draw.
    pub sample: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 3],
}

impl GpuCamera {
    /// `camera` looking at a `width` x `height` image.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let forward = (camera.target - camera.eye).normalize();
        // Up only gives a direction: scaled to at most 1 first, so that no length of it overflows.
        let up_hint = camera.up / camera.up.abs().max_element();
        let right = forward.cross(up_hint).normalize();
        let up = right.cross(forward);
        Self {
            eye: camera.eye.to_array(),
            tan_half_fov: (camera.fov_degrees.to_radians() * 0.5).tan(),
            forward: forward.to_array(),
            aspect: width as f32 / height as f32,
            right: right.to_array(),
            width: width as f32,
            up: up.to_array(),
            height: height as f32,
            sample: 0,
            _pad: [0; 3],
        }
    }

    /// The image width, in pixels.
    pub fn width(&self) -> u32 {
        self.width as u32
    }

    /// The image height, in pixels.
    pub fn height(&self) -> u32 {
        self.height as u32
    }
}

/// What stays fixed while the camera moves: the background or environment, the ambient term and
/// the record counts.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSceneInfo {
    /// What escaping rays return where there is no environment.
    pub background: [f32; 3],
    /// The Whitted model's ambient term, added times a surface's colour.
    pub ambient: f32,
    /// The sphere records.
    pub sphere_count: u32,
    /// The plane records.
    pub plane_count: u32,
    /// The light records.
    pub light_count: u32,
    /// The material records.
    pub material_count: u32,
    /// The triangle records.
    pub triangle_count: u32,
    /// The texture map of the environment's radiance, or NONE: escaping rays return the
    /// background.
    pub environment_map: u32,
    /// The texture map of its irradiance over π (valid with `environment_map`).
    pub irradiance_map: u32,
    /// Multiplies both.
    pub environment_intensity: f32,
    /// cos and sin of the environment's rotation about +y.
    pub environment_turn: [f32; 2],
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
}

/// The threaded BVH's quantization frame ([`QuantizationFrame`]) as the shader reads it. A tree
/// rebuilt on the GPU gets its frame there: the layout kernel writes this record, and the renderer
/// copies it into the globals.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhFrame {
    /// The root box's minimum corner.
    pub origin: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad0: u32,
    /// The quantum of each axis (a power of two).
    pub quantum: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad1: u32,
    /// Its inverse.
    pub inverse_quantum: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad2: u32,
}

impl GpuBvhFrame {
    /// The record of `frame`.
    pub fn new(frame: &QuantizationFrame) -> Self {
        Self {
            origin: frame.origin.to_array(),
            quantum: frame.quantum.to_array(),
            inverse_quantum: frame.inverse_quantum().to_array(),
            ..Default::default()
        }
    }

    /// The frame this record holds.
    pub fn frame(&self) -> QuantizationFrame {
        QuantizationFrame {
            origin: Vec3::from_array(self.origin),
            quantum: Vec3::from_array(self.quantum),
        }
    }
}

/// The fragment shader's uniform: camera, scene constants and BVH frame, each written on its own.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuGlobals {
    /// The camera and which sample the draw traces.
    pub camera: GpuCamera,
    /// The scene's constants.
    pub scene: GpuSceneInfo,
    /// The threaded BVH's quantization frame.
    pub bvh_frame: GpuBvhFrame,
}

/// A sphere as the shader reads it: centre, radius and material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSphere {
    /// The centre.
    pub center: [f32; 3],
    /// The radius.
    pub radius: f32,
    /// Index into the material records.
    pub material: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 3],
}

/// A triangle by its three corners, as the watertight test reads them: two triangles that share an
/// edge hold its corners bit for bit, which is what keeps rays from slipping between them. Primitive
/// `sphere_count + i` of the BVH is triangle `i`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    /// The first corner.
    pub v0: [f32; 3],
    /// The material's index (`& MATERIAL_INDEX_MASK`) and, above it, what the walks' hit test needs
    /// of the material: `TRIANGLE_SINGLE_SIDED`, `TRIANGLE_ALPHA_MASK`, `TRIANGLE_ALPHA_BLEND`.
    pub material: u32,
    /// The second corner.
    pub v1: [f32; 3],
    /// Index of the triangle's vertex normals in the normal records, or `NONE` to shade flat.
    pub normals: u32,
    /// The third corner.
    pub v2: [f32; 3],
    /// The first texel of the triangle's attribute block, or `NONE` (`PackedScene::triangle_attributes`).
    pub attributes: u32,
}

impl GpuSphere {
    /// The box around the sphere.
    pub fn bounds(&self) -> Aabb {
        Aabb::around_sphere(Vec3::from_array(self.center), self.radius)
    }
}

impl GpuTriangle {
    /// The box around the corners (lbvh.wgsl's `primitive_box`, to the bit).
    pub fn bounds(&self) -> Aabb {
        let [v0, v1, v2] = self.corners();
        Aabb::new(v0.min(v1).min(v2), v0.max(v1).max(v2))
    }

    /// The triangle's three corners.
    pub fn corners(&self) -> [Vec3; 3] {
        [self.v0, self.v1, self.v2].map(Vec3::from_array)
    }
}

/// A smooth triangle's vertex normals, interpolated by barycentric coordinates for shading.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangleNormals {
    /// The normal at `v0`.
    pub n0: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad0: f32,
    /// The normal at `v1`.
    pub n1: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad1: f32,
    /// The normal at `v2`.
    pub n2: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad2: f32,
}

/// One texel of the triangles' attribute blocks (`PackedScene::triangle_attributes`): texture
/// coordinates, vertex colours and tangents, as many texels a triangle as it has attributes.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AttributeTexel(pub [f32; 4]);

/// An infinite plane with its checkerboard frame precomputed, so no basis is derived in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPlane {
    /// A point on the plane.
    pub point: [f32; 3],
    /// Material of the even squares (all of the plane when it has no checker).
    pub material: u32,
    /// Unit normal.
    pub normal: [f32; 3],
    /// Material of the odd squares; equal to `material` when the plane has no checker.
    pub checker_material: u32,
    /// First in-plane axis of the squares (unit).
    pub tangent: [f32; 3],
    /// Edge length of a square.
    pub checker_size: f32,
    /// Second in-plane axis: cross(normal, tangent).
    pub bitangent: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad: f32,
}

/// A light (`scene::Light`): its irradiance at normal incidence, E, follows from `kind`
/// (`LIGHT_*` in the preamble).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// Unused by a directional light.
    pub position: [f32; 3],
    /// The light's kind: constant, point, spot or directional (`LIGHT_*`).
    pub kind: u32,
    /// E (constant), candela (point, spot) or lux (directional), per channel.
    pub color: [f32; 3],
    /// Where a point or spot light's window reaches zero; 0 for none.
    pub range: f32,
    /// Unit: where a spot light points, or where a directional light's light travels.
    pub direction: [f32; 3],
    /// A spot's cone as KHR_lights_punctual computes it: the attenuation is
    /// clamp(cos(angle to the axis) * spot_scale + spot_offset, 0, 1)².
    pub spot_scale: f32,
    /// See `spot_scale`.
    pub spot_offset: f32,
    /// Padding to 16 bytes.
    pub _pad: [f32; 3],
}

/// A material (`scene::Material`): the Whitted fields first, then glTF's metallic-roughness ones,
/// which `model` says to use (`MODEL_WHITTED`, `MODEL_GLTF`, `MODEL_UNLIT`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Whitted: diffuse albedo; glTF: base colour.
    pub color: [f32; 3],
    /// Whitted: the Phong highlight's strength.
    pub specular: f32,
    /// Whitted: the Phong exponent.
    pub shininess: f32,
    /// Whitted: the mirror reflection's weight.
    pub reflect: f32,
    /// Whitted: the refraction's weight.
    pub transmit: f32,
    /// The index of refraction.
    pub ior: f32,
    /// Added to the shaded colour (times the emissive map's colour, where there is one).
    pub emission: [f32; 3],
    /// Which fields shade: `MODEL_WHITTED`, `MODEL_GLTF` or `MODEL_UNLIT`.
    pub model: u32,
    /// glTF: KHR_materials_specular's colour factor.
    pub specular_color: [f32; 3],
    /// glTF: metalness, 0..1.
    pub metallic: f32,
    /// glTF: perceptual roughness, 0..1.
    pub roughness: f32,
    /// glTF: KHR_materials_specular's strength.
    pub specular_factor: f32,
    /// glTF: how much the occlusion map darkens indirect light, 0..1.
    pub occlusion_strength: f32,
    /// The maps, each an index into the texture maps or `NONE`: base colour (both models), then
    /// glTF's metallic-roughness, occlusion and emissive maps.
    pub base_map: u32,
    /// See `base_map`.
    pub metallic_roughness_map: u32,
    /// See `base_map`.
    pub occlusion_map: u32,
    /// See `base_map`.
    pub emissive_map: u32,
    /// The base colour's alpha (times the base map's, at a hit); used by triangles whose
    /// `material` word says MASK or BLEND.
    pub alpha: f32,
    /// MASK's cutoff: alpha below it cuts the surface away.
    pub alpha_cutoff: f32,
    /// glTF: the normal map (an index into the texture maps, or `NONE`) and its scale.
    pub normal_map: u32,
    /// See `normal_map`.
    pub normal_scale: f32,
    /// Padding to 16 bytes.
    pub _pad: u32,
    /// The volume's absorption per unit length (`scene::Volume::absorption`).
    pub absorption: [f32; 3],
    /// glTF with KHR_materials_volume: 1 where the surface bounds a volume (rays refract across
    /// it), 0 for a thin wall.
    pub volume: u32,
    /// KHR_materials_specular's maps (indices into the texture maps, or `NONE`): the strength's
    /// (alpha) and the colour's (RGB).
    pub specular_map: u32,
    /// See `specular_map`.
    pub specular_color_map: u32,
    /// Padding to 16 bytes.
    pub _pad1: [u32; 2],
}

/// A texture as a material maps it (`scene::TextureMap`): where its texels are and how texture
/// coordinates reach them. Travelling in their own small array, a texture's size and wrap need no
/// room in every material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTextureMap {
    /// The texture's first texel among all textures' texels (row by row, `width` to a row).
    pub offset: u32,
    /// The texture's width, in texels.
    pub width: u32,
    /// Its height.
    pub height: u32,
    /// The wrap modes, `wrap_u | wrap_v << 8` (`WRAP_*`).
    pub wrap: u32,
    /// The texture transform's rows: (u', v') = (dot(transform_u, (u, v, 1)), dot(transform_v, (u, v, 1))).
    pub transform_u: [f32; 3],
    /// Which texture coordinate set the map reads, 0 or 1.
    pub tex_coord: u32,
    /// See `transform_u`.
    pub transform_v: [f32; 3],
    /// The texture's mip levels (`MIP_LEVELS_MASK`; level k follows level k - 1, each side halved
    /// and rounded up) and its sampler's `FILTER_*` bits.
    pub sampling: u32,
}
