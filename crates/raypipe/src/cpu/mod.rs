//! The CPU reference tracer. Each file mirrors a shader file under the same function names, so that
//! a difference between the GPU and CPU images points at one function. It is the oracle of the tests,
//! the fallback where no adapter exists, and a baseline for benchmarks.

// The walks, the hit tests and the per-pixel tracer are public with the `internals` feature, for the
// tests that hold them to brute force and to formulas; the API is `render` and `render_with`.
#[cfg(feature = "internals")]
pub mod accel;
#[cfg(not(feature = "internals"))]
pub(crate) mod accel;
#[cfg(feature = "internals")]
pub mod admit;
#[cfg(not(feature = "internals"))]
pub(crate) mod admit;
pub(crate) mod brdf;
pub(crate) mod bsdf;
pub(crate) mod environment;
#[cfg(feature = "internals")]
pub mod intersect;
#[cfg(not(feature = "internals"))]
pub(crate) mod intersect;
pub(crate) mod maps;
pub(crate) mod path;
#[cfg(feature = "internals")]
pub mod sampling;
#[cfg(not(feature = "internals"))]
pub(crate) mod sampling;
pub(crate) mod shade;
#[cfg(feature = "internals")]
pub mod trace;
#[cfg(not(feature = "internals"))]
pub(crate) mod trace;

pub use crate::error::MissingBvh;
pub use crate::modes::Count;

use crate::image::Frame;
use crate::modes::Accel;
use crate::records::PackedScene;
use glam::{UVec2, Vec4};
use rayon::prelude::*;
use trace::Tracer;

/// Renders every pixel in parallel (rows across rayon's threads), one sample at each pixel's centre;
/// the result does not depend on the thread count. BVH modes need the scene's BVH.
pub fn render(scene: &PackedScene, accel: Accel) -> Result<Frame, MissingBvh> {
    render_with(scene, accel, Count::Rays, 1, &|| {})
}

/// [`render`] with `samples` samples per pixel (at least 1) and what the fourth channel counts;
/// `row_done` is called as each row finishes (from rayon's threads), for a progress display.
///
/// The GPU renderer's accumulation, sample for sample: colour and count are summed in sample order
/// and divided by the samples (the ray count stays a total: rays traced for the pixel); normal and
/// depth are the centre sample's.
pub fn render_with(
    scene: &PackedScene,
    accel: Accel,
    count: Count,
    samples: u32,
    row_done: &(dyn Fn() + Sync),
) -> Result<Frame, MissingBvh> {
    // Checked once here rather than per pixel.
    Tracer::new(scene, accel)?;
    let (width, height) = (scene.width(), scene.height());
    let samples = samples.max(1);
    let rows: Vec<Vec<([f32; 4], [f32; 4])>> = (0..height)
        .into_par_iter()
        .map(|j| {
            let row = (0..width)
                .map(|i| {
                    let pixel = UVec2::new(i, j);
                    let mut sum = Vec4::ZERO;
                    let mut surface = [0.0; 4];
                    for sample in 0..samples {
                        let mut tracer = Tracer::new(scene, accel).expect("checked above");
                        let trace = tracer.trace_sample(pixel, sample);
                        let counted = match count {
                            Count::Rays => trace.rays,
                            Count::Cost => trace.cost,
                        };
                        sum += trace.color.extend(counted as f32);
                        if sample == 0 {
                            let depth = trace.depth.unwrap_or(crate::image::DEPTH_MISS);
                            surface = trace.normal.extend(depth).to_array();
                        }
                    }
                    (crate::image::sample_mean(sum, samples, count), surface)
                })
                .collect();
            row_done();
            row
        })
        .collect();
    let mut frame = Frame::new(width, height);
    for (pixel, (color, surface)) in rows.into_iter().flatten().enumerate() {
        frame.color[pixel] = color;
        frame.surface[pixel] = surface;
    }
    Ok(frame)
}
