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

mod frame;
mod pipelines;
mod targets;

use pipelines::{SceneBindings, TracePipeline, build_pipeline, check_pipeline};
pub(crate) use targets::target_entry;
use targets::{Accumulation, previous_sample_layout, readbacks, tracer_stage};
pub use targets::{FrameTargets, TARGET_FORMAT, check_frame_size};

use super::region::{BoxCover, TracedPixels};
use super::shader::{RecordKind, SceneFeatures, ShaderConfig, compose};
use super::upload::{SceneResources, upload};
use crate::error::MissingBvh;
use crate::gpu::builders::rayquery::AccelStructures;
use crate::gpu::builders::shared::SharedBuffers;
use crate::gpu::device::readback::TextureReadback;
use crate::gpu::device::timing::PassTimestamps;
use crate::gpu::{GpuContext, GpuError};
use crate::image::Frame;
use crate::modes::Count;
use crate::modes::{Accel, BlasOrder, MemoryMode, Pipeline};
use crate::records::packed::MovedRecords;
use crate::records::{GpuCamera, GpuGlobals, GpuPathGlobals, PackedScene};
use crate::scene::Camera;
use wgpu::util::DeviceExt;

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

/// A frame read back and, where the adapter has timestamp queries, the GPU time of its trace pass.
pub struct TimedFrame {
    /// The frame's targets, read back.
    pub frame: Frame,
    /// The trace pass's GPU time in milliseconds, where the adapter has timestamps.
    pub gpu_ms: Option<f64>,
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
    /// holds, such as triangles' normals; the ones it reads from [`SharedBuffers`] are their
    /// builder's to write (a [`MovingScene`](crate::gpu::MovingScene) does both). The samples start
    /// again.
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
    /// frame (a [`MovingScene`](crate::gpu::MovingScene) makes one: its `renderer`), over trees at
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
                integrator: scene.integrator,
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
                source,
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

    /// The path integrator's epoch from the next sample on (the scene's until this sets another):
    /// a frame's number, so that a sequence's frames draw other numbers, and frames split across
    /// runs draw what one run draws ([`PackedScene::path`]'s epoch is what the CPU twin draws
    /// with). Restarts keep it. One uniform write, as a camera's; the samples start again.
    pub fn set_epoch(&mut self, epoch: u32) {
        self.restart();
        if let Some(path) = &self.resources.path {
            let offset = std::mem::offset_of!(GpuPathGlobals, epoch) as u64;
            self.ctx
                .queue
                .write_buffer(&path.globals, offset, bytemuck::bytes_of(&epoch));
        }
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
