//! `raypipe render`: a scene to PNG or EXR, one frame or a numbered sequence of a moving scene.

use crate::device::{DeviceChoice, RenderOptions, RenderOutcome, render, render_frames};
use crate::io;
use crate::report::median;
use crate::scene_args::{MAX_SPP, SceneArgs};
use anyhow::bail;
use clap::Args;
use raypipe::bvh::BuildTimings;
use raypipe::modes::{Accel, Aov};
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
    /// anti-aliasing, and with the path integrator its light's samples. On the GPU each sample is
    /// its own draw, added to a float sum [default: 1 with the Whitted integrator, 128 with the path
    /// integrator]
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    spp: Option<u32>,
    /// Print render time and rays per second (all samples' rays).
    #[arg(long)]
    stats: bool,
    /// Say nothing on success (by default one line on standard error says what was written).
    #[arg(short, long)]
    quiet: bool,
    /// Render frames of a moving scene (an animated glTF, bounce:N), rebuilding the BVH every
    /// frame (on the GPU with --memory storage, on the CPU with the other memories): K for frames
    /// 0 to K-1, or A..B for frames A to
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

/// Samples per pixel a path-traced image takes where --spp does not say: FLIP against 2048 samples
/// at most 0.04 for the Khronos samples measured (docs/BENCHMARKS.md, "Path tracing").
pub const PATH_SAMPLES: u32 = 128;

impl RenderArgs {
    /// Samples per pixel: --spp, else one for Whitted's images (the paper's) and
    /// [`PATH_SAMPLES`] for the path integrator's.
    fn samples(&self, scene: &raypipe::scene::Scene) -> u32 {
        self.spp.unwrap_or(match scene.settings.integrator {
            raypipe::modes::Integrator::Whitted => 1,
            raypipe::modes::Integrator::Path => PATH_SAMPLES,
        })
    }
}

pub fn run(args: RenderArgs) -> anyhow::Result<ExitCode> {
    let (output, is_exr) = check_output(&args)?;
    let scene = args.scene.load()?;
    let start = args.scene.time.unwrap_or(0.0);
    let options = RenderOptions {
        device: args.device,
        backend: args.scene.backend,
        pipeline: args.scene.pipeline,
        memory: args.scene.memory,
        accel: scene.settings.accel.unwrap_or_default(),
        progress: std::io::stderr().is_terminal(),
        count: args.scene.aov.count(),
        warm_up: args.stats,
        samples: args.samples(&scene),
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
        args.scene.check_builder_for_motion(&scene)?;
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
    let build = options.accel.uses_bvh().then(|| {
        let mut timings = packed.build_bvh_with(args.scene.builder);
        if options.accel == Accel::Wide {
            // The wide walk's tree, collapsed from the built one.
            timings.collapse = packed.bvh.as_ref().map_or(0.0, |bvh| bvh.collapse());
        }
        timings
    });
    let outcome = render(&packed, &options).map_err(|e| e.context(args.scene.spec.clone()))?;
    let frame = &outcome.frame;
    io::write_as(
        &frame.aov_image(args.scene.aov, is_exr, &args.scene.display_transform(&scene)),
        &output,
        is_exr,
    )?;
    if !args.quiet {
        eprintln!(
            "wrote {} ({}x{}, {} samples per pixel, {})",
            output.display(),
            frame.width,
            frame.height,
            options.samples,
            outcome.device
        );
    }

    if args.stats {
        say_stats(&args, options.accel, &scene, &packed, build, &outcome)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The output file and whether it is an EXR, checked before anything renders: its format against
/// the AOV, its frame-number pattern, and that it can be written.
fn check_output(args: &RenderArgs) -> anyhow::Result<(PathBuf, bool)> {
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
    Ok((output, is_exr))
}

/// `--stats`' lines: the scene, the device, and the render's time and rays (or, for a cost render,
/// the nodes tested).
fn say_stats(
    args: &RenderArgs,
    accel: Accel,
    scene: &raypipe::scene::Scene,
    packed: &PackedScene,
    build: Option<BuildTimings>,
    outcome: &RenderOutcome,
) -> anyhow::Result<()> {
    let frame = &outcome.frame;
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
    say_device(args, accel, scene, &outcome.device)?;
    if let (Some(build), Some(bvh)) = (build, &packed.bvh) {
        let collapse = if build.collapse > 0.0 {
            format!(", collapsed into 8-wide nodes in {:.2} ms", build.collapse)
        } else {
            String::new()
        };
        crate::say!(
            "bvh: {} on the CPU in {:.2} ms, {} nodes, depth {}{collapse}",
            args.scene.builder,
            build.total() - build.collapse,
            bvh.nodes.len(),
            bvh.depth
        );
    }
    say_memory(packed.triangles.len())?;
    if args.scene.aov == Aov::Cost {
        let counts = frame.counts();
        let mean = counts.iter().map(|&c| c as f64).sum::<f64>() / counts.len() as f64;
        let max = counts.iter().copied().max().unwrap_or(0);
        crate::say!("cost per primary ray: mean {mean:.1}, max {max} nodes tested (spheres tested for brute force)");
        return Ok(());
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
    let traced = &outcome.traced;
    if traced.pixel_count() < pixels {
        crate::say!(
            "traced {} of {pixels} pixels, in {} rectangles: the scene's boxes project to those, the others' rays miss them",
            traced.pixel_count(),
            traced.rects.len()
        );
    }
    Ok(())
}

/// `--stats`'s line on memory: the process's peak (where the system says it), and its bytes a
/// triangle where the scene has triangles.
fn say_memory(triangles: usize) -> anyhow::Result<()> {
    let Some(peak) = crate::report::peak_host_bytes() else {
        crate::say!("memory: the system does not report the process's peak");
        return Ok(());
    };
    let per_triangle = if triangles > 0 {
        format!(", {:.0} bytes a triangle", peak as f64 / triangles as f64)
    } else {
        String::new()
    };
    crate::say!(
        "memory: peak host {:.1} MiB{per_triangle}",
        peak as f64 / (1u64 << 20) as f64
    );
    Ok(())
}

/// `--stats`'s line on what traced.
fn say_device(args: &RenderArgs, accel: Accel, scene: &raypipe::scene::Scene, device: &str) -> anyhow::Result<()> {
    crate::say!(
        "device: {device}, pipeline {}, memory {}, accel {accel}, integrator {}, {} samples per pixel",
        args.scene.pipeline,
        args.scene.memory,
        scene.settings.integrator,
        args.samples(scene)
    );
    Ok(())
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
            io::write_as(
                &image.aov_image(args.scene.aov, is_exr, &args.scene.display_transform(scene)),
                Path::new(&path),
                is_exr,
            )?;
        } else if Some(frame) == last {
            io::write_as(
                &image.aov_image(args.scene.aov, is_exr, &args.scene.display_transform(scene)),
                output,
                is_exr,
            )?;
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
        say_device(args, options.accel, scene, &outcome.device)?;
        // The first frame pays for pipeline compilation on some drivers: medians skip it.
        let steady = if frames > 1 { 1 } else { 0 };
        if !outcome.builds.is_empty() {
            let b = &outcome.builds[steady..];
            // The GPU's merges write the bounds and links with the hierarchy.
            crate::say!(
                "BVH build per frame (median): morton {:.3} ms, sort {:.3} ms, hierarchy with bounds and links {:.3} ms, 16-byte layout {:.3} ms, 8-wide collapse {:.3} ms, total {:.3} ms",
                median(b.iter().map(|t| t.morton)),
                median(b.iter().map(|t| t.sort)),
                median(b.iter().map(|t| t.hierarchy + t.bounds + t.links)),
                median(b.iter().map(|t| t.layout)),
                median(b.iter().map(|t| t.collapse)),
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
