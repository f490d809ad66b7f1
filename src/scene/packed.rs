//! The scene as flat GPU records: what the fragment shader reads, and what the CPU reference reads too,
//! so both tracers see the same f32 numbers.
//!
//! Every record is `repr(C)` + `Pod`, a multiple of 16 bytes, with its WGSL twin in
//! `src/gpu/shaders/types.wgsl`; `tests/layout.rs` checks sizes and member offsets against naga's.
//! Fields named `_pad*` are padding the WGSL struct gets implicitly.

use super::Scene;
use crate::bvh::aabb::Aabb;
use crate::bvh::layout::GpuNode;
use crate::bvh::morton::MortonBits;
use crate::bvh::threaded::{GpuThreadedNode, QuantizationFrame, ThreadedTree, threaded_nodes};
use crate::bvh::{BuildTimings, Bvh};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Per-frame constants: the camera basis, image size, background and record counts.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuGlobals {
    pub eye: [f32; 3],
    /// tan(fov / 2), fov vertical.
    pub tan_half_fov: f32,
    /// normalize(target - eye).
    pub forward: [f32; 3],
    /// width / height.
    pub aspect: f32,
    /// normalize(cross(forward, up)).
    pub right: [f32; 3],
    pub width: f32,
    /// cross(right, forward): the true up.
    pub up: [f32; 3],
    pub height: f32,
    pub background: [f32; 3],
    pub ambient: f32,
    pub sphere_count: u32,
    pub plane_count: u32,
    pub light_count: u32,
    pub material_count: u32,
    pub triangle_count: u32,
    pub _pad: [u32; 3],
    /// The threaded BVH's quantization frame (`bvh::threaded`): the root box's minimum corner,
    pub bvh_origin: [f32; 3],
    pub _pad1: u32,
    /// the quantum of each axis (a power of two),
    pub bvh_quantum: [f32; 3],
    pub _pad2: u32,
    /// and its inverse.
    pub bvh_inverse_quantum: [f32; 3],
    pub _pad3: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSphere {
    pub center: [f32; 3],
    pub radius: f32,
    /// Index into the material records.
    pub material: u32,
    pub _pad: [u32; 3],
}

/// A triangle as Möller–Trumbore reads it: a corner and the two edges leaving it. Primitive
/// `sphere_count + i` of the BVH is triangle `i`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    pub v0: [f32; 3],
    pub material: u32,
    /// v1 - v0.
    pub e1: [f32; 3],
    /// Index of the triangle's vertex normals in the normal records, or `NONE` to shade flat.
    pub normals: u32,
    /// v2 - v0.
    pub e2: [f32; 3],
    pub _pad: u32,
}

impl GpuSphere {
    pub fn bounds(&self) -> Aabb {
        Aabb::around_sphere(Vec3::from_array(self.center), self.radius)
    }
}

impl GpuTriangle {
    /// The box around the corners the tracers compute: v0, v0 + e1, v0 + e2 (lbvh.wgsl's
    /// `primitive_box`, to the bit).
    pub fn bounds(&self) -> Aabb {
        let v0 = Vec3::from_array(self.v0);
        let (v1, v2) = (v0 + Vec3::from_array(self.e1), v0 + Vec3::from_array(self.e2));
        Aabb::new(v0.min(v1).min(v2), v0.max(v1).max(v2))
    }
}

/// A smooth triangle's vertex normals, interpolated by barycentric coordinates for shading.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangleNormals {
    pub n0: [f32; 3],
    pub _pad0: f32,
    pub n1: [f32; 3],
    pub _pad1: f32,
    pub n2: [f32; 3],
    pub _pad2: f32,
}

/// An infinite plane with its checkerboard frame precomputed, so no basis is derived in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPlane {
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
    pub _pad: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub _pad0: f32,
    pub color: [f32; 3],
    pub _pad1: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    pub color: [f32; 3],
    pub specular: f32,
    pub shininess: f32,
    pub reflect: f32,
    pub transmit: f32,
    pub ior: f32,
}

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
        let [bx, by, bz] = self.e1;
        let [cx, cy, cz] = self.e2;
        out.push([ax, ay, az, self.material as f32]);
        out.push([bx, by, bz, link_texel(self.normals)]);
        out.push([cx, cy, cz, 0.0]);
    }
}

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
        out.push([r, g, b, self.specular]);
        out.push([self.shininess, self.reflect, self.transmit, self.ior]);
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

/// One host struct's layout, for the naga layout test.
pub struct StructLayout {
    pub wgsl_name: &'static str,
    pub size: usize,
    /// (member name, byte offset), padding excluded.
    pub members: &'static [(&'static str, usize)],
}

macro_rules! layout {
    ($ty:ty, $wgsl:literal, [$($field:ident),* $(,)?]) => {
        StructLayout {
            wgsl_name: $wgsl,
            size: std::mem::size_of::<$ty>(),
            members: &[$((stringify!($field), std::mem::offset_of!($ty, $field))),*],
        }
    };
}

/// Every struct that crosses to the GPU, with the WGSL name of its twin.
#[rustfmt::skip]
pub const LAYOUTS: &[StructLayout] = &[
    layout!(GpuGlobals, "Globals", [
        eye, tan_half_fov, forward, aspect, right, width, up, height, background, ambient,
        sphere_count, plane_count, light_count, material_count, triangle_count,
        bvh_origin, bvh_quantum, bvh_inverse_quantum,
    ]),
    layout!(GpuSphere, "Sphere", [center, radius, material]),
    layout!(GpuTriangle, "Triangle", [v0, material, e1, normals, e2]),
    layout!(GpuTriangleNormals, "TriangleNormals", [n0, n1, n2]),
    layout!(GpuPlane, "Plane", [point, material, normal, checker_material, tangent, checker_size, bitangent]),
    layout!(GpuLight, "Light", [position, color]),
    layout!(GpuMaterial, "Material", [color, specular, shininess, reflect, transmit, ior]),
    layout!(GpuNode, "BvhNode", [min, left, max, right, parent, escape]),
    layout!(GpuThreadedNode, "ThreadedNode", [bounds, link]),
];

/// The scene as the tracers read it.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedScene {
    pub globals: GpuGlobals,
    pub max_depth: u32,
    pub spheres: Vec<GpuSphere>,
    pub triangles: Vec<GpuTriangle>,
    /// The vertex normals of the smooth triangles.
    pub triangle_normals: Vec<GpuTriangleNormals>,
    pub planes: Vec<GpuPlane>,
    pub lights: Vec<GpuLight>,
    pub materials: Vec<GpuMaterial>,
    /// The BVH over the primitives (spheres, then triangles), once [`PackedScene::build_bvh`] ran; empty otherwise.
    pub nodes: Vec<GpuNode>,
    /// Longest root-to-leaf path of `nodes`, in edges: the traversal stack's size.
    pub bvh_depth: u32,
    /// The same tree as the stack and threaded walks read it (its frame is in the globals).
    pub threaded_nodes: Vec<GpuThreadedNode>,
}

impl PackedScene {
    /// Packs a validated scene with its final render settings.
    pub fn new(scene: &Scene) -> Result<Self, super::SceneError> {
        scene.validate()?;
        for (what, count) in [
            ("primitives", scene.spheres.len() + scene.triangles.len()),
            ("planes", scene.planes.len()),
            ("lights", scene.lights.len()),
            ("materials", scene.materials.len()),
        ] {
            if count >= MAX_TEXEL_INTEGER as usize {
                return Err(super::SceneError::new(
                    "scene",
                    format!("{count} {what} is more than the {MAX_TEXEL_INTEGER} a record index can hold"),
                ));
            }
        }
        let c = &scene.camera;
        let s = &scene.settings;
        let forward = (c.target - c.eye).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        let globals = GpuGlobals {
            eye: c.eye.to_array(),
            tan_half_fov: (c.fov_degrees.to_radians() * 0.5).tan(),
            forward: forward.to_array(),
            aspect: s.width as f32 / s.height as f32,
            right: right.to_array(),
            width: s.width as f32,
            up: up.to_array(),
            height: s.height as f32,
            background: s.background.to_array(),
            ambient: s.ambient,
            sphere_count: scene.spheres.len() as u32,
            plane_count: scene.planes.len() as u32,
            light_count: scene.lights.len() as u32,
            material_count: scene.materials.len() as u32,
            triangle_count: scene.triangles.len() as u32,
            // Set with the BVH (`set_bvh`).
            ..Default::default()
        };
        let spheres = scene
            .spheres
            .iter()
            .map(|s| GpuSphere {
                center: s.center.to_array(),
                radius: s.radius,
                material: s.material,
                _pad: [0; 3],
            })
            .collect();
        let mut triangle_normals = Vec::new();
        let triangles = scene
            .triangles
            .iter()
            .map(|t| {
                let [v0, v1, v2] = t.vertices;
                let normals = match t.normals {
                    Some([n0, n1, n2]) => {
                        triangle_normals.push(GpuTriangleNormals {
                            n0: n0.to_array(),
                            n1: n1.to_array(),
                            n2: n2.to_array(),
                            ..Default::default()
                        });
                        triangle_normals.len() as u32 - 1
                    }
                    None => crate::bvh::layout::NONE,
                };
                GpuTriangle {
                    v0: v0.to_array(),
                    material: t.material,
                    e1: (v1 - v0).to_array(),
                    normals,
                    e2: (v2 - v0).to_array(),
                    _pad: 0,
                }
            })
            .collect();
        let planes = scene
            .planes
            .iter()
            .map(|p| {
                // Any axis not parallel to the normal spans the plane with it.
                let helper = if p.normal.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
                let tangent = helper.cross(p.normal).normalize();
                let bitangent = p.normal.cross(tangent);
                let (checker_material, checker_size) = match p.checker {
                    Some(checker) => (checker.material, checker.size),
                    None => (p.material, 1.0),
                };
                GpuPlane {
                    point: p.point.to_array(),
                    material: p.material,
                    normal: p.normal.to_array(),
                    checker_material,
                    tangent: tangent.to_array(),
                    checker_size,
                    bitangent: bitangent.to_array(),
                    _pad: 0.0,
                }
            })
            .collect();
        let lights = scene
            .lights
            .iter()
            .map(|l| GpuLight {
                position: l.position.to_array(),
                _pad0: 0.0,
                color: l.color.to_array(),
                _pad1: 0.0,
            })
            .collect();
        let materials = scene
            .materials
            .iter()
            .map(|m| GpuMaterial {
                color: m.color.to_array(),
                specular: m.specular,
                shininess: m.shininess,
                reflect: m.reflect,
                transmit: m.transmit,
                ior: m.ior,
            })
            .collect();
        Ok(Self {
            globals,
            max_depth: s.max_depth,
            spheres,
            triangles,
            triangle_normals,
            planes,
            lights,
            materials,
            nodes: Vec::new(),
            threaded_nodes: Vec::new(),
            bvh_depth: 0,
        })
    }

    /// Spheres and triangles: the primitives the BVH is built over, in its index order.
    pub fn primitive_count(&self) -> usize {
        self.spheres.len() + self.triangles.len()
    }

    /// The primitives' bounding boxes, spheres first.
    pub fn primitive_boxes(&self) -> Vec<Aabb> {
        let spheres = self.spheres.iter().map(GpuSphere::bounds);
        spheres.chain(self.triangles.iter().map(GpuTriangle::bounds)).collect()
    }

    /// Builds the linear BVH over the primitives on the CPU.
    pub fn build_bvh(&mut self, bits: MortonBits) -> BuildTimings {
        let (bvh, timings) = Bvh::build_lbvh(&self.primitive_boxes(), bits);
        self.set_bvh(bvh);
        timings
    }

    pub fn set_bvh(&mut self, bvh: Bvh) {
        assert_eq!(bvh.primitive_count, self.primitive_count());
        self.bvh_depth = bvh.max_depth();
        let (frame, threaded_nodes) = threaded_nodes(&bvh.nodes);
        self.set_quantization_frame(frame);
        self.threaded_nodes = threaded_nodes;
        self.nodes = bvh.nodes;
    }

    /// The threaded nodes with the frame the globals hold.
    pub fn threaded_tree(&self) -> ThreadedTree<'_> {
        let frame = QuantizationFrame {
            origin: Vec3::from_array(self.globals.bvh_origin),
            quantum: Vec3::from_array(self.globals.bvh_quantum),
        };
        ThreadedTree {
            nodes: &self.threaded_nodes,
            frame,
        }
    }

    fn set_quantization_frame(&mut self, frame: QuantizationFrame) {
        self.globals.bvh_origin = frame.origin.to_array();
        self.globals.bvh_quantum = frame.quantum.to_array();
        self.globals.bvh_inverse_quantum = frame.inverse_quantum().to_array();
    }

    pub fn width(&self) -> u32 {
        self.globals.width as u32
    }

    pub fn height(&self) -> u32 {
        self.globals.height as u32
    }
}
