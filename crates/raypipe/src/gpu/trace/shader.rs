//! Assembles the tracer's shader from its files and a small generated preamble.
//!
//! The preamble holds what must be known at compile time (the ray stack size for `--depth`, uniform
//! array lengths, the texture row width) and the memory mode's `load_*` accessors, so one tracer
//! source serves every memory mode and acceleration structure; the pipeline adds its entry points
//! (a full-screen triangle's vertex and fragment stages, or a compute kernel) around it.

use crate::bvh::layout::NONE;
use crate::constants::ray_stack_size;
use crate::gpu::preamble::records_source;
use crate::modes::{Accel, Integrator, MemoryMode, Pipeline};
use crate::records::TexelFormat;
use crate::records::constants::{
    MODEL_GLTF, MODEL_WHITTED, TRIANGLE_ALPHA_BLEND, TRIANGLE_ALPHA_MASK, TRIANGLE_SINGLE_SIDED,
};
use crate::records::packed::{MovedRecords, PackedScene};
use std::fmt::Write;

/// The side of the compute pipeline's square workgroups, in pixels (compute.wgsl's, from the
/// preamble).
pub const COMPUTE_TILE: u32 = 8;

const TEXELS: &str = include_str!("../shaders/texels.wgsl");
const FULLSCREEN: &str = include_str!("../shaders/fullscreen.wgsl");
const COMPUTE: &str = include_str!("../shaders/compute.wgsl");
const INTERSECT: &str = include_str!("../shaders/intersect.wgsl");
const ACCEL_BRUTE: &str = include_str!("../shaders/accel_brute.wgsl");
const ACCEL_STACK: &str = include_str!("../shaders/accel_stack.wgsl");
const ACCEL_STACKLESS: &str = include_str!("../shaders/accel_stackless.wgsl");
const ACCEL_THREADED: &str = include_str!("../shaders/accel_threaded.wgsl");
const ACCEL_WIDE: &str = include_str!("../shaders/accel_wide.wgsl");
const ACCEL_RAYQUERY: &str = include_str!("../shaders/accel_rayquery.wgsl");
const ADMIT: &str = include_str!("../shaders/admit.wgsl");
const MAPS: &str = include_str!("../shaders/maps.wgsl");
const BRDF: &str = include_str!("../shaders/brdf.wgsl");
const ENVIRONMENT: &str = include_str!("../shaders/environment.wgsl");
const SHADE: &str = include_str!("../shaders/shade.wgsl");
const TRACE: &str = include_str!("../shaders/trace.wgsl");
const WHITTED: &str = include_str!("../shaders/whitted.wgsl");
const SAMPLING: &str = include_str!("../shaders/sampling.wgsl");
const BSDF: &str = include_str!("../shaders/bsdf.wgsl");
const PATH: &str = include_str!("../shaders/path.wgsl");
const PIXEL: &str = include_str!("../shaders/pixel.wgsl");

/// The scene's record arrays, each read by the shader through `load_<name>(i)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordKind {
    /// The spheres.
    Sphere,
    /// The triangles.
    Triangle,
    /// The smooth triangles' vertex normals.
    TriangleNormals,
    /// The triangles' attribute blocks (texture coordinates, colours, tangents), texel by texel.
    TriangleAttributes,
    /// The planes.
    Plane,
    /// The lights.
    Light,
    /// The materials' texels, then the texture maps' (`PackedScene::shading`).
    Shading,
    /// The BVH's build layout (the stackless walk's).
    Node,
    /// The BVH depth-first in 16-byte nodes (the stack and threaded walks').
    ThreadedNode,
    /// The BVH collapsed into compressed 8-wide nodes, texel by texel (the wide walk's).
    Wide,
}

impl RecordKind {
    /// Every kind, in the order of the shader's bindings.
    pub const ALL: [RecordKind; 10] = [
        RecordKind::Sphere,
        RecordKind::Triangle,
        RecordKind::TriangleNormals,
        RecordKind::TriangleAttributes,
        RecordKind::Plane,
        RecordKind::Light,
        RecordKind::Shading,
        RecordKind::Node,
        RecordKind::ThreadedNode,
        RecordKind::Wide,
    ];

    /// The records a motion rewrote.
    pub fn moved(moved: MovedRecords) -> &'static [RecordKind] {
        match moved {
            MovedRecords::Spheres => &[RecordKind::Sphere],
            MovedRecords::Triangles => &[RecordKind::Triangle, RecordKind::TriangleNormals],
        }
    }

    /// The array's name in the shader (`load_<name>`, `<name>_records`, `<name>_texels`) and in
    /// messages.
    pub fn name(self) -> &'static str {
        match self {
            RecordKind::Sphere => "sphere",
            RecordKind::Triangle => "triangle",
            RecordKind::TriangleNormals => "triangle_normals",
            RecordKind::TriangleAttributes => "triangle_attributes",
            RecordKind::Plane => "plane",
            RecordKind::Light => "light",
            RecordKind::Shading => "shading",
            RecordKind::Node => "node",
            RecordKind::ThreadedNode => "threaded_node",
            RecordKind::Wide => "wide",
        }
    }
}

/// A scene array the shader reads through `load_<name>(i)`, bound at `binding` in group 0.
#[derive(Clone, Copy, Debug)]
pub struct RecordArray {
    /// Which records.
    pub kind: RecordKind,
    /// The WGSL struct of one record.
    pub wgsl_type: &'static str,
    /// Texels a record takes in texture memory.
    pub texels: usize,
    /// The texels' format in texture memory.
    pub texel_format: TexelFormat,
    /// The binding in group 0.
    pub binding: u32,
    /// Records to declare in uniform mode (uniform arrays have a fixed length).
    pub capacity: usize,
}

/// Where the textures' texels are bound: after the record arrays. They always travel in a texture,
/// whatever the memory mode: images are what texture units are for.
pub(crate) fn texture_pixels_binding(arrays: &[RecordArray]) -> u32 {
    arrays.iter().map(|a| a.binding).max().unwrap_or(0) + 1
}

/// Where the path integrator's two bindings start (its parameters, then its tables' texels): after
/// the ray queries' two, which a scene may or may not use.
pub(crate) fn path_binding(arrays: &[RecordArray]) -> u32 {
    ray_query_binding(arrays) + 2
}

/// Where ray queries' two bindings start ([`crate::gpu::builders::rayquery::AccelStructures`]): after the
/// textures' texels.
pub(crate) fn ray_query_binding(arrays: &[RecordArray]) -> u32 {
    texture_pixels_binding(arrays) + 1
}

/// What kinds of things a scene holds, written into the preamble as constants so that the shader
/// leaves out the code for what the scene lacks. SwiftShader (the browsers' fallback) pays for such
/// code even where no pixel runs it: a frame of the Bunny's triangles took about a fifth less
/// (docs/BENCHMARKS.md). Motion never changes them (spheres stay spheres), so a renderer keeps its
/// pipeline while its scene moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneFeatures {
    /// Spheres.
    pub spheres: bool,
    /// Triangles.
    pub triangles: bool,
    /// Planes.
    pub planes: bool,
    /// A material with a texture.
    pub textures: bool,
    /// A triangle with an attribute block (texture coordinates, vertex colours or tangents).
    pub attributes: bool,
    /// A material with a normal map.
    pub normal_maps: bool,
    /// A glTF material that bounds a volume (KHR_materials_volume).
    pub volumes: bool,
    /// A glTF material (metallic-roughness or unlit).
    pub gltf_materials: bool,
    /// A material that reflects or transmits: rays beyond the primary and shadow rays.
    pub secondary_rays: bool,
    /// A single-sided triangle (`TRIANGLE_SINGLE_SIDED`).
    pub one_sided: bool,
    /// A triangle with alpha MASK.
    pub alpha_mask: bool,
    /// A triangle with alpha BLEND: rays that go on behind a surface.
    pub alpha_blend: bool,
    /// An environment: escaping rays read its radiance, glTF surfaces its irradiance.
    pub environment: bool,
}

impl SceneFeatures {
    /// Every kind: a shader for any scene.
    #[cfg(feature = "internals")]
    pub const ALL: SceneFeatures = SceneFeatures {
        spheres: true,
        triangles: true,
        planes: true,
        textures: true,
        attributes: true,
        normal_maps: true,
        volumes: true,
        gltf_materials: true,
        secondary_rays: true,
        one_sided: true,
        alpha_mask: true,
        alpha_blend: true,
        environment: true,
    };

    /// What `scene` holds, so that the shader compiles in only what it reads.
    pub fn of(scene: &PackedScene) -> SceneFeatures {
        let flags = scene.triangle_flags();
        let environment = scene.globals.scene.environment_map != NONE;
        // The environment's two maps follow the materials'.
        let environment_maps = if environment { 2 } else { 0 };
        SceneFeatures {
            environment,
            one_sided: flags & TRIANGLE_SINGLE_SIDED != 0,
            alpha_mask: flags & TRIANGLE_ALPHA_MASK != 0,
            alpha_blend: flags & TRIANGLE_ALPHA_BLEND != 0,
            spheres: !scene.spheres.is_empty(),
            triangles: !scene.triangles.is_empty(),
            planes: !scene.planes.is_empty(),
            textures: scene.texture_maps.len() > environment_maps,
            attributes: !scene.triangle_attributes.is_empty(),
            normal_maps: scene.materials.iter().any(|m| m.normal_map != NONE),
            volumes: scene.materials.iter().any(|m| m.volume != 0),
            gltf_materials: scene.materials.iter().any(|m| m.model != MODEL_WHITTED),
            // A glTF material always reflects some light: its Fresnel term is never zero.
            secondary_rays: scene
                .materials
                .iter()
                .any(|m| m.model == MODEL_GLTF || m.reflect > 0.0 || m.transmit > 0.0),
        }
    }
}

/// What the tracer's WGSL is composed for: pipeline, memory, walk, depths, record arrays and the
/// scene's features.
pub struct ShaderConfig<'a> {
    /// Fragment or compute.
    pub pipeline: Pipeline,
    /// How the records are bound.
    pub memory: MemoryMode,
    /// The walk.
    pub accel: Accel,
    /// How light is carried: the file of the bounce loop.
    pub integrator: Integrator,
    /// The bounce loop's depth.
    pub max_depth: u32,
    /// Longest root-to-leaf path of the BVH: the traversal stack's size.
    pub bvh_depth: u32,
    /// The record arrays the shader reads.
    pub arrays: &'a [RecordArray],
    /// Width of the scene textures, in texels.
    pub texels_per_row: u32,
    /// Write each pixel's cost (BVH nodes its primary ray tested) instead of its ray count.
    pub write_cost: bool,
    /// What the scene holds.
    pub features: SceneFeatures,
}

/// The tracer's WGSL for `config`: the preamble, the record loaders of its memory mode, the walk,
/// shading, the integrator's bounce loop and the entry point.
pub fn compose(config: &ShaderConfig) -> String {
    let mut source = String::new();
    let w = &mut source;
    if config.accel.needs_ray_queries() {
        // Enable directives come before every declaration.
        writeln!(w, "enable wgpu_ray_query;").unwrap();
    }
    writeln!(
        w,
        "// Generated preamble: {:?} pipeline, memory {:?}, accel {:?}.",
        config.pipeline, config.memory, config.accel
    )
    .unwrap();
    writeln!(w, "const MAX_DEPTH: u32 = {}u;", config.max_depth).unwrap();
    writeln!(
        w,
        "const RAY_STACK_SIZE: u32 = {}u;",
        ray_stack_size(config.max_depth, config.features.alpha_blend)
    )
    .unwrap();
    writeln!(w, "const TEXELS_PER_ROW: u32 = {}u;", config.texels_per_row).unwrap();
    writeln!(w, "const WRITE_COST: bool = {};", config.write_cost).unwrap();
    let features = config.features;
    writeln!(w, "const HAS_SPHERES: bool = {};", features.spheres).unwrap();
    writeln!(w, "const HAS_TRIANGLES: bool = {};", features.triangles).unwrap();
    writeln!(w, "const HAS_PLANES: bool = {};", features.planes).unwrap();
    writeln!(w, "const HAS_TEXTURES: bool = {};", features.textures).unwrap();
    writeln!(w, "const HAS_ATTRIBUTES: bool = {};", features.attributes).unwrap();
    writeln!(w, "const HAS_NORMAL_MAPS: bool = {};", features.normal_maps).unwrap();
    writeln!(w, "const HAS_VOLUMES: bool = {};", features.volumes).unwrap();
    writeln!(w, "const HAS_GLTF_MATERIALS: bool = {};", features.gltf_materials).unwrap();
    writeln!(w, "const HAS_SECONDARY_RAYS: bool = {};", features.secondary_rays).unwrap();
    writeln!(w, "const HAS_ONE_SIDED: bool = {};", features.one_sided).unwrap();
    writeln!(w, "const HAS_ALPHA_MASK: bool = {};", features.alpha_mask).unwrap();
    writeln!(w, "const HAS_ALPHA_BLEND: bool = {};", features.alpha_blend).unwrap();
    writeln!(w, "const HAS_ENVIRONMENT: bool = {};", features.environment).unwrap();
    writeln!(w, "const BVH_STACK_SIZE: u32 = {}u;", config.bvh_depth.max(1)).unwrap();
    writeln!(w, "const COMPUTE_TILE: u32 = {COMPUTE_TILE}u;").unwrap();
    writeln!(w, "@group(0) @binding(0) var<uniform> globals: Globals;").unwrap();
    writeln!(
        w,
        "@group(0) @binding({}) var texture_pixels: texture_2d<f32>;",
        texture_pixels_binding(config.arrays)
    )
    .unwrap();
    if config.accel.needs_ray_queries() {
        let first = ray_query_binding(config.arrays);
        writeln!(
            w,
            "@group(0) @binding({first}) var<storage, read> blas_primitives: array<u32>;"
        )
        .unwrap();
        writeln!(
            w,
            "@group(0) @binding({}) var scene_tlas: acceleration_structure;",
            first + 1
        )
        .unwrap();
    }
    if config.integrator == Integrator::Path {
        let first = path_binding(config.arrays);
        writeln!(w, "@group(0) @binding({first}) var<uniform> path_globals: PathGlobals;").unwrap();
        writeln!(w, "@group(0) @binding({}) var path_texels: texture_2d<f32>;", first + 1).unwrap();
    }
    for array in config.arrays {
        let (name, ty, binding) = (array.kind.name(), array.wgsl_type, array.binding);
        match config.memory {
            MemoryMode::Storage => {
                writeln!(
                    w,
                    "@group(0) @binding({binding}) var<storage, read> {name}_records: array<{ty}>;"
                )
                .unwrap();
                writeln!(w, "fn load_{name}(i: u32) -> {ty} {{ return {name}_records[i]; }}").unwrap();
            }
            MemoryMode::Uniform => {
                let capacity = array.capacity.max(1);
                writeln!(
                    w,
                    "@group(0) @binding({binding}) var<uniform> {name}_records: array<{ty}, {capacity}>;"
                )
                .unwrap();
                writeln!(w, "fn load_{name}(i: u32) -> {ty} {{ return {name}_records[i]; }}").unwrap();
            }
            MemoryMode::Texture => {
                let sample = match array.texel_format {
                    TexelFormat::Float => "f32",
                    TexelFormat::Bits => "u32",
                };
                writeln!(
                    w,
                    "@group(0) @binding({binding}) var {name}_texels: texture_2d<{sample}>;"
                )
                .unwrap();
                let loads: Vec<String> = (0..array.texels)
                    .map(|t| format!("textureLoad({name}_texels, texel_coord(base + {t}u), 0)"))
                    .collect();
                writeln!(
                    w,
                    "fn load_{name}(i: u32) -> {ty} {{ let base = i * {}u; return {name}_from_texels({}); }}",
                    array.texels,
                    loads.join(", ")
                )
                .unwrap();
            }
        }
    }
    let accel = match config.accel {
        Accel::Brute => ACCEL_BRUTE,
        Accel::Stack => ACCEL_STACK,
        Accel::Stackless => ACCEL_STACKLESS,
        Accel::Threaded => ACCEL_THREADED,
        Accel::Wide => ACCEL_WIDE,
        Accel::RayQuery => ACCEL_RAYQUERY,
    };
    source.push('\n');
    source.push_str(&records_source());
    let entry_points = match config.pipeline {
        Pipeline::Fragment => FULLSCREEN,
        Pipeline::Compute => COMPUTE,
    };
    let integrator: &[&str] = match config.integrator {
        Integrator::Whitted => &[WHITTED],
        Integrator::Path => &[SAMPLING, BSDF, PATH],
    };
    let parts = [TEXELS, INTERSECT, MAPS, ADMIT, accel, BRDF, ENVIRONMENT, SHADE, TRACE]
        .into_iter()
        .chain(integrator.iter().copied())
        .chain([PIXEL, entry_points]);
    for part in parts {
        source.push('\n');
        source.push_str(part);
    }
    source
}
