//! A scene renders alike at every size the scene rules accept: scaled by a power of two (exact in
//! floating point) the image is bit for bit the same, and its depth exactly scaled; scaled until its
//! farthest point sits at `MAX_COORDINATE`, or its smallest sphere at `MIN_RADIUS`, it matches within
//! the colour tolerance. Ray offsets and intersection arithmetic must scale with the scene for this
//! to hold (no absolute epsilon, no overflowing square), on the CPU and on the GPU.

use crate::common::harness::Test;
use crate::common::*;
use raypipe::Choice;
use raypipe::gpu::GpuContext;
use raypipe::image::Frame;
use raypipe::image::diff::Tolerance;
use raypipe::modes::{Accel, MemoryMode};
use raypipe::records::PackedScene;
use raypipe::scene::{MAX_COORDINATE, MIN_RADIUS, Scene};

fn base() -> Scene {
    whitted_with_quad(96, 72)
}

/// Every length of the scene times `k`.
fn scaled(scene: &Scene, k: f32) -> Scene {
    let mut scene = scene.clone();
    scene.camera.eye *= k;
    scene.camera.target *= k;
    scene.lights.iter_mut().for_each(|l| l.position *= k);
    for sphere in &mut scene.spheres {
        sphere.center *= k;
        sphere.radius *= k;
    }
    for triangle in &mut scene.triangles {
        triangle.vertices.iter_mut().for_each(|v| *v *= k);
    }
    for plane in &mut scene.planes {
        plane.point *= k;
        if let Some(checker) = &mut plane.checker {
            checker.size *= k;
        }
    }
    scene
}

/// The largest coordinate in the scene, and its smallest sphere radius.
fn extremes(scene: &Scene) -> (f32, f32) {
    let c = &scene.camera;
    let points = [c.eye, c.target]
        .into_iter()
        .chain(scene.lights.iter().map(|l| l.position))
        .chain(scene.spheres.iter().map(|s| s.center.abs() + s.radius))
        .chain(scene.triangles.iter().flat_map(|t| t.vertices))
        .chain(scene.planes.iter().map(|p| p.point));
    let far = points.map(|p| p.abs().max_element()).fold(0.0, f32::max);
    let small = scene.spheres.iter().map(|s| s.radius).fold(f32::INFINITY, f32::min);
    (far, small)
}

/// Power-of-two factors near both ends of the accepted range, and the two factors that put the
/// scene exactly at the ends (the sizes rounded to f32 stay inside).
fn factors(scene: &Scene) -> ([f32; 2], [f32; 2]) {
    let (far, small) = extremes(scene);
    let exact = [2f32.powi(-38), 2f32.powi(53)];
    let at_limits = [MIN_RADIUS / small * (1.0 + 1e-6), MAX_COORDINATE / far * (1.0 - 1e-6)];
    for k in exact.into_iter().chain(at_limits) {
        let (far_k, small_k) = extremes(&scaled(scene, k));
        assert!(
            far_k <= MAX_COORDINATE && small_k >= MIN_RADIUS,
            "factor {k:e} leaves the range"
        );
    }
    (exact, at_limits)
}

fn pack(scene: &Scene, accel: Accel) -> PackedScene {
    let mut packed = PackedScene::new(scene).unwrap_or_else(|e| panic!("the scaled scene is refused: {e}"));
    if accel.uses_bvh() {
        packed.build_bvh();
    }
    packed
}

fn check(render: impl Fn(&PackedScene, Accel) -> Frame, accels: &[Accel], device: &str) {
    let scene = base();
    let (exact, at_limits) = factors(&scene);
    for &accel in accels {
        let reference = render(&pack(&scene, accel), accel);
        let lit = reference.color.iter().filter(|c| c[0] + c[1] + c[2] > 0.3).count();
        assert!(
            lit > reference.color.len() / 2,
            "{device} {accel:?}: the scene renders dark"
        );
        for k in exact {
            let frame = render(&pack(&scaled(&scene, k), accel), accel);
            let name = format!("{device} {accel:?} scaled by {k:e}");
            assert!(
                frame.color == reference.color,
                "{name}: the colours differ from scale 1"
            );
            let depth_scaled = frame
                .depth()
                .data
                .iter()
                .zip(&reference.depth().data)
                .all(|(a, b)| *a == b * k);
            assert!(depth_scaled, "{name}: depth is not the scale-1 depth times the factor");
        }
        for k in at_limits {
            let frame = render(&pack(&scaled(&scene, k), accel), accel);
            assert_images_match(
                &format!("scale-{k:e}-{accel:?}"),
                &frame.display(),
                &reference.display(),
                Tolerance::COLOR,
            );
        }
    }
}

fn cpu_renders_alike_at_every_accepted_scale() {
    check(render_cpu, Accel::ALL, "cpu");
}

fn gpu_renders_alike_at_every_accepted_scale(ctx: &GpuContext) {
    for memory in [MemoryMode::Storage, MemoryMode::Texture] {
        let render = |scene: &PackedScene, accel| render_gpu(ctx, scene, memory, accel);
        check(
            render,
            &[Accel::Brute, Accel::Threaded],
            &format!("{} {memory:?}", ctx.describe()),
        );
    }
}

/// Past either end, the scene is refused with the limit in the message.
fn beyond_the_range_is_refused() {
    let scene = base();
    let (far, small) = extremes(&scene);
    let message = |k: f32| PackedScene::new(&scaled(&scene, k)).unwrap_err().to_string();
    let too_big = message(MAX_COORDINATE / far * 1.01);
    assert!(too_big.contains("must lie within 1e17 of the origin"), "{too_big}");
    let too_small = message(MIN_RADIUS / small * 0.99);
    assert!(too_small.contains("at least 1e-12"), "{too_small}");
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        plain cpu_renders_alike_at_every_accepted_scale,
        gpu gpu_renders_alike_at_every_accepted_scale,
        plain beyond_the_range_is_refused,
    ]
}
