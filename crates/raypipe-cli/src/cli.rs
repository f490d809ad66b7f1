//! The subcommands and their dispatch.

use crate::{bench, bvh, diff, info, render, view};
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
    /// Trace a scene live in a window: fly through it, switch modes, watch the frame time.
    View(view::ViewArgs),
}

/// Runs the command line; errors are returned for `main` to print as one line with exit code 2.
pub fn run() -> anyhow::Result<ExitCode> {
    match Cli::parse().command {
        Command::Render(args) => render::run(args),
        Command::Diff(args) => diff::run(args),
        Command::Bvh(args) => bvh::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Info => info::run(),
        Command::View(args) => view::run(args),
    }
}
