//! `raypipe bench`: frames per second against primitive count, per acceleration and memory mode (the
//! paper's Figure 4), with every mode's image checked against brute force's before it is timed.

mod motion;

use crate::args::choice;
use crate::plot::{Series, write_fps_plot};
use crate::report::median;
use anyhow::{Context, bail};
use clap::Args;
use pollster::block_on;
use raypipe::Choice;
use raypipe::bvh::BuildTimings;
use raypipe::gpu::{GpuContext, MovingScene, Renderer, RendererOptions, TreeUpdate};
use raypipe::image::Frame;
use raypipe::image::diff::{Tolerance, compare};
use raypipe::modes::Backend;
use raypipe::modes::{Accel, BlasOrder, Builder, Integrator, MemoryMode, Pipeline};
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use raypipe::scene::is_model_file;
use raypipe::scene::model::{MeshAs, ModelOptions};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub struct BenchArgs {
    /// A built-in family whose size takes the count (random, sphere, torus or bounce), or a model file
    /// (.ply, .obj, .off, .gltf, .glb) with that many spheres on its surface.
    #[arg(default_value = "random")]
    pub(crate) scene: String,
    #[arg(long, value_delimiter = ',', default_values_t = [1000, 2000, 5000, 10000, 20000])]
    pub(crate) counts: Vec<usize>,
    /// With a model file: time spheres on its surface, one point per count (the default), or its
    /// triangles, one point (--counts unused).
    #[arg(long = "as", value_parser = choice::<MeshAs>())]
    pub(crate) as_: Option<MeshAs>,
    /// The acceleration modes to time [default: every one the adapter has: rayquery where it has
    /// ray queries]
    #[arg(long, value_parser = choice::<Accel>(), value_delimiter = ',')]
    pub(crate) accel: Vec<Accel>,
    #[arg(long, value_parser = choice::<MemoryMode>(), value_delimiter = ',', default_values_t = [MemoryMode::Storage])]
    pub(crate) memory: Vec<MemoryMode>,
    /// The stages that trace, each timed at every point: the fragment shader of a full-screen
    /// triangle (the paper's) and a compute kernel.
    #[arg(long, value_parser = choice::<Pipeline>(), value_delimiter = ',', default_values_t = Pipeline::ALL.to_vec())]
    pub(crate) pipeline: Vec<Pipeline>,
    /// How light is carried [default: the scene's own: path for a glTF file, whitted for the
    /// others]
    #[arg(long, value_parser = choice::<Integrator>())]
    pub(crate) integrator: Option<Integrator>,
    #[arg(long, default_value_t = 256)]
    pub(crate) width: u32,
    #[arg(long, default_value_t = 256)]
    pub(crate) height: u32,
    /// Timed frames per point, after the warm-up frames.
    #[arg(long, default_value_t = 10)]
    pub(crate) frames: usize,
    #[arg(long, default_value_t = 2)]
    pub(crate) warmup: usize,
    /// Samples per pixel of every timed frame (as `render --spp`); times and rays cover them all.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=crate::scene_args::MAX_SPP as i64))]
    pub(crate) spp: u32,
    /// How the BVH over a still scene is built, once per count: the LBVH (Karras 2012), or binned
    /// SAH (a better tree, built about 50 times slower). Not with --rebuild or --motion, which
    /// rebuild the LBVH every frame.
    #[arg(long, value_parser = choice::<Builder>(), default_value_t)]
    pub(crate) builder: Builder,
    /// With rayquery: the order the driver's BLASes get the primitives in (the scene's own order
    /// shows what the Morton sort buys a driver that builds in the order it is given).
    #[arg(long, value_parser = choice::<BlasOrder>(), default_value_t)]
    pub(crate) blas_order: BlasOrder,
    /// Rebuild the LBVH on the GPU before every frame (storage memory), timed separately; with
    /// rayquery, the driver's BLASes and TLAS.
    #[arg(long)]
    pub(crate) rebuild: bool,
    #[arg(long, value_parser = choice::<Backend>())]
    pub(crate) backend: Option<Backend>,
    /// Where results.csv, results.json and the plot fps.png (and fps.svg) go.
    #[arg(long, default_value = "bench-results")]
    pub(crate) out: PathBuf,
    /// Also print the JSON array to stdout.
    #[arg(long)]
    pub(crate) json: bool,
    /// Time a moving scene (an animated glTF, or bounce:N) frame by frame, split into clip
    /// evaluation, skinning, BVH build, upload and trace, per memory mode, pipeline and walk
    /// (results in motion.csv and motion.json; --counts unused).
    #[arg(long)]
    pub(crate) motion: bool,
    /// With --motion: also refit a tree built at the first frame, and time its trace against the
    /// fresh build's frame by frame (storage memory; refit.csv).
    #[arg(long, requires = "motion")]
    pub(crate) refit: bool,
    /// With --motion: frames per second of the clip's time (frame k at k / fps).
    #[arg(long, default_value_t = 30.0)]
    pub(crate) fps: f32,
}

#[derive(Serialize, Clone)]
struct Row {
    count: usize,
    pipeline: String,
    accel: String,
    memory: String,
    width: u32,
    height: u32,
    /// Samples per pixel of each frame.
    spp: u32,
    frames: usize,
    ms_median: f64,
    ms_min: f64,
    ms_max: f64,
    fps: f64,
    mrays_per_s: f64,
    /// GPU time of the per-frame build (median), with --rebuild: the LBVH's, or with rayquery the
    /// driver's BLASes and TLAS (where the adapter times work between passes).
    build_ms_median: Option<f64>,
    /// The same build's phases, each the median over the frames.
    build_phases_ms: Option<BuildPhases>,
    /// "gpu timestamps" or "wall clock".
    clock: String,
    adapter: String,
    backend: String,
    /// How the tree was built: "lbvh" or "sah".
    builder: String,
    /// With rayquery: the BLASes' primitive order, "morton" or "scene".
    blas_order: String,
}

/// Per-phase medians of a rebuild's timings (`BuildTimings`' phases).
#[derive(Serialize, Clone, Copy)]
struct BuildPhases {
    morton: f64,
    sort: f64,
    hierarchy: f64,
    bounds: f64,
    links: f64,
    /// The 16-byte depth-first layout of the stack and threaded walks.
    layout: f64,
    /// The collapse into the wide walk's compressed 8-wide nodes.
    collapse: f64,
}

impl BuildPhases {
    fn median_of(builds: &[BuildTimings]) -> Option<Self> {
        let phase = |f: fn(&BuildTimings) -> f64| median(builds.iter().map(f));
        (!builds.is_empty()).then(|| Self {
            morton: phase(|b| b.morton),
            sort: phase(|b| b.sort),
            hierarchy: phase(|b| b.hierarchy),
            bounds: phase(|b| b.bounds),
            links: phase(|b| b.links),
            layout: phase(|b| b.layout),
            collapse: phase(|b| b.collapse),
        })
    }
}

fn name<T: Choice>(value: &T) -> String {
    value.name().to_string()
}

fn options(pipeline: Pipeline, memory: MemoryMode, accel: Accel) -> RendererOptions {
    RendererOptions {
        pipeline,
        memory,
        accel,
        ..Default::default()
    }
}

/// The scene of one bench point, at the given size, packed with a CPU-built BVH: a built-in family
/// at `count` spheres, or a model with `count` spheres on its surface or as its triangles.
fn scene(
    family: &str,
    as_: MeshAs,
    count: usize,
    size: (u32, u32),
    builder: Builder,
    integrator: Option<Integrator>,
) -> anyhow::Result<(Scene, PackedScene)> {
    let mut scene = if is_model_file(Path::new(family)) {
        let options = ModelOptions {
            as_: Some(as_),
            spheres: (as_ == MeshAs::Spheres).then_some(count),
            ..Default::default()
        };
        Scene::load_with(family, &options)?
    } else if ["random", "sphere", "torus", "bounce"].contains(&family) {
        Scene::load(&format!("{family}:{count}"))?
    } else {
        bail!(
            "bench scene '{family}': use a family that takes a count (random, sphere, torus or bounce) or a model file"
        );
    };
    (scene.settings.width, scene.settings.height) = size;
    scene.settings.integrator = integrator.unwrap_or(scene.settings.integrator);
    let mut packed = PackedScene::new(&scene)?;
    packed.build_bvh_with(builder);
    Ok((scene, packed))
}

/// Brute force's image of a count's scene at a small size: what every mode must reproduce before it
/// is timed.
struct Reference {
    scene: PackedScene,
    brute: Frame,
}

impl Reference {
    /// At 64x48, or the bench's size where that is smaller.
    fn new(ctx: &GpuContext, args: &BenchArgs, as_: MeshAs, count: usize) -> anyhow::Result<Self> {
        let size = (args.width.min(64), args.height.min(48));
        let (_, scene) = scene(&args.scene, as_, count, size, args.builder, args.integrator)?;
        let mut renderer = block_on(Renderer::new(
            ctx,
            &scene,
            options(Pipeline::Fragment, MemoryMode::Storage, Accel::Brute),
        ))?;
        let brute = block_on(renderer.read_frame())?.frame;
        Ok(Self { scene, brute })
    }

    /// Renders `accel` in `memory` through `pipeline` and requires brute force's image (the fragment
    /// pipeline's); a mode that cannot run (a scene too big for uniform memory, say) reports why.
    fn check(&self, ctx: &GpuContext, pipeline: Pipeline, accel: Accel, memory: MemoryMode) -> anyhow::Result<()> {
        let mut renderer = block_on(Renderer::new(ctx, &self.scene, options(pipeline, memory, accel)))?;
        let frame = block_on(renderer.read_frame())?.frame;
        let color = compare(&frame.display(), &self.brute.display())?;
        let depth = compare(&frame.depth(), &self.brute.depth())?;
        Tolerance::COLOR
            .check(&color)
            .and_then(|_| Tolerance::DEPTH.check(&depth))
            .map_err(|e| anyhow::anyhow!("its image differs from brute force's: {e}"))
    }
}

/// What a point times: a renderer over the tree built once, or with --rebuild (for a walk that
/// reads a tree) a moving scene whose tree the GPU builds again before every frame.
enum Timed {
    /// Boxed alike: either is large.
    Still(Box<Renderer>),
    Rebuilt(Box<MovingScene>),
}

impl Timed {
    fn new(
        ctx: &GpuContext,
        args: &BenchArgs,
        scene: &Scene,
        packed: &PackedScene,
        options: RendererOptions,
    ) -> anyhow::Result<Self> {
        Ok(if args.rebuild && options.accel.uses_bvh() {
            let moving = block_on(MovingScene::new(ctx, scene, options, TreeUpdate::Rebuild))?;
            Timed::Rebuilt(Box::new(moving))
        } else {
            Timed::Still(Box::new(block_on(Renderer::new(ctx, packed, options))?))
        })
    }

    fn renderer(&self) -> &Renderer {
        match self {
            Timed::Still(renderer) => renderer,
            Timed::Rebuilt(moving) => moving.renderer(),
        }
    }
}

pub fn run(args: BenchArgs) -> anyhow::Result<ExitCode> {
    if args.motion {
        return motion::run(&args);
    }
    let ctx = block_on(GpuContext::require(args.backend))?;
    let clock = if ctx.timestamps { "gpu timestamps" } else { "wall clock" };
    if !ctx.timestamps {
        eprintln!(
            "notice: {} has no timestamp queries; timing with the wall clock",
            ctx.describe()
        );
    }
    let as_ = check_args(&args)?;
    // A model's triangles are one point, whatever the counts.
    let counts = if as_ == MeshAs::Triangles {
        vec![0]
    } else {
        args.counts.clone()
    };
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create", args.out.display()))?;
    let accels = accels(&args, &ctx);
    let points = counts.len() * args.pipeline.len() * accels.len() * args.memory.len();
    let bar = crate::device::progress_bar(
        true,
        points as u64,
        "{spinner} bench {bar:40} {pos}/{len} {msg}, {elapsed}",
    );
    let mut rows = Vec::new();
    let mut refused = Vec::new();
    for &count in &counts {
        let (loaded, packed) = scene(
            &args.scene,
            as_,
            count,
            (args.width, args.height),
            args.builder,
            args.integrator,
        )?;
        let count = packed.primitive_count();
        // Made on first need: a run of brute force alone does not render it.
        let mut reference: Option<Reference> = None;
        for &accel in &accels {
            for (&pipeline, &memory) in args
                .pipeline
                .iter()
                .flat_map(|p| args.memory.iter().map(move |m| (p, m)))
            {
                let point = format!("{count} {} {} {}", name(&pipeline), name(&accel), name(&memory));
                bar.set_message(format!("{point}: compiling, checking the image"));
                let checked = if (pipeline, accel) == (Pipeline::Fragment, Accel::Brute) {
                    Ok(())
                } else {
                    let reference = match &mut reference {
                        Some(reference) => reference,
                        empty => empty.insert(Reference::new(&ctx, &args, as_, count)?),
                    };
                    reference.check(&ctx, pipeline, accel, memory)
                };
                let modes = RendererOptions {
                    blas_order: args.blas_order,
                    ..options(pipeline, memory, accel)
                };
                let timed = checked.and_then(|()| Timed::new(&ctx, &args, &loaded, &packed, modes));
                let mut timed = match timed {
                    Ok(timed) => timed,
                    Err(e) => {
                        refused.push(format!("{point}: {}", crate::report::message(&e)));
                        bar.inc(1);
                        continue;
                    }
                };
                let frames = time_frames(&args, &mut timed, |frame, total| {
                    bar.set_message(format!("{point}: frame {frame} of {total}"))
                })?;
                rows.push(Row::of_frames(
                    &args,
                    &ctx,
                    clock,
                    (count, pipeline, accel, memory),
                    frames,
                ));
                // After every point: a run cut short keeps what it measured.
                write_results(&args.out, &rows)?;
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    let json = write_results(&args.out, &rows)?;
    write_plot(&args, &ctx, &rows)?;
    for line in &refused {
        eprintln!("refused: {line}");
    }
    if args.json {
        crate::say!("{json}");
    } else {
        print_table(&args, &ctx, clock, &rows)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The acceleration modes asked for, or every one the adapter has.
pub(crate) fn accels(args: &BenchArgs, ctx: &GpuContext) -> Vec<Accel> {
    if args.accel.is_empty() {
        ctx.accels()
    } else {
        args.accel.clone()
    }
}

/// Refuses combinations that cannot run; says how a model file is measured.
fn check_args(args: &BenchArgs) -> anyhow::Result<MeshAs> {
    anyhow::ensure!(args.frames >= 1, "--frames must be at least 1");
    anyhow::ensure!(
        args.builder.follows_motion() || !(args.rebuild || args.motion),
        "--builder {} builds a still scene's tree once; --rebuild and --motion rebuild the LBVH every frame",
        args.builder
    );
    anyhow::ensure!(
        !args.rebuild || args.memory.iter().all(|&m| m == MemoryMode::Storage),
        "--rebuild builds the BVH on the GPU, which the shader reads from storage memory: use --memory storage"
    );
    let as_ = args.as_.unwrap_or(MeshAs::Spheres);
    anyhow::ensure!(
        as_ == MeshAs::Spheres || is_model_file(Path::new(&args.scene)),
        "--as triangles times a model file's triangles: name a .ply, .obj, .off, .gltf or .glb"
    );
    Ok(as_)
}

impl Row {
    /// A point's row (its count, pipeline, walk and memory) from its timed frames (frame times,
    /// builds, rays of one frame).
    fn of_frames(
        args: &BenchArgs,
        ctx: &GpuContext,
        clock: &str,
        point: (usize, Pipeline, Accel, MemoryMode),
        frames: TimedFrames,
    ) -> Row {
        let (count, pipeline, accel, memory) = point;
        let TimedFrames {
            mut times,
            builds,
            driver_builds,
            rays,
        } = frames;
        times.sort_by(f64::total_cmp);
        let ms = median(times.iter().copied());
        Row {
            count,
            pipeline: name(&pipeline),
            accel: name(&accel),
            memory: name(&memory),
            width: args.width,
            height: args.height,
            spp: args.spp,
            frames: args.frames,
            ms_median: ms,
            ms_min: times[0],
            ms_max: times[times.len() - 1],
            fps: 1e3 / ms,
            mrays_per_s: rays as f64 / (ms * 1e3),
            build_ms_median: if driver_builds.is_empty() {
                (!builds.is_empty()).then(|| median(builds.iter().map(BuildTimings::total)))
            } else {
                Some(median(driver_builds.iter().copied()))
            },
            build_phases_ms: BuildPhases::median_of(&builds),
            clock: clock.into(),
            adapter: ctx.info.name.clone(),
            backend: format!("{:?}", ctx.info.backend),
            builder: name(&args.builder),
            blas_order: name(&args.blas_order),
        }
    }
}

/// The points as a table on standard output, under the adapter and the size.
fn print_table(args: &BenchArgs, ctx: &GpuContext, clock: &str, rows: &[Row]) -> anyhow::Result<()> {
    crate::say!(
        "adapter: {} ({clock}), {}x{}, BVH built by {}",
        ctx.describe(),
        args.width,
        args.height,
        args.builder
    );
    crate::say!(
        "{:>8} {:>9} {:>10} {:>8} {:>10} {:>10} {:>10}",
        "count",
        "pipeline",
        "accel",
        "memory",
        "ms",
        "fps",
        "Mrays/s"
    );
    for r in rows {
        crate::say!(
            "{:>8} {:>9} {:>10} {:>8} {:>10.3} {:>10.2} {:>10.2}",
            r.count,
            r.pipeline,
            r.accel,
            r.memory,
            r.ms_median,
            r.fps,
            r.mrays_per_s
        );
    }
    crate::say!(
        "results: {}/results.csv, results.json, fps.png, fps.svg",
        args.out.display()
    );
    Ok(())
}

/// What [`time_frames`] measured.
struct TimedFrames {
    /// The frames' times (GPU timestamps, else the wall clock).
    times: Vec<f64>,
    /// The LBVH builds' phases, with --rebuild.
    builds: Vec<BuildTimings>,
    /// The driver's BLAS and TLAS builds (GPU milliseconds), with --rebuild and rayquery.
    driver_builds: Vec<f64>,
    /// The rays of the last frame.
    rays: u64,
}

/// Times `args.frames` frames after `args.warmup` warm-up frames, the rebuild (where there is one;
/// with rayquery and --rebuild, the driver's structures' build) recorded before each. `progress`
/// hears of each frame as it starts (1-based).
fn time_frames(args: &BenchArgs, timed: &mut Timed, progress: impl Fn(usize, usize)) -> anyhow::Result<TimedFrames> {
    let mut measured = TimedFrames {
        times: Vec::new(),
        builds: Vec::new(),
        driver_builds: Vec::new(),
        rays: 0,
    };
    let driver_builds = args.rebuild && timed.renderer().options().accel.needs_ray_queries();
    let total = args.warmup + args.frames;
    for frame in 0..total {
        progress(frame + 1, total);
        let start = std::time::Instant::now();
        let traced = match timed {
            Timed::Still(renderer) => {
                if driver_builds {
                    renderer.rebuild_structures();
                }
                block_on(renderer.render_samples(args.spp, |_| {}, |_| {}))?
            }
            Timed::Rebuilt(moving) => {
                // Posed where it stands: the tree is built again all the same.
                moving.pose(0.0)?;
                block_on(moving.render_samples(args.spp, |_| {}))?
            }
        };
        let wall = start.elapsed().as_secs_f64() * 1e3;
        if frame >= args.warmup {
            measured.times.push(traced.gpu_ms.unwrap_or(wall));
            measured.rays = traced.frame.rays();
            if let Timed::Rebuilt(moving) = timed {
                measured.builds.extend(block_on(moving.read_build())?);
            }
            if let Some(ms) = block_on(timed.renderer().read_structures_build_ms())?.filter(|_| driver_builds) {
                measured.driver_builds.push(ms);
            }
        }
    }
    Ok(measured)
}

/// results.csv and results.json in `out`; returns the JSON.
fn write_results(out: &Path, rows: &[Row]) -> anyhow::Result<String> {
    crate::report::write_csv(&out.join("results.csv"), rows)?;
    let json = serde_json::to_string_pretty(rows)?;
    std::fs::write(out.join("results.json"), &json).with_context(|| format!("{}: cannot write", out.display()))?;
    Ok(json)
}

/// fps against count, one line per (pipeline, accel, memory), titled with the adapter and resolution.
fn write_plot(args: &BenchArgs, ctx: &GpuContext, rows: &[Row]) -> anyhow::Result<()> {
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let mut label = r.accel.clone();
        if args.pipeline.len() > 1 {
            label = format!("{label}, {}", r.pipeline);
        }
        if args.memory.len() > 1 {
            label = format!("{label} ({})", r.memory);
        }
        match series.iter_mut().find(|s| s.name == label) {
            Some(s) => s.points.push((r.count as f64, r.fps)),
            None => series.push(Series {
                name: label,
                points: vec![(r.count as f64, r.fps)],
            }),
        }
    }
    // A model's file name, not its whole path.
    let scene = Path::new(&args.scene)
        .file_name()
        .map_or(args.scene.clone(), |name| name.to_string_lossy().into_owned());
    let title = format!(
        "{scene} {}, {}x{}, {} ({:?}){}",
        if args.as_ == Some(MeshAs::Triangles) {
            "triangles"
        } else {
            "spheres"
        },
        args.width,
        args.height,
        ctx.info.name,
        ctx.info.backend,
        if args.rebuild { ", BVH rebuilt every frame" } else { "" }
    );
    write_fps_plot(&series, &title, &args.out.join("fps.png"), &args.out.join("fps.svg"))
}
