//! The native window: winit's event loop, a wgpu surface, and each frame traced, displayed, overlaid
//! with the panel and presented.

use crate::panel::{self, Playback, Readout};
use crate::player::{FlyKeys, Player, Screen, Timings, overlay_pass};
use crate::{Host, ModeKey, Modes, ScreenshotError, Script, Summary, ViewError, ViewerOptions};
use pollster::block_on;
use raypipe::gpu::GpuContext;
use raypipe::scene::environment::is_environment_file;
use std::sync::Arc;
use web_time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, OwnedDisplayHandle};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// How often an idle viewer (nothing to trace, nothing moving) redraws its panel.
const IDLE_REDRAW: std::time::Duration = std::time::Duration::from_millis(100);
/// A scripted run's motion step per frame: the same frames every run, whatever the frame rate.
const SCRIPT_STEP: f32 = 1.0 / 30.0;

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
        frames: viewer.gpu.as_ref().map_or(0, |g| g.player.frames),
        trace_ms: median(steady(&viewer.trace_times)),
        frame_ms: median(steady(&viewer.frame_times)).unwrap_or(0.0),
    })
}

/// What lives on the GPU once the window exists.
struct Gpu {
    window: Arc<Window>,
    screen: Screen,
    player: Player,
    panel: PanelPainter,
}

/// egui's state for the panel drawn over the frame.
struct PanelPainter {
    egui: egui::Context,
    state: egui_winit::State,
    renderer: egui_wgpu::Renderer,
}

#[derive(Default)]
struct Input {
    orbiting: bool,
    panning: bool,
    cursor: Option<(f64, f64)>,
    fly: FlyKeys,
}

struct Viewer {
    /// What the window starts with; the player owns the scene once the window is open.
    options: ViewerOptions,
    host: Box<dyn Host>,
    display_handle: OwnedDisplayHandle,
    gpu: Option<Gpu>,
    input: Input,
    show_panel: bool,
    last_frame: Instant,
    /// The last frame traced nothing (its samples were all gathered) and nothing moves: the next
    /// may wait for input or the panel's refresh.
    idle: bool,
    /// Per frame: the trace pass's GPU time (with timestamps), and the wall clock between frames.
    trace_times: Vec<f64>,
    frame_times: Vec<f64>,
    outcome: Result<(), ViewError>,
}

impl Viewer {
    fn new(options: ViewerOptions, host: Box<dyn Host>, display_handle: OwnedDisplayHandle) -> Self {
        Self {
            // A scripted run shows what `render` shows: no panel over the frame.
            show_panel: options.script.is_none(),
            options,
            host,
            display_handle,
            gpu: None,
            input: Input::default(),
            last_frame: Instant::now(),
            idle: false,
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
        let size = window.inner_size();
        let mut modes = self.options.modes;
        let adapter = ctx.describe();
        let screen = Screen::new(ctx, surface, (size.width, size.height), modes.vsync)
            .ok_or_else(|| ViewError::Window(format!("{adapter} cannot present to this window")))?;
        let ctx = &screen.ctx;
        if !ctx.memory_modes().contains(&modes.memory) {
            modes.memory = ctx.default_memory();
        }
        let mut player = block_on(Player::new(
            ctx,
            self.options.name.clone(),
            self.options.scene.clone(),
            modes,
            screen.size(),
            self.options.samples,
        ))?;
        player.start_at(self.options.time);
        player.tone_map_chosen = self.options.tone_map_chosen;
        player.integrator_chosen = self.options.integrator_chosen;
        if self.options.script.is_some() {
            player.clock.step = Some(SCRIPT_STEP);
        }
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(&ctx.device, screen.config.format, Default::default());
        Ok(Gpu {
            window,
            screen,
            player,
            panel: PanelPainter {
                egui,
                state: egui_state,
                renderer: egui_renderer,
            },
        })
    }

    /// Switches to `asked` if it can serve the scene; otherwise keeps the modes and says why.
    fn set_modes(&mut self, asked: Modes) {
        let Some(gpu) = &mut self.gpu else { return };
        if asked.vsync != gpu.player.modes.vsync {
            gpu.screen.set_vsync(asked.vsync);
        }
        if let Some(request) = gpu.player.set_modes(asked) {
            let built = block_on(request.build(&gpu.screen.ctx));
            gpu.player.install(request, built);
        }
    }

    /// A dropped file: its scene replaces the current one, or its environment lights it; or its
    /// one-line error shows and the current scene and environment stay.
    fn open_file(&mut self, path: &std::path::Path) {
        let Some(gpu) = &mut self.gpu else { return };
        let name = path.display().to_string();
        if is_environment_file(&name) {
            match self.host.load_environment(path) {
                Ok(environment) => {
                    let request = gpu.player.relight(Some(environment));
                    let built = block_on(request.build(&gpu.screen.ctx));
                    gpu.player.install(request, built);
                }
                Err(why) => gpu.player.say(why.to_string()),
            }
            return;
        }
        match self.host.load(path) {
            Ok(scene) => {
                let request = gpu.player.open(name, scene);
                let built = block_on(request.build(&gpu.screen.ctx));
                gpu.player.install(request, built);
                gpu.window.set_title(&format!("raypipe · {}", gpu.player.name));
            }
            Err(why) => gpu.player.say(why.to_string()),
        }
    }

    fn key(&mut self, code: KeyCode, pressed: bool) {
        // winit's key names are the browser's `KeyboardEvent.code` names, which FlyKeys takes.
        if self.input.fly.set(&format!("{code:?}"), pressed) || !pressed {
            return;
        }
        let Some(gpu) = &mut self.gpu else { return };
        if let Some(key) = mode_key(code) {
            let asked = gpu.player.modes.after(key, &gpu.screen.ctx.accels());
            return self.set_modes(asked);
        }
        let mut asked = gpu.player.modes;
        match code {
            KeyCode::KeyR => gpu.player.camera.reset(),
            KeyCode::KeyY => asked.vsync = !asked.vsync,
            KeyCode::KeyH => self.show_panel = !self.show_panel,
            KeyCode::KeyP => {
                let path = self.host.screenshot_path(gpu.player.modes.view);
                let said = match self.screenshot(&path) {
                    Ok(()) => format!("saved {}", path.display()),
                    Err(why) => why.to_string(),
                };
                log::info!("{said}");
                if let Some(gpu) = &mut self.gpu {
                    gpu.player.message = Some(said);
                }
                return;
            }
            _ => {}
        }
        if asked != gpu.player.modes {
            self.set_modes(asked);
        }
    }

    /// Saves the frame shown (tracing one sample first where none is); the error says why not.
    fn screenshot(&mut self, path: &std::path::Path) -> Result<(), ScreenshotError> {
        let Some(gpu) = &mut self.gpu else {
            return Err(ScreenshotError::NoFrame);
        };
        let frame = block_on(gpu.player.read_frame(&gpu.screen.ctx))?;
        let modes = &gpu.player.modes;
        Ok(self.host.save(&frame, modes.view, &modes.display, path)?)
    }

    fn draw(&mut self, event_loop: &ActiveEventLoop) {
        let script = self.options.script.clone();
        let Some(gpu) = &mut self.gpu else { return };
        // wgpu said at its last poll that the device is gone: the window says so and closes.
        if let Err(lost) = gpu.screen.ctx.live() {
            return self.fail(event_loop, lost.into());
        }
        if let Some(script) = &script
            && script.orbit_degrees != 0.0
            && gpu.player.frames > 0
        {
            gpu.player.camera.orbit_degrees(script.orbit_degrees);
        }
        let mut asked = None;
        let show_panel = self.show_panel;
        let report = gpu.player.frame(
            &gpu.screen,
            self.input.fly.direction(),
            Timings::Wait,
            |player, encoder, view| {
                if !show_panel {
                    return Vec::new();
                }
                let (modes, first) = draw_panel(&mut gpu.panel, &gpu.window, &gpu.screen, player, encoder, view);
                asked = Some(modes);
                first
            },
        );
        self.last_frame = Instant::now();
        self.idle = !report.traced && !gpu.player.moving() && !self.input.fly.any();
        if !report.presented {
            return;
        }
        self.trace_times.extend(report.gpu_ms);
        // The first frame's interval counts from the window's opening.
        if gpu.player.frames > 1 {
            self.frame_times.push(report.seconds * 1e3);
        }
        if let Some(asked) = asked
            && asked != gpu.player.modes
        {
            self.set_modes(asked);
        }
        if let Some(script) = script {
            self.finish_script(event_loop, &script);
        }
    }

    fn finish_script(&mut self, event_loop: &ActiveEventLoop, script: &Script) {
        let frames = self.gpu.as_ref().map_or(0, |g| g.player.frames);
        if frames == 1 {
            for path in &script.drops {
                self.open_file(path);
            }
        }
        if frames < script.frames.max(1) {
            return;
        }
        if let Some(path) = &script.screenshot
            && let Err(why) = self.screenshot(path)
        {
            return self.fail(event_loop, why.into());
        }
        event_loop.exit();
    }
}

/// Records the panel over the frame; returns the modes the panel asks for and the command buffers
/// to submit before the frame's. Its time slider and speed go to the player's clock at once.
fn draw_panel(
    panel: &mut PanelPainter,
    window: &Window,
    screen: &Screen,
    player: &mut Player,
    encoder: &mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
) -> (Modes, Vec<wgpu::CommandBuffer>) {
    let ctx = &screen.ctx;
    let raw = panel.state.take_egui_input(window);
    let adapter = ctx.describe();
    let accels = ctx.accels();
    let (width, height) = screen.size();
    let readout = Readout {
        scene: &player.name,
        adapter: &adapter,
        primitives: player.primitives(),
        size: (width, height),
        fps: player.rate.fps,
        frame_ms: player.rate.frame_ms,
        timestamps: ctx.timestamps,
        // The frame's full ray count lives in its targets; the panel counts primary rays.
        mrays_per_s: (width as u64 * height as u64) as f64 / (player.rate.frame_ms.max(1e-6) * 1e3),
        samples: (player.gathered(), player.spp),
        build_ms: player.build_ms,
        accels: &accels,
        message: player.message.as_deref(),
    };
    let modes = player.modes;
    let mut playback = player.scene.motion.as_ref().map(|_| Playback {
        time: player.clock.time,
        duration: player.duration(),
        speed: player.clock.speed,
    });
    let mut asked = modes;
    let output = panel.egui.run_pass(raw, |ui_ctx| {
        asked = panel::draw(ui_ctx, &modes, &readout, playback.as_mut());
    });
    if let Some(playback) = playback {
        player.clock.speed = playback.speed;
        if playback.time != player.clock.time {
            player.seek(playback.time);
        }
    }
    panel.state.handle_platform_output(window, output.platform_output);
    let jobs = panel.egui.tessellate(output.shapes, output.pixels_per_point);
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [width, height],
        pixels_per_point: output.pixels_per_point,
    };
    for (id, deltas) in &output.textures_delta.set {
        for delta in deltas {
            panel.renderer.update_texture(&ctx.device, &ctx.queue, *id, delta);
        }
    }
    let first = panel
        .renderer
        .update_buffers(&ctx.device, &ctx.queue, encoder, &jobs, &screen);
    let pass = overlay_pass(encoder, view, "panel");
    panel.renderer.render(&mut pass.forget_lifetime(), &jobs, &screen);
    for id in &output.textures_delta.free {
        panel.renderer.free_texture(id);
    }
    (asked, first)
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
            Some(gpu) if self.show_panel => gpu.panel.state.on_window_event(&gpu.window, &event).consumed,
            _ => false,
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = &mut self.gpu
                    && size.width > 0
                    && size.height > 0
                {
                    gpu.screen.resize(size.width, size.height);
                    if let Err(error) = gpu.player.resize(size.width, size.height) {
                        gpu.player.say(error.to_string());
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
                    if let Some(gpu) = &mut self.gpu {
                        let height = gpu.screen.config.height as f32;
                        if self.input.orbiting {
                            gpu.player.camera.orbit(dx, dy);
                        } else if self.input.panning {
                            gpu.player.camera.pan(dx, dy, height);
                        }
                    }
                }
                self.input.cursor = Some((x, y));
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(gpu) = &mut self.gpu {
                    gpu.player.camera.dolly(steps);
                }
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
        KeyCode::KeyI => ModeKey::Integrator,
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
            KeyCode::KeyI,
            KeyCode::Space,
            KeyCode::KeyW,
            KeyCode::Enter,
        ];
        for code in codes {
            assert_eq!(mode_key(code), ModeKey::from_code(&format!("{code:?}")), "{code:?}");
        }
        assert_eq!(codes.iter().filter(|&&c| mode_key(c).is_some()).count(), 8);
    }
}
