//! One render, on the device the user chose: the GPU, the CPU reference, or the GPU with a CPU fallback.

use crate::bvh::BuildTimings;
use crate::bvh::lbvh::LbvhBuilder;
use crate::bvh::morton::MortonBits;
use crate::cpu;
use crate::gpu::build::{GpuLbvhBuilder, depth_bound};
use crate::gpu::context::Backend;
use crate::gpu::upload::MemoryMode;
use crate::gpu::{GpuContext, GpuRenderer};
use crate::image::Frame;
use crate::scene::Scene;
use crate::scene::packed::PackedScene;
use clap::ValueEnum;
use std::time::Instant;

/// How a ray finds its closest primitive. The default is the fastest measured mode (docs/BENCHMARKS.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Accel {
    /// Every ray against every primitive.
    Brute,
    /// The linear BVH, walked with a per-pixel stack, nearer child first.
    Stack,
    /// The linear BVH, walked without a stack (Hapala et al. 2011): parent links, nearer child first.
    Stackless,
    /// The linear BVH, walked without a stack along escape links, in fixed depth-first order.
    #[default]
    Threaded,
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
    /// Frames carry each pixel's cost (BVH nodes its primary ray tested) instead of its ray count.
    pub write_cost: bool,
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

/// The CPU reference tracer, in words.
fn cpu_description() -> String {
    format!("CPU reference ({} threads)", rayon::current_num_threads())
}

/// The GPU the options ask for: `None` for the CPU (with a notice when `auto` found no adapter).
fn open_device(options: &RenderOptions) -> anyhow::Result<Option<GpuContext>> {
    Ok(match options.device {
        DeviceChoice::Cpu => None,
        DeviceChoice::Gpu => Some(GpuContext::require(options.backend)?),
        DeviceChoice::Auto => {
            let ctx = GpuContext::new(options.backend)?;
            if ctx.is_none() {
                eprintln!("notice: no GPU adapter found; rendering on the CPU reference tracer");
            }
            ctx
        }
    })
}

pub fn render(scene: &PackedScene, options: &RenderOptions) -> anyhow::Result<RenderOutcome> {
    match open_device(options)? {
        Some(ctx) => {
            let renderer = if options.write_cost {
                GpuRenderer::with_cost(&ctx, scene, options.memory, options.accel)?
            } else {
                GpuRenderer::new(&ctx, scene, options.memory, options.accel)?
            };
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
            let frame = cpu::render_with(scene, options.accel, options.progress, options.write_cost);
            Ok(RenderOutcome {
                frame,
                device: cpu_description(),
                wall_ms: start.elapsed().as_secs_f64() * 1e3,
                gpu_ms: None,
            })
        }
    }
}

/// What a sequence of frames took, frame by frame.
pub struct FramesOutcome {
    pub device: String,
    /// BVH build time per frame, per phase: GPU timestamps on the GPU (zeros without them), wall
    /// clock on the CPU; empty for brute force.
    pub builds: Vec<BuildTimings>,
    /// Render time per frame: GPU timestamps where the adapter has them, else wall clock.
    pub render_ms: Vec<f64>,
    /// Rays traced per frame.
    pub rays: Vec<u64>,
}

/// Renders `frames` frames of a (moving) scene, rebuilding the BVH every frame, and hands each
/// frame to `emit`. On the GPU the build runs in compute passes in the same submission as the
/// frame, reading and writing buffers the fragment shader then reads: no round trip to the host
/// between build and trace; this needs storage memory. On the CPU, one reusable builder serves
/// every frame.
pub fn render_frames(
    scene: &Scene,
    options: &RenderOptions,
    frames: u32,
    mut emit: impl FnMut(u32, &Frame) -> anyhow::Result<()>,
) -> anyhow::Result<FramesOutcome> {
    anyhow::ensure!(!options.write_cost, "--aov cost renders single frames; drop --frames");
    let first = PackedScene::new(scene)?;
    let n = first.primitive_count();
    let mut outcome = FramesOutcome {
        device: String::new(),
        builds: Vec::new(),
        render_ms: Vec::new(),
        rays: Vec::new(),
    };
    let spheres_at = |frame: u32| -> anyhow::Result<PackedScene> { Ok(PackedScene::new(&scene.at_frame(frame))?) };
    match open_device(options)? {
        Some(ctx) => {
            anyhow::ensure!(
                options.memory == MemoryMode::Storage,
                "--frames rebuilds the BVH on the GPU, which the shader reads from storage memory: use --memory storage"
            );
            outcome.device = ctx.describe();
            let mut builder =
                GpuLbvhBuilder::new(&ctx, MortonBits::Bits30, first.spheres.len(), first.triangles.len())?;
            // The triangles stand still: written once. The spheres move: written every frame.
            builder.write_scene(&first)?;
            let mut layout = first;
            layout.bvh_depth = depth_bound(n, builder.bits());
            let renderer = GpuRenderer::with_shared_buffers(&ctx, &layout, options.accel, &builder.shared_buffers())?;
            for frame in 0..frames {
                if frame > 0 {
                    builder.write_spheres(&spheres_at(frame)?.spheres);
                }
                let start = Instant::now();
                let timed = renderer.render_after(|encoder| {
                    if options.accel.uses_bvh() {
                        builder.encode(encoder, false);
                    }
                })?;
                let wall = start.elapsed().as_secs_f64() * 1e3;
                if options.accel.uses_bvh() {
                    let mut timings = builder.read_timings()?;
                    timings.links += timed.layout_ms.unwrap_or(0.0);
                    outcome.builds.push(timings);
                }
                outcome.render_ms.push(timed.gpu_ms.unwrap_or(wall));
                outcome.rays.push(timed.frame.rays());
                emit(frame, &timed.frame)?;
            }
        }
        None => {
            outcome.device = cpu_description();
            let mut builder = LbvhBuilder::<u64>::new();
            // Frame 0 is packed already.
            let mut first = Some(first);
            for frame in 0..frames {
                let mut packed = match first.take() {
                    Some(packed) => packed,
                    None => spheres_at(frame)?,
                };
                if options.accel.uses_bvh() {
                    let timings = builder.build(&packed.primitive_boxes(), MortonBits::Bits30);
                    packed.set_bvh(builder.to_bvh());
                    outcome.builds.push(timings);
                }
                let start = Instant::now();
                let frame_image = cpu::render(&packed, options.accel, options.progress);
                outcome.render_ms.push(start.elapsed().as_secs_f64() * 1e3);
                outcome.rays.push(frame_image.rays());
                emit(frame, &frame_image)?;
            }
        }
    }
    Ok(outcome)
}
