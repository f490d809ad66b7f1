//! The LBVH built in compute passes against the CPU build: bit-identical node arrays from the same
//! Morton codes, 30-bit and 63-bit, and a valid tree from the GPU's own codes.

use crate::common::harness::Test;
use pollster::block_on;
use raypipe::bvh::aabb::Aabb;
use raypipe::bvh::layout::GpuNode;
use raypipe::bvh::morton::MortonBits;
use raypipe::bvh::sah::sah_cost;
use raypipe::bvh::threaded::threaded_nodes;
use raypipe::bvh::wide::{self, WideTree};
use raypipe::bvh::{Bvh, centroid_codes};
use raypipe::gpu::GpuContext;
use raypipe::gpu::builders::lbvh::{BuildVariant, Codes, GpuLbvhBuilder, SiblingBoxes};
use raypipe::gpu::builders::threaded_layout::GpuThreadedLayout;
use raypipe::gpu::builders::wide_collapse::GpuWideCollapse;
use raypipe::records::{GpuSphere, PackedScene};
use raypipe::rng::SplitMix64;

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

/// Both code widths; each compiles its own kernels.
const WIDTHS: [MortonBits; 2] = [MortonBits::Bits30, MortonBits::Bits63];

/// `n` spheres within a thousandth of one point, and one a unit away: a 30-bit grid puts the cluster in
/// a handful of cells, so their codes tie; 63-bit codes tell them apart in their low word.
fn clustered_spheres(n: usize, seed: u64) -> Vec<GpuSphere> {
    let mut spheres = random_spheres(n, seed, n);
    for sphere in &mut spheres {
        sphere.center = sphere.center.map(|c| 1.0 + c * 1e-4);
        sphere.radius *= 1e-4;
    }
    if let Some(far) = spheres.last_mut() {
        far.center = [2.0, 2.0, 2.0];
    }
    spheres
}

fn boxes(spheres: &[GpuSphere]) -> Vec<Aabb> {
    spheres.iter().map(GpuSphere::bounds).collect()
}

fn check_same_codes(builder: &mut GpuLbvhBuilder, spheres: &[GpuSphere], what: &str) {
    let bits = builder.bits();
    let what = format!("{what}, {}-bit codes", bits.total_bits());
    let boxes = boxes(spheres);
    let codes = centroid_codes(&boxes, bits);
    let (cpu, _) = Bvh::build_from_codes(&boxes, &codes, bits);
    block_on(builder.resize(spheres.len(), 0)).unwrap();
    builder.write_spheres(spheres);
    builder.write_codes(&codes);
    block_on(builder.build(Codes::Given)).unwrap();
    let nodes = block_on(builder.read_nodes()).unwrap();
    let first_difference = nodes.iter().zip(&cpu.nodes).position(|(g, c)| g != c);
    assert_eq!(nodes.len(), cpu.nodes.len(), "{what}: node counts");
    assert_eq!(first_difference, None, "{what}: first differing node");
    check_threaded_layout(builder, &cpu.nodes, &what);
    check_wide_collapse(builder, &cpu.nodes, &what);
}

/// The wide BVH of the GPU's nodes, collapsed on the GPU, against the CPU's of the same nodes.
/// The GPU places nodes and leaves in the order its counters hand out, so the trees are compared
/// as the walks see them: every node's frame, slots and boxes, and its children's, depth first.
fn check_wide_collapse(builder: &GpuLbvhBuilder, nodes: &[GpuNode], what: &str) {
    let ctx = builder.context();
    let n = builder.count();
    let depth = raypipe::bvh::lbvh::depth_bound(n, builder.bits());
    let collapse = block_on(GpuWideCollapse::new(ctx, &builder.buffers().nodes, n, depth)).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    collapse.encode(&mut encoder);
    ctx.queue.submit([encoder.finish()]);
    let gpu_texels = block_on(collapse.read(ctx)).unwrap();
    let cpu_texels = wide::wide_texels(nodes, n);
    let tree = |texels| WideTree {
        texels,
        root: wide::leaf_texels(n),
        stack_size: depth,
    };
    if n == 0 {
        return;
    }
    let (gpu, cpu) = (walk_order(&tree(&gpu_texels)), walk_order(&tree(&cpu_texels)));
    let first_difference = gpu.iter().zip(&cpu).position(|(g, c)| g != c);
    assert_eq!(first_difference, None, "{what}: first differing word of the wide trees");
    assert_eq!(gpu.len(), cpu.len(), "{what}: wide trees' sizes");
}

/// A wide tree as the walks see it: each node's words but where its children are stored, then
/// its children in slot order (a leaf's primitive, an internal child's own words).
fn walk_order(tree: &WideTree) -> Vec<u32> {
    let mut words = Vec::new();
    let mut pending = vec![tree.root];
    while let Some(texel) = pending.pop() {
        let node = tree.node(texel);
        let mut own: Vec<u32> = bytemuck::cast_slice(&[node]).to_vec();
        own[4] = 0; // child_base
        own[5] = 0; // leaf_base
        words.extend(own);
        for slot in (0..wide::WIDTH).rev() {
            if node.slots & (1 << slot) == 0 {
                continue;
            }
            if node.imask() & (1 << slot) != 0 {
                pending.push(node.child(slot));
            } else {
                words.push(tree.word(node.child(slot)));
            }
        }
    }
    words
}

/// The threaded layout of the GPU's nodes, laid out on the GPU, against the CPU's of the same nodes.
fn check_threaded_layout(builder: &GpuLbvhBuilder, nodes: &[GpuNode], what: &str) {
    let ctx = builder.context();
    let layout = block_on(GpuThreadedLayout::new(ctx, &builder.buffers().nodes, builder.count())).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    layout.encode(&mut encoder);
    ctx.queue.submit([encoder.finish()]);
    let (frame, threaded) = block_on(layout.read(ctx)).unwrap();
    let (cpu_frame, cpu_threaded) = threaded_nodes(nodes);
    assert_eq!(frame, cpu_frame, "{what}: quantization frames");
    let first_difference = threaded.iter().zip(&cpu_threaded).position(|(g, c)| g != c);
    assert_eq!(threaded.len(), cpu_threaded.len(), "{what}: threaded node counts");
    assert_eq!(first_difference, None, "{what}: first differing threaded node");
}

fn same_codes_give_identical_nodes(ctx: &GpuContext) {
    for bits in WIDTHS {
        let mut builder = block_on(GpuLbvhBuilder::new(ctx, bits, 0, 0)).unwrap();
        for n in [0, 1, 2, 3, 100, 1023, 1024, 1025, 5000, 8192, 8193] {
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
}

/// Every variant of the kernels the device runs builds alike: each way the sort can rank pairs
/// (runs, lane groups in workgroup memory, subgroups where the device has them), over many tiles
/// and a partial last one, with many equal digits; and each way the merges pass sibling boxes. The
/// best variant, which the tests above use, is checked there with both code widths; the others
/// share its digit extraction and are checked with 30-bit codes.
fn every_build_variant_gives_identical_nodes(ctx: &GpuContext) {
    let variants = BuildVariant::variants(ctx);
    // Runs and the shared path run everywhere, and so do atomic sibling boxes.
    assert!(variants.len() >= 2, "{variants:?}");
    assert!(
        variants.iter().any(|v| v.sibling_boxes == SiblingBoxes::Atomics),
        "{variants:?}"
    );
    for variant in variants.into_iter().skip(1) {
        let mut builder = block_on(GpuLbvhBuilder::with_variant(ctx, MortonBits::Bits30, 0, 0, variant)).unwrap();
        let what = format!("{variant:?}");
        check_same_codes(
            &mut builder,
            &random_spheres(40_000, 9, 40_000),
            &format!("{what}, 40,000 spheres"),
        );
        check_same_codes(
            &mut builder,
            &random_spheres(3000, 2, 3),
            &format!("{what}, 3,000 spheres on 3 centres"),
        );
        check_same_codes(&mut builder, &random_spheres(1, 1, 1), &format!("{what}, 1 sphere"));
    }
}

fn same_codes_give_identical_nodes_with_duplicate_centroids(ctx: &GpuContext) {
    for bits in WIDTHS {
        let mut builder = block_on(GpuLbvhBuilder::new(ctx, bits, 0, 0)).unwrap();
        check_same_codes(&mut builder, &random_spheres(4000, 3, 7), "4,000 spheres on 7 centres");
        check_same_codes(&mut builder, &random_spheres(2048, 4, 1), "2,048 coincident spheres");
        check_same_codes(&mut builder, &clustered_spheres(3000, 5), "3,000 clustered spheres");
    }
}

fn wide_codes_split_what_narrow_codes_tie() {
    let spheres = clustered_spheres(3000, 5);
    let boxes = boxes(&spheres);
    let distinct = |bits| {
        let mut codes = centroid_codes(&boxes, bits);
        codes.sort_unstable();
        codes.dedup();
        codes.len()
    };
    // The test above relies on this: the cluster ties in few 30-bit cells, and 63-bit codes tell
    // apart nearly all of its (about 1,900) distinct centres.
    let (narrow, wide) = (distinct(MortonBits::Bits30), distinct(MortonBits::Bits63));
    assert!(narrow < 100, "30-bit codes tell {narrow} cells apart in the cluster");
    assert!(wide > 1500, "63-bit codes tell only {wide} cells apart in the cluster");
}

fn own_codes_give_a_valid_tree(ctx: &GpuContext) {
    for bits in WIDTHS {
        check_own_codes(block_on(GpuLbvhBuilder::new(ctx, bits, 0, 0)).unwrap(), bits);
    }
}

fn check_own_codes(mut builder: GpuLbvhBuilder, bits: MortonBits) {
    for (n, centres) in [(1, 1), (2, 2), (10_000, 10_000), (3000, 5)] {
        let spheres = random_spheres(n, 11, centres);
        block_on(builder.resize(n, 0)).unwrap();
        builder.write_spheres(&spheres);
        block_on(builder.build(Codes::Computed)).unwrap();
        let bvh = Bvh {
            nodes: block_on(builder.read_nodes()).unwrap(),
            primitive_count: n,
        };
        bvh.validate(&boxes(&spheres))
            .unwrap_or_else(|e| panic!("{n} spheres: {e}"));
        // The GPU's division may round the quantization scale differently from the CPU's: the
        // trees may then differ, both valid (checked above), and no worse than a code's rounding
        // can make one: the same depth within 2 and SAH cost within 5 %.
        let (cpu, _) = Bvh::build_lbvh(&boxes(&spheres), bits);
        let (gpu_cost, cpu_cost) = (sah_cost(&bvh), sah_cost(&cpu));
        let (gpu_depth, cpu_depth) = (bvh.max_depth() as i64, cpu.max_depth() as i64);
        assert!(
            (gpu_depth - cpu_depth).abs() <= 2 && (gpu_cost - cpu_cost).abs() <= 0.05 * cpu_cost,
            "{n} spheres, {}-bit codes: the GPU's own codes gave depth {gpu_depth} and SAH {gpu_cost}, \
             the CPU's depth {cpu_depth} and SAH {cpu_cost}",
            bits.total_bits()
        );
    }
}

/// Spheres and triangles in one build: the GPU's triangle boxes are the CPU's to the bit, so the same
/// codes give the same nodes, and the GPU's own codes give a valid tree over both kinds.
fn spheres_and_triangles_build_alike(ctx: &GpuContext) {
    let mut scene = crate::common::mixed_scene(16, 8, 700);
    scene.settings.width = 16;
    scene.settings.height = 16;
    let packed = PackedScene::new(&scene).unwrap();
    assert!(!packed.triangles.is_empty() && !packed.spheres.is_empty());
    let boxes = packed.primitive_boxes();
    let codes = centroid_codes(&boxes, MortonBits::Bits30);
    let (cpu, _) = Bvh::build_from_codes(&boxes, &codes, MortonBits::Bits30);

    let mut builder = block_on(GpuLbvhBuilder::new(ctx, MortonBits::Bits30, 0, 0)).unwrap();
    block_on(builder.write_scene(&packed)).unwrap();
    builder.write_codes(&codes);
    block_on(builder.build(Codes::Given)).unwrap();
    assert!(
        block_on(builder.read_nodes()).unwrap() == cpu.nodes,
        "GPU and CPU nodes differ"
    );

    block_on(builder.build(Codes::Computed)).unwrap();
    let own = Bvh {
        nodes: block_on(builder.read_nodes()).unwrap(),
        primitive_count: boxes.len(),
    };
    own.validate(&boxes).unwrap();
}

/// The boxes a refit of `tree` over `boxes` must give: each leaf its primitive's, each internal
/// node the union of its children's, the links untouched.
fn refitted(tree: &[GpuNode], boxes: &[Aabb]) -> Vec<GpuNode> {
    let mut out = tree.to_vec();
    fn refit(out: &mut [GpuNode], boxes: &[Aabb], node: usize) -> Aabb {
        let b = if out[node].is_leaf() {
            boxes[out[node].left as usize]
        } else {
            let (left, right) = (out[node].left as usize, out[node].right as usize);
            refit(out, boxes, left).union(refit(out, boxes, right))
        };
        (out[node].min, out[node].max) = (b.min.to_array(), b.max.to_array());
        b
    }
    if !out.is_empty() {
        refit(&mut out, boxes, 0);
    }
    out
}

/// A tree built over spheres, refitted after they move, in every variant of the kernels: the
/// links are the build's and every box is its children's union, to the bit.
fn a_refit_keeps_the_tree_and_fits_its_boxes(ctx: &GpuContext) {
    for variant in BuildVariant::variants(ctx) {
        let mut builder = block_on(GpuLbvhBuilder::with_variant(ctx, MortonBits::Bits30, 0, 0, variant)).unwrap();
        for (n, seed) in [(1, 3), (2, 4), (20_000, 5)] {
            let before = random_spheres(n, seed, n);
            block_on(builder.resize(n, 0)).unwrap();
            builder.write_spheres(&before);
            block_on(builder.build(Codes::Computed)).unwrap();
            let tree = block_on(builder.read_nodes()).unwrap();
            let after = random_spheres(n, seed + 100, n);
            builder.write_spheres(&after);
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            builder.encode_refit(&mut encoder);
            ctx.queue.submit([encoder.finish()]);
            let refit = block_on(builder.read_nodes()).unwrap();
            assert!(
                refit == refitted(&tree, &boxes(&after)),
                "{variant:?}, {n} spheres: the refit differs from the CPU's"
            );
            assert!(n < 2 || refit != tree, "{n} spheres: the refit moved no box");
        }
    }
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu a_refit_keeps_the_tree_and_fits_its_boxes,
        gpu same_codes_give_identical_nodes,
        gpu every_build_variant_gives_identical_nodes,
        gpu same_codes_give_identical_nodes_with_duplicate_centroids,
        plain wide_codes_split_what_narrow_codes_tie,
        gpu own_codes_give_a_valid_tree,
        gpu spheres_and_triangles_build_alike,
    ]
}
