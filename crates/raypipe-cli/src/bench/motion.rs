//! `raypipe bench FILE --motion`: the frame of a moving scene (a glTF animation, or `bounce`) split
//! into its parts, per memory mode, pipeline and walk: evaluating the clip, skinning (the GPU's
//! compute pass in storage memory, the CPU elsewhere), building the BVH (on the GPU in storage
//! memory, on the CPU elsewhere), writing what moved (the CPU path), and tracing. With `--refit`,
//! each storage point also keeps a second tree that is only refitted after the first frame, and
//! times its trace against the fresh build's at the same pose, frame by frame.

use super::BenchArgs;
use crate::report::median;
use anyhow::Context;
use pollster::block_on;
use raypipe::Choice;
use raypipe::cpu;
use raypipe::gpu::{GpuContext, MovingScene, RendererOptions, TreeUpdate};
use raypipe::image::Frame;
use raypipe::image::diff::{Tolerance, compare};
use raypipe::modes::{Accel, MemoryMode};
use raypipe::records::PackedScene;
use raypipe::scene::is_model_file;
use raypipe::scene::model::{MeshAs, ModelOptions};
use raypipe::scene::{Motion, Scene};
use serde::Serialize;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

/// One point: the medians of its timed frames.
#[derive(Serialize, Clone)]
struct MotionRow {
    scene: String,
    triangles: usize,
    spheres: usize,
    pipeline: String,
    accel: String,
    memory: String,
    width: u32,
    height: u32,
    spp: u32,
    frames: usize,
    /// Where the primitives are moved and the BVH built: "gpu" (storage memory) or "cpu".
    moved_on: String,
    /// Evaluating the clip at the frame's time: node transforms, joint matrices, morph weights (CPU).
    eval_ms: f64,
    /// Posing the primitives: the GPU's skinning pass, or the CPU's skinning (or spheres' move)
    /// and repacking.
    skin_ms: f64,
    /// The BVH build: its GPU passes (and the threaded layout), or the CPU builder; with ray
    /// queries, the driver's BLAS and TLAS build (GPU timestamps between passes, 0 where the
    /// device has none).
    build_ms: f64,
    /// With the wide walk: the tree collapsed into compressed 8-wide nodes, after the build.
    collapse_ms: f64,
    /// Writing the moved records to the GPU, and on the CPU path the nodes built there.
    upload_ms: f64,
    trace_ms: f64,
    /// eval + skin + build + collapse + upload + trace.
    frame_ms: f64,
    /// (skin + build + collapse) / frame: the share of the frame that moving the scene costs.
    motion_share: f64,
    /// With --refit: the refit (and layout) time, and the refitted tree's trace time over the
    /// fresh tree's at the last frame.
    refit_ms: Option<f64>,
    refit_trace_ratio_last: Option<f64>,
    /// The first timed frame at which refitting (refit + trace of the refitted tree) costs more
    /// than rebuilding (build + trace of the fresh tree); none if refitting wins throughout.
    refit_loses_from_frame: Option<usize>,
    adapter: String,
    backend: String,
}

/// One frame of a refit comparison.
#[derive(Serialize, Clone)]
struct RefitFrame {
    pipeline: String,
    accel: String,
    /// Frames since the refitted tree was built.
    frame: usize,
    time: f32,
    build_ms: f64,
    refit_ms: f64,
    trace_rebuilt_ms: f64,
    trace_refitted_ms: f64,
}

/// What one frame cost, in milliseconds.
#[derive(Clone, Copy, Default)]
struct FrameTimes {
    eval: f64,
    skin: f64,
    build: f64,
    collapse: f64,
    upload: f64,
    trace: f64,
}

fn elapsed_ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// Evaluating the clips alone (on the CPU), timed: the part of moving the scene both paths share.
fn evaluate(motion: &Motion, t: f32) -> f64 {
    let start = Instant::now();
    if let Motion::Animations(animations) = motion {
        for animated in animations {
            std::hint::black_box(animated.instance_poses(t));
        }
    }
    elapsed_ms(start)
}

fn load(args: &BenchArgs) -> anyhow::Result<Scene> {
    let mut scene = if is_model_file(Path::new(&args.scene)) {
        let options = ModelOptions {
            as_: Some(MeshAs::Triangles),
            ..Default::default()
        };
        Scene::load_with(&args.scene, &options)?
    } else {
        Scene::load(&args.scene)?
    };
    anyhow::ensure!(
        scene.motion.is_some(),
        "{}: the scene does not move (--motion times an animated glTF or bounce:N)",
        args.scene
    );
    scene.settings.width = args.width;
    scene.settings.height = args.height;
    scene.settings.integrator = args.integrator.unwrap_or(scene.settings.integrator);
    Ok(scene)
}

pub fn run(args: &BenchArgs) -> anyhow::Result<ExitCode> {
    let ctx = block_on(GpuContext::require(args.backend))?;
    // The GPU's phases run in one submission: only timestamp queries tell them apart.
    anyhow::ensure!(
        ctx.timestamps,
        "bench --motion splits a frame's GPU work by timestamp queries, which {} lacks; bench --rebuild times whole frames by the wall clock",
        ctx.describe()
    );
    anyhow::ensure!(args.frames >= 1, "--frames must be at least 1");
    anyhow::ensure!(
        args.fps.is_finite() && args.fps > 0.0,
        "--fps must be a positive number"
    );
    let scene = load(args)?;
    let motion = scene.motion.as_ref().expect("checked in load");
    let times: Vec<f32> = (0..args.warmup + args.frames)
        .map(|k| motion.looped(k as f32 / args.fps))
        .collect();
    // Every point's first timed frame is checked against the CPU's image of that time.
    let check_time = times[args.warmup];
    let reference = {
        let mut packed = PackedScene::new(&scene.at_time(check_time)?)?;
        packed.build_bvh();
        cpu::render(&packed, Accel::Threaded)?
    };
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create", args.out.display()))?;
    let accels = super::accels(args, &ctx);
    let bar = crate::device::progress_bar(
        true,
        (args.pipeline.len() * accels.len() * args.memory.len()) as u64,
        "{spinner} bench --motion {bar:40} {pos}/{len} {msg}, {elapsed}",
    );
    let name = Path::new(&args.scene)
        .file_name()
        .map_or(args.scene.clone(), |n| n.to_string_lossy().into_owned());
    let mut rows = Vec::new();
    let mut refit_frames = Vec::new();
    let mut refused = Vec::new();
    let check = Check {
        time: check_time,
        reference: &reference,
    };
    for &memory in &args.memory {
        for &pipeline in &args.pipeline {
            for &accel in &accels {
                let point = format!("{} {} {}", pipeline.name(), accel.name(), memory.name());
                bar.set_message(point.clone());
                let options = RendererOptions {
                    pipeline,
                    memory,
                    accel,
                    ..Default::default()
                };
                match time_point(&ctx, &scene, options, args, &times, &check) {
                    Ok((frames, refits)) => {
                        rows.push(MotionRow::new(&name, &scene, options, args, &ctx, &frames, &refits));
                        refit_frames.extend(refits);
                        // After every point: a run cut short keeps what it measured.
                        write_results(&args.out, &rows, &refit_frames)?;
                    }
                    Err(e) => refused.push(format!("{point}: {}", crate::report::message(&e))),
                }
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    let json = write_results(&args.out, &rows, &refit_frames)?;
    for line in &refused {
        eprintln!("refused: {line}");
    }
    if args.json {
        crate::say!("{json}");
        return Ok(ExitCode::SUCCESS);
    }
    print_table(args, &ctx, &name, scene.triangles.len(), &rows)?;
    crate::say!("results: {}/motion.csv, motion.json", args.out.display());
    Ok(if rows.is_empty() {
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    })
}

/// The CPU's image of the first timed frame, which every point's must match.
struct Check<'a> {
    time: f32,
    reference: &'a Frame,
}

/// One point's timed frames and refit comparison, its image checked first.
fn time_point(
    ctx: &GpuContext,
    scene: &Scene,
    options: RendererOptions,
    args: &BenchArgs,
    times: &[f32],
    check: &Check,
) -> anyhow::Result<(Vec<FrameTimes>, Vec<RefitFrame>)> {
    let (frames, first, refits) = frames_of_point(ctx, scene, options, args, times)?;
    let color = compare(&first.display(), &check.reference.display())?;
    Tolerance::COLOR
        .check(&color)
        .map_err(|e| anyhow::anyhow!("its image at {} s differs from the CPU's: {e}", check.time))?;
    Ok((frames, refits))
}

impl MotionRow {
    /// The medians of a point's frames.
    fn new(
        name: &str,
        scene: &Scene,
        options: RendererOptions,
        args: &BenchArgs,
        ctx: &GpuContext,
        frames: &[FrameTimes],
        refits: &[RefitFrame],
    ) -> Self {
        let part = |f: fn(&FrameTimes) -> f64| median(frames.iter().map(f));
        let (eval, skin, build, upload, trace) = (
            part(|f| f.eval),
            part(|f| f.skin),
            part(|f| f.build),
            part(|f| f.upload),
            part(|f| f.trace),
        );
        let collapse = part(|f| f.collapse);
        let frame_ms = eval + skin + build + collapse + upload + trace;
        let (refit_ms, refit_trace_ratio_last, refit_loses_from_frame) = summarize_refits(refits);
        let on_gpu = options.memory == MemoryMode::Storage;
        Self {
            scene: name.to_string(),
            triangles: scene.triangles.len(),
            spheres: scene.spheres.len(),
            pipeline: options.pipeline.name().into(),
            accel: options.accel.name().into(),
            memory: options.memory.name().into(),
            width: args.width,
            height: args.height,
            spp: args.spp,
            frames: args.frames,
            moved_on: if on_gpu { "gpu" } else { "cpu" }.into(),
            eval_ms: eval,
            skin_ms: skin,
            build_ms: build,
            collapse_ms: collapse,
            upload_ms: upload,
            trace_ms: trace,
            frame_ms,
            motion_share: (skin + build + collapse) / frame_ms,
            refit_ms,
            refit_trace_ratio_last,
            refit_loses_from_frame,
            adapter: ctx.info.name.clone(),
            backend: format!("{:?}", ctx.info.backend),
        }
    }
}

/// The points as a table on standard output, under the adapter, the scene and the size.
fn print_table(
    args: &BenchArgs,
    ctx: &GpuContext,
    name: &str,
    triangles: usize,
    rows: &[MotionRow],
) -> anyhow::Result<()> {
    crate::say!(
        "adapter: {} (gpu timestamps), {name}: {} triangles, {}x{}, {} frames at {} fps",
        ctx.describe(),
        triangles,
        args.width,
        args.height,
        args.frames,
        args.fps
    );
    crate::say!(
        "{:>9} {:>10} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>7} {:>8} {:>6}",
        "pipeline",
        "accel",
        "memory",
        "eval",
        "skin",
        "build",
        "collapse",
        "upload",
        "trace",
        "frame",
        "moving",
        "refit",
        "ratio"
    );
    for r in rows {
        crate::say!(
            "{:>9} {:>10} {:>8} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>6.1}% {:>8} {:>6}",
            r.pipeline,
            r.accel,
            r.memory,
            r.eval_ms,
            r.skin_ms,
            r.build_ms,
            r.collapse_ms,
            r.upload_ms,
            r.trace_ms,
            r.frame_ms,
            100.0 * r.motion_share,
            r.refit_ms.map(|m| format!("{m:.3}")).unwrap_or_default(),
            r.refit_trace_ratio_last.map(|m| format!("{m:.2}")).unwrap_or_default(),
        );
    }
    Ok(())
}

/// The refit time (median), the trace ratio at the last frame, and the first frame from which
/// refitting costs more than rebuilding.
fn summarize_refits(refits: &[RefitFrame]) -> (Option<f64>, Option<f64>, Option<usize>) {
    let Some(last) = refits.last() else {
        return (None, None, None);
    };
    let loses = refits
        .iter()
        .find(|r| r.refit_ms + r.trace_refitted_ms > r.build_ms + r.trace_rebuilt_ms)
        .map(|r| r.frame);
    (
        Some(median(refits.iter().map(|r| r.refit_ms))),
        Some(last.trace_refitted_ms / last.trace_rebuilt_ms),
        loses,
    )
}

/// One point's frames through the library's moving scene: in storage memory the primitives
/// posed (skinned) and the BVH rebuilt on the GPU in the frame's submission, elsewhere (WebGL2's
/// route) posed and built on the CPU, then the moved records and the nodes rewritten, as the
/// viewer and the page do. Returns the timed frames, the first timed frame's image and, with
/// --refit in storage memory, the refit comparison against a second scene whose tree is only
/// refitted after the first frame.
fn frames_of_point(
    ctx: &GpuContext,
    scene: &Scene,
    options: RendererOptions,
    args: &BenchArgs,
    times: &[f32],
) -> anyhow::Result<(Vec<FrameTimes>, Frame, Vec<RefitFrame>)> {
    let motion = scene.motion.as_ref().expect("a moving scene");
    let mut moving = block_on(MovingScene::new(ctx, scene, options, TreeUpdate::Rebuild))?;
    let mut refitting = if args.refit && options.accel.uses_bvh() && options.memory == MemoryMode::Storage {
        Some(block_on(MovingScene::new(ctx, scene, options, TreeUpdate::Refit))?)
    } else {
        None
    };
    let mut frames = Vec::new();
    let mut refits = Vec::new();
    let mut first = None;
    for (k, &t) in times.iter().enumerate() {
        let eval = evaluate(motion, t);
        let cost = moving.pose(t)?;
        let traced = block_on(moving.render_samples(args.spp, |_| {}))?;
        let (build, collapse) = match block_on(moving.read_build())? {
            Some(timings) => (timings.total() - timings.collapse, timings.collapse),
            // Ray queries: the driver's structures, built on the GPU before the trace.
            None => (
                block_on(moving.renderer().read_structures_build_ms())?.unwrap_or(0.0),
                0.0,
            ),
        };
        // Posing evaluates the clips again before it skins (or writes the skinning's matrices).
        let skin = block_on(moving.read_skinning_ms())?.unwrap_or(0.0) + (cost.pose_ms - eval).max(0.0);
        let trace = traced.gpu_ms.unwrap_or(0.0);
        if let Some(refitting) = &mut refitting {
            refitting.pose(t)?;
            let refitted = block_on(refitting.render_samples(args.spp, |_| {}))?;
            if k == args.warmup {
                // The refitted tree must give the fresh one's image.
                let color = compare(&refitted.frame.display(), &traced.frame.display())?;
                Tolerance::COLOR
                    .check(&color)
                    .map_err(|e| anyhow::anyhow!("the refitted tree's image differs from the rebuilt one's: {e}"))?;
            }
            if k >= args.warmup {
                refits.push(RefitFrame {
                    pipeline: options.pipeline.name().into(),
                    accel: options.accel.name().into(),
                    frame: k,
                    time: t,
                    build_ms: build,
                    refit_ms: block_on(refitting.read_refit_ms())?.unwrap_or(0.0),
                    trace_rebuilt_ms: trace,
                    trace_refitted_ms: refitted.gpu_ms.unwrap_or(0.0),
                });
            }
        }
        if k >= args.warmup {
            first.get_or_insert(traced.frame);
            frames.push(FrameTimes {
                eval,
                skin,
                build,
                collapse,
                upload: cost.upload_ms,
                trace,
            });
        }
    }
    Ok((frames, first.expect("at least one timed frame"), refits))
}

/// motion.csv, motion.json and, with refits, refit.csv in `out`; returns the JSON.
fn write_results(out: &Path, rows: &[MotionRow], refits: &[RefitFrame]) -> anyhow::Result<String> {
    crate::report::write_csv(&out.join("motion.csv"), rows)?;
    if !refits.is_empty() {
        crate::report::write_csv(&out.join("refit.csv"), refits)?;
    }
    let json = serde_json::to_string_pretty(&serde_json::json!({ "points": rows, "refit": refits }))?;
    std::fs::write(out.join("motion.json"), &json).with_context(|| format!("{}: cannot write", out.display()))?;
    Ok(json)
}
