//! The compute pipeline traces what the fragment pipeline traces: on one adapter their targets are
//! equal bit for bit, for every walk and memory mode, ray counts and costs, one sample and several.

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

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![gpu compute_equals_fragment]
}
