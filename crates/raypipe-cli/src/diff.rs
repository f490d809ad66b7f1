//! `raypipe diff`: two images compared by raypipe's per-pixel metric (the one every test uses) and by
//! FLIP (NVIDIA's perceptual difference, through the `nv-flip` crate), with a pass mark on one of
//! the figures.

use crate::io;
use anyhow::bail;
use clap::{Args, ValueEnum};
use raypipe::image::{FloatImage, diff, linear_to_srgb};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// What `--threshold` applies to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Metric {
    /// The mean per-pixel error (see docs/scene-format.md).
    #[default]
    Mean,
    /// The 99th percentile of the per-pixel error.
    P99,
    /// The mean FLIP error: how different the images look, 0 (alike) to 1.
    Flip,
}

/// The tests' pass marks (`Tolerance` in src/image/diff.rs), for `--tolerance`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum NamedTolerance {
    /// GPU against CPU colour: mean error at most 1e-3, its 99th percentile at most 0.02.
    Color,
    /// First-hit distance between devices: mean at most 1e-3, 99th percentile at most 1e-4.
    Depth,
    /// Equal: both 0.
    Exact,
}

impl NamedTolerance {
    pub fn tolerance(self) -> diff::Tolerance {
        match self {
            NamedTolerance::Color => diff::Tolerance::COLOR,
            NamedTolerance::Depth => diff::Tolerance::DEPTH,
            NamedTolerance::Exact => diff::Tolerance::EXACT,
        }
    }
}

#[derive(Args)]
pub struct DiffArgs {
    a: PathBuf,
    b: PathBuf,
    /// Write a picture of the per-pixel error here (FLIP's error map, magma, with --metric flip).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Largest value of --metric that passes: a finite number, 0 or more.
    #[arg(long, default_value_t = 0.01, value_parser = threshold)]
    threshold: f64,
    #[arg(long, value_enum, default_value_t)]
    metric: Metric,
    /// Pass where both the mean and the 99th percentile are within one of the tests' tolerances,
    /// instead of --metric and --threshold: the pass mark a browser test shares with the Rust ones.
    #[arg(long, value_enum, conflicts_with_all = ["threshold", "metric"])]
    tolerance: Option<NamedTolerance>,
}

fn threshold(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        Ok(_) => Err("the threshold must be a finite number, 0 or more".into()),
        Err(_) => Err(format!("'{text}' is not a number")),
    }
}

/// FLIP's figures of two images and its error map, one value per pixel in [0, 1].
struct Flip {
    mean: f64,
    p99: f64,
    map: nv_flip::FlipImageFloat,
}

/// An image's colour as FLIP reads it, 8-bit sRGB: PNG values as they are, EXR radiance encoded as
/// PNG files are. `None` for an image without R, G and B (a depth EXR).
fn srgb8(image: &FloatImage, path: &Path) -> Option<nv_flip::FlipImageRgb8> {
    let index = |name: &str| image.channels.iter().position(|c| c == name);
    let rgb = [index("R")?, index("G")?, index("B")?];
    let linear = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let bytes: Vec<u8> = (0..image.pixel_count())
        .flat_map(|i| {
            let pixel = image.pixel(i);
            rgb.map(|c| {
                let v = if linear { linear_to_srgb(pixel[c]) } else { pixel[c] };
                (v.clamp(0.0, 1.0) * 255.0).round() as u8
            })
        })
        .collect();
    Some(nv_flip::FlipImageRgb8::with_data(image.width, image.height, &bytes))
}

/// FLIP of `a` against `b` (the reference), at FLIP's default viewing distance.
fn flip(a: (&FloatImage, &Path), b: (&FloatImage, &Path)) -> Option<Flip> {
    let (test, reference) = (srgb8(a.0, a.1)?, srgb8(b.0, b.1)?);
    let map = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mut pool = nv_flip::FlipPool::from_image(&map);
    Some(Flip {
        mean: pool.mean() as f64,
        p99: pool.get_percentile(0.99, false) as f64,
        map,
    })
}

pub fn run(args: DiffArgs) -> anyhow::Result<ExitCode> {
    if let Some(out) = &args.out
        && !out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr"))
    {
        bail!("{}: --out writes a .png or .exr file", out.display());
    }
    let a = io::read(&args.a)?;
    let b = io::read(&args.b)?;
    // Sizes and channels are checked here, before FLIP (which requires equal sizes) runs.
    let errors = diff::pixel_errors(&a, &b)
        .map_err(|e| anyhow::anyhow!("{} and {}: {e}", args.a.display(), args.b.display()))?;
    let stats = diff::stats(&errors);
    let flip = flip((&a, &args.a), (&b, &args.b));
    let flip_figures = match &flip {
        Some(f) => format!("FLIP mean {:.6}  p99 {:.6}", f.mean, f.p99),
        None => "FLIP n/a (not colour images)".into(),
    };
    crate::say!(
        "mean {:.6}  p99 {:.6}  max {:.6}  differing pixels {} of {}  {flip_figures}",
        stats.mean,
        stats.p99,
        stats.max,
        stats.differing,
        stats.pixels
    );
    if let Some(named) = args.tolerance {
        let tolerance = named.tolerance();
        if let Some(out) = &args.out {
            let full_scale = (10.0 * tolerance.p99).max(1e-6);
            io::write(&diff::error_image(&errors, a.width, a.height, full_scale), out)?;
        }
        if let Err(mismatch) = tolerance.check(&stats) {
            crate::say!("FAIL: {mismatch}");
            return Ok(ExitCode::from(1));
        }
        return Ok(ExitCode::SUCCESS);
    }
    let measured = match (args.metric, &flip) {
        (Metric::Mean, _) => stats.mean,
        (Metric::P99, _) => stats.p99,
        (Metric::Flip, Some(f)) => f.mean,
        (Metric::Flip, None) => bail!(
            "{}, {}: --metric flip compares colour images (R, G and B channels)",
            args.a.display(),
            args.b.display()
        ),
    };
    if let Some(out) = &args.out {
        let picture = match (args.metric, &flip) {
            (Metric::Flip, Some(f)) => flip_picture(&f.map),
            // Full scale at ten times the threshold, so a passing image stays dark.
            _ => diff::error_image(&errors, a.width, a.height, (10.0 * args.threshold).max(1e-6)),
        };
        io::write(&picture, out)?;
    }
    if measured > args.threshold {
        let metric = args.metric.to_possible_value().expect("no variant is skipped");
        crate::say!(
            "FAIL: {} {measured:.6} is above the threshold {}",
            metric.get_name(),
            args.threshold
        );
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

/// FLIP's error map in its magma colours, as display values.
fn flip_picture(map: &nv_flip::FlipImageFloat) -> FloatImage {
    let colours = map.apply_color_lut(&nv_flip::magma_lut());
    FloatImage {
        width: colours.width(),
        height: colours.height(),
        channels: ["R", "G", "B"].map(String::from).to_vec(),
        data: colours.to_vec().into_iter().map(|v| v as f32 / 255.0).collect(),
    }
}
