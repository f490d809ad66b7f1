//! One frame loop for every host: the scene, its modes, camera and tracer, and the motion's clock,
//! stepped the same way in the window (`app.rs`) and on the page (crates/raypipe-web). A host owns
//! its event loop, surface and controls; each frame it calls [`Player::advance`], records
//! [`Player::encode`] into its encoder, presents, and calls [`Player::finish`].
//!
//! Changing modes or the scene needs a new tracer, which is built asynchronously (a window blocks
//! on it, a page awaits it): [`Player::set_modes`] and [`Player::open`] return a
//! [`TracerRequest`] to build, and [`Player::install`] puts its result in place; on failure the
//! current scene and tracer stay and the message shows.

use crate::tracer::{TraceError, Tracer};
use crate::{CameraControl, Modes};
use glam::Vec3;
use raypipe::gpu::{Display, GpuContext};
use raypipe::scene::{Camera, Scene};

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

pub struct Player {
    pub name: String,
    /// The scene as loaded (its motion's time 0).
    pub scene: Scene,
    pub modes: Modes,
    pub camera: CameraControl,
    pub tracer: Tracer,
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
    /// Tracer requests made: a tracer that lands after a later request is dropped.
    requested: u32,
}

/// A tracer to build for new modes or a new scene; [`Player::install`] takes the result.
pub struct TracerRequest {
    pub modes: Modes,
    /// A new scene and its name; `None` keeps the current one.
    pub new_scene: Option<(String, Scene)>,
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
            requested: 0,
        })
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
    pub fn advance(&mut self, seconds: f32, fly: Vec3) -> bool {
        if fly != Vec3::ZERO {
            let step = FLY_PER_SECOND * seconds.min(LONGEST_FLY_STEP);
            self.camera.fly(fly.x * step, fly.y * step, fly.z * step);
        }
        if self.moving() && self.frames > 0 {
            let elapsed = self.clock.step.unwrap_or(seconds * self.clock.speed);
            self.seek(self.clock.time + elapsed);
        }
        // Either restarts the samples if it changes anything.
        self.tracer.renderer.set_camera(&self.camera.camera);
        if self.scene.motion.is_some() && self.tracer.time != Some(self.clock.time) {
            match self.tracer.pose(&self.scene, self.clock.time, self.modes.accel) {
                Ok(Some(ms)) => self.build_ms = Some(ms),
                Ok(None) => {}
                Err(why) => self.say(why.to_string()),
            }
        }
        self.tracer.renderer.samples() < self.spp
    }

    /// Records the frame into `encoder`: the next sample where `trace`, then the display pass
    /// into `target`.
    pub fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        display: &Display,
        target: &wgpu::TextureView,
        trace: bool,
    ) {
        if trace {
            self.tracer.encode(encoder);
        }
        self.tracer
            .show(display, encoder, target, self.modes.view, &self.camera.camera);
    }

    /// Ends a frame `seconds` after the last, whose trace took `gpu_ms` where that was measured.
    pub fn finish(&mut self, seconds: f64, gpu_ms: Option<f64>) {
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
        self.request(self.modes, Some((name, scene)))
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
            scene,
            size: self.tracer.renderer.size(),
            camera,
            serial: self.requested,
        }
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
        "pipeline {}, acceleration {} (built by {}), memory {}, depth {}, view {}{}",
        modes.pipeline,
        modes.accel,
        modes.builder,
        modes.memory,
        modes.depth,
        modes.view,
        if modes.paused { ", paused" } else { "" }
    );
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
