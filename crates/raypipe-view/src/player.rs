//! One frame loop for every host: the scene, its modes, camera and tracer, and the motion's clock,
//! stepped the same way in the window (`app.rs`) and on the page (crates/raypipe-web). A host owns
//! its event loop, its [`Screen`] and its controls; at each of its frames it calls
//! [`Player::frame`], which advances the clock and the camera, traces, shows, lets the host draw
//! its overlay into the same encoder, presents, and keeps the frame rate.
//!
//! Changing modes or the scene needs a new tracer, which is built asynchronously (a window blocks
//! on it, a page awaits it): [`Player::set_modes`] and [`Player::open`] return a
//! [`TracerRequest`] to build, and [`Player::install`] puts its result in place; on failure the
//! current scene and tracer stay and the message shows.

use crate::tracer::{TraceError, Tracer, next_texture, present_format};
use crate::{CameraControl, Modes};
use glam::Vec3;
use raypipe::gpu::{Display, GpuContext, GpuError};
use raypipe::image::Frame;
use raypipe::scene::{Camera, Environment, Scene};
use std::collections::HashSet;
use web_time::Instant;

/// Fly speed: the distance to the target per second.
const FLY_PER_SECOND: f32 = 0.8;
/// The longest frame the fly keys move the camera for: a stall does not throw it far.
const LONGEST_FLY_STEP: f32 = 0.25;

/// The motion's clock, in seconds of scene time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clock {
    /// Where the scene stands.
    pub time: f32,
    /// Scene seconds per wall-clock second.
    pub speed: f32,
    /// A fixed step per frame instead of the wall clock (scripted runs: the same frames every
    /// time).
    pub step: Option<f32>,
    /// Where a scene's motion starts when it opens (`--time`, the page's `time`).
    pub start: f32,
}

impl Default for Clock {
    fn default() -> Self {
        Self {
            time: 0.0,
            speed: 1.0,
            step: None,
            start: 0.0,
        }
    }
}

/// Frames per second and milliseconds per frame, smoothed over the last frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameRate {
    pub fps: f64,
    /// The trace's GPU time where the adapter has timestamps, else the time between frames.
    pub frame_ms: f64,
}

impl FrameRate {
    fn update(&mut self, seconds: f64, gpu_ms: Option<f64>) {
        let seconds = seconds.max(1e-6);
        self.fps = if self.fps == 0.0 {
            1.0 / seconds
        } else {
            0.9 * self.fps + 0.1 / seconds
        };
        self.frame_ms = gpu_ms.unwrap_or(1e3 / self.fps);
    }
}

/// Where a host presents its frames: the window's or the canvas's surface, as configured, and the
/// display pass that draws into it.
pub struct Screen {
    pub ctx: GpuContext,
    pub surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
    pub display: Display,
}

impl Screen {
    /// The surface configured for `size` pixels in a linear format ([`present_format`]), presented
    /// as `vsync` says; `None` where the surface offers no format to present in.
    pub fn new(ctx: GpuContext, surface: wgpu::Surface<'static>, size: (u32, u32), vsync: bool) -> Option<Self> {
        let caps = surface.get_capabilities(&ctx.adapter);
        let format = present_format(&caps)?;
        let config = surface_config(&caps, format, size, vsync);
        surface.configure(&ctx.device, &config);
        Some(Self {
            display: Display::new(&ctx, format),
            ctx,
            surface,
            config,
        })
    }

    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// The surface at a new size (a window resized).
    pub fn resize(&mut self, width: u32, height: u32) {
        (self.config.width, self.config.height) = (width, height);
        self.surface.configure(&self.ctx.device, &self.config);
    }

    /// Presentation with or without waiting for the display's refresh, as the surface allows.
    pub fn set_vsync(&mut self, vsync: bool) {
        let caps = self.surface.get_capabilities(&self.ctx.adapter);
        self.config.present_mode = present_mode(&caps, vsync);
        self.surface.configure(&self.ctx.device, &self.config);
    }
}

/// Whether a frame waits for its GPU times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Timings {
    /// Not read: a page cannot wait for the GPU inside an animation frame, and a read that spans
    /// the browser's event loop would hold the tracer.
    Skip,
    /// Read after presenting, waiting for the frame: the trace pass's time (with timestamps) and,
    /// where the BVH is rebuilt on the GPU, the build's.
    #[cfg(not(target_arch = "wasm32"))]
    Wait,
}

/// What one [`Player::frame`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameReport {
    /// It traced a sample (a still frame with all its samples only shows them again).
    pub traced: bool,
    /// It presented: a surface with no texture to give this time presents nothing.
    pub presented: bool,
    /// Seconds since the previous call.
    pub seconds: f64,
    /// The trace pass's GPU time, where it was read.
    pub gpu_ms: Option<f64>,
}

/// The fly keys held down, by the names a browser's `KeyboardEvent.code` gives them (winit's
/// `KeyCode` names are the same): W and S forward and back, D and A right and left, E and Q up and
/// down.
#[derive(Clone, Debug, Default)]
pub struct FlyKeys {
    held: HashSet<&'static str>,
}

impl FlyKeys {
    const KEYS: [&'static str; 6] = ["KeyW", "KeyS", "KeyD", "KeyA", "KeyE", "KeyQ"];

    /// Notes a key going down or up; returns whether it is a fly key.
    pub fn set(&mut self, code: &str, down: bool) -> bool {
        let Some(key) = Self::KEYS.iter().find(|&&k| k == code) else {
            return false;
        };
        if down {
            self.held.insert(key);
        } else {
            self.held.remove(key);
        }
        true
    }

    /// Whether any is held.
    pub fn any(&self) -> bool {
        !self.held.is_empty()
    }

    /// Forward, right and up, each -1, 0 or 1.
    pub fn direction(&self) -> Vec3 {
        let held = |k: &str| self.held.contains(k) as i32 as f32;
        Vec3::new(
            held("KeyW") - held("KeyS"),
            held("KeyD") - held("KeyA"),
            held("KeyE") - held("KeyQ"),
        )
    }
}

pub struct Player {
    pub name: String,
    /// The scene as loaded (its motion's time 0).
    pub scene: Scene,
    pub modes: Modes,
    pub camera: CameraControl,
    tracer: Tracer,
    pub clock: Clock,
    /// Samples per pixel a still frame gathers, one per frame.
    pub spp: u32,
    /// The last BVH build's time, where one was timed.
    pub build_ms: Option<f64>,
    /// The one-line message to show, if any.
    pub message: Option<String>,
    pub rate: FrameRate,
    /// Frames finished.
    pub frames: u32,
    /// Whether the tone map was chosen (by the host's settings or through `set_modes`): until it
    /// is, each scene opened is shown with its own (`Scene::tone_map`).
    pub tone_map_chosen: bool,
    /// Whether the integrator was chosen: until it is, each scene opened is traced with its own
    /// (path for a glTF file, Whitted for the paper's scenes).
    pub integrator_chosen: bool,
    /// Tracer requests made: a tracer that lands after a later request is dropped.
    requested: u32,
    last_frame: Instant,
    last_presented: Instant,
}

/// A tracer to build for new modes or a new scene; [`Player::install`] takes the result.
pub struct TracerRequest {
    pub modes: Modes,
    /// A new scene and its name; `None` keeps the current one.
    pub new_scene: Option<(String, Scene)>,
    /// Whether it lights the current scene anew (`scene` holds the scene in its new environment);
    /// the camera and clock stay.
    pub relit: bool,
    /// What the tracer traces: the new scene, or a copy of the current one.
    scene: Scene,
    size: (u32, u32),
    camera: Camera,
    serial: u32,
}

impl TracerRequest {
    pub async fn build(&self, ctx: &GpuContext) -> Result<Tracer, TraceError> {
        Tracer::new(ctx, &self.scene, &self.modes, self.size, &self.camera).await
    }
}

impl Player {
    /// A player of `scene` at `size` pixels; the tracer is built here.
    pub async fn new(
        ctx: &GpuContext,
        name: String,
        scene: Scene,
        modes: Modes,
        size: (u32, u32),
        spp: u32,
    ) -> Result<Self, TraceError> {
        let camera = CameraControl::new(scene.camera);
        let tracer = Tracer::new(ctx, &scene, &modes, size, &camera.camera).await?;
        Ok(Self {
            name,
            build_ms: tracer.cpu_build_ms,
            scene,
            modes,
            camera,
            tracer,
            clock: Clock::default(),
            spp: spp.max(1),
            message: None,
            rate: FrameRate::default(),
            frames: 0,
            tone_map_chosen: false,
            integrator_chosen: false,
            requested: 0,
            last_frame: Instant::now(),
            last_presented: Instant::now(),
        })
    }

    /// One frame on `screen`: the camera flown along `fly` (forward, right, up, each -1 to 1) and
    /// the clock advanced by the time since the last call, the scene posed, the next sample traced
    /// (unless all are gathered) and shown; then `overlay` records what the host draws over it
    /// into the same encoder (returning command buffers to submit first, as egui's do), and the
    /// frame is submitted and presented. The frame rate counts presented frames.
    pub fn frame(
        &mut self,
        screen: &Screen,
        fly: Vec3,
        timings: Timings,
        overlay: impl FnOnce(&mut Player, &mut wgpu::CommandEncoder, &wgpu::TextureView) -> Vec<wgpu::CommandBuffer>,
    ) -> FrameReport {
        let now = Instant::now();
        let seconds = (now - self.last_frame).as_secs_f64();
        self.last_frame = now;
        let traced = self.advance(seconds as f32, fly);
        let mut report = FrameReport {
            traced,
            presented: false,
            seconds,
            gpu_ms: None,
        };
        let Some(texture) = next_texture(&screen.surface, &screen.ctx.device, &screen.config) else {
            return report;
        };
        let view = texture.texture.create_view(&Default::default());
        let ctx = &screen.ctx;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.encode(&mut encoder, &screen.display, &view, traced);
        let first = overlay(self, &mut encoder, &view);
        ctx.queue.submit(first.into_iter().chain([encoder.finish()]));
        ctx.queue.present(texture);
        report.presented = true;
        if traced {
            report.gpu_ms = self.read_timings(timings);
        }
        let presented = (now - self.last_presented).as_secs_f64();
        self.last_presented = now;
        self.finish(presented, report.gpu_ms);
        report
    }

    /// The frame's GPU times where `timings` waits for them: the trace's is returned, a GPU
    /// rebuild's is kept as the build time.
    fn read_timings(&mut self, timings: Timings) -> Option<f64> {
        match timings {
            Timings::Skip => None,
            #[cfg(not(target_arch = "wasm32"))]
            Timings::Wait => {
                if let Some(ms) = pollster::block_on(self.tracer.read_gpu_build_ms()) {
                    self.build_ms = Some(ms);
                }
                pollster::block_on(self.tracer.renderer().read_gpu_ms()).ok().flatten()
            }
        }
    }

    /// The scene's primitives.
    pub fn primitives(&self) -> usize {
        self.tracer.primitives
    }

    /// Samples per pixel in the frame shown.
    pub fn gathered(&self) -> u32 {
        self.tracer.renderer().targets().samples()
    }

    /// Gathers up to `spp` samples per pixel, from the first again.
    pub fn set_spp(&mut self, spp: u32) {
        self.spp = spp.max(1);
        self.tracer.renderer_mut().restart();
    }

    /// Traces at a new size (the window's or the canvas's); the samples start again.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), GpuError> {
        self.tracer.renderer_mut().resize(width, height)
    }

    /// The size it traces at, in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.tracer.renderer().size()
    }

    /// The frame shown, read back linear (tracing one sample first where none is).
    pub async fn read_frame(&mut self, ctx: &GpuContext) -> Result<Frame, GpuError> {
        self.read_frame_detached(ctx).await
    }

    /// [`Player::read_frame`] as a future that borrows nothing (a page draws on while it waits).
    pub fn read_frame_detached(&mut self, ctx: &GpuContext) -> impl Future<Output = Result<Frame, GpuError>> + 'static {
        if self.tracer.renderer().samples() == 0 {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            self.tracer.encode(&mut encoder);
            ctx.queue.submit([encoder.finish()]);
        }
        self.tracer.renderer().read_back()
    }

    /// Whether the scene moves now (it has motion and is not paused).
    pub fn moving(&self) -> bool {
        self.scene.motion.is_some() && !self.modes.paused
    }

    /// Seconds the motion lasts before it starts again; `None` for still scenes and endless motion.
    pub fn duration(&self) -> Option<f32> {
        self.scene.motion.as_ref().and_then(|m| m.duration())
    }

    /// Starts this scene and every scene opened later at `t` seconds.
    pub fn start_at(&mut self, t: f32) {
        self.clock.start = t;
        self.seek(t);
    }

    /// Puts the motion at `t` seconds (wrapped into its duration); the next frame poses it there.
    pub fn seek(&mut self, t: f32) {
        if let Some(motion) = &self.scene.motion
            && t.is_finite()
        {
            self.clock.time = motion.looped(t);
        }
    }

    /// Starts a frame `seconds` after the last: the camera flown along `fly` (forward, right, up,
    /// each -1 to 1), the clock advanced unless paused, the scene posed where its time changed.
    /// Returns whether the frame traces a sample (a still frame with all its samples does not).
    fn advance(&mut self, seconds: f32, fly: Vec3) -> bool {
        if fly != Vec3::ZERO {
            let step = FLY_PER_SECOND * seconds.min(LONGEST_FLY_STEP);
            self.camera.fly(fly.x * step, fly.y * step, fly.z * step);
        }
        if self.moving() && self.frames > 0 {
            let elapsed = self.clock.step.unwrap_or(seconds * self.clock.speed);
            self.seek(self.clock.time + elapsed);
        }
        // Either restarts the samples if it changes anything.
        self.tracer.renderer_mut().set_camera(&self.camera.camera);
        if self.scene.motion.is_some() && self.tracer.time() != Some(self.clock.time) {
            match self.tracer.pose(self.clock.time) {
                Ok(Some(ms)) => self.build_ms = Some(ms),
                Ok(None) => {}
                Err(why) => self.say(why.to_string()),
            }
        }
        self.tracer.renderer().samples() < self.spp
    }

    /// Records the frame into `encoder`: the next sample where `trace`, then the display pass
    /// into `target`.
    fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        display: &Display,
        target: &wgpu::TextureView,
        trace: bool,
    ) {
        if trace {
            self.tracer.encode(encoder);
        }
        self.tracer.show(
            display,
            encoder,
            target,
            self.modes.view,
            self.modes.display,
            &self.camera.camera,
        );
    }

    /// Ends a frame `seconds` after the last, whose trace took `gpu_ms` where that was measured.
    fn finish(&mut self, seconds: f64, gpu_ms: Option<f64>) {
        if self.frames > 0 {
            self.rate.update(seconds, gpu_ms);
        }
        self.frames += 1;
    }

    /// Shows `why` (and logs it).
    pub fn say(&mut self, why: String) {
        log::warn!("{why}");
        self.message = Some(why);
    }

    /// Switches to `asked`: at once where the current tracer serves it, else by the request
    /// returned. Modes the device cannot serve are refused with their message.
    pub fn set_modes(&mut self, asked: Modes) -> Option<TracerRequest> {
        if asked.display.tone_map != self.modes.display.tone_map {
            self.tone_map_chosen = true;
        }
        if asked.integrator != self.modes.integrator {
            self.integrator_chosen = true;
        }
        if asked.needs_new_tracer(&self.modes) {
            return Some(self.request(asked, None));
        }
        if asked != self.modes {
            log_modes(&asked);
        }
        self.modes = asked;
        None
    }

    /// A request for a tracer of `scene`, which replaces the current one when it is built.
    pub fn open(&mut self, name: String, scene: Scene) -> TracerRequest {
        let mut modes = self.modes;
        if !self.tone_map_chosen {
            modes.display.tone_map = scene.tone_map;
        }
        if !self.integrator_chosen {
            modes.integrator = scene.settings.integrator;
        }
        self.request(modes, Some((name, scene)))
    }

    /// A request for the current scene in `environment` (or none), seen as it is now.
    pub fn relight(&mut self, environment: Option<Environment>) -> TracerRequest {
        let mut request = self.request(self.modes, None);
        request.scene.set_environment(environment);
        request.relit = true;
        request
    }

    fn request(&mut self, modes: Modes, new_scene: Option<(String, Scene)>) -> TracerRequest {
        self.requested += 1;
        let (scene, camera) = match &new_scene {
            Some((_, scene)) => (scene.clone(), scene.camera),
            None => (self.scene.clone(), self.camera.camera),
        };
        TracerRequest {
            modes,
            new_scene,
            relit: false,
            scene,
            size: self.tracer.renderer().size(),
            camera,
            serial: self.requested,
        }
    }

    /// A request for the tracer as it is now (scene, modes, camera, size), to build on a new device
    /// after the last one was lost; [`Player::restore`] puts it in place whatever was asked since.
    pub fn restore_request(&self) -> TracerRequest {
        TracerRequest {
            modes: self.modes,
            new_scene: None,
            relit: false,
            scene: self.scene.clone(),
            size: self.tracer.renderer().size(),
            camera: self.camera.camera,
            serial: self.requested,
        }
    }

    /// Puts a tracer built by [`Player::restore_request`] on a new device in place of the one on
    /// the lost device: the same scene, modes and camera; the motion is posed again at the clock's
    /// time and the samples start again.
    pub fn restore(&mut self, tracer: Tracer) {
        self.build_ms = tracer.cpu_build_ms;
        self.tracer = tracer;
        self.message = None;
    }

    /// Whether a request is still the latest (a page builds tracers while frames go on).
    pub fn is_current(&self, request: &TracerRequest) -> bool {
        request.serial == self.requested
    }

    /// Puts a built tracer in place (with its modes and scene); a failed build leaves everything
    /// as it was and shows why.
    pub fn install(&mut self, request: TracerRequest, built: Result<Tracer, TraceError>) {
        match built {
            Ok(tracer) => {
                self.build_ms = tracer.cpu_build_ms;
                self.tracer = tracer;
                if request.modes != self.modes {
                    log_modes(&request.modes);
                }
                self.modes = request.modes;
                self.message = None;
                if request.relit {
                    self.scene = request.scene;
                }
                if let Some((name, scene)) = request.new_scene {
                    self.camera = CameraControl::new(scene.camera);
                    self.scene = scene;
                    self.name = name;
                    self.clock.time = 0.0;
                    self.seek(self.clock.start);
                }
            }
            Err(why) => {
                let name = request.new_scene.map_or_else(|| self.name.clone(), |(name, _)| name);
                self.say(format!("{name}: {why}"));
            }
        }
    }
}

fn log_modes(modes: &Modes) {
    log::info!(
        "integrator {}, pipeline {}, acceleration {} (built by {}), memory {}, depth {}, view {}{}",
        modes.integrator,
        modes.pipeline,
        modes.accel,
        modes.builder,
        modes.memory,
        modes.depth,
        modes.view,
        if modes.paused { ", paused" } else { "" }
    );
}

/// A render pass into `target` that keeps what is there (the frame the display pass drew), for
/// what a host draws over it: a panel, an overlay.
pub fn overlay_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    label: &str,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// The surface's configuration for a `size` frame in `format`: presented with or without waiting
/// for the display's refresh, as `vsync` says and the surface allows.
pub fn surface_config(
    caps: &wgpu::SurfaceCapabilities,
    format: wgpu::TextureFormat,
    size: (u32, u32),
    vsync: bool,
) -> wgpu::SurfaceConfiguration {
    wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        width: size.0.max(1),
        height: size.1.max(1),
        present_mode: present_mode(caps, vsync),
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes[0],
        view_formats: vec![],
        color_space: Default::default(),
    }
}

/// Without vsync: any mode that does not wait, where the surface has one.
pub fn present_mode(caps: &wgpu::SurfaceCapabilities, vsync: bool) -> wgpu::PresentMode {
    if !vsync && caps.present_modes.iter().any(|m| *m != wgpu::PresentMode::Fifo) {
        wgpu::PresentMode::AutoNoVsync
    } else if vsync {
        wgpu::PresentMode::AutoVsync
    } else {
        wgpu::PresentMode::Fifo
    }
}
