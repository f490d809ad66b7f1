//! The `raypipe` command line: one file per subcommand.

mod bench;
mod bvh;
mod diff;
mod info;
mod render;

pub use render::numbered;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "raypipe", version, about = "Whitted ray tracing in the fragment shader")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to PNG (colour, normals) or EXR (colour, depth).
    Render(render::RenderArgs),
    /// Compare two images: mean and 99th-percentile error, a difference image, exit 1 above a threshold.
    Diff(diff::DiffArgs),
    /// Frames per second against sphere count, per acceleration and memory mode (the paper's Figure 4).
    Bench(bench::BenchArgs),
    /// Build a BVH over a scene's spheres and print its size, depth, SAH cost and build time per phase.
    Bvh(bvh::BvhArgs),
    /// List GPU adapters, their backends, drivers and the limits that matter here.
    Info,
}

/// Runs the command line; errors are returned for `main` to print as one line with exit code 2.
pub fn run() -> anyhow::Result<ExitCode> {
    match Cli::parse().command {
        Command::Render(args) => render::run(args),
        Command::Diff(args) => diff::run(args),
        Command::Bvh(args) => bvh::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Info => info::run(),
    }
}

/// The median of `values` (the upper one of an even count); 0 for none.
fn median(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.into_iter().collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
