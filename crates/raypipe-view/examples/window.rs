//! raypipe inside a winit program of its own: the program owns the window, the surface and the
//! frame loop; raypipe traces a sample a frame into its own targets (gathering while the scene
//! stands still), its display pass draws them into the program's surface texture, and the program
//! draws an overlay of its own over them in the same encoder before it presents.
//!
//! `cargo run --release --example window` (`-- --frames N` closes after N frames).

use raypipe::gpu::{Display, GpuContext, Renderer, RendererOptions, Shown};
use raypipe::image::tonemap::DisplayTransform;
use raypipe::modes::Aov;
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use raypipe_view::{next_texture, overlay_pass, present_format, surface_config};
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

/// The program's overlay: a translucent band along the bottom of the frame.
const OVERLAY: &str = "
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}
@fragment fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(0.1, 0.1, 0.15, 0.6);
}
";

struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    renderer: Renderer,
    display: Display,
    overlay: wgpu::RenderPipeline,
    camera_distance: f32,
}

#[derive(Default)]
struct App {
    gpu: Option<Gpu>,
    frames: u32,
    /// Close after this many frames, where asked.
    frame_limit: Option<u32>,
    error: Option<String>,
}

impl App {
    fn open(&self, event_loop: &ActiveEventLoop) -> Result<Gpu, Box<dyn std::error::Error>> {
        let attributes = Window::default_attributes()
            .with_title("raypipe in a program of its own")
            .with_inner_size(winit::dpi::PhysicalSize::new(480, 360));
        let window = Arc::new(event_loop.create_window(attributes)?);
        let desc =
            wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(event_loop.owned_display_handle()));
        let instance = wgpu::Instance::new(desc);
        let surface = instance.create_surface(window.clone())?;
        let ctx = pollster::block_on(GpuContext::for_surface(&instance, &surface))?;
        let caps = surface.get_capabilities(&ctx.adapter);
        let format = present_format(&caps).ok_or("the surface offers no format")?;
        let size = window.inner_size();
        let config = surface_config(&caps, format, (size.width, size.height), true);
        surface.configure(&ctx.device, &config);

        let mut scene = Scene::load("whitted")?;
        (scene.settings.width, scene.settings.height) = (config.width, config.height);
        let camera_distance = (scene.camera.eye - scene.camera.target).length();
        let mut packed = PackedScene::new(&scene)?;
        packed.build_bvh();
        let renderer = pollster::block_on(Renderer::new(&ctx, &packed, RendererOptions::default()))?;
        let display = Display::new(&ctx, format);
        let overlay = overlay_pipeline(&ctx.device, format);
        Ok(Gpu {
            window,
            surface,
            config,
            ctx,
            renderer,
            display,
            overlay,
            camera_distance,
        })
    }

    fn draw(&mut self, event_loop: &ActiveEventLoop) {
        let Some(gpu) = &mut self.gpu else { return };
        // A device lost (a driver reset, an unplugged GPU): said in one line, and the program ends.
        if let Err(lost) = gpu.ctx.live() {
            eprintln!("error: {lost}");
            event_loop.exit();
            return;
        }
        let Some(texture) = next_texture(&gpu.surface, &gpu.ctx.device, &gpu.config) else {
            return;
        };
        let view = texture.texture.create_view(&Default::default());
        let mut encoder = gpu.ctx.device.create_command_encoder(&Default::default());
        // raypipe: the next sample, then its targets shown in the surface texture.
        if gpu.renderer.samples() < 64 {
            gpu.renderer.encode(&mut encoder);
        }
        let depth_far = 3.0 * gpu.camera_distance;
        let shown = Shown {
            aov: Aov::Color,
            depth_far,
            cost_max: 200.0,
            transform: DisplayTransform::IDENTITY,
        };
        gpu.display.encode(&mut encoder, gpu.renderer.targets(), &view, &shown);
        // The program's own pass over it, in the same encoder.
        let (width, height) = (gpu.config.width, gpu.config.height);
        let mut pass = overlay_pass(&mut encoder, &view, "overlay");
        pass.set_pipeline(&gpu.overlay);
        pass.set_scissor_rect(0, height - height / 8, width, height / 8);
        pass.draw(0..3, 0..1);
        drop(pass);
        gpu.ctx.queue.submit([encoder.finish()]);
        gpu.ctx.queue.present(texture);
        self.frames += 1;
        if self.frame_limit.is_some_and(|limit| self.frames >= limit) {
            event_loop.exit();
        }
        gpu.window.request_redraw();
    }
}

fn overlay_pipeline(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("overlay"),
        source: wgpu::ShaderSource::Wgsl(OVERLAY.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("overlay"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(gpu) => {
                gpu.window.request_redraw();
                self.gpu = Some(gpu);
            }
            Err(error) => {
                self.error = Some(error.to_string());
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                if let Some(gpu) = &mut self.gpu {
                    (gpu.config.width, gpu.config.height) = (size.width, size.height);
                    gpu.surface.configure(&gpu.ctx.device, &gpu.config);
                    if let Err(error) = gpu.renderer.resize(size.width, size.height) {
                        self.error = Some(error.to_string());
                        event_loop.exit();
                    }
                }
            }
            WindowEvent::RedrawRequested => self.draw(event_loop),
            _ => {}
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut app = App::default();
    while let Some(arg) = args.next() {
        match (arg.as_str(), args.next()) {
            ("--frames", Some(n)) => app.frame_limit = Some(n.parse()?),
            _ => return Err(format!("usage: window [--frames N] (got {arg})").into()),
        }
    }
    EventLoop::new()?.run_app(&mut app)?;
    match app.error {
        Some(error) => Err(error.into()),
        None => Ok(()),
    }
}
