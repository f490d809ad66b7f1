// Twins of the host records in src/records/mod.rs. tests/cpu/layout.rs parses this file with naga and
// checks every struct's size and member offsets against the Rust ones. Tail padding is implicit here.

// The camera basis and image size: rewritten alone when the camera moves or the image is resized.
struct Camera {
    eye: vec3<f32>,
    tan_half_fov: f32,
    forward: vec3<f32>,
    aspect: f32,
    right: vec3<f32>,
    width: f32,
    up: vec3<f32>,
    height: f32,
    // Which of each pixel's samples this draw traces (0: the pixel centre).
    sample: u32,
}

struct SceneInfo {
    background: vec3<f32>,
    ambient: f32,
    sphere_count: u32,
    plane_count: u32,
    light_count: u32,
    material_count: u32,
    triangle_count: u32,
    // The environment's radiance and irradiance texture maps (NONE: the background), its
    // intensity, and the cos and sin of its turn about +y.
    environment_map: u32,
    irradiance_map: u32,
    environment_intensity: f32,
    environment_turn: vec2<f32>,
}

// The threaded BVH's quantization frame: root box minimum, quantum per axis, its inverse.
struct BvhFrame {
    origin: vec3<f32>,
    quantum: vec3<f32>,
    inverse_quantum: vec3<f32>,
}

struct Globals {
    camera: Camera,
    scene: SceneInfo,
    bvh_frame: BvhFrame,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    material: u32,
}

// The three corners, as the watertight test reads them. BVH primitive sphere_count + i.
struct Triangle {
    v0: vec3<f32>,
    // The material's index (& MATERIAL_INDEX_MASK) and the TRIANGLE_* flags above it.
    material: u32,
    v1: vec3<f32>,
    // Index of the vertex normals, or NONE to shade with the geometric normal.
    normals: u32,
    v2: vec3<f32>,
    // The first texel of the triangle's attribute block, or NONE (triangle_attributes in shade.wgsl).
    attributes: u32,
}

struct TriangleNormals {
    n0: vec3<f32>,
    n1: vec3<f32>,
    n2: vec3<f32>,
}

struct Plane {
    point: vec3<f32>,
    material: u32,
    normal: vec3<f32>,
    checker_material: u32,
    tangent: vec3<f32>,
    checker_size: f32,
    bitangent: vec3<f32>,
}

// E, the irradiance at normal incidence, follows from kind (LIGHT_* from the preamble).
struct Light {
    position: vec3<f32>,
    kind: u32,
    color: vec3<f32>,
    // 0: no range.
    range: f32,
    direction: vec3<f32>,
    spot_scale: f32,
    spot_offset: f32,
}

// The Whitted fields, then glTF's metallic-roughness ones, which model (MODEL_* from the
// preamble) says to use.
struct Material {
    color: vec3<f32>,
    specular: f32,
    shininess: f32,
    reflect: f32,
    transmit: f32,
    ior: f32,
    emission: vec3<f32>,
    model: u32,
    specular_color: vec3<f32>,
    metallic: f32,
    roughness: f32,
    specular_factor: f32,
    occlusion_strength: f32,
    // Indices of texture maps, or NONE.
    base_map: u32,
    metallic_roughness_map: u32,
    occlusion_map: u32,
    emissive_map: u32,
    // The base colour's alpha, and MASK's cutoff.
    alpha: f32,
    alpha_cutoff: f32,
    // A texture map's index, or NONE, and its scale.
    normal_map: u32,
    normal_scale: f32,
    // A volume's absorption per unit length, and 1 where the surface bounds a volume
    // (KHR_materials_volume), 0 for a thin wall.
    absorption: vec3<f32>,
    volume: u32,
    // KHR_materials_specular's maps (texture map indices, or NONE): strength (alpha), colour (RGB).
    specular_map: u32,
    specular_color_map: u32,
}

// A texture as a material maps it: its first texel among all textures' (row by row), its size, its
// wrap modes (u's | v's << 8; WRAP_* from the preamble), the texture transform's two rows and the
// texture coordinate set it reads (0 or 1).
struct TextureMap {
    offset: u32,
    width: u32,
    height: u32,
    wrap: u32,
    transform_u: vec3<f32>,
    tex_coord: u32,
    transform_v: vec3<f32>,
    // The mip levels (MIP_LEVELS_MASK) and the sampler's FILTER_* bits.
    sampling: u32,
}

// A BVH node (src/bvh/layout.rs): internal nodes first, then leaves; the root is node 0.
struct BvhNode {
    min: vec3<f32>,
    // Internal: left child. Leaf: primitive.
    left: u32,
    max: vec3<f32>,
    // Internal: right child. Leaf: LEAF.
    right: u32,
    // NONE for the root.
    parent: u32,
    // The next node after this subtree in depth-first order; NONE at the end.
    escape: u32,
}

// LEAF, NONE (0xffffffff) and LEAF_BIT come from the preamble (src/records/constants.rs).

// A node of the threaded BVH (src/bvh/threaded.rs), in depth-first order: 16-bit box corners in
// quanta of the globals' frame (min.x | min.y << 16, min.z | max.x << 16, max.y | max.z << 16) and
// one link: the node after the subtree for an internal node, LEAF_BIT | primitive for a leaf.
// A texel of the compressed wide BVH (src/bvh/wide.rs): leaf words four a texel, then nodes of
// five texels, whose bits wide.rs sets out.
struct WideTexel {
    words: vec4<u32>,
}

struct ThreadedNode {
    bounds: vec3<u32>,
    link: u32,
}

fn is_leaf(node: ThreadedNode) -> bool {
    return (node.link & LEAF_BIT) != 0u;
}

// A threaded node's box corners, in quanta.
fn quantized_min(node: ThreadedNode) -> vec3<f32> {
    return vec3<f32>(vec3<u32>(node.bounds.x & 0xffffu, node.bounds.x >> 16u, node.bounds.y & 0xffffu));
}

fn quantized_max(node: ThreadedNode) -> vec3<f32> {
    return vec3<f32>(vec3<u32>(node.bounds.y >> 16u, node.bounds.z & 0xffffu, node.bounds.z >> 16u));
}

// The LBVH build's parameters, one per sort pass at a 256-byte stride (src/gpu/builders/lbvh/source.rs).
struct BuildParams {
    // Primitives: spheres, then triangles.
    count: u32,
    // The lowest key bit of the digit a sort pass orders by.
    shift: u32,
    sphere_count: u32,
}

// The threaded layout kernels' parameters (src/gpu/builders/threaded_layout.rs).
struct CollapseParams {
    // Primitives: n.
    primitive_count: u32,
    // Where the nodes start: the texels of the leaf words before them.
    root_texel: u32,
}

struct LayoutParams {
    // Nodes: 2n - 1 for n primitives.
    node_count: u32,
}
