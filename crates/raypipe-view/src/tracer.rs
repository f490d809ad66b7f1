//! What the viewer traces with: the scene packed for its modes, a renderer, and for a moving scene
//! the per-frame rebuild: on the GPU in storage memory, on the CPU otherwise. Rebuilt whole when a
//! mode changes. Building one is async: a window blocks on it, a web page awaits it.
//!
//! A moving scene keeps its packed records: each new time rewrites only the records that move
//! (spheres, or triangles with their normals), then the BVH over them.

use crate::Modes;
use raypipe::bvh::lbvh::LbvhBuilder;
use raypipe::bvh::morton::MortonBits;
use raypipe::error::InputError;
use raypipe::gpu::build::depth_bound;
use raypipe::gpu::{Display, GpuContext, GpuError, RecordKind, Renderer, RendererOptions, SceneRebuild};
use raypipe::modes::Aov;
use raypipe::modes::{Accel, MemoryMode};
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Scene};

/// Why a tracer could not be made or moved.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// The device cannot trace with the modes asked for.
    #[error("{0}")]
    Modes(String),
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
    /// For a moving scene in storage memory: its spheres and BVH, rebuilt on the GPU before every
    /// frame.
    pub rebuild: Option<SceneRebuild>,
    /// For a moving scene in uniform or texture memory: the CPU builder that rebuilds its BVH
    /// before every frame, whose records are then rewritten in place.
    pub cpu_rebuild: Option<LbvhBuilder<u64>>,
    /// The primitives' count, for the panel.
    pub primitives: usize,
    /// The BVH's build time on the CPU, where it was built there (once).
    pub cpu_build_ms: Option<f64>,
    /// The time of the motion the scene stands at, in seconds; `None` until it first moves.
    pub time: Option<f32>,
    /// A moving scene's records as last posed: each new time rewrites the ones that move.
    moving: Option<PackedScene>,
}

impl Tracer {
    pub async fn new(
        ctx: &GpuContext,
        scene: &Scene,
        modes: &Modes,
        size: (u32, u32),
        camera: &Camera,
    ) -> Result<Self, TraceError> {
        modes.check(ctx).map_err(TraceError::Modes)?;
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
        };
        let primitives = packed.primitive_count();
        if scene.motion.is_some() && !modes.builder.follows_motion() {
            return Err(TraceError::Modes(format!(
                "the {} builder builds a still scene's tree once; this scene moves, and its tree is rebuilt every frame by the LBVH",
                modes.builder
            )));
        }
        if scene.motion.is_some() && modes.memory != MemoryMode::Storage {
            let mut builder = LbvhBuilder::<u64>::new();
            let mut cpu_build_ms = None;
            if modes.accel.uses_bvh() {
                cpu_build_ms = Some(builder.build(&packed.primitive_boxes(), MortonBits::Bits30).total());
                packed.set_bvh(builder.to_bvh());
            }
            let bound = depth_bound(primitives, MortonBits::Bits30);
            let renderer = Renderer::with_depth_bound(ctx, &packed, options, bound).await?;
            return Ok(Self {
                renderer,
                rebuild: None,
                cpu_rebuild: Some(builder),
                primitives,
                cpu_build_ms,
                time: None,
                moving: Some(packed),
            });
        }
        if scene.motion.is_some() {
            let rebuild = SceneRebuild::new(ctx, &scene, &packed, modes.accel, MortonBits::Bits30).await?;
            let renderer = Renderer::with_rebuild(ctx, &packed, &rebuild, options).await?;
            return Ok(Self {
                renderer,
                rebuild: Some(rebuild),
                cpu_rebuild: None,
                primitives,
                cpu_build_ms: None,
                time: None,
                moving: Some(packed),
            });
        }
        let cpu_build_ms = modes
            .accel
            .uses_bvh()
            .then(|| packed.build_bvh_with(modes.builder, MortonBits::Bits30).total());
        let renderer = Renderer::new(ctx, &packed, options).await?;
        Ok(Self {
            renderer,
            rebuild: None,
            cpu_rebuild: None,
            primitives,
            cpu_build_ms,
            time: None,
            moving: None,
        })
    }

    /// Records the next sample per pixel; where the scene moves on the GPU, the first after a
    /// restart poses it (skinning) and rebuilds its BVH first.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(rebuild) = &self.rebuild
            && self.renderer.samples() == 0
        {
            rebuild.encode(encoder);
        }
        self.renderer.encode(encoder);
    }

    /// Moves the scene (as loaded) to `t` seconds of its motion: the moved records written to the
    /// GPU rebuild's buffers, or the BVH rebuilt on the CPU and the moved records and nodes
    /// rewritten. Returns the CPU build's time. The samples start again.
    pub fn pose(&mut self, scene: &Scene, t: f32, accel: Accel) -> Result<Option<f64>, TraceError> {
        let (Some(motion), Some(packed)) = (&scene.motion, &mut self.moving) else {
            return Ok(None);
        };
        self.time = Some(t);
        self.renderer.restart();
        if let Some(rebuild) = &self.rebuild {
            if let Some(moved) = rebuild.move_to(scene, packed, t)? {
                self.renderer.write_moved(packed, moved)?;
            }
            return Ok(None);
        }
        let moved = packed.apply(&motion.moved(scene, t)?);
        let Some(builder) = &mut self.cpu_rebuild else {
            return Ok(None);
        };
        let mut ms = None;
        let mut kinds = RecordKind::moved(moved).to_vec();
        if accel.uses_bvh() {
            ms = Some(builder.build(&packed.primitive_boxes(), MortonBits::Bits30).total());
            packed.set_bvh(builder.to_bvh());
            kinds.extend([RecordKind::Node, RecordKind::ThreadedNode]);
        }
        self.renderer.write_records(packed, &kinds)?;
        Ok(ms)
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
        camera: &Camera,
    ) {
        let depth_far = DEPTH_FAR * (camera.eye - camera.target).length();
        display.encode(encoder, self.renderer.targets(), target, view, depth_far, COST_MAX);
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
