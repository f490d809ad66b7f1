//! glTF files for tests, written here from known geometry: a small builder that packs accessors into
//! one binary buffer and writes the document three ways (a .gltf with data: URIs, a .gltf beside a
//! .bin and image files, a .glb).
#![allow(dead_code)]

use base64::Engine;
use serde_json::{Value, json};
use std::path::Path;

#[derive(Default)]
pub struct GltfBuilder {
    pub bin: Vec<u8>,
    pub buffer_views: Vec<Value>,
    pub accessors: Vec<Value>,
    pub meshes: Vec<Value>,
    pub nodes: Vec<Value>,
    pub materials: Vec<Value>,
    pub textures: Vec<Value>,
    pub samplers: Vec<Value>,
    /// Each image as PNG bytes; written into the buffer, as a data URI or as a file.
    pub images: Vec<Vec<u8>>,
    pub cameras: Vec<Value>,
    pub lights: Vec<Value>,
    pub skins: Vec<Value>,
    pub animations: Vec<Value>,
    /// The default scene's root nodes.
    pub roots: Vec<usize>,
    pub extensions_used: Vec<&'static str>,
}

/// A document with its binary buffer and the external files it names.
struct Packed {
    document: Value,
    bin: Vec<u8>,
    files: Vec<(String, Vec<u8>)>,
}

/// How the document's binary data travels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Packing {
    DataUris,
    ExternalFiles,
    Glb,
}

impl GltfBuilder {
    fn view(&mut self, bytes: &[u8]) -> usize {
        pad(&mut self.bin, 0);
        self.buffer_views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()
        }));
        self.bin.extend_from_slice(bytes);
        self.buffer_views.len() - 1
    }

    /// An accessor of f32 elements of `width` components ("VEC3" for 3...), with min and max.
    pub fn floats(&mut self, values: &[f32], width: usize) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let type_ = ["SCALAR", "VEC2", "VEC3", "VEC4"][width - 1];
        let column = |k: usize| values.iter().skip(k).step_by(width).copied();
        let min: Vec<f32> = (0..width).map(|k| column(k).fold(f32::INFINITY, f32::min)).collect();
        let max: Vec<f32> = (0..width)
            .map(|k| column(k).fold(f32::NEG_INFINITY, f32::max))
            .collect();
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": values.len() / width,
            "type": type_, "min": min, "max": max
        }));
        self.accessors.len() - 1
    }

    /// An accessor of u16 VEC4 elements (JOINTS_0).
    pub fn joints(&mut self, joints: &[[u16; 4]]) -> usize {
        let bytes: Vec<u8> = joints.as_flattened().iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5123, "count": joints.len(), "type": "VEC4"
        }));
        self.accessors.len() - 1
    }

    /// An accessor of column-major MAT4 elements (inverse bind matrices).
    pub fn matrices(&mut self, matrices: &[[f32; 16]]) -> usize {
        let bytes: Vec<u8> = matrices.as_flattened().iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": matrices.len(), "type": "MAT4"
        }));
        self.accessors.len() - 1
    }

    /// An animation of one channel: `node`'s `path` keyed at `times` to `values` (`width` floats
    /// a key, three times that for CUBICSPLINE), interpolated as `interpolation` says.
    pub fn animate(
        &mut self,
        node: usize,
        path: &str,
        interpolation: &str,
        times: &[f32],
        values: &[f32],
        width: usize,
    ) {
        let input = self.floats(times, 1);
        let output = self.floats(values, width);
        self.animations.push(json!({
            "channels": [{ "sampler": 0, "target": { "node": node, "path": path } }],
            "samplers": [{ "input": input, "output": output, "interpolation": interpolation }]
        }));
    }

    /// An accessor of normalized unsigned bytes, `width` to an element (COLOR_0 as "VEC4").
    pub fn unorm8(&mut self, values: &[u8], width: usize) -> usize {
        let view = self.view(values);
        let type_ = ["SCALAR", "VEC2", "VEC3", "VEC4"][width - 1];
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5121, "normalized": true, "count": values.len() / width, "type": type_
        }));
        self.accessors.len() - 1
    }

    pub fn indices(&mut self, indices: &[u16]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5123, "count": indices.len(), "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }

    /// A mesh of one triangle-list primitive; `uvs` adds TEXCOORD_0.
    pub fn mesh(
        &mut self,
        positions: &[[f32; 3]],
        uvs: Option<&[[f32; 2]]>,
        indices: &[u16],
        material: Option<usize>,
    ) -> usize {
        let position = self.floats(positions.as_flattened(), 3);
        let mut attributes = json!({ "POSITION": position });
        if let Some(uvs) = uvs {
            attributes["TEXCOORD_0"] = json!(self.floats(uvs.as_flattened(), 2));
        }
        let mut primitive = json!({ "attributes": attributes, "indices": self.indices(indices) });
        if let Some(material) = material {
            primitive["material"] = json!(material);
        }
        self.meshes.push(json!({ "primitives": [primitive] }));
        self.meshes.len() - 1
    }

    pub fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// A base-colour texture of an RGBA8 image (`width` x `height`, row 0 at v = 0), with wrap
    /// modes (10497 REPEAT, 33071 CLAMP_TO_EDGE, 33648 MIRRORED_REPEAT) and nearest filters.
    pub fn texture(&mut self, rgba: &[u8], width: u32, height: u32, wrap: [u32; 2]) -> usize {
        let mut png_bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut png_bytes, width, height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.write_header().unwrap().write_image_data(rgba).unwrap();
        self.images.push(png_bytes);
        self.samplers.push(json!({
            "magFilter": 9728, "minFilter": 9728, "wrapS": wrap[0], "wrapT": wrap[1]
        }));
        self.textures
            .push(json!({ "source": self.images.len() - 1, "sampler": self.samplers.len() - 1 }));
        self.textures.len() - 1
    }

    pub fn material(&mut self, material: Value) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// The document, with images and the buffer packed as `packing` says; `stem` names the
    /// external files.
    fn document(&self, packing: Packing, stem: &str) -> Packed {
        let mut bin = self.bin.clone();
        let mut buffer_views = self.buffer_views.clone();
        let mut files = Vec::new();
        let encode = |bytes: &[u8], mime: &str| {
            format!(
                "data:{mime};base64,{}",
                base64::engine::general_purpose::STANDARD.encode(bytes)
            )
        };
        let images: Vec<Value> = self
            .images
            .iter()
            .enumerate()
            .map(|(i, png)| match packing {
                Packing::DataUris => json!({ "uri": encode(png, "image/png") }),
                Packing::ExternalFiles => {
                    let name = format!("{stem} image {i}.png");
                    files.push((name.clone(), png.clone()));
                    json!({ "uri": name.replace(' ', "%20") })
                }
                Packing::Glb => {
                    pad(&mut bin, 0);
                    buffer_views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": png.len() }));
                    bin.extend_from_slice(png);
                    json!({ "bufferView": buffer_views.len() - 1, "mimeType": "image/png" })
                }
            })
            .collect();
        pad(&mut bin, 0);
        let buffer = match packing {
            Packing::DataUris => json!({ "byteLength": bin.len(), "uri": encode(&bin, "application/octet-stream") }),
            Packing::ExternalFiles => {
                files.push((format!("{stem}.bin"), bin.clone()));
                json!({ "byteLength": bin.len(), "uri": format!("{stem}.bin") })
            }
            Packing::Glb => json!({ "byteLength": bin.len() }),
        };
        let mut document = json!({
            "asset": { "version": "2.0", "generator": "raypipe tests" },
            "scene": 0,
            "scenes": [{ "nodes": self.roots }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "accessors": self.accessors,
            "bufferViews": buffer_views,
            "buffers": [buffer],
        });
        for (key, list) in [
            ("materials", &self.materials),
            ("textures", &self.textures),
            ("samplers", &self.samplers),
            ("cameras", &self.cameras),
            ("skins", &self.skins),
            ("animations", &self.animations),
        ] {
            if !list.is_empty() {
                document[key] = json!(list);
            }
        }
        if !images.is_empty() {
            document["images"] = json!(images);
        }
        if !self.lights.is_empty() {
            document["extensions"] = json!({ "KHR_lights_punctual": { "lights": self.lights } });
        }
        if !self.extensions_used.is_empty() {
            document["extensionsUsed"] = json!(self.extensions_used);
        }
        Packed { document, bin, files }
    }

    /// A .gltf with every buffer and image as a data: URI.
    pub fn gltf(&self) -> Vec<u8> {
        serde_json::to_vec_pretty(&self.document(Packing::DataUris, "").document).unwrap()
    }

    /// The file's bytes packed as `packing` says, written to `dir/stem.gltf` or `.glb` with any
    /// external files beside it; returns the path.
    pub fn write(&self, dir: &Path, stem: &str, packing: Packing) -> std::path::PathBuf {
        let Packed { document, bin, files } = self.document(packing, stem);
        for (name, bytes) in files {
            std::fs::write(dir.join(name), bytes).unwrap();
        }
        let path = dir.join(format!(
            "{stem}.{}",
            if packing == Packing::Glb { "glb" } else { "gltf" }
        ));
        let bytes = match packing {
            Packing::Glb => glb(&serde_json::to_vec(&document).unwrap(), &bin),
            _ => serde_json::to_vec_pretty(&document).unwrap(),
        };
        std::fs::write(&path, bytes).unwrap();
        path
    }
}

/// A GLB container: the 12-byte header, the JSON chunk padded with spaces, the BIN chunk with zeros.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    pad(&mut json, b' ');
    let mut bin = bin.to_vec();
    pad(&mut bin, 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// Pads `bytes` to a multiple of 4 bytes, as glTF aligns buffer views and GLB chunks.
fn pad(bytes: &mut Vec<u8>, with: u8) {
    bytes.resize(bytes.len().next_multiple_of(4), with);
}

/// A unit quad in the xy plane, corners (0,0) to (1,1), facing +z, with UVs that put texture row 0
/// (v = 0) at the top (y = 1), as glTF images are: `uv_scale` times the unit square.
pub fn quad(uv_scale: f32) -> ([[f32; 3]; 4], [[f32; 2]; 4], [u16; 6]) {
    let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let uvs = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]].map(|[u, v]: [f32; 2]| [u * uv_scale, v * uv_scale]);
    (positions, uvs, [0, 1, 2, 0, 2, 3])
}

/// A 2x2 RGBA image, row by row: red, green; blue, white.
pub const CHECKER: [[u8; 4]; 4] = [
    [255, 0, 0, 255],
    [0, 255, 0, 255],
    [0, 0, 255, 255],
    [255, 255, 255, 255],
];

/// glTF's wrap modes, by their sampler numbers.
pub const REPEAT: u32 = 10497;
pub const CLAMP_TO_EDGE: u32 = 33071;
pub const MIRRORED_REPEAT: u32 = 33648;

/// A quad textured with a 2x2 checker (red, green / blue, white), its UVs `uv_scale` times the unit
/// square, with wrap modes `wrap`.
pub fn textured_quad(uv_scale: f32, wrap: [u32; 2]) -> GltfBuilder {
    let mut b = GltfBuilder::default();
    let checker = CHECKER.as_flattened();
    let texture = b.texture(checker, 2, 2, wrap);
    let material = b.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": texture }, "metallicFactor": 0 }
    }));
    let (positions, uvs, indices) = quad(uv_scale);
    let mesh = b.mesh(&positions, Some(&uvs), &indices, Some(material));
    b.roots = vec![b.node(json!({ "mesh": mesh }))];
    b
}

/// The textured quad seen square-on by a camera of the file's own, at distance 1, whose view the
/// quad fills exactly: pixel (x, y) of a square image of `size` looks at uv = ((x + 0.5) / size,
/// (y + 0.5) / size) times `uv_scale`.
pub fn framed_textured_quad(uv_scale: f32, wrap: [u32; 2]) -> GltfBuilder {
    let mut b = textured_quad(uv_scale, wrap);
    let fov = 2.0 * 0.5f32.atan();
    b.cameras = vec![json!({ "type": "perspective", "perspective": { "yfov": fov, "znear": 0.01 } })];
    let camera = b.node(json!({ "camera": 0, "translation": [0.5, 0.5, 1.0] }));
    b.roots.push(camera);
    b
}

/// The skinned cylinder's joint 1: its height, where the cylinder bends.
pub const BEND_HEIGHT: f32 = 1.0;

/// The skinned cylinder's vertices per ring: enough that its smooth normals stay near its faces'
/// (a coarser one puts the shadow terminator where the GPU's and CPU's rounding disagree).
const CYLINDER_SIDES: usize = 24;

/// A cylinder of radius 0.25 from y = 0 to 2 along +y, `rings` rings of 24 vertices, skinned to two
/// joints: joint 0 at the origin, joint 1 (its child) at y = 1. A vertex's weight on joint 1 is
/// its height's smoothstep from 0.5 to 1.5. Joint 1 turns from 0 to 90 degrees about z between
/// t = 0 and 1 (LINEAR). Returns the builder, the rest positions and each vertex's weight on
/// joint 1.
pub fn skinned_cylinder(rings: usize) -> (GltfBuilder, Vec<[f32; 3]>, Vec<f32>) {
    let mut b = GltfBuilder::default();
    let mut positions = Vec::new();
    let mut weights = Vec::new();
    for ring in 0..rings {
        let y = 2.0 * ring as f32 / (rings - 1) as f32;
        let x = ((y - 0.5) / 1.0).clamp(0.0, 1.0);
        let w = x * x * (3.0 - 2.0 * x);
        for k in 0..CYLINDER_SIDES {
            let a = k as f32 * std::f32::consts::TAU / CYLINDER_SIDES as f32;
            positions.push([0.25 * a.cos(), y, 0.25 * a.sin()]);
            weights.push(w);
        }
    }
    let mut indices = Vec::new();
    for ring in 0..rings - 1 {
        for k in 0..CYLINDER_SIDES {
            let n = CYLINDER_SIDES;
            let (a, b2) = ((ring * n + k) as u16, (ring * n + (k + 1) % n) as u16);
            let (c, d) = (a + n as u16, b2 + n as u16);
            indices.extend_from_slice(&[a, c, b2, b2, c, d]);
        }
    }
    let position = b.floats(positions.as_flattened(), 3);
    let index = b.indices(&indices);
    // A joint is named only where it weighs something (the validator warns of the others).
    let (joint_list, weight_values): (Vec<[u16; 4]>, Vec<[f32; 4]>) = weights
        .iter()
        .map(|&w| match w {
            0.0 => ([0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            1.0 => ([1, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            w => ([0, 1, 0, 0], [1.0 - w, w, 0.0, 0.0]),
        })
        .unzip();
    let joints = b.joints(&joint_list);
    let weight = b.floats(weight_values.as_flattened(), 4);
    for (accessor, target) in [(position, 34962), (joints, 34962), (weight, 34962), (index, 34963)] {
        let view = b.accessors[accessor]["bufferView"].as_u64().unwrap() as usize;
        b.buffer_views[view]["target"] = json!(target);
    }
    b.meshes.push(json!({ "primitives": [{
        "attributes": { "POSITION": position, "JOINTS_0": joints, "WEIGHTS_0": weight },
        "indices": index
    }]}));
    let mesh_node = b.node(json!({ "mesh": 0, "skin": 0 }));
    let root = b.node(json!({ "children": [2] }));
    let bend = b.node(json!({ "translation": [0.0, BEND_HEIGHT, 0.0] }));
    let identity = [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    let mut lowered = identity;
    lowered[13] = -BEND_HEIGHT;
    let inverse_binds = b.matrices(&[identity, lowered]);
    b.skins
        .push(json!({ "joints": [root, bend], "inverseBindMatrices": inverse_binds }));
    b.roots = vec![mesh_node, root];
    let half = std::f32::consts::FRAC_1_SQRT_2;
    b.animate(
        bend,
        "rotation",
        "LINEAR",
        &[0.0, 1.0],
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, half, half],
        4,
    );
    (b, positions, weights)
}

/// A unit quad in z = 0 with one morph target that lifts every vertex by `lift` in z; its weight
/// goes from 0 to 1 between t = 0 and 1 (LINEAR).
pub fn morphing_quad(lift: f32) -> GltfBuilder {
    let mut b = GltfBuilder::default();
    let (positions, _, indices) = quad(1.0);
    let position = b.floats(positions.as_flattened(), 3);
    let offsets = b.floats(&[0.0, 0.0, lift].repeat(4), 3);
    let index = b.indices(&indices);
    b.meshes.push(json!({
        "primitives": [{ "attributes": { "POSITION": position }, "indices": index, "targets": [{ "POSITION": offsets }] }],
        "weights": [0.0]
    }));
    let node = b.node(json!({ "mesh": 0 }));
    b.roots = vec![node];
    b.animate(node, "weights", "LINEAR", &[0.0, 1.0], &[0.0, 1.0], 1);
    b
}

/// The unit quad with every attribute a material can read: NORMAL (+z), TEXCOORD_0, TEXCOORD_1 (the
/// square turned a quarter), COLOR_0 (normalized bytes, a different colour at each corner); its
/// material's base colour map (the checker) reads set 1, its normal map (one texel tilting the
/// normal toward +v) set 0, and the file has no TANGENT, so MikkTSpace makes them. A camera looks at
/// it from +z, a point light shines from above one corner.
pub fn attribute_quad() -> GltfBuilder {
    let mut b = GltfBuilder::default();
    let checker = b.texture(CHECKER.as_flattened(), 2, 2, [REPEAT; 2]);
    let tilt = b.texture(&[128, 200, 230, 255], 1, 1, [REPEAT; 2]);
    // KHR_materials_specular's strength (alpha, linear) and colour (RGB, sRGB) in one image.
    let shine = b.texture(&[188, 255, 128, 64], 1, 1, [REPEAT; 2]);
    let material = b.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": checker, "texCoord": 1 }, "metallicFactor": 0, "roughnessFactor": 0.5 },
        "normalTexture": { "index": tilt, "scale": 0.8 },
        "extensions": { "KHR_materials_specular": {
            "specularFactor": 0.9, "specularTexture": { "index": shine },
            "specularColorFactor": [1, 0.8, 0.6], "specularColorTexture": { "index": shine, "texCoord": 1 },
        } },
    }));
    let (positions, uvs, indices) = quad(1.0);
    let mesh = b.mesh(&positions, Some(&uvs), &indices, Some(material));
    let normals = b.floats(&[0.0, 0.0, 1.0].repeat(4), 3);
    let turned: Vec<f32> = uvs.iter().flat_map(|[u, v]| [*v, 1.0 - u]).collect();
    let uvs1 = b.floats(&turned, 2);
    let colors = b.unorm8(
        &[255, 64, 64, 255, 64, 255, 64, 255, 64, 64, 255, 255, 255, 255, 255, 128],
        4,
    );
    let attributes = &mut b.meshes[mesh]["primitives"][0]["attributes"];
    attributes["NORMAL"] = json!(normals);
    attributes["TEXCOORD_1"] = json!(uvs1);
    attributes["COLOR_0"] = json!(colors);
    b.roots = vec![b.node(json!({ "mesh": mesh }))];
    b.cameras = vec![json!({ "type": "perspective", "perspective": { "yfov": 1.0, "znear": 0.01 } })];
    let camera = b.node(json!({ "camera": 0, "translation": [0.5, 0.5, 1.2] }));
    b.lights = vec![json!({ "type": "point", "intensity": 3 })];
    let light =
        b.node(json!({ "translation": [1.2, 1.4, 0.8], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    b.roots.extend([camera, light]);
    b.extensions_used = vec!["KHR_lights_punctual", "KHR_materials_specular"];
    b
}
