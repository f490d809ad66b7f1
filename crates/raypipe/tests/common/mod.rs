//! Shared test harness: a GPU context or a loud skip, renders at test sizes, and image assertions
//! that leave the images behind for a human when they fail.
#![allow(dead_code)]

use raypipe::gpu::upload::MemoryMode;
use raypipe::gpu::{GpuContext, GpuRenderer};
use raypipe::image::diff::{self, Tolerance};
use raypipe::image::{FloatImage, Frame, io};
use raypipe::render::Accel;
use raypipe::scene::Scene;
use raypipe::scene::packed::PackedScene;
use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the raypipe binary with `args`.
pub fn raypipe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raypipe")).args(args).output().unwrap()
}

/// Exit code 2, exactly one line on stderr that starts with `error:` and contains every `needle`.
pub fn assert_clean_error(output: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(output.status.code(), Some(2), "stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(lines.len(), 1, "one error line expected: {stderr}");
    for needle in needles {
        assert!(lines[0].contains(needle), "{needle:?} not in {:?}", lines[0]);
    }
}

/// The adapter wgpu picks (honouring `WGPU_BACKEND`), or `None` with a message. With
/// `RAYPIPE_REQUIRE_GPU=1` a missing adapter fails the test instead.
pub fn gpu() -> Option<GpuContext> {
    let ctx = GpuContext::new(None).unwrap_or_else(|e| panic!("opening the GPU failed: {e:#}"));
    if ctx.is_none() {
        assert!(
            std::env::var("RAYPIPE_REQUIRE_GPU").as_deref() != Ok("1"),
            "RAYPIPE_REQUIRE_GPU=1 but no GPU adapter was found (install mesa-vulkan-drivers)"
        );
        eprintln!("SKIPPED: no GPU adapter found; set RAYPIPE_REQUIRE_GPU=1 to make this a failure");
    }
    ctx
}

/// A scene at a test size and depth, packed.
pub fn packed(spec: &str, width: u32, height: u32, max_depth: u32) -> PackedScene {
    let mut scene = Scene::load(spec).unwrap();
    scene.settings.width = width;
    scene.settings.height = height;
    scene.settings.max_depth = max_depth;
    PackedScene::new(&scene).unwrap()
}

pub fn render_gpu(ctx: &GpuContext, scene: &PackedScene, memory: MemoryMode, accel: Accel) -> Frame {
    GpuRenderer::new(ctx, scene, memory, accel)
        .and_then(|r| r.render())
        .unwrap_or_else(|e| panic!("GPU render failed on {}: {e:#}", ctx.describe()))
        .frame
}

fn output_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("image-failures");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts that `actual` matches `expected` within `tolerance`. On failure writes
/// `NAME-expected.*`, `NAME-actual.*` and `NAME-difference.png` and names them in the panic.
pub fn assert_images_match(name: &str, actual: &FloatImage, expected: &FloatImage, tolerance: Tolerance) {
    let errors = diff::pixel_errors(actual, expected).unwrap();
    let stats = diff::stats(&errors);
    if let Err(message) = tolerance.check(&stats) {
        let dir = output_dir();
        let ext = if actual.channels.len() == 3 && actual.data.iter().all(|v| (0.0..=1.0).contains(v)) {
            "png"
        } else {
            "exr"
        };
        io::write(actual, &dir.join(format!("{name}-actual.{ext}"))).unwrap();
        io::write(expected, &dir.join(format!("{name}-expected.{ext}"))).unwrap();
        let picture = diff::error_image(&errors, actual.width, actual.height, 0.1);
        io::write(&picture, &dir.join(format!("{name}-difference.png"))).unwrap();
        panic!("{name}: {message}; images in {}", dir.display());
    }
}

/// Colour and depth of two frames must match within the tolerances for different devices.
pub fn assert_frames_match(name: &str, actual: &Frame, expected: &Frame) {
    assert_images_match(
        &format!("{name}-color"),
        &actual.display(),
        &expected.display(),
        Tolerance::COLOR,
    );
    assert_images_match(
        &format!("{name}-depth"),
        &actual.depth(),
        &expected.depth(),
        Tolerance::DEPTH,
    );
}
pub mod models;
