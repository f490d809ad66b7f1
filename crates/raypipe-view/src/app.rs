//! The native window: winit's event loop, a wgpu surface, and each frame traced, displayed, overlaid
//! with the panel and presented.

use crate::camera::CameraControl;
use crate::panel::{self, Readout};
use crate::tracer::Tracer;
use crate::{Host, ModeKey, Modes, Script, Summary, ViewError, ViewerOptions, next_texture, present_format};
use pollster::block_on;
use raypipe::gpu::{Display, GpuContext};
use raypipe::scene::Scene;
use std::collections::HashSet;
use std::sync::Arc;
use web_time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, OwnedDisplayHandle};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Fly speed: the distance to the target per second.
const FLY_PER_SECOND: f32 = 0.8;
/// How often an idle viewer (nothing to trace, nothing moving) redraws its panel.
const IDLE_REDRAW: std::time::Duration = std::time::Duration::from_millis(100);

pub fn run(options: ViewerOptions, host: Box<dyn Host>) -> Result<Summary, ViewError> {
    let event_loop = EventLoop::new().map_err(|e| ViewError::Window(e.to_string()))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut viewer = Viewer::new(options, host, event_loop.owned_display_handle());
    event_loop
        .run_app(&mut viewer)
        .map_err(|e| ViewError::Window(e.to_string()))?;
    viewer.outcome?;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    };
    // The first frames pay for pipeline compilation on some drivers: the medians skip them.
    let steady = |v: &[f64]| v.iter().skip(v.len().min(2)).copied().collect::<Vec<_>>();
    Ok(Summary {
        frames: viewer.frames_drawn,
        trace_ms: median(steady(&viewer.trace_times)),
        frame_ms: median(steady(&viewer.frame_times)).unwrap_or(0.0),
    })
}

/// What lives on the GPU once the window exists.
struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    display: Display,
    tracer: Tracer,
    egui: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
}

#[derive(Default)]
struct Input {
    orbiting: bool,
    panning: bool,
    cursor: Option<(f64, f64)>,
    held: HashSet<KeyCode>,
}

struct Viewer {
    options: ViewerOptions,
    host: Box<dyn Host>,
    display_handle: OwnedDisplayHandle,
    gpu: Option<Gpu>,
    modes: Modes,
    camera: CameraControl,
    input: Input,
    /// The moving scene's frame, advanced unless paused.
    motion_frame: u32,
    frames_drawn: u32,
    show_panel: bool,
    message: Option<String>,
    last_frame: Instant,
    /// The last frame traced nothing (its samples were all gathered) and nothing moves: the next
    /// may wait for input or the panel's refresh.
    idle: bool,
    fps: f64,
    frame_ms: f64,
    build_ms: Option<f64>,
    /// Per frame: the trace pass's GPU time (with timestamps), and the wall clock between frames.
    trace_times: Vec<f64>,
    frame_times: Vec<f64>,
    outcome: Result<(), ViewError>,
}

impl Viewer {
    fn new(options: ViewerOptions, host: Box<dyn Host>, display_handle: OwnedDisplayHandle) -> Self {
        Self {
            modes: options.modes,
            camera: CameraControl::new(options.scene.camera),
            // A scripted run shows what `render` shows: no panel over the frame.
            show_panel: options.script.is_none(),
            options,
            host,
            display_handle,
            gpu: None,
            input: Input::default(),
            motion_frame: 0,
            frames_drawn: 0,
            message: None,
            last_frame: Instant::now(),
            idle: false,
            fps: 0.0,
            frame_ms: 0.0,
            build_ms: None,
            trace_times: Vec::new(),
            frame_times: Vec::new(),
            outcome: Ok(()),
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: ViewError) {
        self.outcome = Err(error);
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Gpu, ViewError> {
        let settings = &self.options.scene.settings;
        let attributes = Window::default_attributes()
            .with_title(format!("raypipe · {}", self.options.name))
            .with_inner_size(winit::dpi::PhysicalSize::new(settings.width, settings.height));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| ViewError::Window(e.to_string()))?,
        );
        // GL needs the display the window lives on; the other backends ignore it.
        let mut desc =
            wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(self.display_handle.clone()));
        if let Some(backend) = self.options.backend {
            desc.backends = backend.backends();
        }
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| ViewError::Window(e.to_string()))?;
        let ctx = block_on(GpuContext::for_surface(&instance, &surface))?;
        let caps = surface.get_capabilities(&ctx.adapter);
        let format = present_format(&caps)
            .ok_or_else(|| ViewError::Window(format!("{} cannot present to this window", ctx.describe())))?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: present_mode(&caps, self.modes.vsync),
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: Default::default(),
        };
        surface.configure(&ctx.device, &config);
        if !ctx.memory_modes().contains(&self.modes.memory) {
            self.modes.memory = ctx.default_memory();
        }
        let tracer = block_on(Tracer::new(
            &ctx,
            &self.options.scene,
            &self.modes,
            (config.width, config.height),
            &self.camera.camera,
        ))
        .map_err(ViewError::Scene)?;
        self.build_ms = tracer.cpu_build_ms;
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(&ctx.device, format, Default::default());
        Ok(Gpu {
            display: Display::new(&ctx, format),
            window,
            surface,
            config,
            ctx,
            tracer,
            egui,
            egui_state,
            egui_renderer,
        })
    }

    /// Switches to `asked` if it can serve the scene; otherwise keeps the modes and says why.
    fn set_modes(&mut self, asked: Modes) {
        let Some(gpu) = &mut self.gpu else { return };
        if asked.vsync != self.modes.vsync {
            let caps = gpu.surface.get_capabilities(&gpu.ctx.adapter);
            gpu.config.present_mode = present_mode(&caps, asked.vsync);
            gpu.surface.configure(&gpu.ctx.device, &gpu.config);
        }
        if asked.needs_new_tracer(&self.modes) {
            if let Err(why) = asked.check(&gpu.ctx) {
                self.message = Some(why);
                return;
            }
            let size = (gpu.config.width, gpu.config.height);
            match block_on(Tracer::new(
                &gpu.ctx,
                &self.options.scene,
                &asked,
                size,
                &self.camera.camera,
            )) {
                Ok(tracer) => {
                    self.build_ms = tracer.cpu_build_ms;
                    gpu.tracer = tracer;
                    self.message = None;
                }
                Err(why) => {
                    log::warn!("{why}");
                    self.message = Some(why);
                    return;
                }
            }
        }
        if asked != self.modes {
            log::info!(
                "pipeline {}, acceleration {}, memory {}, depth {}, view {}{}",
                asked.pipeline,
                asked.accel,
                asked.memory,
                asked.depth,
                asked.view,
                if asked.paused { ", paused" } else { "" }
            );
        }
        self.modes = asked;
    }

    /// A new scene (a dropped file): the viewer keeps the old one if the new one cannot be traced.
    fn set_scene(&mut self, name: String, scene: Scene) {
        let Some(gpu) = &mut self.gpu else { return };
        let camera = CameraControl::new(scene.camera);
        let size = (gpu.config.width, gpu.config.height);
        match block_on(Tracer::new(&gpu.ctx, &scene, &self.modes, size, &camera.camera)) {
            Ok(tracer) => {
                self.build_ms = tracer.cpu_build_ms;
                gpu.tracer = tracer;
                gpu.window.set_title(&format!("raypipe · {name}"));
                self.options.scene = scene;
                self.options.name = name;
                self.camera = camera;
                self.motion_frame = 0;
                self.message = None;
            }
            Err(why) => {
                let why = format!("{name}: {why}");
                log::warn!("{why}");
                self.message = Some(why);
            }
        }
    }

    /// A dropped file: its scene replaces the current one, or its one-line error shows and the
    /// current scene stays.
    fn open_file(&mut self, path: &std::path::Path) {
        let name = path.display().to_string();
        match self.host.load(path) {
            Ok(scene) => self.set_scene(name, scene),
            Err(why) => {
                log::warn!("{why}");
                self.message = Some(why);
            }
        }
    }

    fn key(&mut self, code: KeyCode, pressed: bool) {
        if pressed {
            self.input.held.insert(code);
        } else {
            self.input.held.remove(&code);
            return;
        }
        if let Some(key) = mode_key(code) {
            return self.set_modes(self.modes.after(key));
        }
        let mut asked = self.modes;
        match code {
            KeyCode::KeyR => self.camera.reset(),
            KeyCode::KeyY => asked.vsync = !asked.vsync,
            KeyCode::KeyH => self.show_panel = !self.show_panel,
            KeyCode::KeyP => {
                let path = self.host.screenshot_path(self.modes.view);
                let said = match self.screenshot(&path) {
                    Ok(()) => format!("saved {}", path.display()),
                    Err(why) => why,
                };
                log::info!("{said}");
                self.message = Some(said);
            }
            _ => {}
        }
        if asked != self.modes {
            self.set_modes(asked);
        }
    }

    /// Saves the current frame (the mean of its samples, read back) to `path`; says what happened.
    /// A tracer that has drawn nothing yet (a mode switched this very frame) traces its first
    /// sample now.
    /// Saves the frame shown (tracing one sample first where none is); the error says why not.
    fn screenshot(&mut self, path: &std::path::Path) -> Result<(), String> {
        let Some(gpu) = &mut self.gpu else {
            return Err("no frame yet".into());
        };
        let tracer = &mut gpu.tracer;
        if tracer.renderer.samples() == 0 {
            let mut encoder = gpu.ctx.device.create_command_encoder(&Default::default());
            tracer.encode(&mut encoder, self.modes.accel);
            gpu.ctx.queue.submit([encoder.finish()]);
        }
        let frame = block_on(tracer.renderer.read_back()).map_err(|e| e.to_string())?;
        self.host.save(&frame, self.modes.view, path)
    }

    /// Applies held keys and the script's orbit to the camera, for a frame `seconds` long.
    fn move_camera(&mut self, seconds: f32) {
        let held = |k| self.input.held.contains(&k);
        let axis = |plus, minus| (held(plus) as i32 - held(minus) as i32) as f32;
        let step = FLY_PER_SECOND * seconds.min(0.25);
        let (forward, right, up) = (
            axis(KeyCode::KeyW, KeyCode::KeyS),
            axis(KeyCode::KeyD, KeyCode::KeyA),
            axis(KeyCode::KeyE, KeyCode::KeyQ),
        );
        if (forward, right, up) != (0.0, 0.0, 0.0) {
            self.camera.fly(forward * step, right * step, up * step);
        }
        if let Some(script) = &self.options.script
            && script.orbit_degrees != 0.0
            && self.frames_drawn > 0
        {
            self.camera.orbit_degrees(script.orbit_degrees);
        }
    }

    fn draw(&mut self, event_loop: &ActiveEventLoop) {
        let now = Instant::now();
        let seconds = (now - self.last_frame).as_secs_f64();
        self.last_frame = now;
        self.move_camera(seconds as f32);
        let moving = self.options.scene.motion.is_some() && !self.modes.paused;
        if moving && self.frames_drawn > 0 {
            self.motion_frame += 1;
        }
        let Some(gpu) = &mut self.gpu else { return };
        // Either restarts the samples if it changes anything.
        gpu.tracer.renderer.set_camera(&self.camera.camera);
        if self.options.scene.motion.is_some() && gpu.tracer.motion_frame != Some(self.motion_frame) {
            match gpu
                .tracer
                .advance(&self.options.scene, self.motion_frame, self.modes.accel)
            {
                Ok(Some(ms)) => self.build_ms = Some(ms),
                Ok(None) => {}
                Err(why) => self.message = Some(why),
            }
        }
        // A still frame that has its samples is shown again, not traced again.
        let trace = gpu.tracer.renderer.samples() < self.options.samples.max(1);
        self.idle = !trace && !moving && self.input.held.is_empty();
        let Some(surface_texture) = next_texture(&gpu.surface, &gpu.ctx.device, &gpu.config) else {
            return;
        };
        let view = surface_texture.texture.create_view(&Default::default());
        let ctx = gpu.ctx.clone();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        if trace {
            gpu.tracer.encode(&mut encoder, self.modes.accel);
        }
        gpu.tracer
            .show(&gpu.display, &mut encoder, &view, self.modes.view, &self.camera.camera);
        let mut asked = None;
        if self.show_panel {
            let raw = gpu.egui_state.take_egui_input(&gpu.window);
            let adapter = ctx.describe();
            let readout = Readout {
                scene: &self.options.name,
                adapter: &adapter,
                primitives: gpu.tracer.primitives,
                size: (gpu.config.width, gpu.config.height),
                fps: self.fps,
                frame_ms: self.frame_ms,
                timestamps: ctx.timestamps,
                // The frame's full ray count lives in its targets; the panel counts primary rays.
                mrays_per_s: (gpu.config.width as u64 * gpu.config.height as u64) as f64
                    / (self.frame_ms.max(1e-6) * 1e3),
                samples: (gpu.tracer.renderer.targets().samples(), self.options.samples.max(1)),
                build_ms: self.build_ms,
                message: self.message.as_deref(),
            };
            let modes = self.modes;
            let output = gpu
                .egui
                .run_pass(raw, |ui_ctx| asked = Some(panel::draw(ui_ctx, &modes, &readout)));
            gpu.egui_state
                .handle_platform_output(&gpu.window, output.platform_output);
            let jobs = gpu.egui.tessellate(output.shapes, output.pixels_per_point);
            let screen = egui_wgpu::ScreenDescriptor {
                size_in_pixels: [gpu.config.width, gpu.config.height],
                pixels_per_point: output.pixels_per_point,
            };
            for (id, deltas) in &output.textures_delta.set {
                for delta in deltas {
                    gpu.egui_renderer.update_texture(&ctx.device, &ctx.queue, *id, delta);
                }
            }
            let extra = gpu
                .egui_renderer
                .update_buffers(&ctx.device, &ctx.queue, &mut encoder, &jobs, &screen);
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("panel"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
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
            });
            gpu.egui_renderer.render(&mut pass.forget_lifetime(), &jobs, &screen);
            ctx.queue.submit(extra.into_iter().chain([encoder.finish()]));
            for id in &output.textures_delta.free {
                gpu.egui_renderer.free_texture(id);
            }
        } else {
            ctx.queue.submit([encoder.finish()]);
        }
        ctx.queue.present(surface_texture);
        // The frame's GPU time where the adapter has timestamps; this waits for the frame.
        if trace {
            let gpu_ms = block_on(gpu.tracer.renderer.read_gpu_ms()).ok().flatten();
            self.frame_ms = gpu_ms.unwrap_or(seconds * 1e3);
            if let Some(ms) = gpu_ms {
                self.trace_times.push(ms);
            }
        }
        if self.frames_drawn > 0 {
            self.frame_times.push(seconds * 1e3);
        }
        self.fps = if self.fps == 0.0 {
            1.0 / seconds.max(1e-6)
        } else {
            0.9 * self.fps + 0.1 / seconds.max(1e-6)
        };
        if let Some(rebuild) = &gpu.tracer.rebuild
            && self.modes.accel.uses_bvh()
            && trace
            && let Ok(timings) = block_on(rebuild.read_timings())
        {
            self.build_ms = Some(timings.total());
        }
        self.frames_drawn += 1;
        if let Some(asked) = asked
            && asked != self.modes
        {
            self.set_modes(asked);
        }
        if let Some(script) = self.options.script.clone() {
            self.finish_script(event_loop, &script);
        }
    }

    fn finish_script(&mut self, event_loop: &ActiveEventLoop, script: &Script) {
        if self.frames_drawn == 1 {
            for path in &script.drops {
                self.open_file(path);
            }
        }
        if self.frames_drawn < script.frames.max(1) {
            return;
        }
        if let Some(path) = &script.screenshot
            && let Err(why) = self.screenshot(path)
        {
            return self.fail(event_loop, ViewError::Scene(why));
        }
        event_loop.exit();
    }
}

fn present_mode(caps: &wgpu::SurfaceCapabilities, vsync: bool) -> wgpu::PresentMode {
    let wanted = if vsync {
        wgpu::PresentMode::AutoVsync
    } else {
        wgpu::PresentMode::AutoNoVsync
    };
    if vsync || caps.present_modes.iter().any(|m| *m != wgpu::PresentMode::Fifo) {
        wanted
    } else {
        wgpu::PresentMode::Fifo
    }
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(gpu) => {
                gpu.window.request_redraw();
                self.gpu = Some(gpu);
            }
            Err(error) => self.fail(event_loop, error),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let consumed = match &mut self.gpu {
            Some(gpu) if self.show_panel => gpu.egui_state.on_window_event(&gpu.window, &event).consumed,
            _ => false,
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = &mut self.gpu
                    && size.width > 0
                    && size.height > 0
                {
                    gpu.config.width = size.width;
                    gpu.config.height = size.height;
                    gpu.surface.configure(&gpu.ctx.device, &gpu.config);
                    if let Err(error) = gpu.tracer.renderer.resize(size.width, size.height) {
                        self.message = Some(error.to_string());
                    }
                }
            }
            WindowEvent::RedrawRequested => return self.draw(event_loop),
            WindowEvent::DroppedFile(path) => self.open_file(&path),
            WindowEvent::KeyboardInput { event, .. } if !consumed => {
                if let PhysicalKey::Code(code) = event.physical_key
                    && !event.repeat
                {
                    self.key(code, event.state == ElementState::Pressed);
                }
            }
            WindowEvent::MouseInput { state, button, .. } if !consumed || state == ElementState::Released => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.input.orbiting = down,
                    MouseButton::Right | MouseButton::Middle => self.input.panning = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let Some((px, py)) = self.input.cursor {
                    let (dx, dy) = ((x - px) as f32, (y - py) as f32);
                    if self.input.orbiting {
                        self.camera.orbit(dx, dy);
                    } else if self.input.panning {
                        let height = self.gpu.as_ref().map_or(1, |g| g.config.height) as f32;
                        self.camera.pan(dx, dy, height);
                    }
                }
                self.input.cursor = Some((x, y));
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.camera.dolly(steps);
            }
            _ => {}
        }
        // Input may change what is shown: draw now, not at the idle pace.
        if let Some(gpu) = &self.gpu {
            gpu.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(gpu) = &self.gpu else { return };
        // A still frame with all its samples is only shown again: a few times a second keeps the
        // panel current without spinning a core. Input wakes the loop at once (`window_event`).
        if self.idle && self.options.script.is_none() {
            let next = self.last_frame + IDLE_REDRAW;
            event_loop.set_control_flow(ControlFlow::WaitUntil(next));
            if Instant::now() < next {
                return;
            }
        } else {
            event_loop.set_control_flow(ControlFlow::Poll);
        }
        gpu.window.request_redraw();
    }
}

/// The mode key a window's key is (`ModeKey::from_code` reads the page's).
fn mode_key(code: KeyCode) -> Option<ModeKey> {
    Some(match code {
        KeyCode::KeyB => ModeKey::Accel,
        KeyCode::KeyG => ModeKey::Pipeline,
        KeyCode::KeyM => ModeKey::Memory,
        KeyCode::KeyV => ModeKey::View,
        KeyCode::BracketLeft => ModeKey::FewerBounces,
        KeyCode::BracketRight => ModeKey::MoreBounces,
        KeyCode::Space => ModeKey::Pause,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window and a page map the same keys to the same modes: winit's key names are the
    /// browser's `KeyboardEvent.code` names.
    #[test]
    fn window_and_page_keys_agree() {
        let codes = [
            KeyCode::KeyB,
            KeyCode::KeyG,
            KeyCode::KeyM,
            KeyCode::KeyV,
            KeyCode::BracketLeft,
            KeyCode::BracketRight,
            KeyCode::Space,
            KeyCode::KeyW,
            KeyCode::Enter,
        ];
        for code in codes {
            assert_eq!(mode_key(code), ModeKey::from_code(&format!("{code:?}")), "{code:?}");
        }
        assert_eq!(codes.iter().filter(|&&c| mode_key(c).is_some()).count(), 7);
    }
}
