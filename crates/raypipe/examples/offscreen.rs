//! raypipe in a program of its own: the Whitted scene traced at 320x240 on a wgpu device the
//! program opens itself, read back and written as a PNG, through the library's public API alone.
//! The image is `raypipe render whitted --width 320 --height 240`'s, bit for bit.
//!
//! `cargo run --release --example offscreen -- whitted.png`

use raypipe::gpu::{GpuContext, Renderer, RendererOptions};
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use std::error::Error;

fn main() -> Result<(), Box<dyn Error>> {
    let path = std::env::args().nth(1).unwrap_or_else(|| "offscreen.png".into());
    pollster::block_on(run(&path))
}

async fn run(path: &str) -> Result<(), Box<dyn Error>> {
    // The program's own device, with the adapter's limits: large scenes need them.
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
    let adapter = instance
        .request_adapter(&wgpu::RequestAdapterOptions::default())
        .await?;
    let (device, queue) = adapter
        .request_device(&wgpu::DeviceDescriptor {
            label: Some("the program's device"),
            required_limits: adapter.limits(),
            ..Default::default()
        })
        .await?;
    let ctx = GpuContext::from_device(adapter, device, queue);
    // A device lost later (a driver reset): every operation fails with GpuError::Lost's one line.
    ctx.watch_loss();

    // The scene, packed into the records the shader reads, with its BVH built on the CPU.
    let mut scene = Scene::load("whitted")?;
    (scene.settings.width, scene.settings.height) = (320, 240);
    let mut packed = PackedScene::new(&scene)?;
    packed.build_bvh();

    // Traced in the fragment shader (the default pipeline, threaded walk, storage memory), read back.
    let mut renderer = Renderer::new(&ctx, &packed, RendererOptions::default()).await?;
    let frame = renderer.read_frame().await?.frame;

    // Display-encoded (sRGB) values, rounded to 8 bits as `raypipe render` writes a PNG.
    let display = frame.display();
    image::save_buffer(
        path,
        &display.to_bytes(),
        display.width,
        display.height,
        image::ColorType::Rgb8,
    )?;
    println!("{path}: {}x{} on {}", display.width, display.height, ctx.describe());
    Ok(())
}
