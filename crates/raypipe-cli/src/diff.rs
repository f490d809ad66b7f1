use crate::io;
use clap::Args;
use raypipe::image::diff;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct DiffArgs {
    a: PathBuf,
    b: PathBuf,
    /// Write a picture of the per-pixel error here.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Largest mean error that passes (see docs/scene-format.md for the metric).
    #[arg(long, default_value_t = 0.01)]
    threshold: f64,
}

pub fn run(args: DiffArgs) -> anyhow::Result<ExitCode> {
    let a = io::read(&args.a)?;
    let b = io::read(&args.b)?;
    let errors = diff::pixel_errors(&a, &b)?;
    let stats = diff::stats(&errors);
    println!(
        "mean {:.6}  p99 {:.6}  max {:.6}  differing pixels {} of {}",
        stats.mean, stats.p99, stats.max, stats.differing, stats.pixels
    );
    if let Some(out) = &args.out {
        // Full scale at ten times the threshold, so a passing image stays dark.
        let picture = diff::error_image(&errors, a.width, a.height, (10.0 * args.threshold).max(1e-6));
        io::write(&picture, out)?;
    }
    if stats.mean > args.threshold {
        println!(
            "FAIL: mean error {:.6} is above the threshold {}",
            stats.mean, args.threshold
        );
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}
