//! glTF 2.0 scenes: `.gltf` (JSON, with external or `data:` buffers and images) and `.glb`.
//!
//! The default scene's node hierarchy is flattened into world-space triangles (a mesh that several
//! nodes use appears once for each), with the file's materials (`material.rs`) and base-colour
//! textures, its first perspective camera and its KHR_lights_punctual lights. Everything the file
//! says is checked before it is used: references, every accessor against its buffer view and
//! buffer, counts before allocating, the node graph for cycles and shared children, and numbers for
//! NaN. Errors are one line naming the element (`mesh 3 primitive 0: accessor 7: ...`), which
//! they carry as data too ([`crate::error::Element::Gltf`], the file's parts from the outermost
//! in); what is read but not rendered (points, lines, unused textures) is reported as one notice each.
//!
//! Skins, morph targets and animations are read into a [`Rig`] (`animation.rs`); the primitives are
//! then posed at the first animation's start (or, without one, at rest with skins and weights
//! applied), and a scene that places the file plays the clip it chooses.

mod animation;
mod data;
mod light;
mod material;
mod primitive;
mod tangents;

pub use data::Files;

use super::animation::{Instance, Rig};
use super::{Camera, Light, Material, Texture};
use crate::error::{Element, GltfPart, InputError};
use crate::mesh::Mesh;
use data::read_floats;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::json;
use gltf::json::accessor::Type;
use light::punctual_light;
use primitive::LocalPrimitive;
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

/// The extensions read. KHR_mesh_quantization only widens the accessor types, which every
/// attribute reader takes.
pub(crate) const SUPPORTED_EXTENSIONS: &[&str] = &[
    "EXT_mesh_gpu_instancing",
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_unlit",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
];

/// The extension that places a mesh many times under one node.
const INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// Whether `path` names a glTF file by its extension.
pub(crate) fn is_gltf_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// One mesh primitive placed in the world: an indexed triangle list with its attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    /// The vertices, in world space.
    pub positions: Vec<Vec3>,
    /// The file's vertex normals, where it has them.
    pub normals: Option<Vec<Vec3>>,
    /// TEXCOORD_0, where the file has it.
    pub uvs: Option<Vec<Vec2>>,
    /// TEXCOORD_1, where the file has it.
    pub uvs1: Option<Vec<Vec2>>,
    /// COLOR_0 as linear RGBA (alpha 1 where the file gives RGB), where the file has it.
    pub colors: Option<Vec<Vec4>>,
    /// Each triangle's corners' tangents (xyz unit, w the bitangent's sign): TANGENT's, or
    /// MikkTSpace's where the material has a normal map and the file no TANGENT.
    pub tangents: Option<Vec<[Vec4; 3]>>,
    /// Vertex indices, counter-clockwise from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Index into [`GltfScene::materials`].
    pub material: u32,
}

/// What a glTF file's default scene holds, in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfScene {
    /// The primitives, placed.
    pub primitives: Vec<Primitive>,
    /// The materials the primitives index.
    pub materials: Vec<Material>,
    /// The textures the materials map.
    pub textures: Vec<Texture>,
    /// The first perspective camera met in the node hierarchy.
    pub camera: Option<Camera>,
    /// KHR_lights_punctual's lights, placed.
    pub lights: Vec<Light>,
    /// Where the file has skins, morph targets or animations: what moves, with one instance per
    /// primitive.
    pub rig: Option<Arc<Rig>>,
}

/// Reads a `.gltf` or `.glb` file; its external files are read from its folder. Every error names
/// the path; notices are logged.
pub fn load(path: &Path) -> Result<GltfScene, InputError> {
    let shown = path.display().to_string();
    let bytes = crate::input::read_regular_after_head(path, "glTF file", crate::input::MAX_MODEL_BYTES, |head, _| {
        check_head(head)
    })?;
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let mut notices = Vec::new();
    let scene = parse(&bytes, Files::Folder(folder), &mut notices).map_err(|e| e.in_origin(&shown))?;
    for notice in notices {
        log::info!("{shown}: {notice}");
    }
    Ok(scene)
}

/// A GLB starts with its magic, glTF JSON with `{` (after a byte-order mark or white space).
fn check_head(head: &[u8]) -> Result<(), InputError> {
    let text = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        _ if head.starts_with(b"glTF") => Ok(()),
        Some(b'{') => Ok(()),
        None if head.is_empty() => Err(InputError::new("empty file")),
        _ => Err(InputError::new(
            "not a glTF file: it starts with neither '{' nor the GLB magic 'glTF'",
        )),
    }
}

/// A GLB's total length must cover its 12-byte header and lie within the file. gltf 1.4.1 subtracts
/// the header from it unchecked (`Glb::from_slice`), which overflows for a length below 12: a panic
/// where overflow is checked (found by the fuzz target), a wrapped number elsewhere.
fn check_glb_header(bytes: &[u8]) -> Result<(), InputError> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let Some(length) = bytes.get(8..12) else {
        return Err(InputError::new(format!(
            "GLB header: {} bytes, less than its 12",
            bytes.len()
        )));
    };
    let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]) as u64;
    if length < 12 || length > bytes.len() as u64 {
        return Err(InputError::new(format!(
            "GLB header: total length {length}, where the file has {} bytes and the header 12",
            bytes.len()
        )));
    }
    Ok(())
}

/// Parses glTF JSON or GLB bytes; `files` says where external files may be read from. Things the
/// file holds that are not rendered are reported in `notices`.
pub fn parse(bytes: &[u8], files: Files, notices: &mut Vec<String>) -> Result<GltfScene, InputError> {
    check_glb_header(bytes)?;
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| match e {
        gltf::Error::Deserialize(e) => InputError::new(format!("not glTF JSON: {e}")),
        other => InputError::new(format!("not a glTF file: {other}")),
    })?;
    let mut root = document.into_json();
    check_extensions(&mut root, notices)?;
    validate(&root)?;
    let document = gltf::Document::from_json_without_validation(root);
    let root = document.as_json();
    let buffers = data::load_buffers(root, blob, files)?;
    let mut materials = material::Materials::new();
    materials.read(&document, &buffers, files, notices)?;
    let mut reader = SceneReader {
        root,
        buffers: &buffers,
        materials,
        meshes: HashMap::new(),
        primitives: Vec::new(),
        instances: Vec::new(),
        triangles: 0,
        skipped_modes: 0,
        camera: None,
        lights: Vec::new(),
        notices,
    };
    let (walk, parents) = walk_nodes(&document, reader.notices)?;
    for (node, world) in walk {
        reader.node(&node, world)?;
    }
    if reader.skipped_modes > 0 {
        reader.notices.push(format!(
            "{} primitives of points or lines are skipped",
            reader.skipped_modes
        ));
    }
    if reader.primitives.is_empty() {
        return Err(InputError::new("the scene has no triangles"));
    }
    let moves = !root.skins.is_empty()
        || !root.animations.is_empty()
        || reader.instances.iter().any(|i| !i.rest.targets.is_empty());
    let rig = if moves {
        let mut rig = animation::read_rig(root, &buffers, &parents, reader.notices)?;
        rig.instances = reader.instances;
        Some(Arc::new(rig))
    } else {
        None
    };
    let materials = reader.materials;
    let scene = GltfScene {
        primitives: reader.primitives,
        materials: materials.materials,
        textures: materials.textures,
        camera: reader.camera,
        lights: reader.lights,
        rig,
    };
    Ok(match &scene.rig {
        Some(rig) => scene.posed((!rig.clips.is_empty()).then_some(0), 0.0),
        None => scene,
    })
}

/// Refuses a required extension that is not read; notes each used one that is ignored.
fn check_extensions(root: &mut json::Root, notices: &mut Vec<String>) -> Result<(), InputError> {
    if let Some(name) = root
        .extensions_required
        .iter()
        .find(|name| !SUPPORTED_EXTENSIONS.contains(&name.as_str()))
    {
        return Err(InputError::new(format!(
            "extension {} is required, and raypipe does not read it",
            crate::error::quoted(name)
        )));
    }
    for name in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&name.as_str()) {
            notices.push(format!("extension {} is ignored", crate::error::quoted(name)));
        }
    }
    // Checked here against what raypipe reads; the crate's own list lacks KHR_mesh_quantization.
    root.extensions_required.clear();
    Ok(())
}

/// Every reference in range and every enum known (the crate's checks), first fault first.
fn validate(root: &json::Root) -> Result<(), InputError> {
    use gltf::json::validation::Validate;
    // gltf-json 1.4.1 reads a primitive's POSITION accessor before it checks the index (its
    // `primitive_validate_hook` indexes the accessors directly): checked here first, or a file
    // naming an accessor past the end would panic there (found by the fuzz target).
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&position)
                && index.value() >= root.accessors.len()
            {
                return Err(InputError::of(
                    Element::Gltf(vec![GltfPart::Mesh(m), GltfPart::Primitive(p)]),
                    format!(
                        "POSITION accessor {} does not exist ({} accessors)",
                        index.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    let mut first = None;
    root.validate(root, json::Path::new, &mut |path, error| {
        first.get_or_insert_with(|| format!("{}: {error}", path()));
    });
    first.map_or(Ok(()), |first| Err(InputError::new(first)))
}

/// The scene's nodes with their world matrices, and every node's parent.
type NodeWalk<'a> = (Vec<(gltf::Node<'a>, Mat4)>, Vec<Option<usize>>);

/// Each node of the default scene (or, without scenes, of every root) with its world matrix, parents
/// before children. A node with two parents, a cycle, or a NaN in a transform is an error.
/// Also returns every node's parent.
fn walk_nodes<'a>(document: &'a gltf::Document, notices: &mut Vec<String>) -> Result<NodeWalk<'a>, InputError> {
    let nodes: Vec<gltf::Node> = document.nodes().collect();
    let count = nodes.len();
    let mut parent: Vec<Option<usize>> = vec![None; count];
    for node in document.nodes() {
        for child in node.children() {
            if let Some(first) = parent[child.index()].replace(node.index()) {
                return Err(InputError::in_gltf(
                    GltfPart::Node(child.index()),
                    format!(
                        "a child of nodes {first} and {} (a node has at most one parent)",
                        node.index()
                    ),
                ));
            }
        }
    }
    // Every node has at most one parent, so a node that no root reaches lies on a cycle or below one.
    let mut reached = vec![false; count];
    let mut stack: Vec<usize> = document
        .nodes()
        .filter(|n| parent[n.index()].is_none())
        .map(|n| n.index())
        .collect();
    while let Some(index) = stack.pop() {
        reached[index] = true;
        stack.extend(nodes[index].children().map(|c| c.index()));
    }
    if let Some(index) = reached.iter().position(|&r| !r) {
        return Err(InputError::in_gltf(GltfPart::Node(index), "its parents form a cycle"));
    }
    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => {
            let mut listed = vec![false; count];
            for node in scene.nodes() {
                let fail = |message: String| Err(InputError::in_gltf(GltfPart::Scene(scene.index()), message));
                if let Some(p) = parent[node.index()] {
                    return fail(format!("node {} is a child of node {p}, not a root", node.index()));
                }
                if std::mem::replace(&mut listed[node.index()], true) {
                    return fail(format!("node {} is listed twice", node.index()));
                }
            }
            scene.nodes().collect()
        }
        None => {
            notices.push("no scene: every root node is drawn".into());
            document.nodes().filter(|n| parent[n.index()].is_none()).collect()
        }
    };
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent_world)) = stack.pop() {
        let world = parent_world * local_matrix(document.as_json(), node.index())?;
        if !world.is_finite() {
            return Err(InputError::in_gltf(
                GltfPart::Node(node.index()),
                "its world transform is not finite",
            ));
        }
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
        out.push((node, world));
    }
    Ok((out, parent))
}

/// A node's matrix, or its translation, rotation and scale composed (T * R * S), checked.
fn local_matrix(root: &json::Root, node: usize) -> Result<Mat4, InputError> {
    let transform = animation::rest_transform(&root.nodes[node]);
    transform.check().map_err(|e| e.within(GltfPart::Node(node)))?;
    Ok(transform.matrix())
}

struct SceneReader<'a> {
    root: &'a json::Root,
    buffers: &'a [Vec<u8>],
    materials: material::Materials,
    meshes: HashMap<usize, Rc<Vec<LocalPrimitive>>>,
    primitives: Vec<Primitive>,
    /// One per primitive: its node and skin, for the rig.
    instances: Vec<Instance>,
    /// Triangles placed so far, against the most a render takes.
    triangles: usize,
    skipped_modes: usize,
    camera: Option<Camera>,
    lights: Vec<Light>,
    notices: &'a mut Vec<String>,
}

impl SceneReader<'_> {
    fn node(&mut self, node: &gltf::Node, world: Mat4) -> Result<(), InputError> {
        let in_node = |message: String| InputError::in_gltf(GltfPart::Node(node.index()), message);
        if let Some(mesh) = node.mesh() {
            let local = self.mesh(&mesh)?;
            let skin = node.skin().map(|s| s.index());
            if let Some(skin) = skin {
                let joints = self.root.skins[skin].joints.len();
                for (p, primitive) in local.iter().enumerate() {
                    let in_primitive = |message: String| {
                        let path = vec![
                            GltfPart::Node(node.index()),
                            GltfPart::Mesh(mesh.index()),
                            GltfPart::Primitive(p),
                        ];
                        Err(InputError::of(Element::Gltf(path), message))
                    };
                    match primitive.max_joint {
                        None => return in_primitive(format!("skinned by skin {skin}, without JOINTS_0 and WEIGHTS_0")),
                        Some(j) if j as usize >= joints => {
                            return in_primitive(format!("names joint {j}, and skin {skin} has {joints}"));
                        }
                        Some(_) => {}
                    }
                }
            }
            match self
                .instancing(node)
                .map_err(|e| e.within_named(INSTANCING).within(GltfPart::Node(node.index())))?
            {
                Some(_) if skin.is_some() => {
                    return Err(in_node(
                        "EXT_mesh_gpu_instancing on a skinned mesh, which raypipe does not read".into(),
                    ));
                }
                Some(offsets) => {
                    for offset in offsets {
                        self.place(&local, world, offset, node.index(), skin)?;
                    }
                }
                None => self.place(&local, world, Mat4::IDENTITY, node.index(), skin)?,
            }
        }
        if let Some(camera) = node.camera()
            && self.camera.is_none()
        {
            // Read from the JSON: gltf's `Camera::projection` unwraps the object its type names,
            // which validation only checks for one of the two being there.
            let json = &self.root.cameras[camera.index()];
            match (json.type_, &json.perspective) {
                (json::validation::Checked::Valid(json::camera::Type::Perspective), Some(perspective)) => {
                    let eye = world.transform_point3(Vec3::ZERO);
                    let forward = world.transform_vector3(Vec3::NEG_Z);
                    self.camera = Some(Camera {
                        eye,
                        target: eye + forward,
                        up: world.transform_vector3(Vec3::Y),
                        fov_degrees: perspective.yfov.to_degrees(),
                    });
                }
                (json::validation::Checked::Valid(json::camera::Type::Perspective), None) => {
                    return Err(InputError::in_gltf(
                        GltfPart::Camera(camera.index()),
                        "of type perspective, without its perspective object",
                    ));
                }
                _ => self.note_once("orthographic cameras are skipped"),
            }
        }
        if let Some(light) = node.light() {
            let light = punctual_light(&light, world).map_err(|e| {
                e.within(GltfPart::Light(light.index()))
                    .within(GltfPart::Node(node.index()))
            })?;
            self.lights.push(light);
        }
        Ok(())
    }

    /// The node's EXT_mesh_gpu_instancing transforms, each T * R * S from its TRANSLATION,
    /// ROTATION and SCALE accessors (float VEC3; float or normalized VEC4; float VEC3; as many
    /// elements in each, an absent one the identity), or `None` where the node has none.
    fn instancing(&self, node: &gltf::Node) -> Result<Option<Vec<Mat4>>, InputError> {
        let json = &self.root.nodes[node.index()];
        let Some(extension) = json.extensions.as_ref().and_then(|e| e.others.get(INSTANCING)) else {
            return Ok(None);
        };
        let Some(attributes) = extension.get("attributes").and_then(|a| a.as_object()) else {
            return Err(InputError::new("no attributes object"));
        };
        let read = |name: &str, type_: Type, normalized_ok: bool| -> Result<Option<Vec<f32>>, InputError> {
            let Some(value) = attributes.get(name) else {
                return Ok(None);
            };
            let index = value
                .as_u64()
                .ok_or_else(|| InputError::new(format!("{name} is not an accessor index")))?
                as usize;
            let in_attribute = |message: String| InputError::new(message).within_named(name);
            let accessor = self
                .root
                .accessors
                .get(index)
                .ok_or_else(|| in_attribute(format!("accessor {index} does not exist")))?;
            use json::accessor::ComponentType::{F32, I8, I16};
            let component = match &accessor.component_type {
                json::validation::Checked::Valid(c) => Some(c.0),
                json::validation::Checked::Invalid => None,
            };
            let float = component == Some(F32);
            let normalized = accessor.normalized && matches!(component, Some(I8 | I16));
            if !(float || (normalized_ok && normalized)) {
                return Err(in_attribute(format!(
                    "accessor {index} must be float{}",
                    if normalized_ok {
                        " or normalized signed byte or short"
                    } else {
                        ""
                    }
                )));
            }
            read_floats(self.root, self.buffers, index, &[type_])
                .map(Some)
                .map_err(|e| e.within_named(name))
        };
        let translation = read("TRANSLATION", Type::Vec3, false)?;
        let rotation = read("ROTATION", Type::Vec4, true)?;
        let scale = read("SCALE", Type::Vec3, false)?;
        let counts = [
            ("TRANSLATION", translation.as_ref().map(|v| v.len() / 3)),
            ("ROTATION", rotation.as_ref().map(|v| v.len() / 4)),
            ("SCALE", scale.as_ref().map(|v| v.len() / 3)),
        ];
        let mut given = counts.iter().filter_map(|&(name, count)| Some((name, count?)));
        let Some((first, count)) = given.next() else {
            return Err(InputError::new("none of TRANSLATION, ROTATION and SCALE"));
        };
        if let Some((name, other)) = given.find(|&(_, other)| other != count) {
            return Err(InputError::new(format!(
                "{first} has {count} instances and {name} {other}"
            )));
        }
        (0..count)
            .map(|i| {
                let vec3 = |v: &Option<Vec<f32>>, default: Vec3| {
                    v.as_ref().map_or(default, |v| Vec3::from_slice(&v[3 * i..3 * i + 3]))
                };
                let transform = super::animation::Transform::Decomposed {
                    translation: vec3(&translation, Vec3::ZERO),
                    rotation: rotation
                        .as_ref()
                        .map_or(glam::Quat::IDENTITY, |r| glam::Quat::from_slice(&r[4 * i..4 * i + 4])),
                    scale: vec3(&scale, Vec3::ONE),
                };
                transform.check().map_err(|e| e.within(GltfPart::Instance(i)))?;
                Ok(transform.matrix())
            })
            .collect::<Result<Vec<_>, InputError>>()
            .map(Some)
    }

    fn note_once(&mut self, notice: &str) {
        if !self.notices.iter().any(|n| n == notice) {
            self.notices.push(notice.to_string());
        }
    }

    /// Adds a mesh's primitives at `world` (its node's) times `offset` (an instance's transform
    /// under the node): positions by the matrix, normals by its inverse transpose, and the winding
    /// turned where the matrix mirrors.
    fn place(
        &mut self,
        local: &[LocalPrimitive],
        world: Mat4,
        offset: Mat4,
        node: usize,
        skin: Option<usize>,
    ) -> Result<(), InputError> {
        let world = world * offset;
        let linear = Mat3::from_mat4(world);
        let determinant = linear.determinant();
        let normal_matrix = (determinant != 0.0).then(|| linear.inverse().transpose());
        for primitive in local {
            self.triangles += primitive.triangles.len();
            if self.triangles > crate::scene::MAX_RECORDS {
                return Err(InputError::in_gltf(
                    GltfPart::Node(node),
                    format!(
                        "the scene's triangles pass the {} a render takes",
                        crate::scene::MAX_RECORDS
                    ),
                ));
            }
            let rest = &primitive.rest;
            let positions = rest.positions.iter().map(|&p| world.transform_point3(p)).collect();
            let normals = match (&rest.normals, normal_matrix) {
                (Some(normals), Some(m)) => Some(normals.iter().map(|&n| m * n).collect()),
                _ => None,
            };
            let mirrored = determinant < 0.0;
            let triangles = if mirrored {
                primitive.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect()
            } else {
                primitive.triangles.clone()
            };
            // Tangents turn with the surface (the linear part, not the normals' matrix); the
            // corners' order follows the winding, and a mirror flips the bitangent.
            let tangents = primitive.tangents.as_ref().map(|tangents| {
                tangents
                    .iter()
                    .map(|corners| {
                        let placed = corners.map(|t| {
                            let along = (linear * t.truncate()).normalize_or_zero();
                            along.extend(if mirrored { -t.w } else { t.w })
                        });
                        if mirrored {
                            [placed[0], placed[2], placed[1]]
                        } else {
                            placed
                        }
                    })
                    .collect()
            });
            self.primitives.push(Primitive {
                positions,
                normals,
                uvs: primitive.uvs.clone(),
                uvs1: primitive.uvs1.clone(),
                colors: primitive.colors.clone(),
                tangents,
                triangles,
                material: primitive.material,
            });
            self.instances.push(Instance {
                node,
                skin,
                rest: rest.clone(),
                offset,
            });
        }
        Ok(())
    }
}

impl GltfScene {
    /// The scene with its primitives posed at time `t` of `clip` (at rest for `None`): morphed,
    /// skinned, carried by their animated nodes. A still file is returned as it is.
    pub fn posed(&self, clip: Option<usize>, t: f32) -> GltfScene {
        let mut scene = self.clone();
        if let Some(rig) = &self.rig {
            let pose = rig.pose(clip, t);
            for (primitive, instance) in scene.primitives.iter_mut().zip(&rig.instances) {
                (primitive.positions, primitive.normals) = rig.deform(instance, &pose);
            }
        }
        scene
    }

    /// Every primitive's positions as one mesh (for spheres on the surface, and bounds).
    pub fn mesh(&self) -> Mesh {
        let mut mesh = Mesh::default();
        for primitive in &self.primitives {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend_from_slice(&primitive.positions);
            mesh.triangles
                .extend(primitive.triangles.iter().map(|t| t.map(|i| i + base)));
        }
        mesh
    }

    /// The triangles of every primitive.
    pub fn triangle_count(&self) -> usize {
        self.primitives.iter().map(|p| p.triangles.len()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gltf_paths_by_extension() {
        assert!(is_gltf_path(Path::new("a/b.GLB")));
        assert!(is_gltf_path(Path::new("b.gltf")));
        assert!(!is_gltf_path(Path::new("b.ply")));
    }
}
