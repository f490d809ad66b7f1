//! What the viewer traces with: the scene packed for its modes, a renderer, and for a moving scene
//! the per-frame rebuild: on the GPU in storage memory, on the CPU otherwise. Rebuilt whole when a
//! mode changes. Building one is async: a window blocks on it, a web page awaits it.

use crate::Modes;
use raypipe::bvh::lbvh::LbvhBuilder;
use raypipe::bvh::morton::MortonBits;
use raypipe::gpu::build::depth_bound;
use raypipe::gpu::{Display, DisplayView, GpuContext, Renderer, RendererOptions, SceneRebuild};
use raypipe::modes::{Accel, Count, MemoryMode};
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Scene};

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
    /// The frame of the motion the scene stands at; `None` until it first moves there.
    pub motion_frame: Option<u32>,
}

impl Tracer {
    pub async fn new(
        ctx: &GpuContext,
        scene: &Scene,
        modes: &Modes,
        size: (u32, u32),
        camera: &Camera,
    ) -> Result<Self, String> {
        let mut scene = scene.clone();
        scene.settings.max_depth = modes.depth;
        (scene.settings.width, scene.settings.height) = size;
        let mut packed = PackedScene::new(&scene).map_err(|e| e.to_string())?;
        packed.set_camera(camera, size.0, size.1);
        let options = RendererOptions {
            pipeline: modes.pipeline,
            memory: modes.memory,
            accel: modes.accel,
            count: if modes.view == raypipe::gpu::DisplayView::Cost {
                Count::Cost
            } else {
                Count::Rays
            },
        };
        let primitives = packed.primitive_count();
        if scene.motion.is_some() && modes.memory != MemoryMode::Storage {
            let mut builder = LbvhBuilder::<u64>::new();
            let mut cpu_build_ms = None;
            if modes.accel.uses_bvh() {
                cpu_build_ms = Some(builder.build(&packed.primitive_boxes(), MortonBits::Bits30).total());
                packed.set_bvh(builder.to_bvh());
            }
            let bound = depth_bound(primitives, MortonBits::Bits30);
            let renderer = Renderer::with_depth_bound(ctx, &packed, options, bound)
                .await
                .map_err(|e| e.to_string())?;
            return Ok(Self {
                renderer,
                rebuild: None,
                cpu_rebuild: Some(builder),
                primitives,
                cpu_build_ms,
                motion_frame: None,
            });
        }
        if scene.motion.is_some() {
            let rebuild = SceneRebuild::new(ctx, &packed, modes.accel, MortonBits::Bits30)
                .await
                .map_err(|e| e.to_string())?;
            let renderer = Renderer::with_rebuild(ctx, &packed, &rebuild, options)
                .await
                .map_err(|e| e.to_string())?;
            return Ok(Self {
                renderer,
                rebuild: Some(rebuild),
                cpu_rebuild: None,
                primitives,
                cpu_build_ms: None,
                motion_frame: None,
            });
        }
        let cpu_build_ms = modes
            .accel
            .uses_bvh()
            .then(|| packed.build_bvh(MortonBits::Bits30).total());
        let renderer = Renderer::new(ctx, &packed, options).await.map_err(|e| e.to_string())?;
        Ok(Self {
            renderer,
            rebuild: None,
            cpu_rebuild: None,
            primitives,
            cpu_build_ms,
            motion_frame: None,
        })
    }

    /// Records the next sample per pixel; the first after a restart rebuilds the BVH on the GPU
    /// first, where the scene moves and the walk uses one.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder, accel: Accel) {
        if let Some(rebuild) = &self.rebuild
            && accel.uses_bvh()
            && self.renderer.samples() == 0
        {
            rebuild.encode(encoder);
        }
        self.renderer.encode(encoder);
    }

    /// Moves the scene to `frame` of its motion: the spheres written to the GPU rebuild's buffers,
    /// or the BVH rebuilt on the CPU and the records rewritten. Returns the CPU build's time.
    /// The samples start again.
    pub fn advance(&mut self, scene: &Scene, frame: u32, accel: Accel) -> Result<Option<f64>, String> {
        let mut moved = PackedScene::new(&scene.at_frame(frame)).map_err(|e| e.to_string())?;
        self.motion_frame = Some(frame);
        self.renderer.restart();
        if let Some(rebuild) = &self.rebuild {
            rebuild.write_spheres(&moved.spheres);
            return Ok(None);
        }
        let Some(builder) = &mut self.cpu_rebuild else {
            return Ok(None);
        };
        let mut ms = None;
        if accel.uses_bvh() {
            ms = Some(builder.build(&moved.primitive_boxes(), MortonBits::Bits30).total());
            moved.set_bvh(builder.to_bvh());
        }
        self.renderer.write_scene(&moved).map_err(|e| e.to_string())?;
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
        view: DisplayView,
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
