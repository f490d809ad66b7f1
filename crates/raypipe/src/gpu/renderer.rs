//! The renderer: one full-screen triangle, a passthrough vertex stage, and the tracer in the
//! fragment stage writing the frame targets (colour and ray count, normal and depth, as f32 bits in
//! rgba32uint); or, with [`Pipeline::Compute`], the same tracer in a compute kernel writing the same
//! targets as storage textures. With a BVH walk over a tree the host built, the triangle is drawn
//! under scissors around the tiles the tree's top boxes project to, and the pixels outside get a
//! traced miss's result from a shader that traces nothing ([`super::region`]). It owns its handles and its
//! targets, records its work into a caller's encoder, and never reads back unless asked: a window
//! shows the targets through [`super::display::Display`], files and tests read them with
//! [`Renderer::read_frame`].
//!
//! Samples accumulate: the targets come in two pairs, and each draw adds one sample per pixel to
//! the sums in one pair while writing the other ([`Renderer::encode`]); a camera, scene or size
//! change starts again from the pixel centres ([`Renderer::restart`]).

use super::rayquery::AccelStructures;
use super::readback::TextureReadback;
use super::region::{BoxCover, TracedPixels};
use super::shader::{RecordKind, SceneFeatures, ShaderConfig, compose, ray_query_binding};
use super::threaded::encode_frame_copy;
use super::timing::PassTimestamps;
use super::upload::{SceneResources, SharedBuffers, upload};
use super::{GpuContext, GpuError};
use crate::error::MissingBvh;
use crate::image::Frame;
use crate::modes::Count;
use crate::modes::{Accel, BlasOrder, MemoryMode, Pipeline};
use crate::records::packed::MovedRecords;
use crate::records::{GpuCamera, GpuGlobals, PackedScene};
use crate::scene::Camera;
use wgpu::util::DeviceExt;

/// f32 bits in an integer format: colour-renderable on every backend, read back bit for bit.
pub const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
const TARGET_BYTES_PER_PIXEL: u32 = 16;

/// A triangle whose clip-space corners cover the whole viewport.
const FULLSCREEN_TRIANGLE: [[f32; 2]; 3] = [[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]];
/// The compute kernel's workgroup side (`@workgroup_size(8, 8)` in compute.wgsl).
use super::shader::COMPUTE_TILE;

/// The shader stage that runs the tracer: what its bindings are visible to.
pub(super) fn tracer_stage(pipeline: Pipeline) -> wgpu::ShaderStages {
    match pipeline {
        Pipeline::Fragment => wgpu::ShaderStages::FRAGMENT,
        Pipeline::Compute => wgpu::ShaderStages::COMPUTE,
    }
}

/// How a renderer traces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RendererOptions {
    /// The stage that traces: the fragment shader of a full-screen triangle, or a compute kernel.
    pub pipeline: Pipeline,
    /// How the scene's records reach the shader.
    pub memory: MemoryMode,
    /// Brute force, or one of the BVH walks.
    pub accel: Accel,
    /// What the colour target's fourth channel counts.
    pub count: Count,
    /// With ray queries: the order the driver's structures get the primitives in.
    pub blas_order: BlasOrder,
}

/// The tracer's outputs, one texel per pixel: colour (rgb linear radiance, a the count, both summed
/// over the samples so far) and surface (xyz first-hit normal, w its distance or `DEPTH_MISS`, of
/// the centre sample), both f32 bits.
pub struct FrameTargets {
    /// Linear radiance and the count, summed over the samples (rgba32uint of f32 bits).
    pub color: wgpu::Texture,
    /// The centre sample's first-hit normal and distance (rgba32uint of f32 bits).
    pub surface: wgpu::Texture,
    /// A view of `color`, as the display pass reads it.
    pub color_view: wgpu::TextureView,
    /// A view of `surface`.
    pub surface_view: wgpu::TextureView,
    /// Samples per pixel summed in the colour target (0 before the first draw).
    samples: u32,
}

impl FrameTargets {
    fn new(device: &wgpu::Device, width: u32, height: u32, pipeline: Pipeline) -> Self {
        let written_as = match pipeline {
            Pipeline::Fragment => wgpu::TextureUsages::RENDER_ATTACHMENT,
            Pipeline::Compute => wgpu::TextureUsages::STORAGE_BINDING,
        };
        let [color, surface] = ["color target", "surface target"].map(|label| {
            device.create_texture(&wgpu::TextureDescriptor {
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
                usage: written_as | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        });
        Self {
            color_view: color.create_view(&Default::default()),
            surface_view: surface.create_view(&Default::default()),
            color,
            surface,
            samples: 0,
        }
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.color.width(), self.color.height())
    }

    /// Samples per pixel summed in the colour target (0 before the first draw).
    pub fn samples(&self) -> u32 {
        self.samples
    }
}

/// Two pairs of targets that take turns: a draw reads the sums in one and writes the other.
struct Accumulation {
    targets: [FrameTargets; 2],
    /// `reads[k]` binds `targets[k]` as the previous sample's, for a draw into `targets[1 - k]`
    /// (which a compute kernel finds bound beside them).
    reads: [wgpu::BindGroup; 2],
    /// The pair holding the latest sums.
    current: usize,
    /// The next draw starts the sums again.
    restarted: bool,
}

impl Accumulation {
    fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, width: u32, height: u32, pipeline: Pipeline) -> Self {
        let targets = [0, 1].map(|_| FrameTargets::new(device, width, height, pipeline));
        let reads = [0, 1].map(|k| {
            let view = |binding, view| wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(view),
            };
            let (read, written) = (&targets[k], &targets[1 - k]);
            let mut entries = vec![view(0, &read.color_view), view(1, &read.surface_view)];
            if pipeline == Pipeline::Compute {
                entries.extend([view(2, &written.color_view), view(3, &written.surface_view)]);
            }
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("previous sample"),
                layout,
                entries: &entries,
            })
        });
        Self {
            targets,
            reads,
            current: 0,
            restarted: true,
        }
    }
}

/// A frame read back and, where the adapter has timestamp queries, the GPU time of its trace pass.
pub struct TimedFrame {
    /// The frame's targets, read back.
    pub frame: Frame,
    /// The trace pass's GPU time in milliseconds, where the adapter has timestamps.
    pub gpu_ms: Option<f64>,
}

/// A scene uploaded and a pipeline built for it, ready to trace frames into its targets.
/// The tracer's pipeline: the full-screen triangle's, or the compute kernel's.
enum TracePipeline {
    Fragment {
        pipeline: wgpu::RenderPipeline,
        /// Where the tracer is confined to the scene's projected box: the shader for the pixels
        /// outside it (`fs_miss`).
        miss: Option<wgpu::RenderPipeline>,
        vertices: wgpu::Buffer,
    },
    Compute(wgpu::ComputePipeline),
}

/// The fragment tracer confined to the pixels where a primary ray can hit the scene
/// ([`super::region`]): the BVH's top boxes, and the pixels they project to from the camera now.
struct Confinement {
    cover: BoxCover,
    pixels: TracedPixels,
}

impl Confinement {
    fn new(scene: &PackedScene, camera: &GpuCamera) -> Option<Self> {
        let cover = BoxCover::new(scene.bvh.as_ref()?)?;
        let pixels = cover.traced_pixels(camera);
        Some(Self { cover, pixels })
    }
}

/// The tracer for one scene on one device: its records uploaded, its pipeline built, its frame
/// targets; it records samples into a caller's encoder ([`Renderer::encode`]) or reads frames back.
pub struct Renderer {
    ctx: GpuContext,
    options: RendererOptions,
    pipeline: TracePipeline,
    bind_group: wgpu::BindGroup,
    /// The layout of the previous sample's targets (group 1).
    previous_layout: wgpu::BindGroupLayout,
    globals: GpuGlobals,
    globals_buffer: wgpu::Buffer,
    accumulation: Accumulation,
    /// Where [`Renderer::read_frame`] copies the targets; sized with them.
    readbacks: [TextureReadback; 2],
    /// With a rebuild's stack or threaded nodes: their quantization frame, copied into the globals
    /// every frame.
    bvh_frame: Option<wgpu::Buffer>,
    /// The scene's arrays, kept to be rewritten ([`Renderer::write_scene`]).
    resources: SceneResources,
    /// Where the fragment tracer runs only on the pixels the BVH's boxes project to
    /// ([`super::region`]): a BVH the host knows (not rebuilt on the GPU), no planes (which no box
    /// holds), the ray count (a cost view counts the misses' box tests too).
    confinement: Option<Confinement>,
    /// With ray queries: the driver's acceleration structures over the scene.
    structures: Option<AccelStructures>,
    /// The structures are built before the next sample: new, their records rewritten, or asked
    /// for ([`Renderer::rebuild_structures`]).
    structures_stale: bool,
    timer: Option<PassTimestamps>,
}

impl Renderer {
    /// A renderer over `scene` and its CPU-built BVH (which the BVH walks need), at the scene's
    /// camera and image size.
    pub async fn new(ctx: &GpuContext, scene: &PackedScene, options: RendererOptions) -> Result<Self, GpuError> {
        let depth = scene.bvh.as_ref().map_or(0, |b| b.depth);
        Self::with_depth_bound(ctx, scene, options, depth).await
    }

    /// [`Renderer::new`] for a scene whose BVH will be rebuilt on the CPU and rewritten with
    /// [`Renderer::write_scene`]: the walk's stack is sized for any tree up to `depth_bound`.
    pub async fn with_depth_bound(
        ctx: &GpuContext,
        scene: &PackedScene,
        options: RendererOptions,
        depth_bound: u32,
    ) -> Result<Self, GpuError> {
        ctx.live()?;
        if options.accel.uses_bvh() && scene.primitive_count() > 0 && scene.bvh.is_none() {
            return Err(MissingBvh { accel: options.accel }.into());
        }
        Self::create(ctx, scene, options, None, depth_bound).await
    }

    /// Rewrites the scene's records in place: the moved spheres of a moving scene and its BVH,
    /// rebuilt on the CPU (the route where no compute shaders rebuild it, as in WebGL2). The scene
    /// must have as many records of each kind as the one the renderer was made with, and a tree no
    /// deeper than the renderer's stack.
    pub fn write_scene(&mut self, scene: &PackedScene) -> Result<(), GpuError> {
        self.write_records(scene, &RecordKind::ALL)
    }

    /// The records a motion moved (`scene` as [`PackedScene::apply`] left it): those this renderer
    /// holds, such as triangles' normals; the ones it reads from a [`SceneRebuild`](super::SceneRebuild) are
    /// that rebuild's to write ([`SceneRebuild::write_moved`](super::SceneRebuild::write_moved)). The samples start again.
    pub fn write_moved(&mut self, scene: &PackedScene, moved: MovedRecords) -> Result<(), GpuError> {
        self.write_records(scene, RecordKind::moved(moved))
    }

    /// [`Renderer::write_scene`] for the arrays of `kinds` only: what a motion moved, and the BVH
    /// rebuilt over it. The samples start again.
    pub fn write_records(&mut self, scene: &PackedScene, kinds: &[RecordKind]) -> Result<(), GpuError> {
        self.resources
            .write(&self.ctx.queue, scene, self.options.accel, kinds)?;
        self.restart();
        let (spheres, triangles) = (
            kinds.contains(&RecordKind::Sphere),
            kinds.contains(&RecordKind::Triangle),
        );
        if let Some(structures) = self.structures.as_ref().filter(|_| spheres || triangles) {
            // The driver's structures built again over the moved primitives, with the next sample.
            structures.write_moved(&self.ctx.queue, scene, spheres, triangles);
            self.structures_stale = true;
        }
        let tree_written = kinds
            .iter()
            .any(|k| matches!(k, RecordKind::Node | RecordKind::ThreadedNode | RecordKind::Wide));
        if self.confinement.is_some() && tree_written {
            // The walks test the new tree's boxes from now on.
            self.confinement = Confinement::new(scene, &self.globals.camera);
        }
        if kinds.contains(&RecordKind::ThreadedNode) {
            self.globals.bvh_frame = scene.globals.bvh_frame;
            let offset = std::mem::offset_of!(GpuGlobals, bvh_frame) as u64;
            self.ctx.queue.write_buffer(
                &self.globals_buffer,
                offset,
                bytemuck::bytes_of(&self.globals.bvh_frame),
            );
        }
        Ok(())
    }

    /// A renderer whose spheres and nodes are `shared`, written by compute passes before each
    /// frame (a [`SceneRebuild`](super::SceneRebuild) makes one: its `renderer`), over trees at
    /// most `depth_bound` deep.
    pub async fn with_shared_buffers(
        ctx: &GpuContext,
        scene: &PackedScene,
        shared: &SharedBuffers,
        depth_bound: u32,
        options: RendererOptions,
    ) -> Result<Self, GpuError> {
        if options.memory != MemoryMode::Storage {
            return Err(GpuError::RebuildNeedsStorage { memory: options.memory });
        }
        Self::create(ctx, scene, options, Some(shared), depth_bound).await
    }

    async fn create(
        ctx: &GpuContext,
        scene: &PackedScene,
        options: RendererOptions,
        shared: Option<&SharedBuffers>,
        bvh_depth: u32,
    ) -> Result<Self, GpuError> {
        let (width, height) = (scene.width(), scene.height());
        check_frame_size(&ctx.limits(), width, height)?;
        let RendererOptions {
            pipeline,
            memory,
            accel,
            count,
            blas_order,
        } = options;
        check_pipeline(ctx, pipeline)?;
        let confined = pipeline == Pipeline::Fragment
            && accel.uses_bvh()
            && count == Count::Rays
            && shared.is_none()
            && scene.planes.is_empty();
        let confinement = confined
            .then(|| Confinement::new(scene, &scene.globals.camera))
            .flatten();
        ctx.checked("uploading the scene and building the pipeline", || {
            let resources = upload(ctx, scene, memory, accel, shared, tracer_stage(pipeline))?;
            // Built with the first sample (`Renderer::encode`).
            let structures = accel
                .needs_ray_queries()
                .then(|| AccelStructures::new(ctx, scene, blas_order, shared.map(|s| s.triangles.clone())))
                .transpose()?;
            let globals = scene.globals;
            let globals_buffer = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("globals"),
                contents: bytemuck::bytes_of(&globals),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
            let source = compose(&ShaderConfig {
                pipeline,
                memory,
                accel,
                max_depth: scene.max_depth,
                bvh_depth,
                arrays: &resources.arrays,
                texels_per_row: resources.texels_per_row,
                write_cost: count == Count::Cost,
                features: SceneFeatures::of(scene),
            });
            let previous_layout = previous_sample_layout(&ctx.device, pipeline);
            let (trace_pipeline, bind_group) = build_pipeline(
                ctx,
                pipeline,
                &source,
                &SceneBindings {
                    globals: &globals_buffer,
                    resources: &resources,
                    structures: structures.as_ref(),
                },
                &previous_layout,
                confinement.is_some(),
            );
            Ok(Self {
                ctx: ctx.clone(),
                options,
                pipeline: trace_pipeline,
                bind_group,
                accumulation: Accumulation::new(&ctx.device, &previous_layout, width, height, pipeline),
                previous_layout,
                globals,
                globals_buffer,
                readbacks: readbacks(&ctx.device, width, height),
                bvh_frame: shared.and_then(|s| s.bvh_frame.clone()),
                resources,
                confinement,
                structures_stale: structures.is_some(),
                structures,
                timer: ctx
                    .timestamps
                    .then(|| PassTimestamps::new(&ctx.device, "trace pass", 1)),
            })
        })
        .await
    }

    /// The modes it traces with.
    pub fn options(&self) -> RendererOptions {
        self.options
    }

    /// The device it was made on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The frame's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.targets().size()
    }

    /// The targets holding the latest sums.
    pub fn targets(&self) -> &FrameTargets {
        &self.accumulation.targets[self.accumulation.current]
    }

    /// Samples per pixel the next draw adds to: those summed in [`Renderer::targets`], or 0 after
    /// a restart.
    pub fn samples(&self) -> u32 {
        if self.accumulation.restarted {
            0
        } else {
            self.targets().samples
        }
    }

    /// The next draw starts the sums again, at the pixel centres.
    pub fn restart(&mut self) {
        self.accumulation.restarted = true;
    }

    /// The pixels the next draw traces: the whole frame, or where the fragment tracer is confined
    /// ([`super::region`]) the tiles the BVH's boxes project to, none where they project to no
    /// pixel. The others get the background, one ray each, as a traced miss would.
    pub fn traced_region(&self) -> TracedPixels {
        match &self.confinement {
            Some(confinement) => confinement.pixels.clone(),
            None => {
                let (width, height) = self.size();
                TracedPixels::whole(width, height)
            }
        }
    }

    /// The camera as the shader reads it.
    pub fn camera(&self) -> GpuCamera {
        self.globals.camera
    }

    /// Points the camera; the next frame sees it, and starts the sums again. One uniform write:
    /// nothing is re-uploaded. The camera it points already changes nothing.
    pub fn set_camera(&mut self, camera: &Camera) {
        let (width, height) = self.size();
        let camera = GpuCamera {
            sample: self.globals.camera.sample,
            ..GpuCamera::new(camera, width, height)
        };
        if camera != self.globals.camera {
            self.write_camera(camera);
        }
    }

    /// Traces frames of `width` x `height` pixels from now on: new targets, and the camera's
    /// aspect follows.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), GpuError> {
        if (width, height) == self.size() {
            return Ok(());
        }
        check_frame_size(&self.ctx.limits(), width, height)?;
        self.accumulation = Accumulation::new(
            &self.ctx.device,
            &self.previous_layout,
            width,
            height,
            self.options.pipeline,
        );
        self.readbacks = readbacks(&self.ctx.device, width, height);
        self.write_camera(GpuCamera {
            aspect: width as f32 / height as f32,
            width: width as f32,
            height: height as f32,
            ..self.globals.camera
        });
        Ok(())
    }

    fn write_camera(&mut self, camera: GpuCamera) {
        self.restart();
        self.globals.camera = camera;
        if let Some(confinement) = &mut self.confinement {
            confinement.pixels = confinement.cover.traced_pixels(&camera);
        }
        let offset = std::mem::offset_of!(GpuGlobals, camera) as u64;
        self.ctx
            .queue
            .write_buffer(&self.globals_buffer, offset, bytemuck::bytes_of(&camera));
    }

    /// Records the next sample per pixel (the first after a restart) into the targets: the trace
    /// pass, and before it, where a rebuild feeds the walks, the copy of its quantization frame into
    /// the globals; with ray queries, the build of the driver's structures where they are new or
    /// their records were rewritten, and with the first sample after a restart where a rebuild
    /// poses their triangles. The sample's index reaches the shader through a queue write, as a
    /// camera does: submit each frame before encoding the next.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(frame) = &self.bvh_frame {
            encode_frame_copy(encoder, frame, &self.globals_buffer);
        }
        if let Some(structures) = &self.structures
            && (self.structures_stale || (structures.follows_gpu() && self.samples() == 0))
        {
            // New or rewritten records, or the triangles a rebuild posed (recorded before, with
            // the first sample after a restart).
            structures.encode_build(encoder);
            self.structures_stale = false;
        }
        let sample = self.samples();
        self.globals.camera.sample = sample;
        let offset = (std::mem::offset_of!(GpuGlobals, camera) + std::mem::offset_of!(GpuCamera, sample)) as u64;
        self.ctx
            .queue
            .write_buffer(&self.globals_buffer, offset, bytemuck::bytes_of(&sample));
        let read = self.accumulation.current;
        let written = &self.accumulation.targets[1 - read];
        let previous = &self.accumulation.reads[read];
        match &self.pipeline {
            TracePipeline::Fragment {
                pipeline,
                miss,
                vertices,
            } => {
                let attachments = [&written.color_view, &written.surface_view].map(|view| {
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
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_bind_group(1, previous, &[]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                let (width, height) = written.size();
                match (&self.confinement, miss) {
                    (Some(confinement), Some(miss)) if !confinement.pixels.is_whole(width, height) => {
                        // Every pixel the misses' way first (a shader that traces nothing), then
                        // the tracer over the boxes' pixels, a scissored draw a rectangle.
                        pass.set_pipeline(miss);
                        pass.draw(0..3, 0..1);
                        pass.set_pipeline(pipeline);
                        for rect in &confinement.pixels.rects {
                            pass.set_scissor_rect(rect.x, rect.y, rect.width, rect.height);
                            pass.draw(0..3, 0..1);
                        }
                    }
                    _ => {
                        pass.set_pipeline(pipeline);
                        pass.draw(0..3, 0..1);
                    }
                }
            }
            TracePipeline::Compute(pipeline) => {
                let (width, height) = written.size();
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("trace"),
                    timestamp_writes: self.timer.as_ref().map(|t| t.compute_writes(0)),
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_bind_group(1, previous, &[]);
                pass.dispatch_workgroups(width.div_ceil(COMPUTE_TILE), height.div_ceil(COMPUTE_TILE), 1);
            }
        }
        if let Some(timer) = &self.timer {
            timer.resolve(encoder);
        }
        let accumulation = &mut self.accumulation;
        accumulation.current = 1 - read;
        accumulation.targets[1 - read].samples = sample + 1;
        accumulation.restarted = false;
    }

    /// GPU milliseconds of the last trace pass submitted and finished, where the adapter has
    /// timestamp queries.
    pub async fn read_gpu_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.timer {
            Some(timer) => Ok(Some(timer.read_ms(&self.ctx).await?[0])),
            None => Ok(None),
        }
    }

    /// With ray queries: builds the driver's acceleration structures again before the next sample,
    /// over the records as they are (as a moving scene's are every frame); for benchmarks that time
    /// the build.
    pub fn rebuild_structures(&mut self) {
        self.structures_stale = self.structures.is_some();
    }

    /// GPU milliseconds of the last build of the driver's acceleration structures submitted and
    /// finished, with ray queries, where the device times work between passes.
    pub async fn read_structures_build_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.structures {
            Some(structures) => structures.read_build_ms(&self.ctx).await,
            None => Ok(None),
        }
    }

    /// Traces one frame, one sample per pixel at the centres, and reads both targets back.
    pub async fn read_frame(&mut self) -> Result<TimedFrame, GpuError> {
        self.read_frame_after(|_| {}).await
    }

    /// Records `prepare` (a BVH rebuild, say) and then the frame into one command buffer, so that
    /// the GPU runs both without a round trip to the host; reads both targets back.
    pub async fn read_frame_after(
        &mut self,
        prepare: impl FnOnce(&mut wgpu::CommandEncoder),
    ) -> Result<TimedFrame, GpuError> {
        self.render_samples(1, prepare).await
    }

    /// Traces `samples` samples per pixel from the start (at least 1), one submission each so that
    /// no submission runs long, with `prepare` recorded before the first; reads the average back
    /// (as [`crate::image::sample_mean`] computes it, for the CPU reference too). The GPU time is the sum of the trace passes'.
    pub async fn render_samples(
        &mut self,
        samples: u32,
        prepare: impl FnOnce(&mut wgpu::CommandEncoder),
    ) -> Result<TimedFrame, GpuError> {
        self.render_samples_with(samples, prepare, |_| {}).await
    }

    /// [`Renderer::render_samples`], calling `sample_done` with the count of samples finished after
    /// each: for progress bars.
    pub async fn render_samples_with(
        &mut self,
        samples: u32,
        prepare: impl FnOnce(&mut wgpu::CommandEncoder),
        mut sample_done: impl FnMut(u32),
    ) -> Result<TimedFrame, GpuError> {
        self.ctx.live()?;
        self.restart();
        let mut prepare = Some(prepare);
        let mut gpu_ms = self.timer.as_ref().map(|_| 0.0);
        let ctx = self.ctx.clone();
        for sample in 0..samples.max(1) {
            ctx.checked("rendering", || {
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                if let Some(prepare) = prepare.take() {
                    prepare(&mut encoder);
                }
                self.encode(&mut encoder);
                ctx.queue.submit([encoder.finish()]);
                Ok(())
            })
            .await?;
            let ms = self.read_gpu_ms().await.map_err(|e| ctx.explain(e))?;
            if let (Some(total), Some(ms)) = (gpu_ms.as_mut(), ms) {
                *total += ms;
            }
            sample_done(sample + 1);
        }
        Ok(TimedFrame {
            frame: self.read_back().await?,
            gpu_ms,
        })
    }

    /// Reads the targets' sums back as a frame: mean radiance, the count's total (rays) or mean
    /// (cost), the centre sample's normal and depth.
    pub async fn read_back(&self) -> Result<Frame, GpuError> {
        self.read_back_detached().await
    }

    /// [`Renderer::read_back`] as a future that borrows nothing: the copies are recorded and
    /// submitted here, so that a host that draws on meanwhile (a web page) reads the frame shown now.
    pub fn read_back_detached(&self) -> impl Future<Output = Result<Frame, GpuError>> + 'static {
        let ctx = self.ctx.clone();
        let targets = self.targets();
        let [color, surface] = self.readbacks.clone();
        let scopes = ctx.error_scopes("reading the frame back");
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        color.encode_copy(&mut encoder, &targets.color);
        surface.encode_copy(&mut encoder, &targets.surface);
        ctx.queue.submit([encoder.finish()]);
        let copied = scopes.pop();
        let (width, height) = self.size();
        let samples = targets.samples().max(1);
        let count = self.options.count;
        async move {
            let read = async {
                copied.await?;
                let mut frame = Frame::new(width, height);
                let sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&color.read(&ctx.device).await?);
                frame.color = sums
                    .into_iter()
                    .map(|sum| crate::image::sample_mean(glam::Vec4::from_array(sum), samples, count))
                    .collect();
                frame.surface = bytemuck::pod_collect_to_vec(&surface.read(&ctx.device).await?);
                Ok(frame)
            };
            read.await.map_err(|e| ctx.explain(e))
        }
    }
}

/// Found before anything is allocated: past the adapter's limits wgpu would fail later, with its own
/// words, after the other targets took their memory.
/// Whether a renderer of `width` x `height` fits a device of `limits`: within its largest texture,
/// and each frame target's read-back buffer within its largest buffer. Checked before anything is
/// allocated.
pub fn check_frame_size(limits: &wgpu::Limits, width: u32, height: u32) -> Result<(), GpuError> {
    let max = limits.max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(GpuError::ImageTooLarge { width, height, max });
    }
    // Each target texture, and its read-back buffer (rows padded), is one allocation; wgpu's largest
    // buffer stands for the adapter's largest allocation.
    let bytes = crate::gpu::readback::padded_bytes_per_row(width * TARGET_BYTES_PER_PIXEL) as u64 * height as u64;
    if bytes > limits.max_buffer_size {
        return Err(GpuError::FrameTooLarge {
            width,
            height,
            bytes,
            max: limits.max_buffer_size,
            max_pixels: limits.max_buffer_size / TARGET_BYTES_PER_PIXEL as u64,
        });
    }
    Ok(())
}

fn readbacks(device: &wgpu::Device, width: u32, height: u32) -> [TextureReadback; 2] {
    [0, 1].map(|_| TextureReadback::new(device, width, height, TARGET_BYTES_PER_PIXEL))
}

/// What the pipeline needs of the adapter beyond the fragment stage's rgba32uint targets.
fn check_pipeline(ctx: &GpuContext, pipeline: Pipeline) -> Result<(), GpuError> {
    let usages = ctx.adapter.get_texture_format_features(TARGET_FORMAT).allowed_usages;
    let unsupported = |what| {
        Err(GpuError::PipelineUnsupported {
            adapter: ctx.describe(),
            pipeline,
            what,
        })
    };
    match pipeline {
        Pipeline::Fragment if !usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT) => {
            unsupported("render to rgba32uint targets")
        }
        Pipeline::Compute
            if !ctx
                .adapter
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS) =>
        {
            unsupported("run compute shaders")
        }
        Pipeline::Compute if !usages.contains(wgpu::TextureUsages::STORAGE_BINDING) => {
            unsupported("write rgba32uint storage textures")
        }
        _ => Ok(()),
    }
}

/// A frame target read by a shader stage (`texture_2d<u32>`) at `binding`.
pub(super) fn target_entry(binding: u32, stage: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stage,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Group 1: the previous sample's colour and surface targets; for the compute kernel, the targets
/// it writes too, as storage textures.
fn previous_sample_layout(device: &wgpu::Device, pipeline: Pipeline) -> wgpu::BindGroupLayout {
    let stage = tracer_stage(pipeline);
    let mut entries = vec![target_entry(0, stage), target_entry(1, stage)];
    if pipeline == Pipeline::Compute {
        entries.extend([2, 3].map(|binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: stage,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: TARGET_FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        }));
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("previous sample"),
        entries: &entries,
    })
}

/// What group 0 of the tracer binds.
#[derive(Clone, Copy)]
struct SceneBindings<'a> {
    /// At binding 0.
    globals: &'a wgpu::Buffer,
    /// The scene's record arrays and the textures' texels.
    resources: &'a SceneResources,
    /// With ray queries, after the texels.
    structures: Option<&'a AccelStructures>,
}

/// Group 0 of the tracer: the globals at binding 0, then the scene's records.
fn scene_bind_group(
    device: &wgpu::Device,
    kind: Pipeline,
    bindings: &SceneBindings,
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let SceneBindings {
        globals,
        resources,
        structures,
    } = *bindings;
    let ray_queries = ray_query_binding(&resources.arrays);
    let mut layout_entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: tracer_stage(kind),
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }];
    layout_entries.extend_from_slice(&resources.layout_entries);
    if let Some(structures) = structures {
        layout_entries.extend(structures.layout_entries(ray_queries, tracer_stage(kind)));
    }
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &layout_entries,
    });
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: globals.as_entire_binding(),
    }];
    entries.extend(resources.bind_entries());
    if let Some(structures) = structures {
        entries.extend(structures.bind_entries(ray_queries));
    }
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene"),
        layout: &layout,
        entries: &entries,
    });
    (layout, bind_group)
}

fn build_pipeline(
    ctx: &GpuContext,
    kind: Pipeline,
    source: &str,
    bindings: &SceneBindings,
    previous_layout: &wgpu::BindGroupLayout,
    with_miss: bool,
) -> (TracePipeline, wgpu::BindGroup) {
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("trace"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let (bind_group_layout, bind_group) = scene_bind_group(device, kind, bindings);
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("trace"),
        bind_group_layouts: &[Some(&bind_group_layout), Some(previous_layout)],
        immediate_size: 0,
    });
    if kind == Pipeline::Compute {
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("trace"),
            layout: Some(&layout),
            module: &module,
            entry_point: Some("cs_main"),
            compilation_options: Default::default(),
            cache: None,
        });
        return (TracePipeline::Compute(pipeline), bind_group);
    }
    let target = Some(wgpu::ColorTargetState {
        format: TARGET_FORMAT,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    });
    let fullscreen = |label, fragment_entry| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
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
                entry_point: Some(fragment_entry),
                compilation_options: Default::default(),
                targets: &[target.clone(), target.clone()],
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    let pipeline = fullscreen("trace", "fs_main");
    let miss = with_miss.then(|| fullscreen("trace misses", "fs_miss"));
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("fullscreen triangle"),
        contents: bytemuck::cast_slice(&FULLSCREEN_TRIANGLE),
        usage: wgpu::BufferUsages::VERTEX,
    });
    (
        TracePipeline::Fragment {
            pipeline,
            miss,
            vertices,
        },
        bind_group,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame target past the largest buffer is refused with its figures whatever the adapter:
    /// under a 1 MiB buffer limit, 512x512 (4 MiB a target) is refused and 128x128 passes.
    #[test]
    fn a_frame_past_the_largest_buffer_is_refused() {
        let limits = wgpu::Limits {
            max_buffer_size: 1 << 20,
            ..wgpu::Limits::default()
        };
        match check_frame_size(&limits, 512, 512) {
            Err(GpuError::FrameTooLarge {
                width: 512,
                height: 512,
                bytes,
                max,
                max_pixels,
            }) => assert_eq!((bytes, max, max_pixels), (4 << 20, 1 << 20, 65536)),
            other => panic!("512x512 under a 1 MiB buffer limit: {other:?}"),
        }
        check_frame_size(&limits, 128, 128).unwrap();
        let side = limits.max_texture_dimension_2d;
        assert!(matches!(
            check_frame_size(&limits, side + 1, 8),
            Err(GpuError::ImageTooLarge { .. })
        ));
    }
}
