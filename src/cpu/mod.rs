//! The CPU reference tracer. Each file mirrors a shader file under the same function names, so that
//! a difference between the GPU and CPU images points at one function. It is the oracle of the tests,
//! the fallback where no adapter exists, and a baseline for benchmarks.

pub mod accel;
pub mod intersect;
pub mod shade;
pub mod trace;

use crate::image::Frame;
use crate::render::Accel;
use crate::scene::packed::PackedScene;
use glam::Vec2;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use trace::Tracer;

/// Renders every pixel in parallel (rows across rayon's threads); the result does not depend on the
/// thread count. `progress` shows a bar on a terminal. BVH modes need `scene.nodes` built.
pub fn render(scene: &PackedScene, accel: Accel, progress: bool) -> Frame {
    render_with(scene, accel, progress, false)
}

/// [`render`], with each pixel's cost (see [`trace::PixelTrace::cost`]) in the colour's fourth
/// channel instead of its ray count where `write_cost` is set, as the shader's cost variant.
pub fn render_with(scene: &PackedScene, accel: Accel, progress: bool, write_cost: bool) -> Frame {
    assert!(
        accel == Accel::Brute || scene.primitive_count() == 0 || !scene.nodes.is_empty(),
        "{accel:?} traversal needs the scene's BVH: call PackedScene::build_bvh first"
    );
    let (width, height) = (scene.width(), scene.height());
    let bar = if progress {
        let bar = ProgressBar::new(height as u64);
        bar.set_style(
            ProgressStyle::with_template("{spinner} CPU render {bar:40} {pos}/{len} rows, {eta} left")
                .expect("the template is valid"),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let rows: Vec<Vec<trace::PixelTrace>> = (0..height)
        .into_par_iter()
        .map(|j| {
            let row = (0..width)
                .map(|i| {
                    let mut tracer = Tracer::new(scene, accel);
                    let ray = tracer.camera_ray(Vec2::new(i as f32 + 0.5, j as f32 + 0.5));
                    tracer.trace_pixel(ray)
                })
                .collect();
            bar.inc(1);
            row
        })
        .collect();
    bar.finish_and_clear();
    let mut frame = Frame::new(width, height);
    for (pixel, trace) in rows.into_iter().flatten().enumerate() {
        let count = if write_cost { trace.cost } else { trace.rays };
        frame.color[pixel] = [trace.color.x, trace.color.y, trace.color.z, count as f32];
        frame.surface[pixel] = [
            trace.normal.x,
            trace.normal.y,
            trace.normal.z,
            trace.depth.unwrap_or(crate::image::DEPTH_MISS),
        ];
    }
    frame
}
