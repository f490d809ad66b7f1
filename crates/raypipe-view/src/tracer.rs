//! What the viewer traces with: the scene packed for its modes, a renderer, and for a moving scene
//! in storage memory the per-frame rebuild. Rebuilt whole when a mode changes.

use crate::Modes;
use pollster::block_on;
use raypipe::bvh::morton::MortonBits;
use raypipe::gpu::{GpuContext, GpuError, Renderer, RendererOptions, SceneRebuild};
use raypipe::modes::{Count, MemoryMode};
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Scene};

pub struct Tracer {
    pub renderer: Renderer,
    /// For a moving scene in storage memory: its spheres and BVH, rebuilt before every frame.
    pub rebuild: Option<SceneRebuild>,
    /// The primitives' count, for the panel.
    pub primitives: usize,
    /// The BVH's build time on the CPU, where it was built there (once).
    pub cpu_build_ms: Option<f64>,
}

/// Why a mode cannot serve a scene: the message the panel shows.
pub fn refusal(error: &GpuError) -> String {
    match error {
        GpuError::TooBig {
            memory,
            array,
            records,
            needed,
            allowed,
        } => format!(
            "{memory} memory cannot hold this scene: {records} {array} records need {needed}, the adapter allows {allowed}"
        ),
        other => other.to_string(),
    }
}

impl Tracer {
    pub fn new(
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
            memory: modes.memory,
            accel: modes.accel,
            count: if modes.view == raypipe::gpu::DisplayView::Cost {
                Count::Cost
            } else {
                Count::Rays
            },
        };
        let primitives = packed.primitive_count();
        if scene.motion.is_some() {
            if modes.memory != MemoryMode::Storage {
                return Err(format!(
                    "a moving scene rebuilds its BVH on the GPU every frame, which the shader reads from storage memory, not {} memory",
                    modes.memory
                ));
            }
            let rebuild =
                block_on(SceneRebuild::new(ctx, &packed, modes.accel, MortonBits::Bits30)).map_err(|e| refusal(&e))?;
            let renderer =
                block_on(Renderer::with_rebuild(ctx, &packed, &rebuild, options)).map_err(|e| refusal(&e))?;
            return Ok(Self {
                renderer,
                rebuild: Some(rebuild),
                primitives,
                cpu_build_ms: None,
            });
        }
        let cpu_build_ms = modes
            .accel
            .uses_bvh()
            .then(|| packed.build_bvh(MortonBits::Bits30).total());
        let renderer = block_on(Renderer::new(ctx, &packed, options)).map_err(|e| refusal(&e))?;
        Ok(Self {
            renderer,
            rebuild: None,
            primitives,
            cpu_build_ms,
        })
    }
}
