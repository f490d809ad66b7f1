//! The compute pipeline traces what the fragment pipeline traces: on one adapter their targets are
//! equal bit for bit, for every walk and memory mode, ray counts and costs, one sample and several.
//! And a device compiles each pipeline once.

use crate::common::harness::Test;
use crate::common::*;
use raypipe::gpu::{GpuContext, RendererOptions};
use raypipe::image::Frame;
use raypipe::modes::{Accel, Count, MemoryMode, Pipeline};
use raypipe::records::PackedScene;

fn frame(ctx: &GpuContext, scene: &PackedScene, options: RendererOptions, samples: u32) -> Frame {
    pollster::block_on(renderer(ctx, scene, options).render_samples(samples, |_| {}, |_| {}))
        .unwrap_or_else(|e| panic!("{options:?} failed on {}: {e}", ctx.describe()))
        .frame
}

fn compute_equals_fragment(ctx: &GpuContext) {
    // Odd sizes: the last workgroups of the compute grid reach past the image.
    let mut whitted = PackedScene::new(&whitted_with_quad(75, 53)).unwrap();
    whitted.build_bvh();
    // 10 rows of tiles, where the compute kernel's row step must skip 6, which shares a factor
    // with 10 (compute.wgsl, `tile_row`).
    let mut tall = PackedScene::new(&whitted_with_quad(12, 80)).unwrap();
    tall.build_bvh();
    let mut cloud = packed("random:1500:3", 75, 53, 5);
    cloud.build_bvh();
    let options = |accel, memory, count| RendererOptions {
        pipeline: Pipeline::Fragment,
        memory,
        accel,
        count,
        ..Default::default()
    };
    // Every walk; then, on the threaded walk (and the wide one, whose boxes the shader tests four at
    // a time), the other memory modes (uniform arrays hold
    // whitted's BVH, not the cloud's), costs, and several samples.
    let mut cases = Vec::new();
    for scene in [&whitted, &cloud] {
        for accel in ctx.accels() {
            cases.push((scene, options(accel, MemoryMode::Storage, Count::Rays), 1));
        }
        cases.push((scene, options(Accel::Threaded, MemoryMode::Storage, Count::Cost), 1));
        cases.push((scene, options(Accel::Wide, MemoryMode::Storage, Count::Cost), 1));
        cases.push((scene, options(Accel::Threaded, MemoryMode::Storage, Count::Rays), 3));
    }
    cases.push((&tall, options(Accel::Stack, MemoryMode::Storage, Count::Rays), 1));
    for memory in ctx.memory_modes().into_iter().filter(|&m| m != MemoryMode::Storage) {
        cases.push((&whitted, options(Accel::Threaded, memory, Count::Rays), 2));
        if memory != MemoryMode::Uniform {
            cases.push((&cloud, options(Accel::Threaded, memory, Count::Rays), 1));
            cases.push((&cloud, options(Accel::Wide, memory, Count::Rays), 1));
        }
    }
    for (scene, fragment_options, samples) in cases {
        let fragment = frame(ctx, scene, fragment_options, samples);
        let compute_options = RendererOptions {
            pipeline: Pipeline::Compute,
            ..fragment_options
        };
        let compute = frame(ctx, scene, compute_options, samples);
        let case = format!(
            "{} primitives, {fragment_options:?}, {samples} samples",
            scene.primitive_count()
        );
        let lit = fragment.color.iter().filter(|c| c[0] + c[1] + c[2] > 0.1).count();
        assert!(lit > fragment.color.len() / 4, "{case}: the image is dark");
        assert!(fragment.color == compute.color, "{case}: colour or count differs");
        assert!(fragment.surface == compute.surface, "{case}: normal or depth differs");
    }
}

/// A renderer made again on a device takes the pipelines the first compiled and draws what it
/// drew; another walk or pipeline compiles its own; a wgpu error in the context's error scopes
/// forgets them all, as one of the pipelines might be the one that failed. On a device of its own,
/// so that the other tests' pipelines do not count; not on GL, where a second device of one adapter
/// disturbs the first.
fn pipelines_are_compiled_once_a_device(shared: &GpuContext) {
    if shared.info.backend == wgpu::Backend::Gl {
        return;
    }
    let ctx = pollster::block_on(GpuContext::open(shared.adapter.clone())).unwrap();
    let mut scene = PackedScene::new(&whitted_with_quad(40, 30)).unwrap();
    scene.build_bvh();
    let stack = RendererOptions {
        accel: Accel::Stack,
        ..Default::default()
    };
    assert_eq!(ctx.cached_pipelines(), 0);
    let first = frame(&ctx, &scene, stack, 2);
    let kept = ctx.cached_pipelines();
    assert!(kept > 0, "the first renderer's pipelines are kept");
    let again = frame(&ctx, &scene, stack, 2);
    assert_eq!(ctx.cached_pipelines(), kept, "the second renderer compiled nothing");
    assert!(first.color == again.color && first.surface == again.surface);
    for other in [
        RendererOptions {
            accel: Accel::Threaded,
            ..stack
        },
        RendererOptions {
            pipeline: Pipeline::Compute,
            ..stack
        },
    ] {
        let before = ctx.cached_pipelines();
        frame(&ctx, &scene, other, 1);
        assert!(ctx.cached_pipelines() > before, "{other:?} compiled its own");
    }
    let invalid = pollster::block_on(ctx.checked("making a buffer both mappable and storage", || {
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Ok(buffer)
    }));
    assert!(invalid.is_err(), "wgpu refuses the buffer");
    assert_eq!(ctx.cached_pipelines(), 0, "an error forgets every pipeline");
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![gpu compute_equals_fragment, gpu pipelines_are_compiled_once_a_device]
}
