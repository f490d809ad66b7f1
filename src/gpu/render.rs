//! The render pipeline: one full-screen triangle, a passthrough vertex stage, and the tracer in the
//! fragment stage writing two targets (colour + ray count, normal + depth) as f32 bits in rgba32uint.

use super::GpuContext;
use super::readback::Readback;
use super::shader::{ShaderConfig, compose};
use super::threaded::GpuThreadedLayout;
use super::timing::PassTimestamps;
use super::upload::{MemoryMode, SceneResources, SharedBuffers, upload};
use crate::image::Frame;
use crate::render::Accel;
use crate::scene::packed::PackedScene;
use anyhow::bail;
use wgpu::util::DeviceExt;

/// f32 bits in an integer format: colour-renderable on every backend, read back bit for bit.
const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
const TARGET_BYTES_PER_PIXEL: u32 = 16;

/// A triangle whose clip-space corners cover the whole viewport.
const FULLSCREEN_TRIANGLE: [[f32; 2]; 3] = [[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]];

/// A scene uploaded and a pipeline built for it, ready to draw frames.
pub struct GpuRenderer<'a> {
    ctx: &'a GpuContext,
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    globals: wgpu::Buffer,
    /// With shared buffers and the stack or threaded walk: lays out each frame's rebuilt tree.
    threaded_layout: Option<GpuThreadedLayout>,
    vertices: wgpu::Buffer,
    targets: [wgpu::Texture; 2],
    /// Where each frame's targets are copied to be read; kept from frame to frame.
    readbacks: [Readback; 2],
    timer: Option<PassTimestamps>,
}

/// A frame and, where the adapter has timestamp queries, the GPU time of its render pass.
pub struct TimedFrame {
    pub frame: Frame,
    pub gpu_ms: Option<f64>,
    /// The GPU time of the threaded layout of a rebuilt tree, where one ran and was timed.
    pub layout_ms: Option<f64>,
}

impl<'a> GpuRenderer<'a> {
    pub fn new(ctx: &'a GpuContext, scene: &PackedScene, memory: MemoryMode, accel: Accel) -> anyhow::Result<Self> {
        Self::create(ctx, scene, memory, accel, None, false)
    }

    /// A renderer whose frames carry each pixel's cost (BVH nodes its primary ray tested: box tests of
    /// internal nodes, sphere tests of leaves; spheres tested for brute force) in the colour target's
    /// fourth channel instead of its ray count.
    pub fn with_cost(
        ctx: &'a GpuContext,
        scene: &PackedScene,
        memory: MemoryMode,
        accel: Accel,
    ) -> anyhow::Result<Self> {
        Self::create(ctx, scene, memory, accel, None, true)
    }

    /// A renderer that reads its spheres and nodes from `shared` (storage memory): the buffers of a
    /// GPU LBVH builder. `scene.bvh_depth` must bound the depth of the trees it will build. The
    /// stack and threaded walks lay out each frame's tree themselves, after `render_after`'s `prepare`.
    pub fn with_shared_buffers(
        ctx: &'a GpuContext,
        scene: &PackedScene,
        accel: Accel,
        shared: &SharedBuffers,
    ) -> anyhow::Result<Self> {
        Self::create(ctx, scene, MemoryMode::Storage, accel, Some(shared), false)
    }

    fn create(
        ctx: &'a GpuContext,
        scene: &PackedScene,
        memory: MemoryMode,
        accel: Accel,
        shared: Option<&SharedBuffers>,
        write_cost: bool,
    ) -> anyhow::Result<Self> {
        let (width, height) = (scene.width(), scene.height());
        let limits = ctx.limits();
        if width > limits.max_texture_dimension_2d || height > limits.max_texture_dimension_2d {
            bail!(
                "image {width}x{height} is larger than the adapter's maximum texture size {}",
                limits.max_texture_dimension_2d
            );
        }
        if accel.uses_bvh() && shared.is_none() && scene.primitive_count() > 0 && scene.nodes.is_empty() {
            bail!("--accel {accel:?} needs the scene's BVH: build it before rendering");
        }
        let features = ctx.adapter.get_texture_format_features(TARGET_FORMAT);
        if !features.allowed_usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT) {
            bail!("adapter {} cannot render to rgba32uint targets", ctx.describe());
        }
        ctx.checked("uploading the scene and building the pipeline", || {
            let threaded_layout = match shared {
                Some(shared) if matches!(accel, Accel::Stack | Accel::Threaded) => {
                    Some(GpuThreadedLayout::new(ctx, &shared.nodes, scene.primitive_count())?)
                }
                _ => None,
            };
            let shared = shared.map(|shared| SharedBuffers {
                threaded_nodes: threaded_layout.as_ref().map(|layout| layout.threaded.clone()),
                ..shared.clone()
            });
            let resources = upload(ctx, scene, memory, accel, shared.as_ref())?;
            // A rebuilt tree's quantization frame is copied in on the GPU.
            let globals = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("globals"),
                contents: bytemuck::bytes_of(&scene.globals),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
            let source = compose(&ShaderConfig {
                memory,
                accel,
                max_depth: scene.max_depth,
                bvh_depth: scene.bvh_depth,
                arrays: &resources.arrays,
                texels_per_row: resources.texels_per_row,
                write_cost,
            });
            let (pipeline, bind_group) = build_pipeline(ctx, &source, &resources, &globals);
            let vertices = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("fullscreen triangle"),
                contents: bytemuck::cast_slice(&FULLSCREEN_TRIANGLE),
                usage: wgpu::BufferUsages::VERTEX,
            });
            let targets = ["color target", "surface target"].map(|label| {
                ctx.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: TARGET_FORMAT,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            });
            let readbacks = targets
                .each_ref()
                .map(|_| Readback::new(&ctx.device, width, height, TARGET_BYTES_PER_PIXEL));
            Ok(Self {
                ctx,
                pipeline,
                bind_group,
                globals,
                threaded_layout,
                vertices,
                targets,
                readbacks,
                timer: ctx
                    .timestamps
                    .then(|| PassTimestamps::new(&ctx.device, "render pass", 1)),
            })
        })
    }

    /// Draws one frame and reads both targets back.
    pub fn render(&self) -> anyhow::Result<TimedFrame> {
        self.render_after(|_| {})
    }

    /// Records `prepare` (a BVH build, say) and then the frame into one command buffer, so that the
    /// GPU runs both without a round trip to the host; reads both targets back.
    pub fn render_after(&self, prepare: impl FnOnce(&mut wgpu::CommandEncoder)) -> anyhow::Result<TimedFrame> {
        let ctx = self.ctx;
        ctx.checked("rendering", || {
            let size = self.targets[0].size();
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            prepare(&mut encoder);
            if let Some(layout) = &self.threaded_layout {
                layout.encode(&mut encoder);
                layout.encode_frame_copy(&mut encoder, &self.globals);
            }
            self.encode_pass(&mut encoder);
            for (readback, target) in self.readbacks.iter().zip(&self.targets) {
                readback.copy_from(&mut encoder, target);
            }
            if let Some(timer) = &self.timer {
                timer.resolve(&mut encoder);
            }
            ctx.queue.submit([encoder.finish()]);
            let [color, surface] = self.readbacks.each_ref().map(|r| r.read(&ctx.device));
            let mut frame = Frame::new(size.width, size.height);
            frame.color = bytemuck::pod_collect_to_vec(&color?);
            frame.surface = bytemuck::pod_collect_to_vec(&surface?);
            let gpu_ms = match &self.timer {
                Some(timer) => Some(timer.read_ms(ctx)?[0]),
                None => None,
            };
            let layout_ms = match &self.threaded_layout {
                Some(layout) => layout.read_ms(ctx)?,
                None => None,
            };
            Ok(TimedFrame {
                frame,
                gpu_ms,
                layout_ms,
            })
        })
    }

    fn encode_pass(&self, encoder: &mut wgpu::CommandEncoder) {
        let views = self.targets.each_ref().map(|t| t.create_view(&Default::default()));
        let attachments = views.each_ref().map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("trace"),
            color_attachments: &attachments,
            depth_stencil_attachment: None,
            timestamp_writes: self.timer.as_ref().map(|t| t.render_writes(0)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.draw(0..3, 0..1);
    }
}

fn build_pipeline(
    ctx: &GpuContext,
    source: &str,
    resources: &SceneResources,
    globals: &wgpu::Buffer,
) -> (wgpu::RenderPipeline, wgpu::BindGroup) {
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("trace"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let mut layout_entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }];
    layout_entries.extend_from_slice(&resources.layout_entries);
    let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &layout_entries,
    });
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: globals.as_entire_binding(),
    }];
    entries.extend(resources.bind_entries());
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene"),
        layout: &bind_group_layout,
        entries: &entries,
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("trace"),
        bind_group_layouts: &[Some(&bind_group_layout)],
        immediate_size: 0,
    });
    let target = Some(wgpu::ColorTargetState {
        format: TARGET_FORMAT,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("trace"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 8,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x2],
            })],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[target.clone(), target],
        }),
        multiview_mask: None,
        cache: None,
    });
    (pipeline, bind_group)
}
