//! The CPU reference tracer. Each file mirrors a shader file under the same function names, so that
//! a difference between the GPU and CPU images points at one function. It is the oracle of the tests,
//! the fallback where no adapter exists, and a baseline for benchmarks.

pub mod accel;
pub mod intersect;
pub mod shade;
pub mod trace;

pub use crate::error::MissingBvh;
pub use crate::modes::Count;

use crate::image::Frame;
use crate::modes::Accel;
use crate::records::PackedScene;
use glam::Vec2;
use rayon::prelude::*;
use trace::Tracer;

/// Renders every pixel in parallel (rows across rayon's threads); the result does not depend on the
/// thread count. BVH modes need the scene's BVH.
pub fn render(scene: &PackedScene, accel: Accel) -> Result<Frame, MissingBvh> {
    render_with(scene, accel, Count::Rays, &|| {})
}

/// [`render`], with what the fourth channel counts, and `row_done` called as each row finishes
/// (from rayon's threads), for a progress display.
pub fn render_with(
    scene: &PackedScene,
    accel: Accel,
    count: Count,
    row_done: &(dyn Fn() + Sync),
) -> Result<Frame, MissingBvh> {
    // Checked once here rather than per pixel.
    Tracer::new(scene, accel)?;
    let (width, height) = (scene.width(), scene.height());
    let rows: Vec<Vec<trace::PixelTrace>> = (0..height)
        .into_par_iter()
        .map(|j| {
            let row = (0..width)
                .map(|i| {
                    let mut tracer = Tracer::new(scene, accel).expect("checked above");
                    let ray = tracer.camera_ray(Vec2::new(i as f32 + 0.5, j as f32 + 0.5));
                    tracer.trace_pixel(ray)
                })
                .collect();
            row_done();
            row
        })
        .collect();
    let mut frame = Frame::new(width, height);
    for (pixel, trace) in rows.into_iter().flatten().enumerate() {
        let counted = match count {
            Count::Rays => trace.rays,
            Count::Cost => trace.cost,
        };
        frame.color[pixel] = [trace.color.x, trace.color.y, trace.color.z, counted as f32];
        frame.surface[pixel] = [
            trace.normal.x,
            trace.normal.y,
            trace.normal.z,
            trace.depth.unwrap_or(crate::image::DEPTH_MISS),
        ];
    }
    Ok(frame)
}
