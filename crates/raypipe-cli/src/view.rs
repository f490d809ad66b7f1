//! `raypipe view`: the scene live in a window (the `raypipe-view` crate), with `render`'s scene
//! flags; this side loads dropped files and writes screenshots.

use crate::io;
use crate::scene_args::{SceneArgs, load_scene};
use clap::Args;
use raypipe::image::Frame;
use raypipe::image::tonemap::DisplayTransform;
use raypipe::modes::Aov;
use raypipe::scene::model::ModelOptions;
use raypipe::scene::{Environment, Scene};
use raypipe_view::{Host, HostError, Modes, Script, ViewerOptions};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub struct ViewArgs {
    /// The scene and its flags, as `render` takes them; --width and --height give the window's
    /// starting size, which the traced frame follows after; --aov picks the view.
    #[command(flatten)]
    scene: SceneArgs,
    /// Draw this many frames, then exit (with --screenshot, after saving the last one).
    #[arg(long)]
    frames: Option<u32>,
    /// With --frames: save the last frame here, as `render` writes it.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// With --frames: turn the camera this many degrees about its target every frame.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    orbit: f32,
    /// With --frames: after the first frame, open these files as if dropped on the window.
    #[arg(long)]
    drop: Vec<PathBuf>,
    /// Start with a moving scene's motion paused (at --time), as Space pauses it.
    #[arg(long)]
    paused: bool,
    /// Present without waiting for the display's refresh.
    #[arg(long)]
    no_vsync: bool,
    /// Samples per pixel a still frame gathers, one per frame, before tracing stops (progressive
    /// anti-aliasing); 1 shows `render`'s image.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=crate::scene_args::MAX_SPP as i64))]
    spp: u32,
}

/// `error` about `path`, worded as the command line words it.
fn host_error(path: &Path, error: &anyhow::Error) -> HostError {
    HostError {
        path: path.to_path_buf(),
        reason: crate::report::message(error),
    }
}

/// Dropped files load as `render` loads them; screenshots are written as it writes them.
struct CliHost {
    shots: Cell<u32>,
}

impl Host for CliHost {
    fn load(&self, path: &Path) -> Result<Scene, HostError> {
        let spec = path.to_string_lossy();
        load_scene(&spec, &ModelOptions::default()).map_err(|e| host_error(path, &e))
    }

    fn load_environment(&self, path: &Path) -> Result<Environment, HostError> {
        Environment::load(path).map_err(|e| host_error(path, &e.into()))
    }

    fn save(&self, frame: &Frame, view: Aov, transform: &DisplayTransform, path: &Path) -> Result<(), HostError> {
        let is_exr = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        io::write(&frame.aov_image(view, is_exr, transform), path).map_err(|e| host_error(path, &e))
    }

    fn screenshot_path(&self, view: Aov) -> PathBuf {
        let n = self.shots.get() + 1;
        self.shots.set(n);
        // Depth is a float image, as `render --aov depth` writes it.
        let extension = if view == Aov::Depth { "exr" } else { "png" };
        PathBuf::from(format!("raypipe-{n:03}.{extension}"))
    }
}

pub fn run(args: ViewArgs) -> anyhow::Result<ExitCode> {
    if args.screenshot.is_some() && args.frames.is_none() {
        anyhow::bail!("--screenshot saves the last of --frames N frames: give --frames");
    }
    if let Some(path) = &args.screenshot {
        let wanted = if args.scene.aov == Aov::Depth { "exr" } else { "png" };
        if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case(wanted)) {
            anyhow::bail!(
                "{}: the {} view's screenshots are {} files",
                path.display(),
                match args.scene.aov {
                    Aov::Depth => "depth",
                    _ => "colour, normal and cost",
                },
                wanted.to_uppercase()
            );
        }
        io::check_writable(path)?;
    }
    let scene = args.scene.load()?;
    args.scene.check_builder_for_motion(&scene)?;
    // Checked here, so that a bad size or depth is one line before any window opens.
    raypipe::records::PackedScene::new(&scene).map_err(|e| e.in_origin(&args.scene.spec))?;
    let options = ViewerOptions {
        name: args.scene.spec.clone(),
        modes: Modes {
            pipeline: args.scene.pipeline,
            accel: scene.settings.accel.unwrap_or_default(),
            builder: args.scene.builder,
            memory: args.scene.memory,
            depth: scene.settings.max_depth,
            integrator: scene.settings.integrator,
            view: args.scene.aov,
            paused: args.paused,
            vsync: !args.no_vsync,
            display: args.scene.display_transform(&scene),
        },
        tone_map_chosen: args.scene.tonemap.is_some(),
        integrator_chosen: args.scene.integrator.is_some(),
        time: match args.scene.time {
            Some(t) => args.scene.scene_time(&scene, t)?,
            None => 0.0,
        },
        scene,
        samples: args.spp,
        backend: args.scene.backend,
        script: args.frames.map(|frames| Script {
            frames,
            screenshot: args.screenshot.clone(),
            orbit_degrees: args.orbit,
            drops: args.drop.clone(),
        }),
    };
    let scripted = args.frames.is_some();
    let summary = raypipe_view::run(options, Box::new(CliHost { shots: Cell::new(0) }))?;
    if scripted {
        let trace = summary
            .trace_ms
            .map_or("no timestamp queries".to_string(), |ms| format!("{ms:.2} ms"));
        crate::say!(
            "view: {} frames; median trace pass {trace} (GPU timestamps), median frame {:.2} ms (wall clock: trace, display, present)",
            summary.frames,
            summary.frame_ms
        );
    }
    Ok(ExitCode::SUCCESS)
}
