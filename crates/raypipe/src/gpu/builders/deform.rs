//! Skinning and morphing on the GPU (`shaders/deform.wgsl`): a moving glTF scene's vertices posed
//! from their rest pose in a compute pass, straight into the triangle records the LBVH build and
//! the tracer read, and their shading normals into the renderer's normal records. The CPU evaluates
//! the clip (a few matrices and weights a frame, [`Animated::instance_poses`]); no vertex crosses
//! between host and GPU after the first upload.
//!
//! The CPU twin is [`Rig::deform`](crate::scene::animation::Rig::deform) with
//! [`CornerNormals::corners`]: the GPU folds the placement into the joints' matrices, which is the
//! same map (the weights sum to one), and groups the faces around a position for smooth normals by
//! the rest pose's positions, where the CPU groups by the posed ones (they differ only where
//! vertices that coincide at rest part).

use crate::error::{Element, InputError};
use crate::gpu::device::compute::{grid, storage_buffer};
use crate::gpu::device::pipelines::PipelineKey;
use crate::gpu::device::timing::PassTimestamps;
use crate::gpu::preamble::records_source;
use crate::gpu::{GpuContext, GpuError};
use crate::records::GpuTriangleNormals;
use crate::scene::animation::{
    Animated, CornerNormals, InstancePose, MAX_INFLUENCES, PlacedInstance, RestPrimitive, Rig,
};
use crate::scene::{MAX_COORDINATE, Motion};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use std::cell::OnceCell;
use std::collections::HashMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

const DEFORM: &str = include_str!("../shaders/deform.wgsl");
/// Invocations per workgroup.
const GROUP: u32 = 256;

/// Where a placed primitive's shading normals come from (deform.wgsl's `NORMALS_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
enum NormalSource {
    Flat = 0,
    File = 1,
    Smooth = 2,
}

impl NormalSource {
    const ALL: [NormalSource; 3] = [NormalSource::Flat, NormalSource::File, NormalSource::Smooth];

    fn wgsl_name(self) -> &'static str {
        match self {
            NormalSource::Flat => "NORMALS_FLAT",
            NormalSource::File => "NORMALS_FILE",
            NormalSource::Smooth => "NORMALS_SMOOTH",
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct DeformParams {
    pub vertex_count: u32,
    pub triangle_count: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct DeformInstance {
    pub vertex_first: u32,
    pub vertex_count: u32,
    pub target_first: u32,
    pub target_count: u32,
    pub matrix_first: u32,
    pub skinned: u32,
    pub weight_first: u32,
    pub normals: u32,
    pub crease_cos: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct DeformVertex {
    pub position: [f32; 3],
    pub instance: u32,
    pub normal: [f32; 3],
    pub _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct DeformInfluences {
    pub joints: [u32; 4],
    pub weights_low: [f32; 4],
    pub weights_high: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct DeformOffset {
    pub position: [f32; 4],
    pub normal: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct DeformTriangle {
    pub corners: [u32; 3],
    pub triangle: u32,
    pub groups: [u32; 3],
    pub instance: u32,
}

/// A vertex as the pass posed it (w unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct PosedVertex {
    pub position: [f32; 4],
    pub normal: [f32; 4],
}

/// A posed face's normal and corner angles, for smooth normals (the pass's own scratch).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct Face {
    pub normal: [f32; 4],
    pub angles: [f32; 4],
}

/// The skinning pass's records with a WGSL twin, for the layout test.
#[rustfmt::skip]
#[cfg(feature = "internals")]
pub const LAYOUTS: &[crate::records::layouts::StructLayout] = &[
    crate::records::layouts::struct_layout!(DeformParams, "DeformParams", [vertex_count, triangle_count]),
    crate::records::layouts::struct_layout!(DeformInstance, "DeformInstance", [
        vertex_first, vertex_count, target_first, target_count, matrix_first, skinned, weight_first, normals,
        crease_cos,
    ]),
    crate::records::layouts::struct_layout!(DeformVertex, "DeformVertex", [position, instance, normal]),
    crate::records::layouts::struct_layout!(DeformInfluences, "DeformInfluences", [joints, weights_low, weights_high]),
    crate::records::layouts::struct_layout!(DeformOffset, "DeformOffset", [position, normal]),
    crate::records::layouts::struct_layout!(DeformTriangle, "DeformTriangle", [corners, triangle, groups, instance]),
    crate::records::layouts::struct_layout!(PosedVertex, "PosedVertex", [position, normal]),
    crate::records::layouts::struct_layout!(Face, "Face", [normal, angles]),
];

/// The kernels' WGSL with its preamble.
pub fn shader_source() -> String {
    let mut preamble = format!("// Generated: src/gpu/builders/deform.rs.\nconst GROUP: u32 = {GROUP}u;\n");
    for source in NormalSource::ALL {
        preamble += &format!("const {}: u32 = {}u;\n", source.wgsl_name(), source as u32);
    }
    format!("{preamble}{}\n{DEFORM}", records_source())
}

/// What the pass reads that never changes: every placed primitive of every animation, its rest
/// vertices, joints, morph offsets and triangles, laid end to end.
#[derive(Debug, Default)]
pub(crate) struct DeformRecords {
    pub instances: Vec<DeformInstance>,
    pub vertices: Vec<DeformVertex>,
    pub influences: Vec<DeformInfluences>,
    pub targets: Vec<DeformOffset>,
    pub triangles: Vec<DeformTriangle>,
    /// Per group of faces around a position: where its entries start, then the entries.
    pub groups: Vec<u32>,
    /// Matrices a frame holds; its morph weights follow them.
    pub matrix_count: u32,
    pub weight_count: u32,
    /// Per placed primitive, the farthest a vertex lies from its mesh's origin at rest with every
    /// morph target at full weight: with the frame's matrices, a bound on where it can go.
    reach: Vec<f32>,
}

impl DeformRecords {
    pub fn new(animations: &[Arc<Animated>]) -> Self {
        let mut out = DeformRecords::default();
        // Entries of each group, by global group number, before they are laid out.
        let mut group_entries: Vec<Vec<u32>> = Vec::new();
        for animated in animations {
            for placed in &animated.placed {
                out.add_instance(&animated.rig, placed, &mut group_entries);
            }
        }
        // The weights follow the matrices in the frame.
        for instance in &mut out.instances {
            instance.weight_first += 16 * out.matrix_count;
        }
        let first_entry = group_entries.len() as u32 + 1;
        let mut start = first_entry;
        for entries in &group_entries {
            out.groups.push(start);
            start += entries.len() as u32;
        }
        out.groups.push(start);
        out.groups.extend(group_entries.into_iter().flatten());
        out
    }

    /// One placed instance: its record, its rest vertices and their influences, its morph
    /// offsets, its faces (grouped around each rest position for smooth normals).
    fn add_instance(&mut self, rig: &Rig, placed: &PlacedInstance, group_entries: &mut Vec<Vec<u32>>) {
        let instance = &rig.instances[placed.instance];
        let rest = &instance.rest;
        let vertex_first = self.vertices.len() as u32;
        let index = self.instances.len() as u32;
        let (normals, crease_cos) = match placed.normals {
            CornerNormals::File => (NormalSource::File, 0.0),
            CornerNormals::Smooth(crease) => (NormalSource::Smooth, crease.to_radians().cos()),
            CornerNormals::Flat => (NormalSource::Flat, 0.0),
        };
        let matrices = instance.skin.map_or(1, |s| rig.skins[s].joints.len()) as u32;
        self.instances.push(DeformInstance {
            vertex_first,
            vertex_count: rest.positions.len() as u32,
            target_first: self.targets.len() as u32,
            target_count: rest.targets.len() as u32,
            matrix_first: self.matrix_count,
            skinned: instance.skin.is_some() as u32,
            weight_first: self.weight_count,
            normals: normals as u32,
            crease_cos,
        });
        self.matrix_count += matrices;
        self.weight_count += rest.targets.len() as u32;
        self.add_vertices(rest, index);
        let reach = self.add_targets(rest);
        self.reach.push(reach);
        let smooth = normals == NormalSource::Smooth;
        self.add_faces(placed, rest, (vertex_first, index), smooth.then_some(group_entries));
    }

    fn add_vertices(&mut self, rest: &RestPrimitive, instance: u32) {
        for (v, &position) in rest.positions.iter().enumerate() {
            let normal = rest.normals.as_ref().map_or(Vec3::ZERO, |n| n[v]);
            self.vertices.push(DeformVertex {
                position: position.to_array(),
                instance,
                normal: normal.to_array(),
                _pad: 0,
            });
            self.influences
                .push(rest.influences.get(v).map_or_else(Default::default, |inf| {
                    let mut joints = [0u32; 4];
                    for (k, &joint) in inf.joints.iter().enumerate().take(MAX_INFLUENCES) {
                        joints[k / 2] |= (joint as u32) << (16 * (k % 2));
                    }
                    DeformInfluences {
                        joints,
                        weights_low: inf.weights[..4].try_into().expect("eight weights"),
                        weights_high: inf.weights[4..].try_into().expect("eight weights"),
                    }
                }));
        }
    }

    /// The morph offsets of every vertex, target by target; returns the farthest a vertex lies
    /// from the origin with every target at full weight.
    fn add_targets(&mut self, rest: &RestPrimitive) -> f32 {
        let mut reach = rest.positions.iter().map(|p| p.length()).fold(0.0, f32::max);
        for target in &rest.targets {
            let offsets = target.positions.as_deref().unwrap_or_default();
            reach += offsets.iter().map(|d| d.length()).fold(0.0, f32::max);
            for v in 0..rest.positions.len() {
                let zero = Vec3::ZERO;
                let position = offsets.get(v).unwrap_or(&zero);
                let normal = target.normals.as_deref().and_then(|n| n.get(v)).unwrap_or(&zero);
                self.targets.push(DeformOffset {
                    position: position.extend(0.0).to_array(),
                    normal: normal.extend(0.0).to_array(),
                });
            }
        }
        reach
    }

    /// The placed triangles (`first` is the instance's first vertex and its index); where
    /// `group_entries` is given (smooth normals), each corner joins the group of the faces around
    /// its rest position.
    fn add_faces(
        &mut self,
        placed: &PlacedInstance,
        rest: &RestPrimitive,
        (vertex_first, instance): (u32, u32),
        mut group_entries: Option<&mut Vec<Vec<u32>>>,
    ) {
        let mut group_of: HashMap<[u32; 3], u32> = HashMap::new();
        for (k, corners) in placed.triangles.iter().enumerate() {
            let face = self.triangles.len() as u32;
            let mut groups = [0u32; 3];
            if let Some(group_entries) = group_entries.as_deref_mut() {
                for (c, &v) in corners.iter().enumerate() {
                    let key = rest.positions[v as usize].to_array().map(f32::to_bits);
                    let group = *group_of.entry(key).or_insert_with(|| {
                        group_entries.push(Vec::new());
                        group_entries.len() as u32 - 1
                    });
                    group_entries[group as usize].push(face * 4 + c as u32);
                    groups[c] = group;
                }
            }
            self.triangles.push(DeformTriangle {
                corners: corners.map(|v| vertex_first + v),
                triangle: (placed.first_triangle + k) as u32,
                groups,
                instance,
            });
        }
    }

    /// The frame's matrices and weights as the pass reads them, after checking that no vertex can
    /// leave the space the tracers reach (the CPU path checks each vertex; here a bound per
    /// primitive from its matrices).
    fn frame(&self, poses: &[InstancePose], t: f32) -> Result<Vec<[f32; 4]>, InputError> {
        let mut matrices: Vec<[f32; 4]> = Vec::with_capacity(4 * self.matrix_count as usize);
        let mut weights: Vec<f32> = Vec::with_capacity(self.weight_count as usize);
        for (index, (pose, &reach)) in poses.iter().zip(&self.reach).enumerate() {
            let scale = pose.weights.iter().fold(1.0f32, |s, w| s.max(w.abs()));
            for m in &pose.matrices {
                if !m.is_finite() || !within_reach(m, reach * scale) {
                    let first = self.triangles.iter().find(|t| t.instance == index as u32);
                    let element = first.map_or(Element::Scene, |t| Element::Triangle(t.triangle as usize));
                    return Err(InputError::of(
                        element,
                        format!("at {t} s the animation may move its mesh out of reach (or to NaN)"),
                    ));
                }
                matrices.extend(m.to_cols_array_2d());
            }
            weights.extend(&pose.weights);
        }
        weights.resize(weights.len().next_multiple_of(4).max(4), 0.0);
        matrices.extend(weights.chunks(4).map(|w| [w[0], w[1], w[2], w[3]]));
        Ok(matrices)
    }
}

/// Whether every point within `reach` of the origin stays within the tracers' space through `m`.
fn within_reach(m: &Mat4, reach: f32) -> bool {
    let linear = m.x_axis.truncate().length() + m.y_axis.truncate().length() + m.z_axis.truncate().length();
    m.w_axis.truncate().abs().max_element() + linear * reach <= MAX_COORDINATE
}

/// The skinning pass's buffers but the build's triangle records, which it writes into.
struct DeformBuffers {
    params: wgpu::Buffer,
    instances: wgpu::Buffer,
    vertices: wgpu::Buffer,
    influences: wgpu::Buffer,
    targets: wgpu::Buffer,
    frame: wgpu::Buffer,
    posed: wgpu::Buffer,
    placed: wgpu::Buffer,
    faces: wgpu::Buffer,
    groups: wgpu::Buffer,
    triangle_normals: wgpu::Buffer,
}

impl DeformBuffers {
    fn new(device: &wgpu::Device, records: &DeformRecords, normals: &[GpuTriangleNormals]) -> Self {
        let init = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            // A binding may not be empty: at least one record of the largest kind (influences).
            let mut bytes = contents.to_vec();
            bytes.resize(bytes.len().max(size_of::<DeformInfluences>()), 0);
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: wgpu::BufferUsages::STORAGE | usage,
            })
        };
        let none = wgpu::BufferUsages::empty();
        let frame_words = 16 * records.matrix_count as u64 + records.weight_count.next_multiple_of(4).max(4) as u64;
        Self {
            params: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("deform params"),
                contents: bytemuck::bytes_of(&DeformParams {
                    vertex_count: records.vertices.len() as u32,
                    triangle_count: records.triangles.len() as u32,
                }),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            instances: init("deform instances", bytemuck::cast_slice(&records.instances), none),
            vertices: init("rest vertices", bytemuck::cast_slice(&records.vertices), none),
            influences: init("joint influences", bytemuck::cast_slice(&records.influences), none),
            targets: init("morph offsets", bytemuck::cast_slice(&records.targets), none),
            frame: storage_buffer(device, "deform frame", frame_words * 4, wgpu::BufferUsages::COPY_DST),
            posed: storage_buffer(
                device,
                "posed vertices",
                (records.vertices.len().max(1) * size_of::<PosedVertex>()) as u64,
                wgpu::BufferUsages::COPY_SRC,
            ),
            placed: init("deform triangles", bytemuck::cast_slice(&records.triangles), none),
            faces: storage_buffer(
                device,
                "faces",
                (records.triangles.len().max(1) * size_of::<Face>()) as u64,
                none,
            ),
            groups: init("face groups", bytemuck::cast_slice(&records.groups), none),
            triangle_normals: init(
                "triangle_normals",
                bytemuck::cast_slice(normals),
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            ),
        }
    }

    /// Every buffer at its binding in deform.wgsl, `triangles` (the build's records) at 10.
    fn bindings<'a>(&'a self, triangles: &'a wgpu::Buffer) -> [&'a wgpu::Buffer; 12] {
        [
            &self.params,
            &self.instances,
            &self.vertices,
            &self.influences,
            &self.targets,
            &self.frame,
            &self.posed,
            &self.placed,
            &self.faces,
            &self.groups,
            triangles,
            &self.triangle_normals,
        ]
    }
}

/// The skinning pass over a scene's animations, writing into a rebuild's triangle records and the
/// normal records it hands the renderer.
pub struct GpuDeform {
    ctx: GpuContext,
    animations: Vec<Arc<Animated>>,
    records: DeformRecords,
    kernels: [wgpu::ComputePipeline; 3],
    bind_groups: [wgpu::BindGroup; 3],
    frame: wgpu::Buffer,
    /// The posed vertices, which the tests read back.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))]
    posed: wgpu::Buffer,
    /// The renderer's normal records, which the pass rewrites.
    pub triangle_normals: wgpu::Buffer,
    timer: Option<PassTimestamps>,
}

impl GpuDeform {
    /// The pass for `motion`'s animations (`None` for motion that is not skinning or morphing),
    /// writing into `triangles` (the build's records); `normals` are the scene's normal records,
    /// uploaded here. Its first [`GpuDeform::write_pose`] comes before its first encode.
    pub async fn new(
        ctx: &GpuContext,
        motion: &Motion,
        triangles: &wgpu::Buffer,
        normals: &[GpuTriangleNormals],
    ) -> Result<Option<Self>, GpuError> {
        let Motion::Animations(animations) = motion else {
            return Ok(None);
        };
        let deform = ctx
            .checked("compiling the GPU skinning pass", || {
                Ok(Self::create(ctx, animations.clone(), triangles, normals))
            })
            .await?;
        Ok(Some(deform))
    }

    fn create(
        ctx: &GpuContext,
        animations: Vec<Arc<Animated>>,
        triangles: &wgpu::Buffer,
        normals: &[GpuTriangleNormals],
    ) -> Self {
        let device = &ctx.device;
        let records = DeformRecords::new(&animations);
        let buffers = DeformBuffers::new(device, &records, normals);
        let source: Arc<str> = shader_source().into();
        let module = OnceCell::new();
        // Each kernel binds only what it reads: all twelve buffers at once exceed the eight storage
        // buffers a stage may have. Layouts come from the kernels.
        let all = buffers.bindings(triangles);
        let kernel = |entry_point: &str, bindings: &[u32]| {
            let key = PipelineKey::new(&source, entry_point, "layout from the kernel".to_string());
            let pipeline = ctx.pipelines.compute(key, || {
                let module = module.get_or_init(|| {
                    device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some("deform"),
                        source: wgpu::ShaderSource::Wgsl(source.to_string().into()),
                    })
                });
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry_point),
                    layout: None,
                    module,
                    entry_point: Some(entry_point),
                    compilation_options: Default::default(),
                    cache: None,
                })
            });
            let entries: Vec<wgpu::BindGroupEntry> = bindings
                .iter()
                .map(|&b| wgpu::BindGroupEntry {
                    binding: b,
                    resource: all[b as usize].as_entire_binding(),
                })
                .collect();
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(entry_point),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
            (pipeline, bind_group)
        };
        let (vertices_kernel, vertices_group) = kernel("deform_vertices", &[0, 1, 2, 3, 4, 5, 6]);
        let (gather_kernel, gather_group) = kernel("gather_triangles", &[0, 1, 6, 7, 8, 10, 11]);
        let (smooth_kernel, smooth_group) = kernel("smooth_normals", &[0, 1, 7, 8, 9, 10, 11]);
        Self {
            ctx: ctx.clone(),
            animations,
            records,
            kernels: [vertices_kernel, gather_kernel, smooth_kernel],
            bind_groups: [vertices_group, gather_group, smooth_group],
            frame: buffers.frame,
            posed: buffers.posed,
            triangle_normals: buffers.triangle_normals,
            timer: ctx.timestamps.then(|| PassTimestamps::new(&ctx.device, "skinning", 1)),
        }
    }

    /// Evaluates the animations at scene time `t` on the CPU and writes the matrices and weights the
    /// next [`GpuDeform::encode`] poses the vertices with. Fails where the pose may leave the space
    /// the tracers reach.
    pub fn write_pose(&self, t: f32) -> Result<(), InputError> {
        if !t.is_finite() {
            return Err(InputError::new(format!("time {t} is not finite")));
        }
        let poses: Vec<InstancePose> = self.animations.iter().flat_map(|a| a.instance_poses(t)).collect();
        let frame = self.records.frame(&poses, t)?;
        self.ctx
            .queue
            .write_buffer(&self.frame, 0, bytemuck::cast_slice(&frame));
        Ok(())
    }

    /// Records the pass: vertices, then triangle records and normals.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let vertices = self.records.vertices.len() as u32;
        let triangles = self.records.triangles.len() as u32;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("skinning"),
            timestamp_writes: self.timer.as_ref().map(|t| t.compute_writes(0)),
        });
        for (k, count) in [vertices, triangles, triangles].into_iter().enumerate() {
            let (x, y) = grid(count.div_ceil(GROUP));
            pass.set_pipeline(&self.kernels[k]);
            pass.set_bind_group(0, &self.bind_groups[k], &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        drop(pass);
        if let Some(timer) = &self.timer {
            timer.resolve(encoder);
        }
    }

    /// GPU time of the last pass submitted and finished, where the adapter has timestamps.
    pub async fn read_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.timer {
            Some(timer) => Ok(Some(timer.read_ms(&self.ctx).await?[0])),
            None => Ok(None),
        }
    }

    /// Vertices the pass poses a frame.
    #[cfg(feature = "internals")]
    pub fn vertex_count(&self) -> usize {
        self.records.vertices.len()
    }

    /// The posed vertices' positions, in the order of `DeformRecords`, for tests.
    #[cfg(feature = "internals")]
    pub async fn read_positions(&self) -> Result<Vec<Vec3>, GpuError> {
        let size = (self.records.vertices.len() * size_of::<PosedVertex>()) as u64;
        if size == 0 {
            return Ok(Vec::new());
        }
        let bytes =
            crate::gpu::device::readback::read_buffer(&self.ctx.device, &self.ctx.queue, &self.posed, size).await?;
        let posed: Vec<PosedVertex> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(posed.iter().map(|v| glam::Vec4::from(v.position).truncate()).collect())
    }
}
