use crate::args::choice;
use crate::cli::median;
use crate::device::{DeviceChoice, RenderOptions, render, render_frames};
use crate::io;
use anyhow::bail;
use clap::{Args, ValueEnum};
use raypipe::bvh::morton::MortonBits;
use raypipe::cpu::Count;
use raypipe::gpu::Backend;
use raypipe::image::{FloatImage, Frame, heatmap};
use raypipe::modes::{Accel, MemoryMode, Pipeline};
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use raypipe::scene::animation::ClipChoice;
use raypipe::scene::model::is_model_file;
use raypipe::scene::model::{MeshAs, ModelOptions, Normals};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Aov {
    /// Shaded colour: PNG (sRGB) or EXR (linear).
    #[default]
    Color,
    /// Distance from the eye to the first hit, channel `Z` of a float EXR; +inf where nothing is hit.
    Depth,
    /// First-hit shading normals, mapped from [-1, 1] to [0, 1].
    Normal,
    /// A heat map of each primary ray's cost: BVH nodes tested (box tests of internal nodes, sphere
    /// tests of leaves; spheres tested for brute force), with a colour-scale legend. PNG only.
    Cost,
}

/// What names the scene and how it is traced: the flags `render` and `view` share.
#[derive(Args)]
pub struct SceneArgs {
    /// A built-in scene (whitted, sphere-8k, torus-5k, sphere:N, torus:N, random:N[:SEED],
    /// bounce:N[:SEED]), a TOML scene file, a model file (.ply, .obj, .off) to frame and render, or a glTF
    /// scene (.gltf, .glb) with its camera and lights.
    #[arg(default_value = "whitted", value_name = "SCENE")]
    pub spec: String,
    /// With a model file: render its triangles, or spheres on its surface.
    #[arg(long = "as", value_parser = choice::<MeshAs>())]
    pub as_: Option<MeshAs>,
    /// With a model file: this many spheres, sampled uniformly by area (implies --as spheres).
    /// Without it, --as spheres puts one sphere on every vertex.
    #[arg(long)]
    pub spheres: Option<usize>,
    /// With a model file: rotate it first by these Euler angles in degrees, about x, then y, then z
    /// (say --rotate=-90,0,0 to stand up a model whose up axis is z).
    #[arg(long, value_parser = parse_angles, allow_hyphen_values = true)]
    pub rotate: Option<glam::Vec3>,
    /// With a model file's triangles: shade with the file's vertex normals where it has them, else
    /// smooth ones (auto); with each face's own normal (flat); or with smooth normals computed from
    /// the faces (smooth).
    #[arg(long, value_parser = choice::<Normals>())]
    pub normals: Option<Normals>,
    /// With smooth normals: faces meeting at more than this many degrees keep a sharp edge
    /// (default 60).
    #[arg(long, value_name = "DEGREES")]
    pub crease: Option<f32>,
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Maximum bounces after the primary ray (default 5, or the scene's; at most 32).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=raypipe::scene::MAX_DEPTH_LIMIT as i64))]
    pub depth: Option<u32>,
    #[arg(long, value_parser = choice::<Backend>())]
    pub backend: Option<Backend>,
    /// The stage that traces on the GPU: the fragment shader of a full-screen triangle (the paper's
    /// route), or a compute kernel. The images are the same.
    #[arg(long, value_parser = choice::<Pipeline>(), default_value_t)]
    pub pipeline: Pipeline,
    #[arg(long, value_parser = choice::<MemoryMode>(), default_value_t)]
    pub memory: MemoryMode,
    #[arg(long, value_parser = choice::<Accel>(), default_value_t)]
    pub accel: Accel,
    #[arg(long, value_enum, default_value_t)]
    pub aov: Aov,
    /// With a glTF that has animations: the one that plays, by name or index (default the first).
    #[arg(long, value_name = "NAME|INDEX")]
    pub animation: Option<String>,
    /// For a moving scene (an animated glTF, bounce:N): its time in seconds (with --frames, the
    /// first frame's). Past the end of an animation it holds its last pose, unless --loop.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub time: Option<f32>,
    /// With --time and --frames: an animation starts again at its end.
    #[arg(long = "loop")]
    pub looping: bool,
}

impl SceneArgs {
    /// The motion time `t` seconds asks for: checked, and wrapped where --loop says.
    pub fn scene_time(&self, scene: &Scene, t: f32) -> anyhow::Result<f32> {
        anyhow::ensure!(t.is_finite(), "--time must be a finite number of seconds");
        Ok(match &scene.motion {
            Some(motion) if self.looping => motion.looped(t),
            _ => t,
        })
    }
    /// The scene, with the size and depth the flags give.
    pub fn load(&self) -> anyhow::Result<Scene> {
        let model = ModelOptions {
            as_: self.as_,
            spheres: self.spheres,
            rotate: self.rotate,
            normals: self.normals,
            crease: self.crease,
            animation: self.animation.as_deref().map(ClipChoice::parse),
        };
        let mut scene = load_scene(&self.spec, &model)?;
        if scene.motion.is_none() && (self.time.is_some() || self.looping) {
            bail!(
                "{}: --time and --loop apply to moving scenes (an animated glTF, bounce:N)",
                self.spec
            );
        }
        // Legal but probably not meant: said once, here, rather than per packed frame.
        if scene.spheres.is_empty() && scene.triangles.is_empty() && scene.planes.is_empty() {
            log::warn!(
                "{}: the scene holds nothing to hit: the image is its background",
                self.spec
            );
        } else if scene.lights.is_empty() {
            log::warn!(
                "{}: the scene has no lights: only its ambient term shades it",
                self.spec
            );
        }
        let settings = &mut scene.settings;
        settings.width = self.width.unwrap_or(settings.width);
        settings.height = self.height.unwrap_or(settings.height);
        settings.max_depth = self.depth.unwrap_or(settings.max_depth);
        Ok(scene)
    }
}

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output file; the extension picks PNG or EXR. Default: render.png, or depth.exr for --aov depth.
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[arg(long, value_enum, default_value_t)]
    device: DeviceChoice,
    /// Primary rays per pixel, at jittered positions inside it (the first at its centre), averaged:
    /// anti-aliasing. On the GPU each sample is its own draw, added to a float sum.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    spp: u32,
    /// Print render time and rays per second (all samples' rays).
    #[arg(long)]
    stats: bool,
    /// Say nothing on success (by default one line on standard error says what was written).
    #[arg(short, long)]
    quiet: bool,
    /// Render frames of a moving scene (an animated glTF, bounce:N), rebuilding the BVH every
    /// frame (on the GPU with --memory storage): K for frames 0 to K-1, or A..B for frames A to
    /// B-1 only, so that a sequence splits across machines into the same files. Frame k is at
    /// --time plus k / --fps seconds. Writes the last frame, or every frame when the output name
    /// holds a printf-style number such as frame_%04d.png (numbered by k).
    #[arg(long, value_name = "K|A..B", value_parser = parse_frames)]
    frames: Option<std::ops::Range<u32>>,
    /// Frames per second of scene time, for --frames.
    #[arg(long, default_value_t = 30.0, value_parser = parse_fps)]
    fps: f32,
}

/// `K` (frames 0 to K-1) or `A..B` (frames A to B-1).
fn parse_frames(text: &str) -> Result<std::ops::Range<u32>, String> {
    let number = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{t}' is not a frame number (expected K or A..B)"))
    };
    let range = match text.split_once("..") {
        Some((a, b)) => number(a)?..number(b)?,
        None => 0..number(text)?,
    };
    if range.is_empty() {
        return Err(format!("{text}: no frames (A..B renders frames A to B-1)"));
    }
    Ok(range)
}

fn parse_fps(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(fps) if fps > 0.0 && fps <= 10_000.0 => Ok(fps),
        _ => Err(format!("'{text}': frames per second must be a number in (0, 10000]")),
    }
}

/// The most samples per pixel `--spp` takes: far past where an 8-bit image stops changing.
pub const MAX_SPP: u32 = 65_536;

/// Loads a scene the way every subcommand names one; the model options are flags of model files.
pub fn load_scene(spec: &str, model: &ModelOptions) -> anyhow::Result<Scene> {
    if !model.is_default() && !is_model_file(std::path::Path::new(spec)) {
        bail!(
            "scene '{spec}': --as, --spheres, --rotate, --normals, --crease and --animation apply to model files ({})",
            raypipe::scene::model::model_extension_list()
        );
    }
    if model.as_ == Some(MeshAs::Triangles) && model.spheres.is_some() {
        bail!("{spec}: --spheres needs --as spheres");
    }
    Ok(Scene::load_with(spec, model)?)
}

/// `X,Y,Z` in degrees.
pub fn parse_angles(text: &str) -> Result<glam::Vec3, String> {
    let angles: Vec<f32> = text
        .split(',')
        .map(|a| a.trim().parse::<f32>().map_err(|_| format!("'{a}' is not a number")))
        .collect::<Result<_, _>>()?;
    match angles[..] {
        [x, y, z] if angles.iter().all(|a| a.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err("expected three finite angles in degrees, as in -90,0,0".into()),
    }
}

/// The widest frame number `-o NAME_%0Nd.png` takes: more digits than any u32 has.
const MAX_NUMBER_WIDTH: usize = 10;

/// Where `name`'s `%d` or `%0Nd` is: the text before it, the width N (0 for `%d`; `usize::MAX` for
/// more digits than a usize holds), and the text after.
fn number_pattern(name: &str) -> Option<(&str, usize, &str)> {
    let start = name.find('%')?;
    let rest = &name[start + 1..];
    let digits_end = rest.find(|c: char| !c.is_ascii_digit())?;
    if !rest[digits_end..].starts_with('d') {
        return None;
    }
    let digits = &rest[..digits_end];
    let width = if digits.is_empty() {
        0
    } else {
        digits.parse().unwrap_or(usize::MAX)
    };
    Some((&name[..start], width, &rest[digits_end + 1..]))
}

fn number_width(name: &str) -> Option<usize> {
    number_pattern(name).map(|(_, width, _)| width)
}

/// `name` with its `%d` or `%0Nd` replaced by `frame`; `None` when it holds no such pattern.
pub fn numbered(name: &str, frame: u32) -> Option<String> {
    let (before, width, after) = number_pattern(name)?;
    let width = width.min(MAX_NUMBER_WIDTH);
    Some(format!("{before}{frame:0width$}{after}"))
}

pub fn run(args: RenderArgs) -> anyhow::Result<ExitCode> {
    let output = args.output.clone().unwrap_or_else(|| match args.scene.aov {
        Aov::Depth => "depth.exr".into(),
        _ => "render.png".into(),
    });
    // A device or FIFO (-o /dev/null) has no extension to go by: it gets the AOV's own format.
    let device = std::fs::metadata(&output).is_ok_and(|m| !m.is_file());
    let is_exr =
        output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) || device && args.scene.aov == Aov::Depth;
    let is_png = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) || device && !is_exr;
    if !(is_exr || is_png) {
        bail!("{}: output must end in .png or .exr", output.display());
    }
    if args.scene.aov == Aov::Depth && !is_exr {
        bail!(
            "{}: --aov depth writes a float EXR; name the output *.exr",
            output.display()
        );
    }
    if args.scene.aov == Aov::Cost && is_exr {
        bail!(
            "{}: --aov cost writes a PNG heat map; name the output *.png",
            output.display()
        );
    }

    // A frame-number width beyond any frame count would only make a name too long to create.
    if let Some(width) = number_width(&output.to_string_lossy())
        && width > MAX_NUMBER_WIDTH
    {
        bail!(
            "{}: a frame number {width} digits wide; at most {MAX_NUMBER_WIDTH}",
            output.display()
        );
    }
    // Found before the render, not after it.
    match (numbered(&output.to_string_lossy(), 0), &args.frames) {
        (Some(_), Some(frames)) => {
            let first = numbered(&output.to_string_lossy(), frames.start).expect("a pattern");
            io::check_writable(Path::new(&first))?
        }
        _ => io::check_writable(&output)?,
    }
    let scene = args.scene.load()?;
    let start = args.scene.time.unwrap_or(0.0);
    let options = RenderOptions {
        device: args.device,
        backend: args.scene.backend,
        pipeline: args.scene.pipeline,
        memory: args.scene.memory,
        accel: args.scene.accel,
        progress: std::io::stderr().is_terminal(),
        count: if args.scene.aov == Aov::Cost {
            Count::Cost
        } else {
            Count::Rays
        },
        warm_up: args.stats,
        samples: args.spp,
    };
    if let Some(frames) = args.frames.clone() {
        // Sequences time steady frames instead of a warm-up.
        let options = RenderOptions {
            warm_up: false,
            ..options
        };
        anyhow::ensure!(
            scene.motion.is_some(),
            "{}: --frames renders a moving scene (an animated glTF, bounce:N)",
            args.scene.spec
        );
        // Frame k's time depends on k alone: a split run poses the frames of a whole one.
        let times = frames
            .map(|k| {
                Ok((
                    k,
                    args.scene
                        .scene_time(&scene, start + (k as f64 / args.fps as f64) as f32)?,
                ))
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        return render_sequence(&args, &scene, &output, is_exr, &times, &options);
    }
    let posed = scene
        .at_time(args.scene.scene_time(&scene, start)?)
        .map_err(|e| e.in_origin(&args.scene.spec))?;
    let mut packed = PackedScene::new(&posed).map_err(|e| e.in_origin(&args.scene.spec))?;
    if args.scene.accel.uses_bvh() {
        packed.build_bvh(MortonBits::default());
    }
    let outcome = render(&packed, &options).map_err(|e| e.context(args.scene.spec.clone()))?;
    let frame = &outcome.frame;
    io::write_as(&aov_image(args.scene.aov, is_exr, frame), &output, is_exr)?;
    if !args.quiet {
        eprintln!(
            "wrote {} ({}x{}, {} samples per pixel, {})",
            output.display(),
            frame.width,
            frame.height,
            args.spp,
            outcome.device
        );
    }

    if args.stats {
        let pixels = frame.width as u64 * frame.height as u64;
        let rays = frame.rays();
        crate::say!(
            "scene: {}, {}x{}, {} spheres, {} triangles, {} planes, {} lights, depth {}",
            args.scene.spec,
            frame.width,
            frame.height,
            packed.spheres.len(),
            packed.triangles.len(),
            packed.planes.len(),
            packed.lights.len(),
            packed.max_depth
        );
        say_device(&args, &outcome.device)?;
        if args.scene.aov == Aov::Cost {
            let counts = frame.counts();
            let mean = counts.iter().map(|&c| c as f64).sum::<f64>() / counts.len() as f64;
            let max = counts.iter().copied().max().unwrap_or(0);
            crate::say!(
                "cost per primary ray: mean {mean:.1}, max {max} nodes tested (spheres tested for brute force)"
            );
            return Ok(ExitCode::SUCCESS);
        }
        let (ms, clock) = match outcome.gpu_ms {
            Some(ms) => (ms, "GPU timestamps"),
            None => (outcome.wall_ms, "wall clock"),
        };
        crate::say!(
            "render: {ms:.2} ms ({clock}; wall {:.2} ms), {rays} rays ({:.2} per pixel), {:.2} Mrays/s",
            outcome.wall_ms,
            rays as f64 / pixels as f64,
            rays as f64 / (ms * 1e3)
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `--stats`'s line on what traced.
fn say_device(args: &RenderArgs, device: &str) -> anyhow::Result<()> {
    crate::say!(
        "device: {device}, pipeline {}, memory {}, accel {}, {} samples per pixel",
        args.scene.pipeline,
        args.scene.memory,
        args.scene.accel,
        args.spp
    );
    Ok(())
}

pub fn aov_image(aov: Aov, is_exr: bool, frame: &Frame) -> FloatImage {
    match (aov, is_exr) {
        (Aov::Color, false) => frame.display(),
        (Aov::Color, true) => frame.radiance(),
        (Aov::Depth, _) => frame.depth(),
        (Aov::Normal, _) => frame.normals(),
        (Aov::Cost, _) => heatmap::heatmap(&frame.counts(), frame.width, frame.height),
    }
}

fn render_sequence(
    args: &RenderArgs,
    scene: &Scene,
    output: &Path,
    is_exr: bool,
    times: &[(u32, f32)],
    options: &RenderOptions,
) -> anyhow::Result<ExitCode> {
    let frames = times.len();
    let last = times.last().map(|&(k, _)| k);
    let name = output.to_string_lossy().to_string();
    let pattern = numbered(&name, 0).is_some();
    let outcome = render_frames(scene, options, times, |frame, image| {
        if pattern {
            let path = numbered(&name, frame).expect("checked above");
            io::write_as(&aov_image(args.scene.aov, is_exr, image), Path::new(&path), is_exr)?;
        } else if Some(frame) == last {
            io::write_as(&aov_image(args.scene.aov, is_exr, image), output, is_exr)?;
        }
        Ok(())
    })
    .map_err(|e| e.context(args.scene.spec.clone()))?;
    if !args.quiet {
        let written = if pattern {
            name.clone()
        } else {
            output.display().to_string()
        };
        eprintln!("wrote {written} ({frames} frames, {})", outcome.device);
    }
    if args.stats {
        let s = &scene.settings;
        crate::say!(
            "scene: {}, {}x{}, {} spheres, {} triangles, {frames} frames",
            args.scene.spec,
            s.width,
            s.height,
            scene.spheres.len(),
            scene.triangles.len()
        );
        say_device(args, &outcome.device)?;
        // The first frame pays for pipeline compilation on some drivers: medians skip it.
        let steady = if frames > 1 { 1 } else { 0 };
        if !outcome.builds.is_empty() {
            let b = &outcome.builds[steady..];
            // The GPU's merges write the bounds and links with the hierarchy.
            crate::say!(
                "BVH build per frame (median): morton {:.3} ms, sort {:.3} ms, hierarchy with bounds and links {:.3} ms, 16-byte layout {:.3} ms, total {:.3} ms",
                median(b.iter().map(|t| t.morton)),
                median(b.iter().map(|t| t.sort)),
                median(b.iter().map(|t| t.hierarchy + t.bounds + t.links)),
                median(b.iter().map(|t| t.layout)),
                median(b.iter().map(|t| t.total())),
            );
        }
        let render_ms = median(outcome.render_ms[steady..].iter().copied());
        let rays = median(outcome.rays[steady..].iter().map(|&r| r as f64));
        crate::say!(
            "render per frame (median): {render_ms:.2} ms, {rays:.0} rays, {:.2} Mrays/s",
            rays / (render_ms * 1e3)
        );
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::numbered;

    #[test]
    fn frame_names_follow_printf_patterns() {
        assert_eq!(numbered("frame_%04d.png", 7).as_deref(), Some("frame_0007.png"));
        assert_eq!(numbered("f%d.exr", 12).as_deref(), Some("f12.exr"));
        assert_eq!(numbered("plain.png", 3), None);
        assert_eq!(numbered("odd%x.png", 3), None);
    }
}
