//! The driver's acceleration structures walked by ray queries (`--accel rayquery`) against the
//! stack walk: colour and depth within the tolerances for different devices, and the same ray
//! count, in both pipelines and every memory mode; moving scenes frame by frame; and the refusal on
//! adapters without ray queries (GL, where CI runs these tests a second time).

use crate::common::harness::Test;
use crate::common::*;
use crate::frames::{cpu_frames, gpu_frames, moving_frames};
use raypipe::Choice;
use raypipe::gpu::TreeUpdate;
use raypipe::gpu::{GpuContext, GpuError, Renderer, RendererOptions};
use raypipe::image::Frame;
use raypipe::modes::{Accel, MemoryMode, Pipeline};
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use std::path::Path;

/// Whether the adapter has ray queries; under `RAYPIPE_REQUIRE_GPU=1`, lavapipe (CI's Vulkan
/// adapter, which has them) must offer them, so that CI never skips these tests unseen.
fn has_ray_queries(ctx: &GpuContext) -> bool {
    let lavapipe = ctx.info.backend == wgpu::Backend::Vulkan && ctx.info.name.contains("llvmpipe");
    if std::env::var("RAYPIPE_REQUIRE_GPU").as_deref() == Ok("1") && lavapipe {
        assert!(ctx.ray_queries, "lavapipe offers no ray queries: {}", ctx.describe());
    }
    if !ctx.ray_queries {
        eprintln!(
            "note: {} has no ray queries; only the refusal is tested",
            ctx.describe()
        );
    }
    ctx.ray_queries
}

/// Each pipeline with each memory mode the adapter has.
fn every_route(ctx: &GpuContext) -> Vec<(Pipeline, MemoryMode)> {
    let memories = ctx.memory_modes();
    Pipeline::ALL
        .iter()
        .flat_map(|&p| memories.iter().map(move |&m| (p, m)))
        .collect()
}

/// Both pipelines, for a model too big for uniform memory: the fragment stage from storage
/// buffers, compute from textures (each shader compile costs seconds on lavapipe).
const MODEL_ROUTES: [(Pipeline, MemoryMode); 2] = [
    (Pipeline::Fragment, MemoryMode::Storage),
    (Pipeline::Compute, MemoryMode::Texture),
];

/// `scene` traced by ray queries through each of `routes`, against the stack walk's frame
/// (fragment pipeline, storage memory).
fn assert_like_the_stack_walk(ctx: &GpuContext, name: &str, scene: &PackedScene, routes: &[(Pipeline, MemoryMode)]) {
    let stack = render_gpu(ctx, scene, MemoryMode::Storage, Accel::Stack);
    for &(pipeline, memory) in routes {
        let options = RendererOptions {
            pipeline,
            memory,
            accel: Accel::RayQuery,
            ..Default::default()
        };
        let frame = render_gpu_with(ctx, scene, options);
        let case = format!("rayquery-{name}-{pipeline:?}-{memory:?}");
        assert_frames_match(&case, &frame, &stack);
        // The same tree of rays: primary, shadow and secondary alike.
        assert_eq!(frame.rays(), stack.rays(), "{case}: ray counts differ");
    }
}

fn with_bvh(mut scene: PackedScene) -> PackedScene {
    scene.build_bvh();
    scene
}

fn ray_queries_match_the_stack_walk_on_the_built_ins(ctx: &GpuContext) {
    if !has_ray_queries(ctx) {
        return;
    }
    assert_like_the_stack_walk(
        ctx,
        "whitted",
        &with_bvh(packed("whitted", 64, 48, 5)),
        &every_route(ctx),
    );
    // Spheres that overlap, so that boxes' candidates come back in every order.
    assert_like_the_stack_walk(
        ctx,
        "random",
        &with_bvh(packed("random:600:3", 64, 48, 5)),
        &every_route(ctx),
    );
    // Triangles (opaque, in the driver's hands) among spheres (candidates).
    let mut mixed = mixed_scene(8, 4, 100);
    mixed.settings.width = 64;
    mixed.settings.height = 48;
    assert_like_the_stack_walk(
        ctx,
        "mixed",
        &with_bvh(PackedScene::new(&mixed).unwrap()),
        &every_route(ctx),
    );
}

/// The cost view counts the driver's steps that reach the shader: more than zero where a ray
/// meets the scene, and none where the scene is empty.
fn the_cost_view_counts_the_query_steps(ctx: &GpuContext) {
    if !has_ray_queries(ctx) {
        return;
    }
    let scene = with_bvh(packed("random:200:3", 32, 24, 0));
    let options = RendererOptions {
        accel: Accel::RayQuery,
        count: raypipe::modes::Count::Cost,
        ..Default::default()
    };
    let frame = render_gpu_with(ctx, &scene, options);
    let costs: Vec<f32> = frame.color.iter().map(|c| c[3]).collect();
    assert!(costs.iter().all(|&c| c >= 0.0), "negative costs");
    assert!(costs.iter().any(|&c| c >= 2.0), "no ray met a sphere: {costs:?}");
}

/// Where the adapter lacks ray queries, the mode is refused with the adapter's name, before any
/// frame is traced.
fn without_ray_queries_the_mode_is_refused(ctx: &GpuContext) {
    if ctx.ray_queries {
        eprintln!("note: {} has ray queries; the refusal is tested on GL", ctx.describe());
        return;
    }
    let scene = packed("whitted", 16, 12, 1);
    let options = RendererOptions {
        accel: Accel::RayQuery,
        ..Default::default()
    };
    match pollster::block_on(Renderer::new(ctx, &scene, options)) {
        Err(GpuError::Unsupported { what, .. }) => assert!(what.contains("ray queries"), "{what}"),
        Err(other) => panic!("refused for another reason: {other}"),
        Ok(_) => panic!("{} has no ray queries, yet the mode was accepted", ctx.describe()),
    }
    assert!(!ctx.accels().contains(&Accel::RayQuery));
}

/// A model file at a small size, its BVH built for the stack walk.
fn model(path: &Path, width: u32, height: u32) -> (Scene, PackedScene) {
    let mut scene = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
    scene.settings.width = width;
    scene.settings.height = height;
    let packed = with_bvh(PackedScene::new(&scene).unwrap());
    (scene, packed)
}

/// The Bunny's triangles; a glTF of several meshes and instances; one with alpha MASK and BLEND
/// (non-opaque geometry, decided by the shader, for camera and shadow rays alike).
fn ray_queries_match_the_stack_walk_on_the_models(ctx: &GpuContext, models: &Path) {
    if !has_ray_queries(ctx) {
        return;
    }
    let khronos = |name: &str| models.join("khronos").join(name).join(format!("{name}.glb"));
    for (name, path) in [
        ("bunny", models.join("bunny.ply")),
        ("SimpleInstancing", khronos("SimpleInstancing")),
        ("AlphaBlendModeTest", khronos("AlphaBlendModeTest")),
    ] {
        let (_, packed) = model(&path, 48, 36);
        assert_like_the_stack_walk(ctx, name, &packed, &MODEL_ROUTES);
    }
}

/// An animated glTF, skinned on the GPU (its posed triangles the BLAS's vertices, the structures
/// rebuilt every frame) and rewritten from the CPU in texture memory: the CPU's frames.
fn ray_queries_follow_animated_frames(ctx: &GpuContext, models: &Path) {
    if !has_ray_queries(ctx) {
        return;
    }
    let path = models.join("khronos/CesiumMan/CesiumMan.glb");
    let (scene, _) = model(&path, 48, 36);
    let cpu = cpu_frames(&scene, Accel::Brute, 3);
    assert_ne!(cpu[0], cpu[2], "the model moves");
    let check = |route: &str, frames: Vec<Frame>| {
        for (k, (g, c)) in frames.iter().zip(&cpu).enumerate() {
            assert_frames_match(&format!("rayquery-animated-{route}-{k}"), g, c);
        }
    };
    check("gpu", gpu_frames(ctx, &scene, Accel::RayQuery, 3));
    check(
        "texture",
        moving_frames(
            ctx,
            &scene,
            Accel::RayQuery,
            MemoryMode::Texture,
            TreeUpdate::Rebuild,
            3,
        ),
    );
    // Spheres that move: their boxes rewritten and the structures rebuilt.
    let mut bounce = Scene::load("bounce:300:2").unwrap();
    bounce.settings.width = 48;
    bounce.settings.height = 36;
    let cpu = cpu_frames(&bounce, Accel::Brute, 3);
    for (k, (g, c)) in gpu_frames(ctx, &bounce, Accel::RayQuery, 3)
        .iter()
        .zip(&cpu)
        .enumerate()
    {
        assert_frames_match(&format!("rayquery-bounce-{k}"), g, c);
    }
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu ray_queries_match_the_stack_walk_on_the_built_ins,
        gpu the_cost_view_counts_the_query_steps,
        gpu without_ray_queries_the_mode_is_refused,
        gpu_models ray_queries_match_the_stack_walk_on_the_models,
        gpu_models ray_queries_follow_animated_frames,
    ]
}
