use crate::bvh::morton::MortonBits;
use crate::gpu::context::Backend;
use crate::gpu::upload::MemoryMode;
use crate::image::io;
use crate::render::{Accel, DeviceChoice, RenderOptions, render};
use crate::scene::Scene;
use crate::scene::packed::PackedScene;
use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Aov {
    /// Shaded colour: PNG (sRGB) or EXR (linear).
    #[default]
    Color,
    /// Distance from the eye to the first hit, channel `Z` of a float EXR; +inf where nothing is hit.
    Depth,
    /// First-hit normals, mapped from [-1, 1] to [0, 1].
    Normal,
}

#[derive(Args)]
pub struct RenderArgs {
    /// A built-in scene (whitted, sphere-8k, torus-5k, sphere:N, torus:N, random:N[:SEED]) or a TOML file.
    #[arg(default_value = "whitted")]
    scene: String,
    /// Output file; the extension picks PNG or EXR. Default: render.png, or depth.exr for --aov depth.
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Maximum bounces after the primary ray (default 5, or the scene's).
    #[arg(long)]
    depth: Option<u32>,
    #[arg(long, value_enum, default_value_t)]
    device: DeviceChoice,
    #[arg(long, value_enum)]
    backend: Option<Backend>,
    #[arg(long, value_enum, default_value_t)]
    memory: MemoryMode,
    #[arg(long, value_enum, default_value_t)]
    accel: Accel,
    #[arg(long, value_enum, default_value_t)]
    aov: Aov,
    /// Print render time and rays per second.
    #[arg(long)]
    stats: bool,
}

pub fn run(args: RenderArgs) -> anyhow::Result<ExitCode> {
    let output = args.output.clone().unwrap_or_else(|| match args.aov {
        Aov::Depth => "depth.exr".into(),
        _ => "render.png".into(),
    });
    let is_exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let is_png = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !(is_exr || is_png) {
        bail!("{}: output must end in .png or .exr", output.display());
    }
    if args.aov == Aov::Depth && !is_exr {
        bail!(
            "{}: --aov depth writes a float EXR; name the output *.exr",
            output.display()
        );
    }

    let mut scene = Scene::load(&args.scene)?;
    let settings = &mut scene.settings;
    settings.width = args.width.unwrap_or(settings.width);
    settings.height = args.height.unwrap_or(settings.height);
    settings.max_depth = args.depth.unwrap_or(settings.max_depth);
    let mut packed = PackedScene::new(&scene).with_context(|| args.scene.clone())?;
    if args.accel.uses_bvh() {
        packed.build_bvh(MortonBits::default());
    }

    let options = RenderOptions {
        device: args.device,
        backend: args.backend,
        memory: args.memory,
        accel: args.accel,
        progress: std::io::stderr().is_terminal(),
        warm_up: args.stats,
    };
    let outcome = render(&packed, &options)?;
    let frame = &outcome.frame;
    let image = match (args.aov, is_exr) {
        (Aov::Color, false) => frame.display(),
        (Aov::Color, true) => frame.radiance(),
        (Aov::Depth, _) => frame.depth(),
        (Aov::Normal, _) => frame.normals(),
    };
    io::write(&image, &output)?;

    if args.stats {
        let pixels = frame.width as u64 * frame.height as u64;
        let rays = frame.rays();
        println!(
            "scene: {}, {}x{}, {} spheres, {} planes, {} lights, depth {}",
            args.scene,
            frame.width,
            frame.height,
            packed.spheres.len(),
            packed.planes.len(),
            packed.lights.len(),
            packed.max_depth
        );
        println!(
            "device: {}, memory {:?}, accel {:?}",
            outcome.device, args.memory, args.accel
        );
        let (ms, clock) = match outcome.gpu_ms {
            Some(ms) => (ms, "GPU timestamps"),
            None => (outcome.wall_ms, "wall clock"),
        };
        println!(
            "render: {ms:.2} ms ({clock}; wall {:.2} ms), {rays} rays ({:.2} per pixel), {:.2} Mrays/s",
            outcome.wall_ms,
            rays as f64 / pixels as f64,
            rays as f64 / (ms * 1e3)
        );
    }
    Ok(ExitCode::SUCCESS)
}
