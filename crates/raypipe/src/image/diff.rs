//! Image comparison: the metric every test and `raypipe diff` use.
//!
//! The error of a pixel is the largest error over its channels. A channel's error is
//! |a - b| / max(1, |a|, |b|): absolute for display values in [0, 1], relative for depths and other
//! large values. Two equal non-finite values (an escaped ray's +inf depth in both) agree; a finite
//! value against a non-finite one (a hit against a miss) is an error of 1.

use super::FloatImage;

/// How two images differ, over their pixels' largest channel errors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffStats {
    /// Pixels compared.
    pub pixels: usize,
    /// The mean per-pixel error.
    pub mean: f64,
    /// 99th percentile of the per-pixel error.
    pub p99: f64,
    /// The largest per-pixel error.
    pub max: f64,
    /// Pixels whose error is above 0.
    pub differing: usize,
}

/// A pass mark for [`DiffStats`]: both the mean and the 99th percentile must stay at or below it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// The largest mean error allowed.
    pub mean: f64,
    /// The largest 99th percentile allowed.
    pub p99: f64,
}

impl Tolerance {
    /// GPU against CPU colour, in display units (1.0 = black to white). Float rounding differs between
    /// devices (fused multiply-add, `pow`, `sqrt`), and each bounce off a small sphere magnifies a
    /// direction's rounding error by about distance / radius, so a deep ray may hit a different sphere on
    /// each device: a few pixels may differ a lot (measured: at most 0.25 % at depth 5 on the built-in
    /// sphere clouds), the mean stays tiny (measured: at most 1.5e-4).
    pub const COLOR: Tolerance = Tolerance { mean: 1e-3, p99: 0.02 };
    /// First-hit distance between tracers or devices: relative float rounding, a few edge pixels.
    pub const DEPTH: Tolerance = Tolerance { mean: 1e-3, p99: 1e-4 };
    /// Identical up to float rounding: for images of one device in different memory modes.
    pub const EXACT: Tolerance = Tolerance { mean: 0.0, p99: 0.0 };

    /// Whether `stats` lie within this tolerance.
    pub fn check(&self, stats: &DiffStats) -> Result<(), Mismatch> {
        if stats.mean <= self.mean && stats.p99 <= self.p99 {
            Ok(())
        } else {
            Err(Mismatch::Beyond {
                stats: *stats,
                allowed: *self,
            })
        }
    }
}

fn channel_error(a: f32, b: f32) -> f64 {
    if a == b {
        return 0.0;
    }
    if !(a.is_finite() && b.is_finite()) {
        return 1.0;
    }
    let (a, b) = (a as f64, b as f64);
    (a - b).abs() / 1f64.max(a.abs()).max(b.abs())
}

/// Why two images do not match.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Mismatch {
    /// The images' sizes differ.
    #[error("images differ in size: {}x{} and {}x{}", .a.0, .a.1, .b.0, .b.1)]
    Size {
        /// The first image's width and height.
        a: (u32, u32),
        /// The second's.
        b: (u32, u32),
    },
    /// The images' channels differ.
    #[error("images differ in channels: {a:?} and {b:?}")]
    Channels {
        /// The first image's channel names.
        a: Vec<String>,
        /// The second's.
        b: Vec<String>,
    },
    /// The images differ beyond the tolerance.
    #[error(
        "images differ: mean error {:.3e} (allowed {:.1e}), p99 {:.3e} (allowed {:.1e}), max {:.3e}, {} of {} pixels differ",
        .stats.mean, .allowed.mean, .stats.p99, .allowed.p99, .stats.max, .stats.differing, .stats.pixels
    )]
    Beyond {
        /// The errors measured.
        stats: DiffStats,
        /// The tolerance they exceed.
        allowed: Tolerance,
    },
}

/// Per-pixel errors of two images of equal size and channels.
pub fn pixel_errors(a: &FloatImage, b: &FloatImage) -> Result<Vec<f64>, Mismatch> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(Mismatch::Size {
            a: (a.width, a.height),
            b: (b.width, b.height),
        });
    }
    if a.channels.len() != b.channels.len() {
        return Err(Mismatch::Channels {
            a: a.channels.clone(),
            b: b.channels.clone(),
        });
    }
    Ok((0..a.pixel_count())
        .map(|i| {
            a.pixel(i)
                .iter()
                .zip(b.pixel(i))
                .map(|(&x, &y)| channel_error(x, y))
                .fold(0.0, f64::max)
        })
        .collect())
}

/// The statistics of per-pixel errors.
pub fn stats(errors: &[f64]) -> DiffStats {
    let pixels = errors.len();
    if pixels == 0 {
        return DiffStats {
            pixels,
            mean: 0.0,
            p99: 0.0,
            max: 0.0,
            differing: 0,
        };
    }
    let mut sorted = errors.to_vec();
    sorted.sort_by(f64::total_cmp);
    // Nearest rank: the smallest error that at least 99 % of the pixels do not exceed.
    let rank = ((0.99 * pixels as f64).ceil() as usize).clamp(1, pixels);
    DiffStats {
        pixels,
        mean: errors.iter().sum::<f64>() / pixels as f64,
        p99: sorted[rank - 1],
        max: sorted[pixels - 1],
        differing: errors.iter().filter(|&&e| e > 0.0).count(),
    }
}

/// How `a` and `b` differ: each pixel's largest relative channel error, summarized.
pub fn compare(a: &FloatImage, b: &FloatImage) -> Result<DiffStats, Mismatch> {
    Ok(stats(&pixel_errors(a, b)?))
}

/// A picture of the errors: black where equal, through red and yellow to white at `full_scale`.
pub fn error_image(errors: &[f64], width: u32, height: u32, full_scale: f64) -> FloatImage {
    let data = errors
        .iter()
        .flat_map(|&e| {
            let x = (e / full_scale).clamp(0.0, 1.0) as f32;
            [
                (3.0 * x).min(1.0),
                (3.0 * x - 1.0).clamp(0.0, 1.0),
                (3.0 * x - 2.0).clamp(0.0, 1.0),
            ]
        })
        .collect();
    FloatImage {
        width,
        height,
        channels: ["R", "G", "B"].map(String::from).to_vec(),
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(data: Vec<f32>) -> FloatImage {
        FloatImage {
            width: data.len() as u32,
            height: 1,
            channels: vec!["Y".into()],
            data,
        }
    }

    #[test]
    fn errors_are_absolute_below_one_relative_above_and_treat_misses() {
        assert_eq!(channel_error(0.5, 0.25), 0.25);
        assert_eq!(channel_error(100.0, 101.0), 1.0 / 101.0);
        assert_eq!(channel_error(f32::INFINITY, f32::INFINITY), 0.0);
        assert_eq!(channel_error(f32::INFINITY, 3.0), 1.0);
    }

    #[test]
    fn percentile_is_nearest_rank() {
        let mut errors = vec![0.0; 99];
        errors.push(1.0);
        let s = stats(&errors);
        assert_eq!(s.p99, 0.0);
        assert_eq!(s.max, 1.0);
        errors.push(1.0);
        assert_eq!(stats(&errors).p99, 1.0);
        assert_eq!(s.differing, 1);
    }

    #[test]
    fn size_mismatch_is_an_error() {
        assert!(compare(&image(vec![0.0; 3]), &image(vec![0.0; 4])).is_err());
    }
}
