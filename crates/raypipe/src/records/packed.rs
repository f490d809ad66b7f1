//! A scene packed into records: what both tracers read.

use super::{
    AttributeTexel, GpuBvhFrame, GpuCamera, GpuGlobals, GpuLight, GpuMaterial, GpuPlane, GpuSceneInfo, GpuSphere,
    GpuTextureMap, GpuTriangle, GpuTriangleNormals, MAX_TEXEL_INTEGER, ShadingTexel, TexturePixels,
};
use crate::bvh::aabb::Aabb;
use crate::bvh::layout::{GpuNode, NONE};
use crate::bvh::morton::MortonBits;
use crate::bvh::threaded::{GpuThreadedNode, QuantizationFrame, ThreadedTree, threaded_nodes};
use crate::bvh::wide::{GpuWideTexel, WideTree, leaf_texels, wide_texels};
use crate::bvh::{BuildTimings, Bvh};
use crate::error::{Element, InputError};
use crate::modes::{Builder, Integrator};
use crate::records::constants::{
    ATTRIBUTE_COLOR, ATTRIBUTE_TANGENT, ATTRIBUTE_UV0, ATTRIBUTE_UV1, LIGHT_CONSTANT, LIGHT_DIRECTIONAL, LIGHT_POINT,
    LIGHT_SPOT, MATERIAL_INDEX_MASK, MODEL_GLTF, MODEL_UNLIT, MODEL_WHITTED, TRIANGLE_ALPHA_BLEND, TRIANGLE_ALPHA_MASK,
    TRIANGLE_SINGLE_SIDED, filter_code, wrap_code,
};
use crate::records::path::PathTables;
use crate::records::texels::GpuRecord;
use crate::scene::{
    AlphaMode, Camera, Light, LightKind, Material, Moved, Pbr, Plane, Scene, Sphere, Texture, TextureMap,
    TextureTransform, Triangle,
};
use glam::{Vec2, Vec3};
use std::sync::OnceLock;

/// The BVH over a packed scene's primitives (spheres, then triangles), in the three layouts the
/// walks read.
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
    /// The same tree collapsed into compressed 8-wide nodes, as the wide walk reads it: made the
    /// first time it is asked for, as only that walk reads it.
    wide: OnceLock<Vec<GpuWideTexel>>,
    /// How many primitives the tree holds: where the wide tree's root starts.
    pub primitive_count: usize,
}

impl PackedBvh {
    /// `bvh` with its depth-first copy laid out; the wide collapse waits for its first use.
    pub fn new(bvh: Bvh) -> Self {
        let depth = bvh.max_depth();
        let (frame, threaded_nodes) = threaded_nodes(&bvh.nodes);
        Self {
            nodes: bvh.nodes,
            depth,
            threaded_nodes,
            frame,
            wide: OnceLock::new(),
            primitive_count: bvh.primitive_count,
        }
    }

    /// The wide BVH's texels, collapsed from the nodes the first time they are asked for.
    pub fn wide_texels(&self) -> &Vec<GpuWideTexel> {
        self.wide.get_or_init(|| wide_texels(&self.nodes, self.primitive_count))
    }

    /// Collapses the wide BVH now, where it was not yet; returns the time that took, in
    /// milliseconds.
    pub fn collapse(&self) -> f64 {
        let start = web_time::Instant::now();
        self.wide_texels();
        start.elapsed().as_secs_f64() * 1e3
    }

    /// The wide nodes, collapsed on first use.
    pub fn wide_tree(&self) -> WideTree<'_> {
        WideTree {
            texels: self.wide_texels(),
            root: leaf_texels(self.primitive_count),
            stack_size: self.depth.max(1),
        }
    }

    /// The depth-first 16-byte nodes.
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
    /// Sphere centres.
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
    /// The bounce loop's depth.
    pub max_depth: u32,
    /// How light is carried.
    pub integrator: Integrator,
    /// What the path integrator reads beside the records: its parameters and the environment's
    /// sampling table (made for every scene, so that either integrator can trace it).
    pub path: PathTables,
    /// The spheres, in the BVH's order once built.
    pub spheres: Vec<GpuSphere>,
    /// The triangles, in the BVH's order once built.
    pub triangles: Vec<GpuTriangle>,
    /// The vertex normals of the smooth triangles.
    pub triangle_normals: Vec<GpuTriangleNormals>,
    /// The attribute blocks of the triangles that have texture coordinates, vertex colours or
    /// tangents, texel by texel; a triangle's `attributes` names its first. A block is (u0, v0, u1,
    /// v1) and (u2, v2, present, 0) of set 0, then, as the `ATTRIBUTE_*` bits of `present` say, set 1's
    /// two texels alike, three corners' RGBA colours, three corners' tangents (xyz, w the sign).
    pub triangle_attributes: Vec<AttributeTexel>,
    /// The infinite planes.
    pub planes: Vec<GpuPlane>,
    /// The lights.
    pub lights: Vec<GpuLight>,
    /// The materials.
    pub materials: Vec<GpuMaterial>,
    /// The textures as materials map them.
    pub texture_maps: Vec<GpuTextureMap>,
    /// The materials' texels, then the texture maps': the one array the shader reads both from
    /// (`load_shading`), so that they take one binding (storage memory has 8 a stage). Made with
    /// the two above by [`PackedScene::new`].
    pub shading: Vec<ShadingTexel>,
    /// The textures' mip chains, one texture after another; texture maps say where theirs start.
    pub texture_pixels: TexturePixels,
    /// Where each mesh starts among the triangles ([`crate::scene::Scene::mesh_starts`]): the
    /// driver's structures take one per mesh.
    pub mesh_starts: Vec<u32>,
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
        let material_limit = MATERIAL_INDEX_MASK as usize;
        if scene.materials.len() > material_limit {
            return Err(InputError::of(
                Element::Scene,
                format!(
                    "{} materials: a render takes at most {material_limit} (what a triangle's material word holds)",
                    scene.materials.len()
                ),
            ));
        }
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
        let mut globals = GpuGlobals {
            camera: GpuCamera::new(&scene.camera, s.width, s.height),
            scene: GpuSceneInfo {
                background: s.background.to_array(),
                ambient: s.ambient,
                sphere_count: scene.spheres.len() as u32,
                plane_count: scene.planes.len() as u32,
                light_count: scene.lights.len() as u32,
                material_count: scene.materials.len() as u32,
                triangle_count: scene.triangles.len() as u32,
                environment_map: NONE,
                irradiance_map: NONE,
                environment_intensity: 0.0,
                environment_turn: [1.0, 0.0],
                _pad: [0; 2],
            },
            // Set with the BVH.
            bvh_frame: GpuBvhFrame::default(),
        };
        let spheres = scene.spheres.iter().map(pack_sphere).collect();
        let (triangles, triangle_normals, triangle_attributes) = pack_triangles(&scene.triangles, &scene.materials);
        if triangle_attributes.len() >= MAX_TEXEL_INTEGER as usize {
            return Err(InputError::of(
                Element::Scene,
                format!(
                    "the triangles' texture coordinates, colours and tangents take {} texels: a render takes fewer than {MAX_TEXEL_INTEGER}",
                    triangle_attributes.len()
                ),
            ));
        }
        let planes = scene.planes.iter().map(pack_plane).collect();
        let lights = scene.lights.iter().map(pack_light).collect();
        let (materials, mut texture_maps, mut texture_pixels) = pack_materials(scene);
        if let Some(environment) = &scene.environment {
            let info = &mut globals.scene;
            info.environment_map = push_whole_texture(environment.radiance(), &mut texture_maps, &mut texture_pixels);
            info.irradiance_map = push_whole_texture(environment.irradiance(), &mut texture_maps, &mut texture_pixels);
            info.environment_intensity = environment.intensity;
            let turn = environment.rotation_degrees.to_radians();
            info.environment_turn = [turn.cos(), turn.sin()];
        }
        let mut shading = Vec::new();
        materials.iter().for_each(|m| m.push_texels(&mut shading));
        texture_maps.iter().for_each(|m| m.push_texels(&mut shading));
        let shading = shading.into_iter().map(ShadingTexel).collect();
        Ok(Self {
            globals,
            max_depth: s.max_depth,
            integrator: s.integrator,
            path: PathTables::new(scene.environment.as_ref(), &triangles, &materials),
            spheres,
            triangles,
            triangle_normals,
            triangle_attributes,
            planes,
            lights,
            materials,
            texture_maps,
            shading,
            texture_pixels,
            mesh_starts: scene.mesh_starts.clone(),
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

    /// The flags of every triangle's material word together (`TRIANGLE_*`): what sides and alpha
    /// modes the walks meet.
    pub fn triangle_flags(&self) -> u32 {
        self.triangles
            .iter()
            .fold(0, |flags, t| flags | (t.material & !MATERIAL_INDEX_MASK))
    }

    /// Spheres and triangles: the primitives the BVH is built over, in its index order.
    pub fn primitive_count(&self) -> usize {
        self.spheres.len() + self.triangles.len()
    }

    /// The primitives' bounding boxes, spheres first.
    pub fn primitive_boxes(&self) -> Vec<Aabb> {
        primitive_boxes(&self.spheres, &self.triangles)
    }

    /// Builds the linear BVH over the primitives on the CPU, from the 30-bit Morton codes the GPU's
    /// build uses, so that both build the same tree.
    pub fn build_bvh(&mut self) -> BuildTimings {
        self.build_bvh_with(Builder::Lbvh)
    }

    /// Builds the BVH over the primitives on the CPU with `builder`.
    pub fn build_bvh_with(&mut self, builder: Builder) -> BuildTimings {
        let boxes = self.primitive_boxes();
        let (bvh, timings) = match builder {
            Builder::Lbvh => Bvh::build_lbvh(&boxes, MortonBits::Bits30),
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

    /// The image width, in pixels.
    pub fn width(&self) -> u32 {
        self.globals.camera.width()
    }

    /// The image height, in pixels.
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

/// A triangle's material word: the index, and the flags of the material's side and alpha mode.
fn triangle_material_word(index: u32, material: &Material) -> u32 {
    let sides = if material.double_sided {
        0
    } else {
        TRIANGLE_SINGLE_SIDED
    };
    let alpha = match material.alpha_mode {
        AlphaMode::Opaque => 0,
        AlphaMode::Mask { .. } => TRIANGLE_ALPHA_MASK,
        AlphaMode::Blend => TRIANGLE_ALPHA_BLEND,
    };
    index | sides | alpha
}

/// A triangle's attribute block (`PackedScene::triangle_attributes`), or nothing where it has no
/// attributes.
fn attribute_block(t: &Triangle) -> Vec<AttributeTexel> {
    let mut present = 0;
    for (bit, has) in [
        (ATTRIBUTE_UV0, t.uvs.is_some()),
        (ATTRIBUTE_UV1, t.uvs1.is_some()),
        (ATTRIBUTE_COLOR, t.colors.is_some()),
        (ATTRIBUTE_TANGENT, t.tangents.is_some()),
    ] {
        if has {
            present |= bit;
        }
    }
    if present == 0 {
        return Vec::new();
    }
    let coordinates = |uvs: Option<[Vec2; 3]>, bits: f32| {
        let [a, b, c] = uvs.unwrap_or_default();
        [[a.x, a.y, b.x, b.y], [c.x, c.y, bits, 0.0]]
    };
    let mut block = coordinates(t.uvs, present as f32).to_vec();
    if t.uvs1.is_some() {
        block.extend(coordinates(t.uvs1, 0.0));
    }
    for corners in [t.colors, t.tangents].into_iter().flatten() {
        block.extend(corners.map(|c| c.to_array()));
    }
    block.into_iter().map(AttributeTexel).collect()
}

/// Triangles' records, with the vertex normals and attribute blocks of those that have them in
/// their own records (a triangle links to its own, or holds NONE).
fn pack_triangles(
    triangles: &[Triangle],
    materials: &[Material],
) -> (Vec<GpuTriangle>, Vec<GpuTriangleNormals>, Vec<AttributeTexel>) {
    let mut triangle_normals = Vec::new();
    let mut triangle_attributes = Vec::new();
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
            let block = attribute_block(t);
            let attributes = if block.is_empty() {
                NONE
            } else {
                let first = triangle_attributes.len() as u32;
                triangle_attributes.extend(block);
                first
            };
            GpuTriangle {
                v0: v0.to_array(),
                material: triangle_material_word(t.material, &materials[t.material as usize]),
                v1: v1.to_array(),
                normals,
                v2: v2.to_array(),
                attributes,
            }
        })
        .collect();
    (triangles, triangle_normals, triangle_attributes)
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

fn pack_light(light: &Light) -> GpuLight {
    let (direction, range, cone) = match light.kind {
        LightKind::Constant => (Vec3::ZERO, None, None),
        LightKind::Point { range } => (Vec3::ZERO, range, None),
        LightKind::Spot {
            direction,
            inner_cone,
            outer_cone,
            range,
        } => (direction, range, Some((inner_cone, outer_cone))),
        LightKind::Directional { direction } => (direction, None, None),
    };
    // KHR_lights_punctual's own form of the smooth cone step.
    let (spot_scale, spot_offset) = cone.map_or((0.0, 0.0), |(inner, outer)| {
        let scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
        (scale, -outer.cos() * scale)
    });
    GpuLight {
        position: light.position.to_array(),
        kind: match light.kind {
            LightKind::Constant => LIGHT_CONSTANT,
            LightKind::Point { .. } => LIGHT_POINT,
            LightKind::Spot { .. } => LIGHT_SPOT,
            LightKind::Directional { .. } => LIGHT_DIRECTIONAL,
        },
        color: light.color.to_array(),
        range: range.unwrap_or(0.0),
        direction: direction.to_array(),
        spot_scale,
        spot_offset,
        _pad: [0.0; 3],
    }
}

/// Where a texture's mip chain starts among all textures' texels, and its levels.
#[derive(Clone, Copy)]
struct StoredTexture {
    offset: u32,
    levels: u32,
}

/// Appends `texture`'s mip chain to `pixels`.
fn store_texture(texture: &Texture, pixels: &mut Vec<[u16; 4]>) -> StoredTexture {
    let offset = pixels.len() as u32;
    let levels = texture.push_mip_chain(pixels);
    StoredTexture { offset, levels }
}

/// The record of a map that reads `texture`, stored as `stored`, through `transform` from
/// coordinate set `tex_coord`.
fn texture_map_record(
    texture: &Texture,
    stored: StoredTexture,
    transform: &TextureTransform,
    tex_coord: u32,
) -> GpuTextureMap {
    let [transform_u, transform_v] = transform.rows();
    GpuTextureMap {
        offset: stored.offset,
        width: texture.width,
        height: texture.height,
        wrap: wrap_code(texture.wrap[0]) | wrap_code(texture.wrap[1]) << 8,
        transform_u,
        tex_coord,
        transform_v,
        sampling: stored.levels | filter_code(texture.filter),
    }
}

/// Appends `texture`'s mip chain and a map of the whole of it (coordinate set 0, no transform);
/// returns the map's index.
fn push_whole_texture(texture: &Texture, maps: &mut Vec<GpuTextureMap>, pixels: &mut TexturePixels) -> u32 {
    let stored = store_texture(texture, &mut pixels.0);
    maps.push(texture_map_record(texture, stored, &TextureTransform::default(), 0));
    maps.len() as u32 - 1
}

/// Materials' records, the texture maps they name, and every texture's texels one after another
/// (each map says where its texture's start).
fn pack_materials(scene: &Scene) -> (Vec<GpuMaterial>, Vec<GpuTextureMap>, TexturePixels) {
    // Every texture's mip chain, one after another.
    let mut texture_pixels = Vec::new();
    let stored: Vec<StoredTexture> = scene
        .textures
        .iter()
        .map(|t| store_texture(t, &mut texture_pixels))
        .collect();
    let mut maps = Vec::new();
    let mut map_index = |map: Option<TextureMap>| {
        let Some(map) = map else { return NONE };
        let texture = &scene.textures[map.texture as usize];
        maps.push(texture_map_record(
            texture,
            stored[map.texture as usize],
            &map.transform,
            map.tex_coord,
        ));
        maps.len() as u32 - 1
    };
    let materials = scene
        .materials
        .iter()
        .map(|m| {
            let pbr = m.pbr.unwrap_or_default();
            GpuMaterial {
                color: m.color.to_array(),
                specular: m.specular,
                shininess: m.shininess,
                reflect: m.reflect,
                transmit: m.transmit,
                ior: m.ior,
                emission: m.emission.to_array(),
                model: match m.pbr {
                    None => MODEL_WHITTED,
                    Some(Pbr { unlit: true, .. }) => MODEL_UNLIT,
                    Some(_) => MODEL_GLTF,
                },
                specular_color: pbr.specular_color.to_array(),
                metallic: pbr.metallic,
                roughness: pbr.roughness,
                specular_factor: pbr.specular_factor,
                occlusion_strength: pbr.occlusion_strength,
                base_map: map_index(m.texture),
                metallic_roughness_map: map_index(pbr.metallic_roughness_texture),
                occlusion_map: map_index(pbr.occlusion_texture),
                emissive_map: map_index(pbr.emissive_texture),
                normal_map: map_index(pbr.normal_texture),
                normal_scale: pbr.normal_scale,
                _pad: 0,
                absorption: pbr.volume.map_or(Vec3::ZERO, |v| v.absorption()).to_array(),
                volume: pbr.volume.is_some() as u32,
                specular_map: map_index(pbr.specular_texture),
                specular_color_map: map_index(pbr.specular_color_texture),
                _pad1: [0; 2],
                alpha: m.alpha,
                alpha_cutoff: match m.alpha_mode {
                    AlphaMode::Mask { cutoff } => cutoff,
                    _ => 0.0,
                },
            }
        })
        .collect();
    (materials, maps, TexturePixels(texture_pixels))
}
