//! The LBVH built in compute passes against the CPU build: bit-identical node arrays from the same
//! Morton codes, and a valid tree from the GPU's own codes.

mod common;
use common::gpu;
use raypipe::bvh::aabb::Aabb;
use raypipe::bvh::morton::MortonBits;
use raypipe::bvh::{Bvh, centroid_codes};
use raypipe::gpu::build::GpuLbvhBuilder;
use raypipe::scene::builtin::SplitMix64;
use raypipe::scene::packed::GpuSphere;

fn random_spheres(n: usize, seed: u64, distinct_centres: usize) -> Vec<GpuSphere> {
    let mut rng = SplitMix64::new(seed);
    let centres: Vec<[f32; 3]> = (0..distinct_centres.max(1))
        .map(|_| {
            [
                rng.next_f32() * 10.0 - 5.0,
                rng.next_f32() * 4.0,
                rng.next_f32() * 10.0 - 5.0,
            ]
        })
        .collect();
    (0..n)
        .map(|i| GpuSphere {
            center: centres[(rng.next_u64() as usize) % centres.len()],
            radius: 0.01 + 0.1 * rng.next_f32(),
            material: i as u32 % 5,
            _pad: [0; 3],
        })
        .collect()
}

fn boxes(spheres: &[GpuSphere]) -> Vec<Aabb> {
    spheres.iter().map(GpuSphere::bounds).collect()
}

fn check_same_codes(builder: &mut GpuLbvhBuilder, spheres: &[GpuSphere], what: &str) {
    let boxes = boxes(spheres);
    let codes = centroid_codes(&boxes, MortonBits::Bits30);
    let (cpu, _) = Bvh::build_from_codes(&boxes, &codes, MortonBits::Bits30);
    builder.resize(spheres.len(), 0).unwrap();
    builder.write_spheres(spheres);
    builder.write_codes(&codes);
    builder.build(true).unwrap();
    let nodes = builder.read_nodes().unwrap();
    let first_difference = nodes.iter().zip(&cpu.nodes).position(|(g, c)| g != c);
    assert_eq!(nodes.len(), cpu.nodes.len(), "{what}: node counts");
    assert_eq!(first_difference, None, "{what}: first differing node");
}

#[test]
fn same_codes_give_identical_nodes() {
    let Some(ctx) = gpu() else { return };
    let mut builder = GpuLbvhBuilder::new(&ctx, 0, 0).unwrap();
    for n in [0, 1, 2, 3, 100, 1023, 1024, 1025, 5000] {
        check_same_codes(
            &mut builder,
            &random_spheres(n, n as u64, n),
            &format!("{n} random spheres"),
        );
    }
    check_same_codes(
        &mut builder,
        &random_spheres(30_000, 7, 30_000),
        "30,000 random spheres",
    );
}

#[test]
fn same_codes_give_identical_nodes_with_duplicate_centroids() {
    let Some(ctx) = gpu() else { return };
    let mut builder = GpuLbvhBuilder::new(&ctx, 0, 0).unwrap();
    check_same_codes(&mut builder, &random_spheres(4000, 3, 7), "4,000 spheres on 7 centres");
    check_same_codes(&mut builder, &random_spheres(2048, 4, 1), "2,048 coincident spheres");
}

#[test]
fn own_codes_give_a_valid_tree() {
    let Some(ctx) = gpu() else { return };
    let mut builder = GpuLbvhBuilder::new(&ctx, 0, 0).unwrap();
    for (n, centres) in [(1, 1), (2, 2), (10_000, 10_000), (3000, 5)] {
        let spheres = random_spheres(n, 11, centres);
        builder.resize(n, 0).unwrap();
        builder.write_spheres(&spheres);
        builder.build(false).unwrap();
        let bvh = Bvh {
            nodes: builder.read_nodes().unwrap(),
            primitive_count: n,
        };
        bvh.validate(&boxes(&spheres))
            .unwrap_or_else(|e| panic!("{n} spheres: {e}"));
        // The GPU's division may round the quantization scale differently from the CPU's: the
        // trees may then differ, but both are valid (checked above).
        let (cpu, _) = Bvh::build_lbvh(&boxes(&spheres), MortonBits::Bits30);
        if cpu != bvh {
            eprintln!("note: {n} spheres: the GPU's own Morton codes gave another valid tree than the CPU's");
        }
    }
}

/// Spheres and triangles in one build: the GPU's triangle boxes are the CPU's to the bit, so the same
/// codes give the same nodes, and the GPU's own codes give a valid tree over both kinds.
#[test]
fn spheres_and_triangles_build_alike() {
    let Some(ctx) = gpu() else { return };
    let mut scene = common::models::mixed_scene(16, 8, 700);
    scene.settings.width = 16;
    scene.settings.height = 16;
    let packed = raypipe::scene::packed::PackedScene::new(&scene).unwrap();
    assert!(!packed.triangles.is_empty() && !packed.spheres.is_empty());
    let boxes = packed.primitive_boxes();
    let codes = centroid_codes(&boxes, MortonBits::Bits30);
    let (cpu, _) = Bvh::build_from_codes(&boxes, &codes, MortonBits::Bits30);

    let mut builder = GpuLbvhBuilder::new(&ctx, 0, 0).unwrap();
    builder.write_scene(&packed).unwrap();
    builder.write_codes(&codes);
    builder.build(true).unwrap();
    assert!(builder.read_nodes().unwrap() == cpu.nodes, "GPU and CPU nodes differ");

    builder.build(false).unwrap();
    let own = Bvh {
        nodes: builder.read_nodes().unwrap(),
        primitive_count: boxes.len(),
    };
    own.validate(&boxes).unwrap();
}
