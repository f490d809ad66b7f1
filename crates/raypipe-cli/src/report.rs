//! How the command line reports: the one-line message an error becomes (the library's errors worded
//! in terms of the flags that avoid them), lines on standard output that fail instead of panicking,
//! and the medians its timings print.

use raypipe::gpu::GpuError;
use raypipe::modes::MemoryMode;

/// `error` and its causes on one line, with the library's errors worded in terms of the flags that
/// avoid them.
pub fn message(error: &anyhow::Error) -> String {
    let parts: Vec<String> = error
        .chain()
        .map(|cause| match cause.downcast_ref::<GpuError>() {
            Some(gpu) => gpu_message(gpu),
            None => cause.to_string(),
        })
        .collect();
    raypipe::error::one_line(&parts.join(": "))
}

fn gpu_message(error: &GpuError) -> String {
    match error {
        GpuError::TooBig {
            memory,
            array,
            records,
            needed,
            allowed,
        } => {
            let hint = match memory {
                MemoryMode::Uniform => "; use --memory storage",
                MemoryMode::Storage => "; use --memory texture, or --device cpu",
                MemoryMode::Texture => "; use --device cpu",
            };
            format!(
                "scene too big for --memory {memory}: {records} {array} records need {needed}, the adapter allows {allowed}{hint}"
            )
        }
        GpuError::RebuildNeedsStorage { .. } => {
            "the BVH rebuilt on the GPU is read from storage memory: use --memory storage".into()
        }
        GpuError::MissingBvh(missing) => format!("--accel {} needs the scene's BVH", missing.accel),
        GpuError::ImageTooLarge { width, height, max } => format!(
            "image {width}x{height} is larger than the adapter's maximum texture size {max}; render at most {max}x{max} on the GPU, or use --device cpu"
        ),
        GpuError::FrameTooLarge {
            width,
            height,
            bytes,
            max,
            max_pixels,
        } => format!(
            "image {width}x{height} needs {} MiB per frame target, the adapter allocates at most {} MiB; render at most {max_pixels} pixels on the GPU, or use --device cpu",
            bytes >> 20,
            max >> 20
        ),
        other => other.to_string(),
    }
}

/// Standard output could not take a line: closed by its reader (a pipe into `head`) or full
/// (`> /dev/full`).
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "standard output: {}", self.0)
    }
}

impl std::error::Error for StdoutError {}

impl StdoutError {
    /// Whether the reader went away: nothing left to tell, so the command ends quietly.
    pub fn reader_left(&self) -> bool {
        self.0.kind() == std::io::ErrorKind::BrokenPipe
    }
}

/// `println!` that returns a [`StdoutError`] where `println!` would panic: standard output closed
/// or full.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*).map_err($crate::report::StdoutError)?
    }};
}

/// The median of `values` (for an even count the mean of the middle two, as the peer benchmark
/// takes it); 0 for none.
pub fn median(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.into_iter().collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let half = v.len() / 2;
    if v.len().is_multiple_of(2) {
        (v[half - 1] + v[half]) / 2.0
    } else {
        v[half]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_is_the_middle_value_or_the_mean_of_the_middle_two() {
        assert_eq!(median([]), 0.0);
        assert_eq!(median([3.0]), 3.0);
        assert_eq!(median([5.0, 1.0, 3.0]), 3.0);
        assert_eq!(median([4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median([1.0, 100.0]), 50.5);
    }

    /// A frame past the adapter's largest allocation says how big a frame fits and the way out.
    #[test]
    fn a_frame_too_large_says_what_fits_and_the_way_out() {
        let message = gpu_message(&GpuError::FrameTooLarge {
            width: 512,
            height: 512,
            bytes: 4 << 20,
            max: 1 << 20,
            max_pixels: 65536,
        });
        assert_eq!(
            message,
            "image 512x512 needs 4 MiB per frame target, the adapter allocates at most 1 MiB; render at most 65536 pixels on the GPU, or use --device cpu"
        );
    }
}
