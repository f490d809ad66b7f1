//! One render, on the device the user chose: the GPU, the CPU reference, or the GPU with a CPU
//! fallback; and sequences of frames with the BVH rebuilt every frame.

use anyhow::ensure;
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use pollster::block_on;
use raypipe::bvh::BuildTimings;
use raypipe::cpu::{self, Count};
use raypipe::gpu::trace::region::TracedPixels;
use raypipe::gpu::{GpuContext, MovingScene, Renderer, RendererOptions, TreeUpdate};
use raypipe::image::Frame;
use raypipe::modes::Backend;
use raypipe::modes::{Accel, MemoryMode, Pipeline};
use raypipe::records::{PackedScene, PoseOn, PosedScene};
use raypipe::scene::Scene;
use std::time::{Duration, Instant};

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
    pub pipeline: Pipeline,
    pub memory: MemoryMode,
    pub accel: Accel,
    /// Show progress: rows of a CPU render, samples of a GPU render, frames of a sequence, and the
    /// pipeline's build (drawn only on a terminal).
    pub progress: bool,
    /// What a frame's fourth colour channel counts.
    pub count: Count,
    /// Draw a frame before the timed one: drivers may compile the pipeline at its first draw
    /// (llvmpipe does), which would otherwise count as render time.
    pub warm_up: bool,
    /// Samples per pixel (0 counts as 1).
    pub samples: u32,
}

impl RenderOptions {
    fn renderer(&self) -> RendererOptions {
        RendererOptions {
            pipeline: self.pipeline,
            memory: self.memory,
            accel: self.accel,
            count: self.count,
            ..Default::default()
        }
    }
}

pub struct RenderOutcome {
    pub frame: Frame,
    /// The device that rendered, in words.
    pub device: String,
    /// Wall-clock time of the render (for the GPU: draw, copy and read back; not the pipeline build).
    pub wall_ms: f64,
    /// GPU time of the render pass from timestamp queries, where the adapter has them.
    pub gpu_ms: Option<f64>,
    /// The pixels the GPU's tracer ran on (`Renderer::traced_region`); the CPU traces them all.
    pub traced: TracedPixels,
}

/// The CPU reference tracer, in words.
fn cpu_description() -> String {
    format!("CPU reference ({} threads)", rayon::current_num_threads())
}

/// The GPU the options ask for: `None` for the CPU (with a notice when `auto` found no adapter).
fn open_device(options: &RenderOptions) -> anyhow::Result<Option<GpuContext>> {
    Ok(match options.device {
        DeviceChoice::Cpu => None,
        DeviceChoice::Gpu => Some(block_on(GpuContext::require(options.backend))?),
        DeviceChoice::Auto => {
            let ctx = block_on(GpuContext::new(options.backend))?;
            if ctx.is_none() {
                eprintln!("notice: no GPU adapter found; rendering on the CPU reference tracer");
            }
            ctx
        }
    })
}

/// A progress bar on standard error where `show` (indicatif draws it only on a terminal). It ticks
/// on its own, so that a long GPU draw or shader compile, which blocks this thread, still shows time
/// passing.
pub fn progress_bar(show: bool, len: u64, template: &str) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    bar.set_style(ProgressStyle::with_template(template).expect("the template is valid"));
    bar.enable_steady_tick(Duration::from_millis(100));
    bar
}

/// `make` (a renderer's or a moving scene's construction), with a spinner where `progress` says
/// while the driver compiles the tracer (seconds on llvmpipe).
pub fn compiling<T, E>(progress: bool, make: impl Future<Output = Result<T, E>>) -> Result<T, E> {
    let spinner = progress_bar(progress, 0, "{spinner} compiling the tracer, {elapsed}");
    let made = block_on(make);
    spinner.finish_and_clear();
    made
}

/// The CPU reference's frame, with a progress bar on a terminal.
fn render_cpu(scene: &PackedScene, options: &RenderOptions) -> anyhow::Result<Frame> {
    let bar = progress_bar(
        options.progress,
        scene.height() as u64,
        "{spinner} CPU render {bar:40} {pos}/{len} rows, {eta} left",
    );
    let frame = cpu::render_with(scene, options.accel, options.count, options.samples, &|| bar.inc(1))?;
    bar.finish_and_clear();
    Ok(frame)
}

pub fn render(scene: &PackedScene, options: &RenderOptions) -> anyhow::Result<RenderOutcome> {
    match open_device(options)? {
        Some(ctx) => {
            let mut renderer = compiling(options.progress, Renderer::new(&ctx, scene, options.renderer()))?;
            if options.warm_up {
                block_on(renderer.read_frame())?;
            }
            let bar = progress_bar(
                options.progress,
                options.samples.max(1) as u64,
                "{spinner} GPU render {bar:40} {pos}/{len} samples, {elapsed}",
            );
            let start = Instant::now();
            let timed =
                block_on(renderer.render_samples(options.samples, |_| {}, |done| bar.set_position(done as u64)));
            bar.finish_and_clear();
            let timed = timed?;
            let traced = renderer.traced_region();
            Ok(RenderOutcome {
                traced,
                frame: timed.frame,
                device: ctx.describe(),
                wall_ms: start.elapsed().as_secs_f64() * 1e3,
                gpu_ms: timed.gpu_ms,
            })
        }
        None => {
            let start = Instant::now();
            let frame = render_cpu(scene, options)?;
            Ok(RenderOutcome {
                traced: TracedPixels::whole(frame.width, frame.height),
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

/// Renders a moving scene at each of `times` (a frame number and its time in seconds), rebuilding
/// the BVH every frame, and hands each frame to `emit` with its number. On the GPU the library's
/// [`MovingScene`] rebuilds the tree in compute passes in the frame's submission (storage memory),
/// or on the CPU before it (uniform and texture memory); the CPU reference poses and builds with
/// its CPU half. Each frame rewrites only the records its motion moves.
pub fn render_frames(
    scene: &Scene,
    options: &RenderOptions,
    times: &[(u32, f32)],
    mut emit: impl FnMut(u32, &Frame) -> anyhow::Result<()>,
) -> anyhow::Result<FramesOutcome> {
    ensure!(
        options.count == Count::Rays,
        "--aov cost renders single frames; drop --frames"
    );
    ensure!(scene.motion.is_some(), "the scene does not move");
    ensure!(!times.is_empty(), "no frames to render");
    let mut outcome = FramesOutcome {
        device: String::new(),
        builds: Vec::new(),
        render_ms: Vec::new(),
        rays: Vec::new(),
    };
    // One bar for the sequence; none inside a frame.
    let bar = progress_bar(
        options.progress,
        times.len() as u64,
        "{spinner} frames {bar:40} {pos}/{len}, {eta} left {msg}",
    );
    let options = &RenderOptions {
        progress: false,
        ..*options
    };
    match open_device(options)? {
        Some(ctx) => {
            outcome.device = ctx.describe();
            bar.set_message("(compiling the BVH build and the tracer)");
            let mut moving = block_on(MovingScene::new(&ctx, scene, options.renderer(), TreeUpdate::Rebuild))?;
            bar.set_message("");
            for &(frame, t) in times {
                // The first frame too: a skinning pass starts at the scene's time 0.
                moving.pose(t)?;
                // The path integrator draws frame k's numbers, wherever the sequence starts.
                moving.renderer_mut().set_epoch(frame);
                let start = Instant::now();
                let timed = block_on(moving.render_samples(options.samples, |_| {}))?;
                let wall = start.elapsed().as_secs_f64() * 1e3;
                outcome.builds.extend(block_on(moving.read_build())?);
                outcome.render_ms.push(timed.gpu_ms.unwrap_or(wall));
                outcome.rays.push(timed.frame.rays());
                emit(frame, &timed.frame)?;
                bar.inc(1);
            }
        }
        None => {
            outcome.device = cpu_description();
            let mut posed = PosedScene::new(scene, options.accel, PoseOn::Cpu)?;
            for &(frame, t) in times {
                outcome.builds.extend(posed.pose(t)?.build);
                posed.set_epoch(frame);
                let start = Instant::now();
                let frame_image = render_cpu(posed.packed(), options)?;
                outcome.render_ms.push(start.elapsed().as_secs_f64() * 1e3);
                outcome.rays.push(frame_image.rays());
                emit(frame, &frame_image)?;
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    Ok(outcome)
}
