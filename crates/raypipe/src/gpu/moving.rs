//! A moving scene, owned whole: its records posed at a time, its tree rebuilt (or refitted) on the
//! GPU where the shader reads storage memory and on the CPU otherwise, the moved records written to
//! its renderer, and the GPU's work recorded before the trace that reads it. The viewer, the page,
//! `render --frames` and `bench --motion` all move scenes through it:
//!
//! 1. [`MovingScene::pose`] a time: the CPU moves what it moves (and builds the tree where it
//!    builds it) and writes what changed;
//! 2. [`MovingScene::encode`] (or [`MovingScene::render_samples`]): the first sample after a pose
//!    records the GPU's skinning and tree build in the same command buffer, ahead of the trace,
//!    so that no round trip to the host separates them.
//!
//! It keeps the last two poses' times ([`Poses`]): each surface's motion between frames follows
//! from them and the scene as loaded.

use crate::bvh::BuildTimings;
use crate::error::InputError;
use crate::gpu::rebuild::SceneRebuild;
use crate::gpu::trace::shader::RecordKind;
use crate::gpu::{GpuContext, GpuError, Renderer, RendererOptions, TimedFrame};
use crate::modes::MemoryMode;
use crate::records::posed::MOTION_BITS;
use crate::records::{PackedScene, PoseOn, PosedScene, Poses};
use crate::scene::Scene;

/// How the tree follows the scene from pose to pose.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TreeUpdate {
    /// Built anew after every pose: the paper's answer to moving objects.
    #[default]
    Rebuild,
    /// Built after the first pose, then only refitted: the boxes recomputed bottom-up over the
    /// moved primitives, the topology kept. Cheaper per frame; the tree's quality decays as the
    /// primitives move away from where it was built. On the GPU only (storage memory).
    Refit,
}

/// Why a moving scene could not be made or posed.
#[derive(Debug, thiserror::Error)]
pub enum MotionError {
    /// The pose leaves the space the tracers reach (or its time is not finite).
    #[error(transparent)]
    Input(#[from] InputError),
    /// The device refused the build, the renderer or a write.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// What one [`MovingScene::pose`] cost on the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseCost {
    /// The motion evaluated: the moved records rewritten on the CPU, or the joint matrices and
    /// morph weights of a skinning pass written, in milliseconds.
    pub pose_ms: f64,
    /// The tree's build on the CPU, by phase, where it is built there.
    pub cpu_build: Option<BuildTimings>,
    /// The moved records (and a tree built on the CPU) written to the GPU, in milliseconds.
    pub upload_ms: f64,
}

/// A moving scene and the renderer that traces it.
pub struct MovingScene {
    posed: PosedScene,
    renderer: Renderer,
    /// The build on the GPU (storage memory); `None` where the CPU builds the tree.
    gpu: Option<GpuTree>,
    cpu_build: Option<BuildTimings>,
}

/// The tree built on the GPU, and whether a pose waits for it.
struct GpuTree {
    /// Boxed: it holds the build's buffers and kernels.
    rebuild: Box<SceneRebuild>,
    update: TreeUpdate,
    /// A pose waits for the skinning and the build, recorded before the next sample.
    pending: bool,
    /// Whether a tree was built yet: a refitting scene refits from then on.
    built: bool,
}

/// The GPU's work that a pose waits for, to record before the next trace.
struct PendingBuild<'a> {
    rebuild: &'a SceneRebuild,
    refit: bool,
}

impl GpuTree {
    /// The work a pose waits for, if one does; the pose counts as built from here.
    fn take_pending(&mut self) -> Option<PendingBuild<'_>> {
        if !std::mem::take(&mut self.pending) {
            return None;
        }
        let refit = self.update == TreeUpdate::Refit && self.built;
        self.built = true;
        Some(PendingBuild {
            rebuild: &self.rebuild,
            refit,
        })
    }
}

impl PendingBuild<'_> {
    /// The skinning pass, where the scene has one, and the tree's build or refit.
    fn record(self, encoder: &mut wgpu::CommandEncoder) {
        if self.refit {
            self.rebuild.encode_refit(encoder);
        } else {
            self.rebuild.encode(encoder);
        }
    }
}

impl MovingScene {
    /// `scene` (as loaded) and a renderer of it with `options`; the tree is built on the GPU where
    /// `options.memory` is storage, and on the CPU otherwise (here, for the first time). A still
    /// scene may be given too: every pose then rebuilds its tree where it stands.
    pub async fn new(
        ctx: &GpuContext,
        scene: &Scene,
        options: RendererOptions,
        update: TreeUpdate,
    ) -> Result<Self, MotionError> {
        let on_gpu = options.memory == MemoryMode::Storage;
        if update == TreeUpdate::Refit && !on_gpu {
            return Err(GpuError::RebuildNeedsStorage { memory: options.memory }.into());
        }
        let on = if on_gpu { PoseOn::Gpu } else { PoseOn::Cpu };
        let mut posed = PosedScene::new(scene, options.accel, on)?;
        let (renderer, gpu, cpu_build) = if on_gpu {
            let rebuild = SceneRebuild::new(ctx, scene, posed.packed(), options.accel, MOTION_BITS).await?;
            if let Some(deform) = rebuild.deform() {
                // Posed as the scene loads (its time 0), until the first pose.
                deform.write_pose(0.0)?;
            }
            let renderer = rebuild.renderer(ctx, posed.packed(), options).await?;
            let gpu = GpuTree {
                rebuild: Box::new(rebuild),
                update,
                // The first tree is built before the first trace, posed or not.
                pending: true,
                built: false,
            };
            (renderer, Some(gpu), None)
        } else {
            let build = posed.build();
            let renderer = Renderer::with_depth_bound(ctx, posed.packed(), options, posed.depth_bound()).await?;
            (renderer, None, build)
        };
        Ok(Self {
            posed,
            renderer,
            gpu,
            cpu_build,
        })
    }

    /// Poses the scene at `t` seconds of its motion and writes what moved; the samples start
    /// again. On the GPU the skinning and the tree's build wait for the next sample; on the CPU the
    /// tree is built here.
    pub fn pose(&mut self, t: f32) -> Result<PoseCost, MotionError> {
        let start = web_time::Instant::now();
        if let Some(deform) = self.gpu.as_ref().and_then(|gpu| gpu.rebuild.deform()) {
            deform.write_pose(t)?;
        }
        let skin_ms = start.elapsed().as_secs_f64() * 1e3;
        let step = self.posed.pose(t)?;
        let start = web_time::Instant::now();
        let packed = self.posed.packed();
        match &mut self.gpu {
            Some(gpu) => {
                if let Some(moved) = step.moved {
                    gpu.rebuild.write_moved(packed, moved);
                    self.renderer.write_moved(packed, moved)?;
                }
                gpu.pending = true;
            }
            None => {
                let mut kinds = step.moved.map_or(&[][..], RecordKind::moved).to_vec();
                if step.build.is_some() {
                    kinds.extend([RecordKind::Node, RecordKind::ThreadedNode, RecordKind::Wide]);
                }
                self.renderer.write_records(packed, &kinds)?;
                self.cpu_build = step.build;
            }
        }
        self.renderer.restart();
        Ok(PoseCost {
            pose_ms: skin_ms + step.pose_ms,
            cpu_build: step.build,
            upload_ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// Records the next sample per pixel, after the GPU's skinning and tree build where a pose
    /// waits for them.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(pending) = self.gpu.as_mut().and_then(GpuTree::take_pending) {
            pending.record(encoder);
        }
        self.renderer.encode(encoder);
    }

    /// Traces `samples` samples per pixel from the first and reads the mean back
    /// ([`Renderer::render_samples`]), the GPU's skinning and tree build recorded before the
    /// first where a pose waits for them.
    pub async fn render_samples(&mut self, samples: u32, sample_done: impl FnMut(u32)) -> Result<TimedFrame, GpuError> {
        let pending = self.gpu.as_mut().and_then(GpuTree::take_pending);
        let prepare = |encoder: &mut wgpu::CommandEncoder| {
            if let Some(pending) = pending {
                pending.record(encoder);
            }
        };
        self.renderer.render_samples(samples, prepare, sample_done).await
    }

    /// The renderer that traces the scene.
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    /// The renderer, to move its camera, resize it, or read its frame back. Its records are this
    /// scene's to write.
    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// The scene as loaded.
    pub fn scene(&self) -> &Scene {
        self.posed.scene()
    }

    /// The records as last posed on the CPU (as loaded, for an animation the GPU skins).
    pub fn packed(&self) -> &PackedScene {
        self.posed.packed()
    }

    /// The times of the last two poses.
    pub fn poses(&self) -> Poses {
        self.posed.poses()
    }

    /// Whether the tree is built on the GPU (storage memory) rather than the CPU.
    pub fn builds_on_gpu(&self) -> bool {
        self.gpu.is_some()
    }

    /// The last tree's build on the CPU, by phase, where it is built there and the walk reads one.
    pub fn cpu_build(&self) -> Option<BuildTimings> {
        self.cpu_build
    }

    /// Each phase of the last tree build, wherever it ran: the CPU's wall clock, or the GPU's time
    /// of the last build submitted and finished (zeros without timestamp queries); `None` where no
    /// tree is built (brute force, ray queries).
    pub async fn read_build(&self) -> Result<Option<BuildTimings>, GpuError> {
        match &self.gpu {
            None => Ok(self.cpu_build),
            Some(gpu) if self.renderer.options().accel.uses_bvh() => Ok(Some(gpu.rebuild.read_timings().await?)),
            Some(_) => Ok(None),
        }
    }

    /// GPU milliseconds of the last structure build on the GPU: the LBVH's phases, or with ray
    /// queries the driver's structures; `None` where the device times neither.
    pub async fn read_gpu_build_ms(&self) -> Result<Option<f64>, GpuError> {
        if self.renderer.options().accel.needs_ray_queries() {
            return self.renderer.read_structures_build_ms().await;
        }
        match &self.gpu {
            Some(_) => Ok(self.read_build().await?.map(|timings| timings.total())),
            None => Ok(None),
        }
    }

    /// GPU milliseconds of the last skinning pass, where the GPU skins the scene and times it.
    pub async fn read_skinning_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.gpu {
            Some(gpu) => gpu.rebuild.read_skinning_ms().await,
            None => Ok(None),
        }
    }

    /// GPU milliseconds of the last refit (with its threaded layout or wide collapse), where the
    /// tree is refitted and the device times it.
    pub async fn read_refit_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.gpu {
            Some(gpu) if gpu.update == TreeUpdate::Refit => gpu.rebuild.read_refit_ms().await,
            _ => Ok(None),
        }
    }
}
