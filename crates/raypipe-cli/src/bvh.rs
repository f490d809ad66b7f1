use crate::args::choice;
use clap::{Args, ValueEnum};
use pollster::block_on;
use raypipe::bvh::aabb::Aabb;
use raypipe::bvh::key::Key;
use raypipe::bvh::lbvh::depth_bound;
use raypipe::bvh::lbvh::{Hierarchy, LbvhBuilder};
use raypipe::bvh::morton::MortonBits;
use raypipe::bvh::sah::sah_cost;
use raypipe::bvh::wide::{self, WideTree};
use raypipe::bvh::{BuildTimings, Bvh};
use raypipe::gpu::GpuContext;
use raypipe::gpu::builders::lbvh::{Codes, GpuLbvhBuilder};
use raypipe::gpu::builders::wide_collapse::GpuWideCollapse;
use raypipe::modes::Backend;
use raypipe::modes::Builder;
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use serde::Serialize;
use std::process::ExitCode;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BuildDevice {
    Cpu,
    Gpu,
}

#[derive(Args)]
pub struct BvhArgs {
    /// A built-in scene or a TOML file; the BVH is built over its spheres.
    scene: String,
    #[arg(long, value_parser = choice::<Builder>(), default_value_t)]
    builder: Builder,
    /// Where the LBVH is built: the CPU (rayon) or the GPU (compute passes).
    #[arg(long, value_enum, default_value_t = BuildDevice::Cpu)]
    device: BuildDevice,
    #[arg(long, value_parser = choice::<Backend>())]
    backend: Option<Backend>,
    /// Morton code width of the LBVH.
    #[arg(long, value_parser = choice::<MortonBits>(), default_value_t)]
    morton_bits: MortonBits,
    /// How the CPU LBVH finds its hierarchy: bottom-up merges that also write the bounds and links
    /// (the default, and the GPU's way), or Karras's searches for every node, then bounds and links
    /// in a pass of their own. Both give the same tree.
    #[arg(long, value_parser = choice::<Hierarchy>())]
    hierarchy: Option<Hierarchy>,
    /// Timed builds after one warm-up build; the run with the median total is reported.
    #[arg(long, default_value_t = 5)]
    runs: usize,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct BuildMs {
    morton: f64,
    sort: f64,
    hierarchy: f64,
    bounds: f64,
    links: f64,
    total: f64,
    /// The tree collapsed into the wide walk's compressed 8-wide nodes, on the same device: a phase
    /// of its own, outside the LBVH's total.
    collapse: f64,
}

#[derive(Serialize)]
struct Report {
    scene: String,
    builder: String,
    device: String,
    primitives: usize,
    nodes: usize,
    max_depth: u32,
    mean_leaf_depth: f64,
    sah_cost: f64,
    build_ms: BuildMs,
    mprims_per_s: f64,
}

/// One builder, built once to warm up (allocations, page faults), then `runs` timed rebuilds: the
/// per-frame situation.
fn time_lbvh<K: Key>(boxes: &[Aabb], bits: MortonBits, hierarchy: Hierarchy, runs: usize) -> (Bvh, Vec<BuildTimings>) {
    let mut builder = LbvhBuilder::<K>::with_hierarchy(hierarchy);
    builder.build(boxes, bits);
    let timings = (0..runs).map(|_| builder.build(boxes, bits)).collect();
    (builder.into_bvh(), timings)
}

pub fn run(args: BvhArgs) -> anyhow::Result<ExitCode> {
    let scene = Scene::load(&args.scene)?;
    let packed = PackedScene::new(&scene).map_err(|e| e.in_origin(&args.scene))?;
    let boxes = packed.primitive_boxes();
    // The GPU finds the hierarchy by merges only.
    let hierarchy = match args.device {
        BuildDevice::Gpu => Hierarchy::Merges,
        BuildDevice::Cpu => args.hierarchy.unwrap_or_default(),
    };
    match (args.hierarchy, args.builder, args.device) {
        (Some(_), Builder::Sah, _) => anyhow::bail!("--hierarchy is an option of the LBVH builder"),
        (Some(Hierarchy::Searches), _, BuildDevice::Gpu) => {
            anyhow::bail!("the GPU builder finds the hierarchy by merges only (--hierarchy merges)")
        }
        (_, Builder::Sah, BuildDevice::Gpu) => anyhow::bail!("the binned SAH builder runs on the CPU only"),
        _ => {}
    }
    let Built {
        bvh,
        mut runs,
        device,
        gpu_variant,
        wide_texels,
    } = build_timed(&args, &packed, &boxes, hierarchy)?;
    let collapse = median(runs.iter().map(|t| t.collapse));
    let tree_ms = |t: &BuildTimings| t.total() - t.collapse;
    runs.sort_by(|a, b| tree_ms(a).total_cmp(&tree_ms(b)));
    let t = runs[runs.len() / 2];
    bvh.validate(&boxes)
        .map_err(|e| anyhow::anyhow!("the built BVH is invalid: {e}"))?;
    let wide_tree = WideTree {
        texels: &wide_texels,
        root: wide::leaf_texels(bvh.primitive_count),
        stack_size: bvh.max_depth().max(1),
    };
    wide::validate(&wide_tree, &boxes).map_err(|e| anyhow::anyhow!("the collapsed wide BVH is invalid: {e}"))?;

    let depths = bvh.leaf_depths();
    let report = Report {
        scene: args.scene.clone(),
        builder: match args.builder {
            Builder::Lbvh => format!(
                "lbvh ({}-bit Morton codes, hierarchy by {}{gpu_variant})",
                args.morton_bits.total_bits(),
                match hierarchy {
                    Hierarchy::Merges => "merges",
                    Hierarchy::Searches => "searches",
                }
            ),
            Builder::Sah => "binned SAH (16 bins)".into(),
        },
        device,
        primitives: bvh.primitive_count,
        nodes: bvh.nodes.len(),
        max_depth: depths.iter().copied().max().unwrap_or(0),
        mean_leaf_depth: depths.iter().map(|&d| d as f64).sum::<f64>() / depths.len().max(1) as f64,
        sah_cost: sah_cost(&bvh),
        build_ms: BuildMs {
            morton: t.morton,
            sort: t.sort,
            hierarchy: t.hierarchy,
            bounds: t.bounds,
            links: t.links,
            total: tree_ms(&t),
            collapse,
        },
        mprims_per_s: bvh.primitive_count as f64 / (tree_ms(&t) * 1e3),
    };
    if args.json {
        crate::say!("{}", serde_json::to_string(&report)?);
    } else {
        // Where the merges find the hierarchy, its time holds the bounds and links too.
        let fused = args.builder == Builder::Lbvh && hierarchy == Hierarchy::Merges;
        print_report(&report, fused, runs.len())?;
    }
    Ok(ExitCode::SUCCESS)
}

/// A tree and the timings of its runs, with the device that built it.
struct Built {
    bvh: Bvh,
    runs: Vec<BuildTimings>,
    device: String,
    /// The GPU build's kernels where adapters differ ("" on the CPU).
    gpu_variant: String,
    /// The tree collapsed into wide nodes on the same device, the last run's.
    wide_texels: Vec<wide::GpuWideTexel>,
}

fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut values: Vec<f64> = values.collect();
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(0.0)
}

/// Each run's tree collapsed into wide nodes on the CPU, timed into its timings: the tree of every
/// run is the same, so the last one stands for all.
fn collapse_on_cpu((bvh, mut runs): (Bvh, Vec<BuildTimings>)) -> (Bvh, Vec<BuildTimings>, Vec<wide::GpuWideTexel>) {
    let mut texels = Vec::new();
    for timings in &mut runs {
        let start = std::time::Instant::now();
        texels = wide::wide_texels(&bvh.nodes, bvh.primitive_count);
        timings.collapse = start.elapsed().as_secs_f64() * 1e3;
    }
    (bvh, runs, texels)
}

/// Builds the tree `--runs` times (the GPU once more first, to warm up) with the builder and device
/// asked for.
fn build_timed(args: &BvhArgs, packed: &PackedScene, boxes: &[Aabb], hierarchy: Hierarchy) -> anyhow::Result<Built> {
    let runs = args.runs.max(1);
    let cpu = |built| {
        let (bvh, runs, wide_texels) = collapse_on_cpu(built);
        Built {
            bvh,
            runs,
            device: format!("cpu ({} threads)", rayon::current_num_threads()),
            gpu_variant: String::new(),
            wide_texels,
        }
    };
    Ok(match (args.builder, args.morton_bits) {
        (Builder::Lbvh, bits) if args.device == BuildDevice::Gpu => {
            let ctx = block_on(GpuContext::require(args.backend))?;
            let device = format!("gpu: {}", ctx.describe());
            anyhow::ensure!(
                ctx.timestamps,
                "{device} has no timestamp queries to time the build with"
            );
            let mut builder = block_on(GpuLbvhBuilder::new(
                &ctx,
                bits,
                packed.spheres.len(),
                packed.triangles.len(),
            ))?;
            let gpu_variant = format!("; {}", builder.variant().describe());
            block_on(builder.write_scene(packed))?;
            let depth = depth_bound(boxes.len(), bits);
            let collapse = block_on(GpuWideCollapse::new(&ctx, &builder.buffers().nodes, boxes.len(), depth))?;
            // One build and collapse to warm up, then each run's build and its collapse, timed apart.
            let build_and_collapse = || -> anyhow::Result<BuildTimings> {
                let mut timings = block_on(builder.build(Codes::Computed))?;
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                collapse.encode(&mut encoder);
                ctx.queue.submit([encoder.finish()]);
                timings.collapse = block_on(collapse.read_ms(&ctx))?.unwrap_or(0.0);
                Ok(timings)
            };
            build_and_collapse()?;
            let timings = (0..runs).map(|_| build_and_collapse()).collect::<Result<Vec<_>, _>>()?;
            let bvh = Bvh {
                nodes: block_on(builder.read_nodes())?,
                primitive_count: boxes.len(),
            };
            Built {
                bvh,
                runs: timings,
                device,
                gpu_variant,
                wide_texels: block_on(collapse.read(&ctx))?,
            }
        }
        (Builder::Lbvh, MortonBits::Bits30) => cpu(time_lbvh::<u64>(boxes, args.morton_bits, hierarchy, runs)),
        (Builder::Lbvh, MortonBits::Bits63) => cpu(time_lbvh::<u128>(boxes, args.morton_bits, hierarchy, runs)),
        (Builder::Sah, _) => {
            let mut bvh = None;
            let timings = (0..runs)
                .map(|_| {
                    let (built, timings) = Bvh::build_binned_sah(boxes);
                    bvh = Some(built);
                    timings
                })
                .collect();
            cpu((bvh.expect("at least one run"), timings))
        }
    })
}

/// The report as lines for a reader.
fn print_report(report: &Report, fused: bool, runs: usize) -> anyhow::Result<()> {
    let b = &report.build_ms;
    crate::say!("scene: {}, {} primitives", report.scene, report.primitives);
    crate::say!("builder: {}, device {}", report.builder, report.device);
    crate::say!(
        "nodes: {}, depth: max {}, mean leaf {:.1}",
        report.nodes,
        report.max_depth,
        report.mean_leaf_depth
    );
    crate::say!(
        "SAH cost: {:.2} (traversal and intersection cost 1, relative to the root's area)",
        report.sah_cost
    );
    let bounds_and_links = if fused {
        "bounds and links in the same pass".to_string()
    } else if b.links == 0.0 {
        format!("bounds and links {:.2} ms", b.bounds)
    } else {
        format!("bounds {:.2} ms, links {:.2} ms", b.bounds, b.links)
    };
    crate::say!(
        "build (median of {runs} runs): morton {:.2} ms, sort {:.2} ms, hierarchy {:.2} ms, {bounds_and_links}, total {:.2} ms, {:.1} Mprims/s",
        b.morton,
        b.sort,
        b.hierarchy,
        b.total,
        report.mprims_per_s
    );
    crate::say!(
        "collapse into 8-wide nodes (median): {:.2} ms, {:.2} of the build",
        b.collapse,
        b.collapse / b.total
    );
    Ok(())
}
