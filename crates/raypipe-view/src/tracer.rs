//! What the viewer traces with: the scene packed for its modes and a renderer, or for a moving
//! scene the library's [`MovingScene`], which rebuilds its tree on the GPU in storage memory and on
//! the CPU otherwise. Rebuilt whole when a mode changes. Building one is async: a window blocks on
//! it, a web page awaits it.

use crate::{Modes, ModesError};
use raypipe::error::InputError;
use raypipe::gpu::{
    Display, GpuContext, GpuError, MotionError, MovingScene, Renderer, RendererOptions, Shown, TreeUpdate,
};
use raypipe::image::tonemap::DisplayTransform;
use raypipe::modes::Aov;
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
    #[error(transparent)]
    Motion(#[from] MotionError),
}

/// The depth view's far end, in multiples of the distance to the target.
const DEPTH_FAR: f32 = 3.0;
/// The cost view's top, in nodes tested.
const COST_MAX: f32 = 200.0;

pub struct Tracer {
    stage: Stage,
    /// The primitives' count, for the panel.
    pub primitives: usize,
    /// The BVH's build time on the CPU, where it was built there, when the tracer was made.
    pub cpu_build_ms: Option<f64>,
}

/// A still scene's renderer, or a moving scene with its own (boxed alike: either is large).
enum Stage {
    Still(Box<Renderer>),
    Moving(Box<MovingScene>),
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
        scene.settings.integrator = modes.integrator;
        (scene.settings.width, scene.settings.height) = size;
        let options = RendererOptions {
            pipeline: modes.pipeline,
            memory: modes.memory,
            accel: modes.accel,
            count: modes.view.count(),
            ..Default::default()
        };
        if scene.motion.is_none() {
            let mut packed = PackedScene::new(&scene)?;
            packed.set_camera(camera, size.0, size.1);
            let build = modes.accel.uses_bvh().then(|| packed.build_bvh_with(modes.builder));
            return Ok(Self {
                primitives: packed.primitive_count(),
                stage: Stage::Still(Box::new(Renderer::new(ctx, &packed, options).await?)),
                cpu_build_ms: build.map(|timings| timings.total()),
            });
        }
        if !modes.builder.follows_motion() {
            return Err(ModesError::BuilderCannotFollowMotion(modes.builder).into());
        }
        scene.camera = *camera;
        let moving = MovingScene::new(ctx, &scene, options, TreeUpdate::Rebuild).await?;
        Ok(Self {
            primitives: moving.packed().primitive_count(),
            cpu_build_ms: moving.cpu_build().map(|timings| timings.total()),
            stage: Stage::Moving(Box::new(moving)),
        })
    }

    pub fn renderer(&self) -> &Renderer {
        match &self.stage {
            Stage::Still(renderer) => renderer,
            Stage::Moving(moving) => moving.renderer(),
        }
    }

    pub fn renderer_mut(&mut self) -> &mut Renderer {
        match &mut self.stage {
            Stage::Still(renderer) => renderer,
            Stage::Moving(moving) => moving.renderer_mut(),
        }
    }

    /// The time of the motion the scene stands at, in seconds; `None` until it first moves.
    pub fn time(&self) -> Option<f32> {
        match &self.stage {
            Stage::Still(_) => None,
            Stage::Moving(moving) => moving.poses().current,
        }
    }

    /// Records the next sample per pixel; where the scene moves on the GPU, the first after a
    /// pose skins it and rebuilds its BVH first.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        match &mut self.stage {
            Stage::Still(renderer) => renderer.encode(encoder),
            Stage::Moving(moving) => moving.encode(encoder),
        }
    }

    /// Moves the scene to `t` seconds of its motion ([`MovingScene::pose`]). Returns the CPU
    /// build's time, where the tree is built there. The samples start again.
    pub fn pose(&mut self, t: f32) -> Result<Option<f64>, TraceError> {
        let Stage::Moving(moving) = &mut self.stage else {
            return Ok(None);
        };
        Ok(moving.pose(t)?.cpu_build.map(|timings| timings.total()))
    }

    /// The GPU time of the last BVH rebuild on the GPU, where the scene is rebuilt there and the
    /// walk reads a tree (with ray queries, the driver's structures' build, where the device times
    /// it); this waits for the frame that ran it.
    pub async fn read_gpu_build_ms(&self) -> Option<f64> {
        match &self.stage {
            Stage::Moving(moving) if moving.builds_on_gpu() => moving.read_gpu_build_ms().await.ok().flatten(),
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
        display.encode(encoder, self.renderer().targets(), target, &shown);
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
