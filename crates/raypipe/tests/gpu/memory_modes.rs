//! Uniform, storage and texture memory carry the same scene: the images must be identical.

use crate::common::harness::Test;
use crate::common::*;
use raypipe::Choice;
use raypipe::gpu::{GpuContext, GpuError, Renderer, RendererOptions};
use raypipe::image::diff::Tolerance;
use raypipe::modes::{Accel, MemoryMode};
use raypipe::records::PackedScene;

fn check(ctx: &GpuContext, spec: &str) {
    let mut scene = packed(spec, 64, 48, 5);
    scene.build_bvh();
    for accel in ctx.accels() {
        check_accel(ctx, &scene, accel, spec);
    }
}

fn check_accel(ctx: &GpuContext, scene: &PackedScene, accel: Accel, spec: &str) {
    let storage = render_gpu(ctx, scene, MemoryMode::Storage, accel);
    for &memory in MemoryMode::ALL.iter().filter(|&&m| m != MemoryMode::Storage) {
        let frame = render_gpu(ctx, scene, memory, accel);
        let name = format!("memory-{memory:?}-{accel:?}-{}", spec.replace(':', "-"));
        // Same shader arithmetic on the same data: equal bit for bit, rays included.
        assert_images_match(&name, &frame.display(), &storage.display(), Tolerance::EXACT);
        assert_images_match(&name, &frame.depth(), &storage.depth(), Tolerance::EXACT);
        assert_eq!(frame.rays(), storage.rays(), "{name}: ray counts differ");
    }
}

fn whitted_in_every_memory_mode(ctx: &GpuContext) {
    check(ctx, "whitted");
}

fn random_spheres_in_every_memory_mode(ctx: &GpuContext) {
    // 1,000 spheres are 32 KB, their 1,999 nodes 96 KB: over the 64 KiB uniform limit of most
    // adapters, so the stack mode takes 600 spheres (19 KB, 58 KB).
    check(ctx, "random:600:3");
}

fn triangles_in_every_memory_mode(ctx: &GpuContext) {
    // 192 triangles and 100 spheres: 583 nodes (28 KB) fit the uniform limit.
    let mut scene = crate::common::mixed_scene(8, 4, 100);
    scene.settings.width = 64;
    scene.settings.height = 48;
    let mut scene = PackedScene::new(&scene).unwrap();
    scene.build_bvh();
    for accel in ctx.accels() {
        check_accel(ctx, &scene, accel, "spheres-and-triangles");
    }
}

fn uniform_memory_refuses_a_scene_too_big(ctx: &GpuContext) {
    let scene = packed("sphere-8k", 16, 16, 1);
    let options = RendererOptions {
        memory: MemoryMode::Uniform,
        accel: Accel::Brute,
        ..Default::default()
    };
    let error = pollster::block_on(Renderer::new(ctx, &scene, options))
        .err()
        .expect("8,000 spheres do not fit a 64 KiB uniform buffer");
    assert!(
        matches!(
            error,
            GpuError::TooBig {
                memory: MemoryMode::Uniform,
                array: "sphere",
                records: 8000,
                ..
            }
        ),
        "{error}"
    );
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu whitted_in_every_memory_mode,
        gpu random_spheres_in_every_memory_mode,
        gpu triangles_in_every_memory_mode,
        gpu uniform_memory_refuses_a_scene_too_big,
    ]
}
