//! What the viewer traces with: the scene packed for its modes, a renderer, and for a moving scene
//! the per-frame rebuild: on the GPU in storage memory, on the CPU otherwise. Rebuilt whole when a
//! mode changes. Building one is async: a window blocks on it, a web page awaits it.
//!
//! A moving scene keeps its packed records: each new time rewrites only the records that move
//! (spheres, or triangles with their normals), then the BVH over them.

use crate::{Modes, ModesError};
use raypipe::bvh::morton::MortonBits;
use raypipe::error::InputError;
use raypipe::gpu::{CpuRebuild, Display, GpuContext, GpuError, Renderer, RendererOptions, SceneRebuild, Shown};
use raypipe::image::tonemap::DisplayTransform;
use raypipe::modes::{Aov, MemoryMode};
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Scene};

/// Why a tracer could not be made or moved.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// The device cannot trace with the modes asked for.
    #[error(transparent)]
    Modes(#[from] ModesError),
    #[error(transparent)]
    Scene(#[from] InputError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// The depth view's far end, in multiples of the distance to the target.
const DEPTH_FAR: f32 = 3.0;
/// The cost view's top, in nodes tested.
const COST_MAX: f32 = 200.0;

pub struct Tracer {
    pub renderer: Renderer,
    /// The primitives' count, for the panel.
    pub primitives: usize,
    /// The BVH's build time on the CPU, where it was built there (once).
    pub cpu_build_ms: Option<f64>,
    /// The time of the motion the scene stands at, in seconds; `None` until it first moves.
    pub time: Option<f32>,
    motion: Motion,
}

/// How the tracer's scene moves, if it does.
enum Motion {
    Still,
    /// Storage memory: the primitives and the BVH rebuilt on the GPU before every frame.
    OnGpu {
        /// Boxed: it holds the build's buffers and kernels, far more than the other variants.
        rebuild: Box<SceneRebuild>,
        /// The records as last posed: each new time rewrites the ones that move.
        packed: PackedScene,
    },
    /// Uniform or texture memory: posed and rebuilt on the CPU, then the records that changed
    /// rewritten in place.
    OnCpu {
        rebuild: CpuRebuild,
        packed: PackedScene,
    },
}

impl Tracer {
    pub async fn new(
        ctx: &GpuContext,
        scene: &Scene,
        modes: &Modes,
        size: (u32, u32),
        camera: &Camera,
    ) -> Result<Self, TraceError> {
        modes.check(ctx)?;
        let mut scene = scene.clone();
        scene.settings.max_depth = modes.depth;
        (scene.settings.width, scene.settings.height) = size;
        let mut packed = PackedScene::new(&scene)?;
        packed.set_camera(camera, size.0, size.1);
        let options = RendererOptions {
            pipeline: modes.pipeline,
            memory: modes.memory,
            accel: modes.accel,
            count: modes.view.count(),
            ..Default::default()
        };
        let primitives = packed.primitive_count();
        let (renderer, cpu_build, motion) = if scene.motion.is_none() {
            let build = modes
                .accel
                .uses_bvh()
                .then(|| packed.build_bvh_with(modes.builder, MortonBits::Bits30));
            (Renderer::new(ctx, &packed, options).await?, build, Motion::Still)
        } else if !modes.builder.follows_motion() {
            return Err(ModesError::BuilderCannotFollowMotion(modes.builder).into());
        } else if modes.memory == MemoryMode::Storage {
            let rebuild = SceneRebuild::new(ctx, &scene, &packed, modes.accel, MortonBits::Bits30).await?;
            let renderer = rebuild.renderer(ctx, &packed, options).await?;
            let rebuild = Box::new(rebuild);
            (renderer, None, Motion::OnGpu { rebuild, packed })
        } else {
            let (rebuild, build) = CpuRebuild::new(&mut packed, modes.accel);
            let bound = rebuild.depth_bound(primitives);
            let renderer = Renderer::with_depth_bound(ctx, &packed, options, bound).await?;
            (renderer, build, Motion::OnCpu { rebuild, packed })
        };
        Ok(Self {
            renderer,
            primitives,
            cpu_build_ms: cpu_build.map(|timings| timings.total()),
            time: None,
            motion,
        })
    }

    /// Records the next sample per pixel; where the scene moves on the GPU, the first after a
    /// restart poses it (skinning) and rebuilds its BVH first.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Motion::OnGpu { rebuild, .. } = &self.motion
            && self.renderer.samples() == 0
        {
            rebuild.encode(encoder);
        }
        self.renderer.encode(encoder);
    }

    /// Moves the scene (as loaded) to `t` seconds of its motion: the moved records written to the
    /// GPU rebuild's buffers, or the BVH rebuilt on the CPU and the moved records and nodes
    /// rewritten. Returns the CPU build's time. The samples start again.
    pub fn pose(&mut self, scene: &Scene, t: f32) -> Result<Option<f64>, TraceError> {
        if scene.motion.is_none() {
            return Ok(None);
        }
        self.time = Some(t);
        self.renderer.restart();
        match &mut self.motion {
            Motion::Still => Ok(None),
            Motion::OnGpu { rebuild, packed } => {
                if let Some(moved) = rebuild.move_to(scene, packed, t)? {
                    self.renderer.write_moved(packed, moved)?;
                }
                Ok(None)
            }
            Motion::OnCpu { rebuild, packed } => {
                let step = rebuild.move_to(scene, packed, t)?;
                rebuild.write(&step, packed, &mut self.renderer)?;
                Ok(step.build.map(|timings| timings.total()))
            }
        }
    }

    /// The GPU time of the last BVH rebuild on the GPU, where the scene is rebuilt there and the
    /// walk reads a tree (with ray queries, the driver's structures' build, where the device times
    /// it); this waits for the frame that ran it.
    pub async fn read_gpu_build_ms(&self) -> Option<f64> {
        match &self.motion {
            Motion::OnGpu { .. } if self.renderer.options().accel.needs_ray_queries() => {
                self.renderer.read_structures_build_ms().await.ok().flatten()
            }
            Motion::OnGpu { rebuild, .. } if self.renderer.options().accel.uses_bvh() => {
                rebuild.read_timings().await.ok().map(|timings| timings.total())
            }
            _ => None,
        }
    }
}

impl Tracer {
    /// Records the display pass: the mean of the samples gathered, shown as `view` into `target`;
    /// the depth view fades out at three times the camera's distance to its target.
    pub fn show(
        &self,
        display: &Display,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        view: Aov,
        transform: DisplayTransform,
        camera: &Camera,
    ) {
        let shown = Shown {
            aov: view,
            depth_far: DEPTH_FAR * (camera.eye - camera.target).length(),
            cost_max: COST_MAX,
            transform,
        };
        display.encode(encoder, self.renderer.targets(), target, &shown);
    }
}

/// The surface's next texture to draw into, or `None` this time: an outdated or lost surface is
/// configured again; a minimized window or a busy compositor is tried again at the next frame.
pub fn next_texture(
    surface: &wgpu::Surface<'_>,
    device: &wgpu::Device,
    config: &wgpu::SurfaceConfiguration,
) -> Option<wgpu::SurfaceTexture> {
    match surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(texture) | wgpu::CurrentSurfaceTexture::Suboptimal(texture) => {
            Some(texture)
        }
        wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
            surface.configure(device, config);
            None
        }
        _ => None,
    }
}

/// The format to present in: a linear one where the surface offers it, since the display pass
/// encodes sRGB itself, as PNG files hold it; `None` where the surface offers none.
pub fn present_format(caps: &wgpu::SurfaceCapabilities) -> Option<wgpu::TextureFormat> {
    caps.formats
        .iter()
        .copied()
        .find(|f| !f.is_srgb())
        .or(caps.formats.first().copied())
}
