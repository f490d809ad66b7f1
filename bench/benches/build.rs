//! BVH build throughput: raypipe's LBVH (CPU, its hierarchy by merges and by searches, and GPU on
//! the adapter at hand) beside the builders of the `bvh` crate (binned SAH, parallel) and `obvhs`
//! (PLOC, parallel, fastest settings), all over the same sphere boxes. Run:
//! `cargo bench -p raypipe-bench`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use raypipe::bvh::aabb::Aabb;
use raypipe::bvh::lbvh::{Hierarchy, LbvhBuilder};
use raypipe::bvh::morton::MortonBits;
use raypipe::gpu::GpuContext;
use raypipe::gpu::builders::lbvh::GpuLbvhBuilder;
use raypipe_bench::random_boxes;
use std::time::Duration;

const SIZES: [usize; 4] = [10_000, 100_000, 1_000_000, 4_000_000];

/// A box for the `bvh` crate, which wants shapes that remember their node.
#[derive(Clone)]
struct BvhShape {
    aabb: bvh::aabb::Aabb<f32, 3>,
    node: usize,
}

impl bvh::aabb::Bounded<f32, 3> for BvhShape {
    fn aabb(&self) -> bvh::aabb::Aabb<f32, 3> {
        self.aabb
    }
}

impl bvh::bounding_hierarchy::BHShape<f32, 3> for BvhShape {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

fn bvh_shapes(boxes: &[Aabb]) -> Vec<BvhShape> {
    let point = |v: glam::Vec3| nalgebra::Point3::new(v.x, v.y, v.z);
    boxes
        .iter()
        .map(|b| BvhShape {
            aabb: bvh::aabb::Aabb::with_bounds(point(b.min), point(b.max)),
            node: 0,
        })
        .collect()
}

fn obvhs_boxes(boxes: &[Aabb]) -> Vec<obvhs::aabb::Aabb> {
    let v = |v: glam::Vec3| glam::Vec3A::new(v.x, v.y, v.z);
    boxes
        .iter()
        .map(|b| obvhs::aabb::Aabb::new(v(b.min), v(b.max)))
        .collect()
}

fn cpu_builders(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu_build");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for n in SIZES {
        let (_, boxes) = random_boxes(n);
        group.throughput(Throughput::Elements(n as u64));
        // A builder kept from build to build, as a per-frame rebuild keeps it.
        let mut builder = LbvhBuilder::<u64>::new();
        group.bench_with_input(BenchmarkId::new("raypipe_lbvh", n), &boxes, |b, boxes| {
            b.iter(|| builder.build(boxes, MortonBits::Bits30))
        });
        // The same tree with Karras's searches for the hierarchy.
        let mut builder = LbvhBuilder::<u64>::with_hierarchy(Hierarchy::Searches);
        group.bench_with_input(BenchmarkId::new("raypipe_lbvh_searches", n), &boxes, |b, boxes| {
            b.iter(|| builder.build(boxes, MortonBits::Bits30))
        });
        let shapes = bvh_shapes(&boxes);
        group.bench_with_input(BenchmarkId::new("bvh_build_par", n), &shapes, |b, shapes| {
            b.iter_batched_ref(
                || shapes.clone(),
                |shapes| {
                    <bvh::bvh::Bvh<f32, 3> as bvh::bounding_hierarchy::BoundingHierarchy<f32, 3>>::build_par(shapes)
                },
                criterion::BatchSize::LargeInput,
            )
        });
        let aabbs = obvhs_boxes(&boxes);
        group.bench_with_input(BenchmarkId::new("obvhs_ploc_fastest", n), &aabbs, |b, aabbs| {
            b.iter(|| {
                let mut core = Duration::ZERO;
                obvhs::bvh2::builder::build_bvh2(aabbs, obvhs::BvhBuildParams::fastest_build(), &mut core)
            })
        });
    }
    group.finish();
}

fn gpu_builder(c: &mut Criterion) {
    let Ok(Some(ctx)) = pollster::block_on(GpuContext::new(None)) else {
        eprintln!("no GPU adapter: skipping the GPU build benchmark");
        return;
    };
    if !ctx.timestamps {
        eprintln!(
            "{}: no timestamp queries, skipping the GPU build benchmark",
            ctx.describe()
        );
        return;
    }
    let mut group = c.benchmark_group(format!("gpu_build ({})", ctx.info.name));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let mut builder =
        pollster::block_on(GpuLbvhBuilder::new(&ctx, MortonBits::Bits30, 0, 0)).expect("the build compiles");
    // A software adapter takes seconds per million primitives: stop there.
    let software = ctx.info.device_type == wgpu::DeviceType::Cpu;
    for n in SIZES.into_iter().filter(|&n| !software || n <= 1_000_000) {
        let (packed, _) = random_boxes(n);
        if pollster::block_on(builder.resize(n, 0)).is_err() {
            eprintln!("{n} primitives do not fit the adapter's buffers: skipped");
            continue;
        }
        builder.write_spheres(&packed.spheres);
        group.throughput(Throughput::Elements(n as u64));
        // GPU time of the build's compute passes, from timestamp queries.
        group.bench_function(BenchmarkId::new("raypipe_lbvh_gpu", n), |b| {
            b.iter_custom(|iterations| {
                (0..iterations)
                    .map(|_| {
                        let timings = pollster::block_on(builder.build(raypipe::gpu::builders::lbvh::Codes::Computed))
                            .expect("the build runs");
                        Duration::from_secs_f64(timings.total() / 1e3)
                    })
                    .sum()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, cpu_builders, gpu_builder);
criterion_main!(benches);
