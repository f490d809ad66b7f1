//! Uniform, storage and texture memory carry the same scene: the images must be identical.

mod common;
use common::*;
use raypipe::bvh::morton::MortonBits;
use raypipe::gpu::GpuContext;
use raypipe::gpu::upload::MemoryMode;
use raypipe::image::diff::Tolerance;
use raypipe::render::Accel;
use raypipe::scene::packed::PackedScene;

fn check(spec: &str) {
    let Some(ctx) = gpu() else { return };
    let mut scene = packed(spec, 64, 48, 5);
    scene.build_bvh(MortonBits::Bits30);
    for accel in [Accel::Brute, Accel::Stack, Accel::Stackless, Accel::Threaded] {
        check_accel(&ctx, &scene, accel, spec);
    }
}

fn check_accel(ctx: &GpuContext, scene: &PackedScene, accel: Accel, spec: &str) {
    let storage = render_gpu(ctx, scene, MemoryMode::Storage, accel);
    for memory in [MemoryMode::Uniform, MemoryMode::Texture] {
        let frame = render_gpu(ctx, scene, memory, accel);
        let name = format!("memory-{memory:?}-{accel:?}-{}", spec.replace(':', "-"));
        // Same shader arithmetic on the same data: equal bit for bit, rays included.
        assert_images_match(&name, &frame.display(), &storage.display(), Tolerance::EXACT);
        assert_images_match(&name, &frame.depth(), &storage.depth(), Tolerance::EXACT);
        assert_eq!(frame.rays(), storage.rays(), "{name}: ray counts differ");
    }
}

#[test]
fn whitted_in_every_memory_mode() {
    check("whitted");
}

#[test]
fn random_spheres_in_every_memory_mode() {
    // 1,000 spheres are 32 KB, their 1,999 nodes 96 KB: over the 64 KiB uniform limit of most
    // adapters, so the stack mode takes 600 spheres (19 KB, 58 KB).
    check("random:600:3");
}

#[test]
fn triangles_in_every_memory_mode() {
    let Some(ctx) = gpu() else { return };
    // 192 triangles and 100 spheres: 583 nodes (28 KB) fit the uniform limit.
    let mut scene = models::mixed_scene(8, 4, 100);
    scene.settings.width = 64;
    scene.settings.height = 48;
    let mut scene = PackedScene::new(&scene).unwrap();
    scene.build_bvh(MortonBits::Bits30);
    for accel in [Accel::Brute, Accel::Stack, Accel::Stackless, Accel::Threaded] {
        check_accel(&ctx, &scene, accel, "spheres-and-triangles");
    }
}

#[test]
fn uniform_memory_refuses_a_scene_too_big_and_suggests_storage() {
    let Some(ctx) = gpu() else { return };
    let scene = packed("sphere-8k", 16, 16, 1);
    let error = raypipe::gpu::GpuRenderer::new(&ctx, &scene, MemoryMode::Uniform, Accel::Brute)
        .err()
        .expect("8,000 spheres do not fit a 64 KiB uniform buffer");
    let message = format!("{error:#}");
    assert!(message.contains("--memory storage"), "{message}");
}
