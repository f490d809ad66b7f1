//! Bringing the scene to the shader: uniform buffers, storage buffers, or rgba32float textures.

use super::GpuContext;
use super::shader::RecordArray;
use crate::render::Accel;
use crate::scene::packed::{GpuRecord, MAX_TEXEL_INTEGER, PackedScene};
use anyhow::bail;
use clap::ValueEnum;
use wgpu::util::DeviceExt;

/// How scene records reach the fragment shader.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum MemoryMode {
    /// Uniform buffers: fast, but small (64 KiB per array on most adapters).
    Uniform,
    /// Storage buffers: up to the adapter's buffer limit.
    #[default]
    Storage,
    /// rgba32float textures read with textureLoad: the route where fragment shaders have no storage
    /// buffers (WebGL2).
    Texture,
}

/// Texture rows are 2048 texels wide: the smallest maximum texture size WebGL2 guarantees.
pub const TEXELS_PER_ROW: u32 = 2048;

/// Buffers that already live on the GPU and replace the scene's own in storage memory: the spheres
/// and nodes of a [`super::build::GpuLbvhBuilder`], rebuilt there every frame, and the threaded
/// nodes laid out from them.
#[derive(Clone)]
pub struct SharedBuffers {
    pub spheres: wgpu::Buffer,
    pub nodes: wgpu::Buffer,
    /// Set by the renderer, which lays them out (`super::threaded`).
    pub threaded_nodes: Option<wgpu::Buffer>,
}

/// The scene's arrays on the GPU, ready to bind.
pub struct SceneResources {
    pub arrays: Vec<RecordArray>,
    pub layout_entries: Vec<wgpu::BindGroupLayoutEntry>,
    resources: Vec<Resource>,
    pub texels_per_row: u32,
}

enum Resource {
    Buffer(wgpu::Buffer),
    Texture(wgpu::TextureView),
}

impl SceneResources {
    pub fn bind_entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        self.arrays
            .iter()
            .zip(&self.resources)
            .map(|(array, resource)| wgpu::BindGroupEntry {
                binding: array.binding,
                resource: match resource {
                    Resource::Buffer(buffer) => buffer.as_entire_binding(),
                    Resource::Texture(view) => wgpu::BindingResource::TextureView(view),
                },
            })
            .collect()
    }
}

pub fn upload(
    ctx: &GpuContext,
    scene: &PackedScene,
    memory: MemoryMode,
    accel: Accel,
    shared: Option<&SharedBuffers>,
) -> anyhow::Result<SceneResources> {
    if shared.is_some() && memory != MemoryMode::Storage {
        bail!("a BVH built on the GPU is read from storage memory: use --memory storage");
    }
    let limits = ctx.limits();
    let texels_per_row = TEXELS_PER_ROW.min(limits.max_texture_dimension_2d);
    let mut out = SceneResources {
        arrays: Vec::new(),
        layout_entries: Vec::new(),
        resources: Vec::new(),
        texels_per_row,
    };
    for (index, (name, records)) in scene_records(scene, accel).into_iter().enumerate() {
        let array = record_array(index, name, records);
        let binding = array.binding;
        let shared_buffer = match (shared, name) {
            (Some(shared), "sphere") => Some(shared.spheres.clone()),
            (Some(shared), "node") => Some(shared.nodes.clone()),
            (Some(shared), "threaded_node") => shared.threaded_nodes.clone(),
            _ => None,
        };
        let (ty, resource) = match memory {
            MemoryMode::Storage if shared_buffer.is_some() => (
                buffer_binding(false),
                Resource::Buffer(shared_buffer.expect("checked by the match guard")),
            ),
            MemoryMode::Uniform | MemoryMode::Storage => {
                let uniform = memory == MemoryMode::Uniform;
                // Bindings may not be empty: an empty array travels as one zeroed record.
                let mut bytes = records.bytes().to_vec();
                if bytes.is_empty() {
                    bytes.resize(records.record_size(), 0);
                }
                let (limit, usage) = if uniform {
                    (limits.max_uniform_buffer_binding_size, wgpu::BufferUsages::UNIFORM)
                } else {
                    (limits.max_storage_buffer_binding_size, wgpu::BufferUsages::STORAGE)
                };
                if bytes.len() as u64 > limit {
                    let hint = if uniform { "; use --memory storage" } else { "" };
                    bail!(
                        "scene too big for --memory {}: {} {name} records need {} bytes, the adapter allows {limit}{hint}",
                        if uniform { "uniform" } else { "storage" },
                        records.len(),
                        bytes.len()
                    );
                }
                let buffer = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(name),
                    contents: &bytes,
                    usage,
                });
                (buffer_binding(uniform), Resource::Buffer(buffer))
            }
            MemoryMode::Texture => {
                // Indices (node links among them) travel as exact floats: below 2^24.
                if records.len() > MAX_TEXEL_INTEGER as usize {
                    bail!(
                        "scene too big for --memory texture: {} {name} records, more than the {MAX_TEXEL_INTEGER} a texel can index; use --memory storage",
                        records.len()
                    );
                }
                let mut texels = records.texel_data();
                let rows = texels.len().div_ceil(texels_per_row as usize).max(1);
                if rows > limits.max_texture_dimension_2d as usize {
                    bail!(
                        "scene too big for --memory texture: {} {name} records need {rows} rows of {texels_per_row} texels, the adapter allows {}",
                        records.len(),
                        limits.max_texture_dimension_2d
                    );
                }
                texels.resize(rows * texels_per_row as usize, [0.0; 4]);
                let size = wgpu::Extent3d {
                    width: texels_per_row,
                    height: rows as u32,
                    depth_or_array_layers: 1,
                };
                let texture = ctx.device.create_texture_with_data(
                    &ctx.queue,
                    &wgpu::TextureDescriptor {
                        label: Some(name),
                        size,
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: wgpu::TextureFormat::Rgba32Float,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                        view_formats: &[],
                    },
                    wgpu::util::TextureDataOrder::LayerMajor,
                    bytemuck::cast_slice(&texels),
                );
                let ty = wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                };
                (ty, Resource::Texture(texture.create_view(&Default::default())))
            }
        };
        out.layout_entries.push(wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty,
            count: None,
        });
        out.resources.push(resource);
        out.arrays.push(array);
    }
    Ok(out)
}

/// The scene's record arrays in binding order (binding 0 is the globals); BVH modes add the nodes.
fn scene_records(scene: &PackedScene, accel: Accel) -> Vec<(&'static str, &dyn RecordSlice)> {
    let mut records: Vec<(&'static str, &dyn RecordSlice)> = vec![
        ("sphere", &scene.spheres),
        ("triangle", &scene.triangles),
        ("triangle_normals", &scene.triangle_normals),
        ("plane", &scene.planes),
        ("light", &scene.lights),
        ("material", &scene.materials),
    ];
    match accel {
        Accel::Brute => {}
        Accel::Stack | Accel::Threaded => records.push(("threaded_node", &scene.threaded_nodes)),
        Accel::Stackless => records.push(("node", &scene.nodes)),
    }
    records
}

/// What the shader declares for each of the scene's arrays.
pub fn record_arrays(scene: &PackedScene, accel: Accel) -> Vec<RecordArray> {
    scene_records(scene, accel)
        .into_iter()
        .enumerate()
        .map(|(index, (name, records))| record_array(index, name, records))
        .collect()
}

/// The array at `index` among the scene's record arrays: bindings follow the globals' 0.
fn record_array(index: usize, name: &'static str, records: &dyn RecordSlice) -> RecordArray {
    RecordArray {
        name,
        wgsl_type: records.wgsl_type(),
        texels: records.texels(),
        binding: index as u32 + 1,
        capacity: records.len(),
    }
}

/// A read-only buffer binding of the fragment stage: uniform or storage.
fn buffer_binding(uniform: bool) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: if uniform {
            wgpu::BufferBindingType::Uniform
        } else {
            wgpu::BufferBindingType::Storage { read_only: true }
        },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// A slice of records of one type, seen without its type so `upload` can loop over arrays.
trait RecordSlice {
    fn wgsl_type(&self) -> &'static str;
    fn texels(&self) -> usize;
    fn record_size(&self) -> usize;
    fn len(&self) -> usize;
    fn bytes(&self) -> &[u8];
    fn texel_data(&self) -> Vec<[f32; 4]>;
}

impl<T: GpuRecord> RecordSlice for Vec<T> {
    fn wgsl_type(&self) -> &'static str {
        T::WGSL_TYPE
    }
    fn texels(&self) -> usize {
        T::TEXELS
    }
    fn record_size(&self) -> usize {
        std::mem::size_of::<T>()
    }
    fn len(&self) -> usize {
        self.as_slice().len()
    }
    fn bytes(&self) -> &[u8] {
        bytemuck::cast_slice(self)
    }
    fn texel_data(&self) -> Vec<[f32; 4]> {
        let mut out = Vec::with_capacity(self.as_slice().len() * T::TEXELS);
        for record in self {
            record.push_texels(&mut out);
        }
        out
    }
}
