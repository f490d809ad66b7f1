//! The driver's own acceleration structures, for [`Accel::RayQuery`](crate::modes::Accel): the
//! scene's primitives in bottom-level structures (BLASes) and one top-level structure (TLAS) over
//! them, built by the driver (on ray-tracing hardware where the GPU has it) and walked in the
//! shader with ray queries (`shaders/accel_rayquery.wgsl`).
//!
//! Each mesh's triangles (a model file's, a glTF primitive's: [`PackedScene::mesh_starts`]) go to up
//! to two BLASes, and the spheres to one, each BLAS one TLAS instance with the identity transform
//! (the scene's instances arrive placed, their triangles copied):
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

use crate::bvh::morton::{MortonBits, centroid_codes};
use crate::gpu::device::timing::PassTimestamps;
use crate::gpu::{GpuContext, GpuError};
use crate::modes::BlasOrder;
use crate::records::PackedScene;
use crate::records::constants::MATERIAL_INDEX_MASK;
use rayon::prelude::*;
use std::ops::Range;
use wgpu::util::DeviceExt;

/// What a BLAS holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BlasKind {
    /// Triangles the driver tests alone: double-sided, without alpha.
    OpaqueTriangles,
    /// Triangles whose hits the shader decides (single-sided, alpha MASK or BLEND): non-opaque.
    ShaderTriangles,
    /// Spheres, as boxes the shader intersects.
    Spheres,
}

/// The scene's primitives in the BLASes' order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct BlasLayout {
    /// The scene primitive (spheres first, then triangles) of each BLAS primitive, the BLASes one
    /// after another: every triangle BLAS before the spheres'.
    pub primitives: Vec<u32>,
    /// Each BLAS's kind and its primitives' range in `primitives`; none is empty.
    pub parts: Vec<(BlasKind, Range<usize>)>,
}

impl BlasLayout {
    /// Each primitive's BLAS (its mesh's, of its kind), and its place there: in `order`, Morton
    /// order of the centroids (30-bit codes over the whole scene's centroid bounds, ties by index)
    /// or the scene's.
    pub fn new(scene: &PackedScene, order: BlasOrder) -> Self {
        let sphere_count = scene.spheres.len() as u32;
        // The triangles' meshes: mesh k starts at mesh_starts[k] (0 before the first start).
        let mut mesh_of = vec![0u32; scene.triangles.len()];
        for (k, &start) in scene.mesh_starts.iter().enumerate() {
            let end = scene.mesh_starts.get(k + 1).map_or(mesh_of.len(), |&e| e as usize);
            mesh_of[start as usize..end].fill(k as u32 + 1);
        }
        let blas_of = |i: u32| {
            if i < sphere_count {
                return (BlasKind::Spheres, 0);
            }
            let t = (i - sphere_count) as usize;
            let kind = if scene.triangles[t].material & !MATERIAL_INDEX_MASK != 0 {
                BlasKind::ShaderTriangles
            } else {
                BlasKind::OpaqueTriangles
            };
            (kind, mesh_of[t])
        };
        let mut primitives: Vec<u32> = (0..scene.primitive_count() as u32).collect();
        let rank = |kind: BlasKind| kind as u32;
        if order == BlasOrder::Morton {
            let codes = centroid_codes(&scene.primitive_boxes(), MortonBits::Bits30);
            primitives.par_sort_unstable_by_key(|&i| {
                let (kind, mesh) = blas_of(i);
                (rank(kind), mesh, codes[i as usize], i)
            });
        } else {
            primitives.par_sort_by_key(|&i| {
                let (kind, mesh) = blas_of(i);
                (rank(kind), mesh)
            });
        }
        // One BLAS per run of one kind and mesh.
        let mut parts: Vec<(BlasKind, Range<usize>)> = Vec::new();
        let mut current = None;
        for (j, &i) in primitives.iter().enumerate() {
            let blas = blas_of(i);
            if current != Some(blas) {
                parts.push((blas.0, j..j));
                current = Some(blas);
            }
            parts.last_mut().expect("pushed above").1.end = j + 1;
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
pub(crate) struct AccelStructures {
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
    /// Creates the structures for `scene`, its primitives in `order`, to be built by
    /// [`AccelStructures::encode_build`]. Its triangles are read from `gpu_triangles` where a
    /// rebuild poses them on the GPU (a buffer with `BLAS_INPUT` usage, holding `scene.triangles`'
    /// records), else from a copy of their own.
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
        let layout = BlasLayout::new(scene, order);
        let limits = ctx.limits();
        let largest = layout.parts.iter().map(|(_, r)| r.len()).max().unwrap_or(0) as u64;
        for (what, needed, allowed) in [
            (
                "instances (one a mesh's BLAS)",
                layout.parts.len() as u64,
                limits.max_tlas_instance_count as u64,
            ),
            (
                "primitives in one BLAS",
                largest,
                limits.max_blas_primitive_count as u64,
            ),
        ] {
            if needed > allowed {
                return Err(GpuError::Limit { what, needed, allowed });
            }
        }
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
        let corners: Vec<u32> = layout
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
        let sphere_order: Vec<u32> = layout
            .primitives
            .iter()
            .copied()
            .filter(|&p| p < sphere_count)
            .collect();
        let boxes = (!sphere_order.is_empty()).then(|| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("ray query sphere boxes"),
                contents: bytemuck::cast_slice(&sphere_boxes(scene, &sphere_order)),
                usage: input,
            })
        });
        // A binding may not be empty: a scene without primitives binds one unread name.
        let names = if layout.primitives.is_empty() {
            vec![0]
        } else {
            layout.primitives.clone()
        };
        let primitives = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray query primitives"),
            contents: bytemuck::cast_slice(&names),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let flags = wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE;
        let blases: Vec<Blas> = layout
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
                        // The triangle BLASes come first, their corners in the same order.
                        first_index: Some(3 * blas.range.start as u32),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::records::constants::TRIANGLE_SINGLE_SIDED;
    use crate::scene::{Material, Scene, Sphere, Triangle};
    use glam::Vec3;

    /// Two meshes of three triangles each along x, one single-sided triangle in the second, and
    /// two spheres.
    fn scene() -> PackedScene {
        let triangle = |x: f32| Triangle {
            vertices: [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 0.5, 0.0, 0.0),
                Vec3::new(x, 0.5, 0.0),
            ],
            ..Triangle::default()
        };
        let scene = Scene {
            materials: vec![Material::default()],
            // Out of order along x, so that the sort has work to do.
            triangles: [5.0, 0.0, 2.0, 7.0, 1.0, 3.0].map(triangle).to_vec(),
            mesh_starts: vec![0, 3],
            spheres: [4.0, -1.0]
                .map(|x| Sphere {
                    center: Vec3::new(x, 0.0, 0.0),
                    radius: 0.25,
                    material: 0,
                })
                .to_vec(),
            ..Scene::default()
        };
        let mut packed = PackedScene::new(&scene).unwrap();
        packed.triangles[4].material |= TRIANGLE_SINGLE_SIDED;
        packed
    }

    #[test]
    fn a_blas_per_mesh_and_kind_in_morton_order() {
        let layout = BlasLayout::new(&scene(), BlasOrder::Morton);
        let parts: Vec<(BlasKind, Vec<u32>)> = layout
            .parts
            .iter()
            .map(|(kind, range)| (*kind, layout.primitives[range.clone()].to_vec()))
            .collect();
        // Primitives: spheres 0 (x 4) and 1 (x -1), then triangles 2.. (x 5, 0, 2 | 7, 1, 3).
        assert_eq!(
            parts,
            vec![
                (BlasKind::OpaqueTriangles, vec![3, 4, 2]),
                (BlasKind::OpaqueTriangles, vec![7, 5]),
                (BlasKind::ShaderTriangles, vec![6]),
                (BlasKind::Spheres, vec![1, 0]),
            ]
        );
    }

    #[test]
    fn the_scene_order_keeps_each_blas_in_file_order() {
        let layout = BlasLayout::new(&scene(), BlasOrder::Scene);
        assert_eq!(layout.primitives, vec![2, 3, 4, 5, 7, 6, 0, 1]);
        assert_eq!(layout.parts.len(), 4);
    }
}
