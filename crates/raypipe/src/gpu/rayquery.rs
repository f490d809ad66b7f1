//! The driver's own acceleration structures, for [`Accel::RayQuery`](crate::modes::Accel): the
//! scene's primitives in bottom-level structures (BLASes) and one top-level structure (TLAS) over
//! them, built by the driver (on ray-tracing hardware where the GPU has it) and walked in the
//! shader with ray queries (`shaders/accel_rayquery.wgsl`).
//!
//! The primitives go to up to three BLASes, each one TLAS instance with the identity transform:
//! - triangles the driver may decide alone (double-sided, no alpha) as opaque triangle geometry;
//! - triangles whose hits the shader decides (single-sided, alpha MASK or BLEND) as non-opaque
//!   triangle geometry, each met handed to the shader as a candidate for the walks' own hit test;
//! - spheres as boxes (AABB geometry), intersected in the shader.
//!
//! Each BLAS holds its primitives in Morton order: a driver that builds its tree in the order it is
//! given (lavapipe's does) builds a good tree from it, where the file's order made lavapipe's tree
//! some 90 times slower to trace (docs/BENCHMARKS.md). A storage array names the scene primitive
//! (spheres first, then triangles, as the BVH walks name them) of each BLAS primitive: an instance's
//! custom index is where its BLAS's names start.

use super::timing::PassTimestamps;
use super::{GpuContext, GpuError};
use crate::bvh::morton::{MortonBits, centroid_codes};
use crate::modes::BlasOrder;
use crate::records::PackedScene;
use crate::records::constants::MATERIAL_INDEX_MASK;
use rayon::prelude::*;
use std::ops::Range;
use wgpu::util::DeviceExt;

/// What a BLAS holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlasKind {
    /// Triangles the driver tests alone: double-sided, without alpha.
    OpaqueTriangles,
    /// Triangles whose hits the shader decides (single-sided, alpha MASK or BLEND): non-opaque.
    ShaderTriangles,
    /// Spheres, as boxes the shader intersects.
    Spheres,
}

/// The scene's primitives in the BLASes' order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlasLayout {
    /// The scene primitive (spheres first, then triangles) of each BLAS primitive, the BLASes one
    /// after another.
    pub primitives: Vec<u32>,
    /// Each BLAS's kind and its primitives' range in `primitives`; none is empty.
    pub parts: Vec<(BlasKind, Range<usize>)>,
}

impl BlasLayout {
    /// Each primitive's BLAS, and its place there: in `order`, Morton order of the centroids (30-bit
    /// codes over the whole scene's centroid bounds, ties by index) or the scene's.
    pub fn new(scene: &PackedScene, order: BlasOrder) -> Self {
        let mut sorted: Vec<u32> = (0..scene.primitive_count() as u32).collect();
        if order == BlasOrder::Morton {
            let codes = centroid_codes(&scene.primitive_boxes(), MortonBits::Bits30);
            sorted.par_sort_unstable_by_key(|&i| (codes[i as usize], i));
        }
        let sphere_count = scene.spheres.len() as u32;
        let kind_of = |i: u32| {
            if i < sphere_count {
                BlasKind::Spheres
            } else if scene.triangles[(i - sphere_count) as usize].material & !MATERIAL_INDEX_MASK != 0 {
                BlasKind::ShaderTriangles
            } else {
                BlasKind::OpaqueTriangles
            }
        };
        let mut primitives = Vec::with_capacity(sorted.len());
        let mut parts = Vec::new();
        for kind in [BlasKind::OpaqueTriangles, BlasKind::ShaderTriangles, BlasKind::Spheres] {
            let start = primitives.len();
            primitives.extend(sorted.iter().copied().filter(|&i| kind_of(i) == kind));
            if primitives.len() > start {
                parts.push((kind, start..primitives.len()));
            }
        }
        Self { primitives, parts }
    }
}

/// The identity, as a TLAS instance's 3x4 row-major transform.
const IDENTITY: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// Bytes between a sphere's boxes in the box buffer: min and max corners, 3 floats each.
const BOX_STRIDE: u64 = 24;
/// Bytes between triangle corners in the vertex buffer, which holds the triangle records
/// (`GpuTriangle`: three 16-byte rows, each a corner and a word).
const CORNER_STRIDE: u64 = 16;

struct Blas {
    kind: BlasKind,
    range: Range<usize>,
    blas: wgpu::Blas,
    triangles: Option<wgpu::BlasTriangleGeometrySizeDescriptor>,
    boxes: Option<wgpu::BlasAABBGeometrySizeDescriptor>,
}

/// A scene's BLASes and TLAS on one device, with the buffers they are built from; rebuilt from
/// moved records with [`AccelStructures::write_moved`] and [`AccelStructures::encode_build`], or
/// every frame from triangles that move on the GPU.
///
/// wgpu 30 builds acceleration structures afresh every time: its update mode (`PreferUpdate`,
/// refitting a built structure) is not implemented yet ("only rebuild implemented" in wgpu-core), so
/// a moving scene's structures are rebuilt.
pub struct AccelStructures {
    /// The triangle records, the BLASes' vertices (corner `3 i + k` of triangle `i`): a buffer of
    /// their own, or the records a GPU rebuild poses ([`AccelStructures::follows_gpu`]).
    vertices: Option<wgpu::Buffer>,
    /// Whether the vertices are posed on the GPU every frame, and the structures must be rebuilt
    /// before every frame.
    follows_gpu: bool,
    /// The build's GPU time, where the device times work between passes.
    timer: Option<PassTimestamps>,
    /// The triangle BLASes' corners, three a triangle, in the BLASes' order.
    indices: Option<wgpu::Buffer>,
    /// The spheres' boxes, in the sphere BLAS's order.
    boxes: Option<wgpu::Buffer>,
    /// [`BlasLayout::primitives`], bound for the shader.
    primitives: wgpu::Buffer,
    /// The sphere BLAS's spheres, in its order.
    sphere_order: Vec<u32>,
    blases: Vec<Blas>,
    tlas: wgpu::Tlas,
}

impl AccelStructures {
    /// Creates the structures for `scene`, its primitives in `order`, to be built by [`AccelStructures::encode_build`]. Its
    /// triangles are read from `gpu_triangles` where a rebuild poses them on the GPU (a buffer with
    /// `BLAS_INPUT` usage, holding `scene.triangles`' records), else from a copy of their own.
    pub fn new(
        ctx: &GpuContext,
        scene: &PackedScene,
        order: BlasOrder,
        gpu_triangles: Option<wgpu::Buffer>,
    ) -> Result<Self, GpuError> {
        if !ctx.ray_queries {
            return Err(GpuError::Unsupported {
                adapter: ctx.describe(),
                what: "trace with ray queries (--accel rayquery needs Vulkan, DX12 or Metal ray queries)",
            });
        }
        let device = &ctx.device;
        let order = BlasLayout::new(scene, order);
        let input = wgpu::BufferUsages::BLAS_INPUT | wgpu::BufferUsages::COPY_DST;
        let sphere_count = scene.spheres.len() as u32;
        let follows_gpu = gpu_triangles.is_some();
        let vertices = match gpu_triangles {
            Some(buffer) => Some(buffer),
            None => (!scene.triangles.is_empty()).then(|| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("ray query vertices"),
                    contents: bytemuck::cast_slice(&scene.triangles),
                    usage: input,
                })
            }),
        };
        let corners: Vec<u32> = order
            .primitives
            .iter()
            .filter(|&&p| p >= sphere_count)
            .flat_map(|&p| {
                let first = 3 * (p - sphere_count);
                [first, first + 1, first + 2]
            })
            .collect();
        let indices = (!corners.is_empty()).then(|| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("ray query corners"),
                contents: bytemuck::cast_slice(&corners),
                usage: input,
            })
        });
        let sphere_order: Vec<u32> = order.primitives.iter().copied().filter(|&p| p < sphere_count).collect();
        let boxes = (!sphere_order.is_empty()).then(|| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("ray query sphere boxes"),
                contents: bytemuck::cast_slice(&sphere_boxes(scene, &sphere_order)),
                usage: input,
            })
        });
        // A binding may not be empty: a scene without primitives binds one unread name.
        let names = if order.primitives.is_empty() {
            vec![0]
        } else {
            order.primitives.clone()
        };
        let primitives = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray query primitives"),
            contents: bytemuck::cast_slice(&names),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let flags = wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE;
        let blases: Vec<Blas> = order
            .parts
            .iter()
            .map(|(kind, range)| {
                let count = range.len() as u32;
                let (triangles, boxes, sizes) = match kind {
                    BlasKind::Spheres => {
                        let size = wgpu::BlasAABBGeometrySizeDescriptor {
                            primitive_count: count,
                            flags: wgpu::AccelerationStructureGeometryFlags::NO_DUPLICATE_ANY_HIT_INVOCATION,
                        };
                        let sizes = wgpu::BlasGeometrySizeDescriptors::AABBs {
                            descriptors: vec![size.clone()],
                        };
                        (None, Some(size), sizes)
                    }
                    _ => {
                        let size = wgpu::BlasTriangleGeometrySizeDescriptor {
                            vertex_format: wgpu::VertexFormat::Float32x3,
                            vertex_count: 3 * scene.triangles.len() as u32,
                            index_format: Some(wgpu::IndexFormat::Uint32),
                            index_count: Some(3 * count),
                            flags: if *kind == BlasKind::OpaqueTriangles {
                                wgpu::AccelerationStructureGeometryFlags::OPAQUE
                            } else {
                                wgpu::AccelerationStructureGeometryFlags::NO_DUPLICATE_ANY_HIT_INVOCATION
                            },
                        };
                        let sizes = wgpu::BlasGeometrySizeDescriptors::Triangles {
                            descriptors: vec![size.clone()],
                        };
                        (Some(size), None, sizes)
                    }
                };
                let blas = device.create_blas(
                    &wgpu::CreateBlasDescriptor {
                        label: Some("ray query BLAS"),
                        flags,
                        update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                    },
                    sizes,
                );
                Blas {
                    kind: *kind,
                    range: range.clone(),
                    blas,
                    triangles,
                    boxes,
                }
            })
            .collect();
        let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("ray query TLAS"),
            max_instances: blases.len().max(1) as u32,
            flags,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        for (k, blas) in blases.iter().enumerate() {
            tlas[k] = Some(wgpu::TlasInstance::new(
                &blas.blas,
                IDENTITY,
                blas.range.start as u32,
                0xff,
            ));
        }
        Ok(Self {
            vertices,
            follows_gpu,
            timer: ctx
                .encoder_timestamps
                .then(|| PassTimestamps::new(device, "ray query build", 1)),
            indices,
            boxes,
            primitives,
            sphere_order,
            blases,
            tlas,
        })
    }

    /// Records a build of every BLAS, from the vertex and box buffers as they are then, and of the
    /// TLAS over them.
    pub fn encode_build(&self, encoder: &mut wgpu::CommandEncoder) {
        let entries: Vec<wgpu::BlasBuildEntry> = self
            .blases
            .iter()
            .map(|blas| {
                let geometry = match (&blas.triangles, &blas.boxes) {
                    (Some(size), _) => wgpu::BlasGeometries::TriangleGeometries(vec![wgpu::BlasTriangleGeometry {
                        size,
                        vertex_buffer: self.vertices.as_ref().expect("a triangle BLAS has vertices"),
                        first_vertex: 0,
                        vertex_stride: CORNER_STRIDE,
                        index_buffer: self.indices.as_ref(),
                        first_index: Some(3 * self.triangle_offset(blas) as u32),
                        transform_buffer: None,
                        transform_buffer_offset: None,
                    }]),
                    (None, Some(size)) => wgpu::BlasGeometries::AabbGeometries(vec![wgpu::BlasAabbGeometry {
                        size,
                        stride: BOX_STRIDE,
                        aabb_buffer: self.boxes.as_ref().expect("a sphere BLAS has boxes"),
                        primitive_offset: 0,
                    }]),
                    (None, None) => unreachable!("every BLAS holds triangles or boxes"),
                };
                wgpu::BlasBuildEntry {
                    blas: &blas.blas,
                    geometry,
                }
            })
            .collect();
        if let Some(timer) = &self.timer {
            timer.write(encoder, 0, false);
        }
        encoder.build_acceleration_structures(entries.iter(), [&self.tlas]);
        if let Some(timer) = &self.timer {
            timer.write(encoder, 0, true);
            timer.resolve(encoder);
        }
    }

    /// Whether the triangles are posed on the GPU, so that every frame needs a build first.
    pub fn follows_gpu(&self) -> bool {
        self.follows_gpu
    }

    /// GPU milliseconds of the last build submitted and finished, where the device times work
    /// between passes.
    pub async fn read_build_ms(&self, ctx: &GpuContext) -> Result<Option<f64>, GpuError> {
        match &self.timer {
            Some(timer) => Ok(Some(timer.read_ms(ctx).await?[0])),
            None => Ok(None),
        }
    }

    /// The triangles before `blas` among the triangle BLASes': where its corners start, over 3.
    fn triangle_offset(&self, blas: &Blas) -> usize {
        self.blases
            .iter()
            .take_while(|b| !std::ptr::eq(*b, blas))
            .filter(|b| b.kind != BlasKind::Spheres)
            .map(|b| b.range.len())
            .sum()
    }

    /// Rewrites the vertices (unless the GPU poses them) and boxes from a moved scene's records (as
    /// many as before), as `spheres` and `triangles` say they moved: the next
    /// [`AccelStructures::encode_build`] builds over them.
    pub fn write_moved(&self, queue: &wgpu::Queue, scene: &PackedScene, spheres: bool, triangles: bool) {
        if let Some(vertices) = self.vertices.as_ref().filter(|_| triangles && !self.follows_gpu) {
            queue.write_buffer(vertices, 0, bytemuck::cast_slice(&scene.triangles));
        }
        if let Some(boxes) = self.boxes.as_ref().filter(|_| spheres) {
            queue.write_buffer(boxes, 0, bytemuck::cast_slice(&sphere_boxes(scene, &self.sphere_order)));
        }
    }

    /// The BLASes' kinds and primitive counts, in the TLAS's instance order.
    pub fn blas_sizes(&self) -> Vec<(BlasKind, usize)> {
        self.blases.iter().map(|b| (b.kind, b.range.len())).collect()
    }

    /// The shader's bindings at `first` and after: the primitives' names, then the TLAS.
    pub fn layout_entries(&self, first: u32, stage: wgpu::ShaderStages) -> [wgpu::BindGroupLayoutEntry; 2] {
        [
            wgpu::BindGroupLayoutEntry {
                binding: first,
                visibility: stage,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: first + 1,
                visibility: stage,
                ty: wgpu::BindingType::AccelerationStructure { vertex_return: false },
                count: None,
            },
        ]
    }

    /// What [`AccelStructures::layout_entries`] binds.
    pub fn bind_entries(&self, first: u32) -> [wgpu::BindGroupEntry<'_>; 2] {
        [
            wgpu::BindGroupEntry {
                binding: first,
                resource: self.primitives.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: first + 1,
                resource: self.tlas.as_binding(),
            },
        ]
    }
}

/// The boxes of `order`'s spheres, min and max corners.
fn sphere_boxes(scene: &PackedScene, order: &[u32]) -> Vec<[f32; 6]> {
    order
        .iter()
        .map(|&i| {
            let b = scene.spheres[i as usize].bounds();
            [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z]
        })
        .collect()
}
