//! A scene packed into records: what both tracers read.

use super::{
    GpuBvhFrame, GpuCamera, GpuGlobals, GpuLight, GpuMaterial, GpuPlane, GpuSceneInfo, GpuSphere, GpuTriangle,
    GpuTriangleNormals, GpuTriangleUvs, MAX_TEXEL_INTEGER, TexturePixels,
};
use crate::bvh::aabb::Aabb;
use crate::bvh::layout::{GpuNode, NONE};
use crate::bvh::morton::MortonBits;
use crate::bvh::threaded::{GpuThreadedNode, QuantizationFrame, ThreadedTree, threaded_nodes};
use crate::bvh::{BuildTimings, Bvh};
use crate::error::{Element, InputError};
use crate::modes::Builder;
use crate::scene::{Camera, Moved, Plane, Scene, Sphere, Triangle};
use glam::Vec3;

/// The BVH over a packed scene's primitives (spheres, then triangles), in the two layouts the walks
/// read.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedBvh {
    /// The build layout, with parent and escape links: the stackless walk's.
    pub nodes: Vec<GpuNode>,
    /// Longest root-to-leaf path of `nodes`, in edges: the traversal stack's size.
    pub depth: u32,
    /// The same tree depth-first in 16-byte nodes, as the stack and threaded walks read it.
    pub threaded_nodes: Vec<GpuThreadedNode>,
    /// The frame the threaded nodes' boxes are quantized in.
    pub frame: QuantizationFrame,
}

impl PackedBvh {
    pub fn new(bvh: Bvh) -> Self {
        let depth = bvh.max_depth();
        let (frame, threaded_nodes) = threaded_nodes(&bvh.nodes);
        Self {
            nodes: bvh.nodes,
            depth,
            threaded_nodes,
            frame,
        }
    }

    pub fn threaded_tree(&self) -> ThreadedTree<'_> {
        ThreadedTree {
            nodes: &self.threaded_nodes,
            frame: self.frame,
            stack_size: self.depth.max(1),
        }
    }
}

/// The boxes of BVH primitives: `spheres`, then `triangles`, as the tracers index them.
pub fn primitive_boxes(spheres: &[GpuSphere], triangles: &[GpuTriangle]) -> Vec<Aabb> {
    let spheres = spheres.iter().map(GpuSphere::bounds);
    spheres.chain(triangles.iter().map(GpuTriangle::bounds)).collect()
}

/// Which records a motion rewrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MovedRecords {
    Spheres,
    /// Triangles and their vertex normals.
    Triangles,
}

/// The scene as the tracers read it.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedScene {
    /// The camera at the scene's image size, the scene constants, and the BVH's frame where it has
    /// one. A renderer starts from these and may move the camera or resize the image.
    pub globals: GpuGlobals,
    pub max_depth: u32,
    pub spheres: Vec<GpuSphere>,
    pub triangles: Vec<GpuTriangle>,
    /// The vertex normals of the smooth triangles.
    pub triangle_normals: Vec<GpuTriangleNormals>,
    /// The corner texture coordinates of the triangles that have them.
    pub triangle_uvs: Vec<GpuTriangleUvs>,
    pub planes: Vec<GpuPlane>,
    pub lights: Vec<GpuLight>,
    pub materials: Vec<GpuMaterial>,
    /// The textures' texels, one texture after another; materials say where theirs start.
    pub texture_pixels: TexturePixels,
    /// The BVH, once [`PackedScene::build_bvh`] or [`PackedScene::set_bvh`] made it.
    pub bvh: Option<PackedBvh>,
}

pub use crate::scene::MAX_RECORDS;
// Every record index must stay exact in the f32 texels of texture memory.
const _: () = assert!(MAX_RECORDS < MAX_TEXEL_INTEGER as usize);

impl PackedScene {
    /// Packs a validated scene with its render settings.
    pub fn new(scene: &Scene) -> Result<Self, InputError> {
        scene.validate()?;
        for (what, count) in [
            ("primitives", scene.spheres.len() + scene.triangles.len()),
            ("planes", scene.planes.len()),
            ("lights", scene.lights.len()),
            ("materials", scene.materials.len()),
            ("textures", scene.textures.len()),
        ] {
            if count > MAX_RECORDS {
                return Err(InputError::of(
                    Element::Scene,
                    format!("{count} {what}: a render takes at most {MAX_RECORDS} (what a record index can hold)"),
                ));
            }
        }
        let s = &scene.settings;
        let globals = GpuGlobals {
            camera: GpuCamera::new(&scene.camera, s.width, s.height),
            scene: GpuSceneInfo {
                background: s.background.to_array(),
                ambient: s.ambient,
                sphere_count: scene.spheres.len() as u32,
                plane_count: scene.planes.len() as u32,
                light_count: scene.lights.len() as u32,
                material_count: scene.materials.len() as u32,
                triangle_count: scene.triangles.len() as u32,
                _pad: [0; 3],
            },
            // Set with the BVH.
            bvh_frame: GpuBvhFrame::default(),
        };
        let spheres = scene.spheres.iter().map(pack_sphere).collect();
        let (triangles, triangle_normals, triangle_uvs) = pack_triangles(&scene.triangles);
        let planes = scene.planes.iter().map(pack_plane).collect();
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
        let (materials, texture_pixels) = pack_materials(scene);
        Ok(Self {
            globals,
            max_depth: s.max_depth,
            spheres,
            triangles,
            triangle_normals,
            triangle_uvs,
            planes,
            lights,
            materials,
            texture_pixels,
            bvh: None,
        })
    }

    /// Moves the primitives `moved` names, in place: sphere centres, or triangle corners and their
    /// normals' records. Nothing else is repacked; the BVH, if any, is out of date until rebuilt.
    /// The records that changed are returned.
    pub fn apply(&mut self, moved: &Moved) -> MovedRecords {
        match moved {
            Moved::Spheres(centers) => {
                for (sphere, center) in self.spheres.iter_mut().zip(centers) {
                    sphere.center = center.to_array();
                }
                MovedRecords::Spheres
            }
            Moved::Triangles(runs) => {
                for run in runs {
                    let records = &mut self.triangles[run.first..run.first + run.vertices.len()];
                    for (k, record) in records.iter_mut().enumerate() {
                        let [v0, v1, v2] = run.vertices[k];
                        (record.v0, record.v1, record.v2) = (v0.to_array(), v1.to_array(), v2.to_array());
                        if let Some(normals) = &run.normals
                            && record.normals != NONE
                        {
                            let [n0, n1, n2] = normals[k];
                            let slot = &mut self.triangle_normals[record.normals as usize];
                            (slot.n0, slot.n1, slot.n2) = (n0.to_array(), n1.to_array(), n2.to_array());
                        }
                    }
                }
                MovedRecords::Triangles
            }
        }
    }

    /// Spheres and triangles: the primitives the BVH is built over, in its index order.
    pub fn primitive_count(&self) -> usize {
        self.spheres.len() + self.triangles.len()
    }

    /// The primitives' bounding boxes, spheres first.
    pub fn primitive_boxes(&self) -> Vec<Aabb> {
        primitive_boxes(&self.spheres, &self.triangles)
    }

    /// Builds the linear BVH over the primitives on the CPU.
    pub fn build_bvh(&mut self, bits: MortonBits) -> BuildTimings {
        self.build_bvh_with(Builder::Lbvh, bits)
    }

    /// Builds the BVH over the primitives on the CPU with `builder` (the LBVH from `bits`-bit Morton
    /// codes).
    pub fn build_bvh_with(&mut self, builder: Builder, bits: MortonBits) -> BuildTimings {
        let boxes = self.primitive_boxes();
        let (bvh, timings) = match builder {
            Builder::Lbvh => Bvh::build_lbvh(&boxes, bits),
            Builder::Sah => Bvh::build_binned_sah(&boxes),
        };
        self.set_bvh(bvh);
        timings
    }

    /// Attaches a BVH over this scene's primitives (in their order).
    pub fn set_bvh(&mut self, bvh: Bvh) {
        assert_eq!(
            bvh.primitive_count,
            self.primitive_count(),
            "a BVH over another scene's primitives"
        );
        let bvh = PackedBvh::new(bvh);
        self.globals.bvh_frame = GpuBvhFrame::new(&bvh.frame);
        self.bvh = Some(bvh);
    }

    /// Points the camera at a `width` x `height` image.
    pub fn set_camera(&mut self, camera: &Camera, width: u32, height: u32) {
        self.globals.camera = GpuCamera::new(camera, width, height);
    }

    pub fn width(&self) -> u32 {
        self.globals.camera.width()
    }

    pub fn height(&self) -> u32 {
        self.globals.camera.height()
    }
}

fn pack_sphere(s: &Sphere) -> GpuSphere {
    GpuSphere {
        center: s.center.to_array(),
        radius: s.radius,
        material: s.material,
        _pad: [0; 3],
    }
}

/// Triangles' records, with the vertex normals and texture coordinates of those that have them in
/// their own records (a triangle links to its own, or holds NONE).
fn pack_triangles(triangles: &[Triangle]) -> (Vec<GpuTriangle>, Vec<GpuTriangleNormals>, Vec<GpuTriangleUvs>) {
    let mut triangle_normals = Vec::new();
    let mut triangle_uvs = Vec::new();
    let triangles = triangles
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
                None => NONE,
            };
            let uvs = match t.uvs {
                Some([a, b, c]) => {
                    triangle_uvs.push(GpuTriangleUvs {
                        uv01: [a.x, a.y, b.x, b.y],
                        uv2: c.to_array(),
                        _pad: [0.0; 2],
                    });
                    triangle_uvs.len() as u32 - 1
                }
                None => NONE,
            };
            GpuTriangle {
                v0: v0.to_array(),
                material: t.material,
                v1: v1.to_array(),
                normals,
                v2: v2.to_array(),
                uvs,
            }
        })
        .collect();
    (triangles, triangle_normals, triangle_uvs)
}

/// A plane with the axes its checker squares follow.
fn pack_plane(p: &Plane) -> GpuPlane {
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
}

/// Materials' records, and every texture's texels one after another (each material says where its
/// texture's start).
fn pack_materials(scene: &Scene) -> (Vec<GpuMaterial>, TexturePixels) {
    // Every texture's texels, one after another: where each starts.
    let mut texture_pixels = Vec::new();
    let texture_offsets: Vec<u32> = scene
        .textures
        .iter()
        .map(|t| {
            let offset = texture_pixels.len() as u32;
            texture_pixels.extend_from_slice(&t.texels);
            offset
        })
        .collect();
    let materials = scene
        .materials
        .iter()
        .map(|m| {
            let texture = m
                .texture
                .map(|t| (texture_offsets[t as usize], &scene.textures[t as usize]));
            GpuMaterial {
                color: m.color.to_array(),
                specular: m.specular,
                shininess: m.shininess,
                reflect: m.reflect,
                transmit: m.transmit,
                ior: m.ior,
                emission: m.emission.to_array(),
                texture_offset: texture.map_or(NONE, |(offset, _)| offset),
                texture_width: texture.map_or(0, |(_, t)| t.width),
                texture_height: texture.map_or(0, |(_, t)| t.height),
                texture_wrap: texture.map_or(0, |(_, t)| t.wrap[0].code() | t.wrap[1].code() << 8),
                _pad: 0,
            }
        })
        .collect();
    (materials, TexturePixels(texture_pixels))
}
