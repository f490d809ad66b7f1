//! Bringing the scene to the shader: uniform buffers, storage buffers, or textures (rgba32float, or
//! rgba32uint for records of integers only).

use super::shader::{RecordArray, RecordKind, path_binding, texture_pixels_binding};
use crate::bvh::layout::GpuNode;
use crate::bvh::threaded::GpuThreadedNode;
use crate::bvh::wide::GpuWideTexel;
use crate::gpu::builders::shared::SharedBuffers;
use crate::gpu::{Capacity, GpuContext, GpuError};
use crate::modes::{Accel, Integrator, MemoryMode};
use crate::records::{GpuRecord, MAX_TEXEL_INTEGER, PackedScene, TexelFormat, TexturePixels};
use wgpu::util::DeviceExt;

/// Texture rows are 2048 texels wide: the smallest maximum texture size WebGL2 guarantees.
pub const TEXELS_PER_ROW: u32 = 2048;

/// The scene's arrays on the GPU, ready to bind.
pub struct SceneResources {
    /// The record arrays, in binding order.
    pub arrays: Vec<RecordArray>,
    /// Their bind group layout's entries.
    pub layout_entries: Vec<wgpu::BindGroupLayoutEntry>,
    resources: Vec<Resource>,
    /// Width of the scene textures, in texels.
    pub texels_per_row: u32,
    /// Every texture's texels (rgba16float, `texels_per_row` wide), bound after the arrays.
    texture_pixels: wgpu::TextureView,
    /// With the path integrator: its parameters and tables, bound after the ray queries' place.
    pub path: Option<PathResources>,
}

/// The path integrator's parameters (a uniform buffer the renderer rewrites with each epoch) and
/// tables (rgba32float, `texels_per_row` wide).
pub struct PathResources {
    /// The parameters, `PathGlobals`.
    pub globals: wgpu::Buffer,
    texels: wgpu::TextureView,
}

enum Resource {
    Buffer(wgpu::Buffer),
    /// A buffer another owner writes (a rebuild's spheres and nodes).
    Shared(wgpu::Buffer),
    Texture(wgpu::Texture, wgpu::TextureView),
}

impl SceneResources {
    /// The bind group entries of the scene's arrays, in binding order.
    pub fn bind_entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        let mut entries: Vec<_> = self
            .arrays
            .iter()
            .zip(&self.resources)
            .map(|(array, resource)| wgpu::BindGroupEntry {
                binding: array.binding,
                resource: match resource {
                    Resource::Buffer(buffer) | Resource::Shared(buffer) => buffer.as_entire_binding(),
                    Resource::Texture(_, view) => wgpu::BindingResource::TextureView(view),
                },
            })
            .collect();
        entries.push(wgpu::BindGroupEntry {
            binding: texture_pixels_binding(&self.arrays),
            resource: wgpu::BindingResource::TextureView(&self.texture_pixels),
        });
        if let Some(path) = &self.path {
            let first = path_binding(&self.arrays);
            entries.push(wgpu::BindGroupEntry {
                binding: first,
                resource: path.globals.as_entire_binding(),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: first + 1,
                resource: wgpu::BindingResource::TextureView(&path.texels),
            });
        }
        entries
    }

    /// Rewrites the arrays of the `kinds` given in place with `scene`'s records, which must be as
    /// many as those uploaded (a moving scene, its BVH rebuilt on the CPU): no new buffer, texture
    /// or pipeline. Arrays another owner writes are left to it.
    pub fn write(
        &self,
        queue: &wgpu::Queue,
        scene: &PackedScene,
        accel: Accel,
        kinds: &[RecordKind],
    ) -> Result<(), GpuError> {
        for ((kind, records), (array, resource)) in scene_records(scene, accel)
            .into_iter()
            .zip(self.arrays.iter().zip(&self.resources))
        {
            if !kinds.contains(&kind) {
                continue;
            }
            if records.len() != array.capacity {
                return Err(GpuError::RecordCountChanged {
                    array: kind.name(),
                    records: records.len(),
                    uploaded: array.capacity,
                });
            }
            match resource {
                Resource::Shared(_) => {}
                Resource::Buffer(buffer) => {
                    if !records.bytes().is_empty() {
                        queue.write_buffer(buffer, 0, records.bytes());
                    }
                }
                Resource::Texture(texture, _) => {
                    let mut texels = records.texel_data();
                    texels.resize((texture.width() * texture.height()) as usize, [0; 4]);
                    queue.write_texture(
                        texture.as_image_copy(),
                        bytemuck::cast_slice(&texels),
                        wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(texture.width() * 16),
                            rows_per_image: Some(texture.height()),
                        },
                        texture.size(),
                    );
                }
            }
        }
        Ok(())
    }
}

/// Uploads `scene`'s record arrays in `memory` (buffers or textures; `shared` ones are bound, not
/// written) for shaders of `stage`.
pub fn upload(
    ctx: &GpuContext,
    scene: &PackedScene,
    memory: MemoryMode,
    accel: Accel,
    shared: Option<&SharedBuffers>,
    stage: wgpu::ShaderStages,
) -> Result<SceneResources, GpuError> {
    if shared.is_some() && memory != MemoryMode::Storage {
        return Err(GpuError::RebuildNeedsStorage { memory });
    }
    let limits = ctx.limits();
    let texels_per_row = TEXELS_PER_ROW.min(limits.max_texture_dimension_2d);
    let mut out = SceneResources {
        arrays: Vec::new(),
        layout_entries: Vec::new(),
        resources: Vec::new(),
        texels_per_row,
        texture_pixels: upload_texture_pixels(ctx, &scene.texture_pixels, texels_per_row)?,
        path: None,
    };
    for (index, (kind, records)) in scene_records(scene, accel).into_iter().enumerate() {
        let array = record_array(index, kind, records);
        let name = kind.name();
        let binding = array.binding;
        let shared_buffer = match (shared, kind) {
            (Some(shared), RecordKind::Sphere) => Some(shared.spheres.clone()),
            (Some(shared), RecordKind::Triangle) => Some(shared.triangles.clone()),
            (Some(shared), RecordKind::Node) => Some(shared.nodes.clone()),
            (Some(shared), RecordKind::ThreadedNode) => shared.threaded_nodes.clone(),
            (Some(shared), RecordKind::Wide) => shared.wide.clone(),
            (Some(shared), RecordKind::TriangleNormals) => shared.triangle_normals.clone(),
            _ => None,
        };
        let (ty, resource) = match memory {
            MemoryMode::Storage if shared_buffer.is_some() => (
                buffer_binding(false),
                Resource::Shared(shared_buffer.expect("checked by the match guard")),
            ),
            MemoryMode::Uniform | MemoryMode::Storage => buffer_resource(ctx, memory, name, records)?,
            MemoryMode::Texture => texture_resource(ctx, name, records, texels_per_row)?,
        };
        out.layout_entries.push(wgpu::BindGroupLayoutEntry {
            binding,
            visibility: stage,
            ty,
            count: None,
        });
        out.resources.push(resource);
        out.arrays.push(array);
    }
    out.layout_entries.push(wgpu::BindGroupLayoutEntry {
        binding: texture_pixels_binding(&out.arrays),
        visibility: stage,
        ty: texture_binding(TexelFormat::Float),
        count: None,
    });
    if scene.integrator == Integrator::Path {
        let first = path_binding(&out.arrays);
        out.layout_entries.push(wgpu::BindGroupLayoutEntry {
            binding: first,
            visibility: stage,
            ty: buffer_binding(true),
            count: None,
        });
        out.layout_entries.push(wgpu::BindGroupLayoutEntry {
            binding: first + 1,
            visibility: stage,
            ty: texture_binding(TexelFormat::Float),
            count: None,
        });
        out.path = Some(upload_path_tables(ctx, scene, texels_per_row)?);
    }
    Ok(out)
}

/// The path integrator's parameters and its tables' texels (rgba32float).
fn upload_path_tables(ctx: &GpuContext, scene: &PackedScene, texels_per_row: u32) -> Result<PathResources, GpuError> {
    let globals = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("path globals"),
        contents: bytemuck::bytes_of(&scene.path.globals),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    });
    let texels = texel_view(
        ctx,
        ("path tables", "path table texel"),
        &scene.path.texels,
        wgpu::TextureFormat::Rgba32Float,
        texels_per_row,
    )?;
    Ok(PathResources { globals, texels })
}

/// A record array as a uniform or storage buffer, within the adapter's binding size.
fn buffer_resource(
    ctx: &GpuContext,
    memory: MemoryMode,
    name: &'static str,
    records: &dyn RecordSlice,
) -> Result<(wgpu::BindingType, Resource), GpuError> {
    let limits = ctx.limits();
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
    // Moving scenes rewrite their records in place (`SceneResources::write`).
    let usage = usage | wgpu::BufferUsages::COPY_DST;
    if bytes.len() as u64 > limit {
        return Err(GpuError::TooBig {
            memory,
            array: name,
            records: records.len(),
            needed: Capacity::Bytes(bytes.len() as u64),
            allowed: Capacity::Bytes(limit),
        });
    }
    let buffer = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(name),
        contents: &bytes,
        usage,
    });
    Ok((buffer_binding(uniform), Resource::Buffer(buffer)))
}

/// A record array as texels, `texels_per_row` to a row of a texture.
fn texture_resource(
    ctx: &GpuContext,
    name: &'static str,
    records: &dyn RecordSlice,
    texels_per_row: u32,
) -> Result<(wgpu::BindingType, Resource), GpuError> {
    // Indices (node links among them) travel as exact floats: below 2^24.
    if records.len() > MAX_TEXEL_INTEGER as usize {
        return Err(GpuError::TooBig {
            memory: MemoryMode::Texture,
            array: name,
            records: records.len(),
            needed: Capacity::ExactIndices { records: None },
            allowed: Capacity::ExactIndices {
                records: Some(MAX_TEXEL_INTEGER as u64),
            },
        });
    }
    let mut texels = records.texel_data();
    let rows = texture_rows(ctx, (name, records.len()), texels.len(), texels_per_row)?;
    texels.resize(rows * texels_per_row as usize, [0; 4]);
    let format = records.texel_format();
    let texture = texel_texture(
        ctx,
        name,
        texture_format(format),
        (texels_per_row, rows as u32),
        bytemuck::cast_slice(&texels),
    );
    let view = texture.create_view(&Default::default());
    Ok((texture_binding(format), Resource::Texture(texture, view)))
}

/// The textures' texels in one rgba16float texture, `texels_per_row` wide.
fn upload_texture_pixels(
    ctx: &GpuContext,
    pixels: &TexturePixels,
    texels_per_row: u32,
) -> Result<wgpu::TextureView, GpuError> {
    texel_view(
        ctx,
        ("texture pixels", "texture pixel"),
        &pixels.0,
        wgpu::TextureFormat::Rgba16Float,
        texels_per_row,
    )
}

/// `texels` in a texture of `format`, `texels_per_row` wide, its last row padded with zeros (one
/// texel where there are none: a binding cannot be empty); the names are the texture's label and,
/// for the message where the adapter cannot hold them, what one texel is.
fn texel_view<T: bytemuck::Pod>(
    ctx: &GpuContext,
    (label, texel): (&'static str, &'static str),
    texels: &[T],
    format: wgpu::TextureFormat,
    texels_per_row: u32,
) -> Result<wgpu::TextureView, GpuError> {
    let rows = texture_rows(ctx, (texel, texels.len()), texels.len(), texels_per_row)?;
    let width = if texels.is_empty() { 1 } else { texels_per_row };
    let mut padded = texels.to_vec();
    padded.resize(rows * width as usize, T::zeroed());
    let texture = texel_texture(ctx, label, format, (width, rows as u32), bytemuck::cast_slice(&padded));
    Ok(texture.create_view(&Default::default()))
}

/// The rows `texels` texels take at `texels_per_row` (at least one), or why the adapter's textures
/// cannot hold them; `array` names the records and counts them, for the message.
fn texture_rows(
    ctx: &GpuContext,
    array: (&'static str, usize),
    texels: usize,
    texels_per_row: u32,
) -> Result<usize, GpuError> {
    let rows = texels.div_ceil(texels_per_row as usize).max(1);
    let most = ctx.limits().max_texture_dimension_2d;
    if rows > most as usize {
        return Err(GpuError::TooBig {
            memory: MemoryMode::Texture,
            array: array.0,
            records: array.1,
            needed: Capacity::TextureRows {
                rows: rows as u64,
                texels_per_row: Some(texels_per_row),
            },
            allowed: Capacity::TextureRows {
                rows: most as u64,
                texels_per_row: None,
            },
        });
    }
    Ok(rows)
}

/// A 2D texture of `size` (width, rows) texels of `format`, holding `bytes`: the texel route's
/// arrays and the textures' pixels, read with `textureLoad`.
fn texel_texture(
    ctx: &GpuContext,
    label: &str,
    format: wgpu::TextureFormat,
    size: (u32, u32),
    bytes: &[u8],
) -> wgpu::Texture {
    ctx.device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytes,
    )
}

fn texture_format(format: TexelFormat) -> wgpu::TextureFormat {
    match format {
        TexelFormat::Float => wgpu::TextureFormat::Rgba32Float,
        TexelFormat::Bits => wgpu::TextureFormat::Rgba32Uint,
    }
}

/// How the shader binds a texel texture: unfiltered, read with `textureLoad`.
fn texture_binding(format: TexelFormat) -> wgpu::BindingType {
    let sample_type = match format {
        TexelFormat::Float => wgpu::TextureSampleType::Float { filterable: false },
        TexelFormat::Bits => wgpu::TextureSampleType::Uint,
    };
    wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    }
}

/// The scene's record arrays in binding order (binding 0 is the globals); BVH modes add the nodes.
fn scene_records(scene: &PackedScene, accel: Accel) -> Vec<(RecordKind, &dyn RecordSlice)> {
    let mut records: Vec<(RecordKind, &dyn RecordSlice)> = vec![
        (RecordKind::Sphere, &scene.spheres),
        (RecordKind::Triangle, &scene.triangles),
        (RecordKind::TriangleNormals, &scene.triangle_normals),
        (RecordKind::TriangleAttributes, &scene.triangle_attributes),
        (RecordKind::Plane, &scene.planes),
        (RecordKind::Light, &scene.lights),
        (RecordKind::Shading, &scene.shading),
    ];
    // A scene whose BVH is rebuilt on the GPU has none of its own: its node arrays come shared.
    static NO_NODES: Vec<GpuNode> = Vec::new();
    static NO_THREADED_NODES: Vec<GpuThreadedNode> = Vec::new();
    static NO_WIDE_TEXELS: Vec<GpuWideTexel> = Vec::new();
    let bvh = scene.bvh.as_ref();
    match accel {
        // The driver's structures reach the shader beside these (`crate::gpu::builders::rayquery`).
        Accel::Brute | Accel::RayQuery => {}
        Accel::Stack | Accel::Threaded => records.push((
            RecordKind::ThreadedNode,
            bvh.map_or(&NO_THREADED_NODES, |b| &b.threaded_nodes),
        )),
        Accel::Stackless => records.push((RecordKind::Node, bvh.map_or(&NO_NODES, |b| &b.nodes))),
        Accel::Wide => records.push((RecordKind::Wide, bvh.map_or(&NO_WIDE_TEXELS, |b| b.wide_texels()))),
    }
    records
}

/// What the shader declares for each of the scene's arrays.
#[cfg(feature = "internals")]
pub fn record_arrays(scene: &PackedScene, accel: Accel) -> Vec<RecordArray> {
    scene_records(scene, accel)
        .into_iter()
        .enumerate()
        .map(|(index, (kind, records))| record_array(index, kind, records))
        .collect()
}

/// The array at `index` among the scene's record arrays: bindings follow the globals' 0.
fn record_array(index: usize, kind: RecordKind, records: &dyn RecordSlice) -> RecordArray {
    RecordArray {
        kind,
        wgsl_type: records.wgsl_type(),
        texels: records.texels(),
        texel_format: records.texel_format(),
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
    fn texel_format(&self) -> TexelFormat;
    /// The records' texels, as the bits of `texel_format`'s values.
    fn texel_data(&self) -> Vec<[u32; 4]>;
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
    fn texel_format(&self) -> TexelFormat {
        T::TEXEL_FORMAT
    }
    fn texel_data(&self) -> Vec<[u32; 4]> {
        let mut out = Vec::with_capacity(self.as_slice().len() * T::TEXELS);
        for record in self {
            record.push_texels(&mut out);
        }
        out
    }
}
