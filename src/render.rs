//! One render, on the device the user chose: the GPU, the CPU reference, or the GPU with a CPU fallback.

use crate::cpu;
use crate::gpu::context::Backend;
use crate::gpu::upload::MemoryMode;
use crate::gpu::{GpuContext, GpuRenderer};
use crate::image::Frame;
use crate::scene::packed::PackedScene;
use clap::ValueEnum;
use std::time::Instant;

/// How a ray finds its closest primitive.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Accel {
    /// Every ray against every primitive.
    #[default]
    Brute,
    /// The linear BVH, walked with a per-pixel stack, nearer child first.
    Stack,
}

impl Accel {
    pub fn uses_bvh(self) -> bool {
        self != Accel::Brute
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum DeviceChoice {
    /// The GPU, or the CPU (with a notice) where no adapter exists.
    #[default]
    Auto,
    Gpu,
    Cpu,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct RenderOptions {
    pub device: DeviceChoice,
    pub backend: Option<Backend>,
    pub memory: MemoryMode,
    pub accel: Accel,
    /// Show a progress bar for CPU renders (only drawn on a terminal).
    pub progress: bool,
    /// Draw a frame before the timed one: drivers may compile the pipeline at its first draw
    /// (llvmpipe does), which would otherwise count as render time.
    pub warm_up: bool,
}

pub struct RenderOutcome {
    pub frame: Frame,
    /// The device that rendered, in words.
    pub device: String,
    /// Wall-clock time of the render (for the GPU: draw, copy and read back; not the pipeline build).
    pub wall_ms: f64,
    /// GPU time of the render pass from timestamp queries, where the adapter has them.
    pub gpu_ms: Option<f64>,
}

pub fn render(scene: &PackedScene, options: &RenderOptions) -> anyhow::Result<RenderOutcome> {
    let ctx = match options.device {
        DeviceChoice::Cpu => None,
        DeviceChoice::Gpu => Some(GpuContext::require(options.backend)?),
        DeviceChoice::Auto => {
            let ctx = GpuContext::new(options.backend)?;
            if ctx.is_none() {
                eprintln!("notice: no GPU adapter found; rendering on the CPU reference tracer");
            }
            ctx
        }
    };
    match ctx {
        Some(ctx) => {
            let renderer = GpuRenderer::new(&ctx, scene, options.memory, options.accel)?;
            if options.warm_up {
                renderer.render()?;
            }
            let start = Instant::now();
            let timed = renderer.render()?;
            Ok(RenderOutcome {
                frame: timed.frame,
                device: ctx.describe(),
                wall_ms: start.elapsed().as_secs_f64() * 1e3,
                gpu_ms: timed.gpu_ms,
            })
        }
        None => {
            let start = Instant::now();
            let frame = cpu::render(scene, options.accel, options.progress);
            Ok(RenderOutcome {
                frame,
                device: format!("CPU reference ({} threads)", rayon::current_num_threads()),
                wall_ms: start.elapsed().as_secs_f64() * 1e3,
                gpu_ms: None,
            })
        }
    }
}
