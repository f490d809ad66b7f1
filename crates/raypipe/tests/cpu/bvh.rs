//! The linear BVH: structure on awkward inputs (property tests), and traversal against brute force.

use glam::Vec3;
use proptest::prelude::*;
use raypipe::bvh::aabb::Aabb;
use raypipe::bvh::key::Key;
use raypipe::bvh::lbvh::{Hierarchy, LbvhBuilder};
use raypipe::bvh::morton::MortonBits;
use raypipe::bvh::sah::{build_binned_sah, sah_cost};
use raypipe::bvh::threaded::{self, GpuThreadedNode, threaded_nodes};
use raypipe::bvh::wide::{self, GpuWideTexel, NODE_TEXELS, WideTree};
use raypipe::bvh::{Bvh, centroid_codes};
use raypipe::cpu::accel::{
    brute_closest, brute_occluded, traverse_stack, traverse_stackless, traverse_threaded, traverse_wide,
};
use raypipe::cpu::admit::Primitives;
use raypipe::cpu::intersect::{Hit, HitKind, Ray};
use raypipe::records::packed::primitive_boxes;
use raypipe::records::{GpuSphere, GpuTriangle, PackedBvh};
use raypipe::rng::SplitMix64;

fn spheres_to_boxes(spheres: &[(Vec3, f32)]) -> Vec<Aabb> {
    spheres.iter().map(|&(c, r)| Aabb::around_sphere(c, r)).collect()
}

/// The LBVH with its hierarchy found by Karras's searches, and by merges with several chunk sizes
/// (tiny ones leave most of the tree to the merge that joins the chunks).
fn lbvh_variants<K: Key>(boxes: &[Aabb], bits: MortonBits) -> Vec<(String, Bvh)> {
    let searches = LbvhBuilder::<K>::with_hierarchy(Hierarchy::Searches);
    let mut variants = vec![("searches".to_string(), searches.build_into(boxes, bits).0)];
    for chunk in [1, 2, 3, 64, 4096] {
        let merges = LbvhBuilder::<K>::with_hierarchy(Hierarchy::Merges).with_merge_chunk(chunk);
        variants.push((format!("merges in chunks of {chunk}"), merges.build_into(boxes, bits).0));
    }
    variants
}

/// Both ways of finding the hierarchy, every chunk size: one node array, bit for bit.
fn check_hierarchies_agree(boxes: &[Aabb]) -> Result<(), TestCaseError> {
    for bits in [MortonBits::Bits30, MortonBits::Bits63] {
        let (default, _) = Bvh::build_lbvh(boxes, bits);
        let variants = match bits {
            MortonBits::Bits30 => lbvh_variants::<u64>(boxes, bits),
            MortonBits::Bits63 => lbvh_variants::<u128>(boxes, bits),
        };
        for (name, bvh) in variants {
            prop_assert!(bvh == default, "{:?} {} over {} boxes differs", bits, name, boxes.len());
        }
    }
    Ok(())
}

fn check_all_builders(boxes: &[Aabb]) -> Result<(), TestCaseError> {
    check_hierarchies_agree(boxes)?;
    for bits in [MortonBits::Bits30, MortonBits::Bits63] {
        let (bvh, _) = Bvh::build_lbvh(boxes, bits);
        prop_assert_eq!(
            bvh.validate(boxes),
            Ok(()),
            "LBVH {:?} over {} boxes",
            bits,
            boxes.len()
        );
        let (frame, threaded) = threaded_nodes(&bvh.nodes);
        prop_assert_eq!(
            threaded::validate(&frame, &threaded, boxes),
            Ok(()),
            "threaded LBVH {:?} over {} boxes",
            bits,
            boxes.len()
        );
        let packed = PackedBvh::new(bvh);
        prop_assert_eq!(
            wide::validate(&packed.wide_tree(), boxes),
            Ok(()),
            "wide LBVH {:?} over {} boxes",
            bits,
            boxes.len()
        );
    }
    let sah = build_binned_sah(boxes);
    prop_assert_eq!(sah.validate(boxes), Ok(()), "binned SAH over {} boxes", boxes.len());
    let (frame, threaded) = threaded_nodes(&sah.nodes);
    prop_assert_eq!(
        threaded::validate(&frame, &threaded, boxes),
        Ok(()),
        "threaded binned SAH over {} boxes",
        boxes.len()
    );
    let packed = PackedBvh::new(sah);
    prop_assert_eq!(
        wide::validate(&packed.wide_tree(), boxes),
        Ok(()),
        "wide binned SAH over {} boxes",
        boxes.len()
    );
    Ok(())
}

fn vec3(range: std::ops::Range<f32>) -> impl Strategy<Value = Vec3> {
    (range.clone(), range.clone(), range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Random spheres, clustered spheres, spheres on a line, coincident spheres, and tiny spheres.
fn scenes() -> impl Strategy<Value = Vec<(Vec3, f32)>> {
    let random = prop::collection::vec((vec3(-100.0..100.0), 0.001f32..5.0), 0..400);
    let clustered = (
        prop::collection::vec(vec3(-50.0..50.0), 1..5),
        prop::collection::vec((0usize..5, vec3(-0.01..0.01), 0.001f32..0.01), 1..400),
    )
        .prop_map(|(centres, members)| {
            members
                .into_iter()
                .map(|(c, offset, r)| (centres[c % centres.len()] + offset, r))
                .collect()
        });
    let collinear = (vec3(-1.0..1.0), prop::collection::vec(-10.0f32..10.0, 1..300))
        .prop_map(|(dir, ts)| ts.into_iter().map(|t| (dir * t, 0.05)).collect());
    let coincident = (
        vec3(-5.0..5.0),
        1usize..300,
        prop::collection::vec(vec3(-1.0..1.0), 0..20),
    )
        .prop_map(|(c, n, others)| {
            let mut v: Vec<(Vec3, f32)> = (0..n).map(|_| (c, 0.5)).collect();
            v.extend(others.into_iter().map(|o| (o, 0.1)));
            v
        });
    let tiny = prop::collection::vec((vec3(-1e-4..1e-4), 1e-7f32..1e-6), 1..200);
    prop_oneof![random, clustered, collinear, coincident, tiny]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn builders_give_valid_trees(spheres in scenes()) {
        check_all_builders(&spheres_to_boxes(&spheres))?;
    }
}

#[test]
fn zero_one_and_two_primitives() {
    for n in 0usize..=2 {
        let boxes: Vec<Aabb> = (0..n)
            .map(|i| Aabb::around_sphere(Vec3::splat(i as f32), 0.5))
            .collect();
        check_hierarchies_agree(&boxes).unwrap();
        let (bvh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
        assert_eq!(bvh.nodes.len(), (2 * n).saturating_sub(1));
        bvh.validate(&boxes).unwrap();
        wide::validate(&PackedBvh::new(bvh).wide_tree(), &boxes).unwrap();
    }
}

#[test]
fn a_corrupted_tree_fails_validation() {
    let boxes = spheres_to_boxes(
        &(0..50)
            .map(|i| (Vec3::new(i as f32, 0.0, 0.0), 0.4))
            .collect::<Vec<_>>(),
    );
    let (bvh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
    bvh.validate(&boxes).unwrap();
    let mut corruptions: Vec<(&str, Bvh)> = Vec::new();
    let mut b = bvh.clone();
    b.nodes[3].min[0] += 0.5;
    corruptions.push(("a loose box", b));
    let mut b = bvh.clone();
    b.nodes[5].escape = 0;
    corruptions.push(("a wrong escape", b));
    let mut b = bvh.clone();
    let last = b.nodes.len() - 1;
    b.nodes[last].left = b.nodes[last - 1].left;
    corruptions.push(("a primitive in two leaves", b));
    let mut b = bvh.clone();
    b.nodes[7].parent = 1;
    corruptions.push(("a wrong parent", b));
    for (what, corrupted) in corruptions {
        assert!(corrupted.validate(&boxes).is_err(), "{what} passed validation");
    }
}

#[test]
fn a_corrupted_wide_tree_fails_validation() {
    let boxes = spheres_to_boxes(
        &(0..200)
            .map(|i| (Vec3::new(i as f32, (i % 7) as f32, (i % 3) as f32), 0.4))
            .collect::<Vec<_>>(),
    );
    let (bvh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
    let packed = PackedBvh::new(bvh);
    let tree = packed.wide_tree();
    wide::validate(&tree, &boxes).unwrap();
    let root = tree.root as usize;
    let node = tree.node(tree.root);
    assert_eq!(node.slots, 0xff, "the root of 200 primitives has eight children");
    let slot = node.slots.trailing_zeros() as usize;
    let mut corruptions: Vec<(&str, Vec<GpuWideTexel>)> = Vec::new();
    let mut c = packed.wide_texels().clone();
    // The root's first slot's high x corner brought down to its low one.
    let low_x = (node.lo[0][slot / 4] >> (8 * (slot % 4))) & 0xff;
    c[root + 3].words[2 + slot / 4] &= !(0xff << (8 * (slot % 4)));
    c[root + 3].words[2 + slot / 4] |= low_x << (8 * (slot % 4));
    corruptions.push(("a box that no longer holds its primitives", c));
    let mut c = packed.wide_texels().clone();
    c[root + 1].words[0] += NODE_TEXELS;
    corruptions.push(("a child base one node off", c));
    let mut c = packed.wide_texels().clone();
    c[0].words[1] = c[0].words[0];
    corruptions.push(("a primitive in two leaves", c));
    let mut c = packed.wide_texels().clone();
    c[root].words[0] = (f32::from_bits(c[root].words[0]) + 1.0).to_bits();
    corruptions.push(("a node frame moved along x", c));
    for (what, corrupted) in corruptions {
        let tree = WideTree {
            texels: &corrupted,
            ..tree
        };
        assert!(wide::validate(&tree, &boxes).is_err(), "{what} passed validation");
    }
    // A walk visiting a node at depth d has d groups waiting: the stack must be as deep as the
    // deepest node, and no deeper is asked.
    let deepest = deepest_wide_node(&tree, tree.root);
    assert!(deepest >= 2 && deepest <= tree.stack_size, "depth {deepest}");
    let stack = |stack_size| WideTree { stack_size, ..tree };
    wide::validate(&stack(deepest), &boxes).unwrap();
    assert!(
        wide::validate(&stack(deepest - 1), &boxes).is_err(),
        "a stack of {} passed a tree {deepest} deep",
        deepest - 1
    );
}

/// The depth of the deepest node below the one at `texel` (0 for that node).
fn deepest_wide_node(tree: &WideTree, texel: u32) -> u32 {
    let node = tree.node(texel);
    (0..wide::WIDTH)
        .filter(|&slot| node.imask() & (1 << slot) != 0)
        .map(|slot| 1 + deepest_wide_node(tree, node.child(slot)))
        .max()
        .unwrap_or(0)
}

#[test]
fn a_corrupted_threaded_tree_fails_validation() {
    let boxes = spheres_to_boxes(
        &(0..50)
            .map(|i| (Vec3::new(i as f32, (i % 3) as f32, 0.0), 0.4))
            .collect::<Vec<_>>(),
    );
    let (bvh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
    let (frame, nodes) = threaded_nodes(&bvh.nodes);
    threaded::validate(&frame, &nodes, &boxes).unwrap();
    let internal = nodes.iter().position(|n| !n.is_leaf() && n.link > 5).unwrap();
    let leaf = nodes.iter().position(GpuThreadedNode::is_leaf).unwrap();
    let mut corruptions: Vec<(&str, Vec<GpuThreadedNode>)> = Vec::new();
    let mut c = nodes.clone();
    // min.x moved up to max.x
    c[leaf].bounds[0] = (c[leaf].bounds[0] & 0xffff_0000) | (c[leaf].bounds[1] >> 16);
    corruptions.push(("a box that no longer holds its primitive", c));
    let mut c = nodes.clone();
    c[internal].link -= 1;
    corruptions.push(("a link short of the subtree's end", c));
    let mut c = nodes.clone();
    let other = nodes.iter().rposition(GpuThreadedNode::is_leaf).unwrap();
    c[other].link = c[leaf].link;
    corruptions.push(("a primitive in two leaves", c));
    for (what, corrupted) in corruptions {
        assert!(
            threaded::validate(&frame, &corrupted, &boxes).is_err(),
            "{what} passed validation"
        );
    }
    // A frame moved by one quantum leaves some box short of its primitives.
    let mut moved = frame;
    moved.origin.x += moved.quantum.x * 2.0;
    assert!(
        threaded::validate(&moved, &nodes, &boxes).is_err(),
        "a shifted frame passed validation"
    );
}

#[test]
fn equal_codes_keep_primitive_order_and_build_a_balanced_tree() {
    // 1,024 coincident centroids: one Morton code, so the split falls back to the index bits.
    let boxes = vec![Aabb::around_sphere(Vec3::ZERO, 1.0); 1024];
    let (bvh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
    bvh.validate(&boxes).unwrap();
    assert_eq!(bvh.max_depth(), 10, "index bits split a power of two evenly");
    let leaves: Vec<u32> = bvh.nodes[1023..].iter().map(|n| n.left).collect();
    assert_eq!(leaves, (0..1024).collect::<Vec<_>>(), "stable sort keeps input order");
}

#[test]
fn lbvh_sah_cost_is_close_to_binned_sah() {
    let mut rng = SplitMix64::new(11);
    let boxes: Vec<Aabb> = (0..20_000)
        .map(|_| Aabb::around_sphere(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()), 0.002))
        .collect();
    let (lbvh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
    let ratio = sah_cost(&lbvh) / sah_cost(&build_binned_sah(&boxes));
    assert!((1.0..1.5).contains(&ratio), "LBVH / SAH cost ratio {ratio}");
}

#[test]
fn given_codes_give_the_same_tree() {
    let mut rng = SplitMix64::new(5);
    let boxes: Vec<Aabb> = (0..5000)
        .map(|_| Aabb::around_sphere(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()), 0.01))
        .collect();
    let codes = centroid_codes(&boxes, MortonBits::Bits30);
    let (a, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
    let (b, _) = Bvh::build_from_codes(&boxes, &codes, MortonBits::Bits30);
    assert_eq!(a, b);
}

/// Scenes over several of the default merge chunks, with runs of coincident centroids that cross
/// chunk boundaries: the merges give the searches' tree.
#[test]
fn merges_across_default_chunks_equal_searches() {
    let mut rng = SplitMix64::new(23);
    let mut boxes: Vec<Aabb> = (0..70_000)
        .map(|_| Aabb::around_sphere(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()), 0.001))
        .collect();
    // 30,000 coincident spheres: one Morton code over more than a chunk
    boxes.extend((0..30_000).map(|_| Aabb::around_sphere(Vec3::splat(0.25), 0.001)));
    for bits in [MortonBits::Bits30, MortonBits::Bits63] {
        let (merges, _) = Bvh::build_lbvh_with(&boxes, bits, Hierarchy::Merges);
        let (searches, _) = Bvh::build_lbvh_with(&boxes, bits, Hierarchy::Searches);
        assert!(merges == searches, "{bits:?}: the merges and the searches differ");
        assert_eq!(merges.validate(&boxes), Ok(()));
    }
}

/// A builder kept from frame to frame must forget the last frame: each build equals a fresh one,
/// whether the scene grows, shrinks or empties.
#[test]
fn a_reused_builder_equals_a_fresh_one() {
    let mut rng = SplitMix64::new(11);
    let mut builder = LbvhBuilder::<u64>::new();
    for n in [3000, 17, 1, 0, 2, 5000, 640] {
        let boxes: Vec<Aabb> = (0..n)
            .map(|_| Aabb::around_sphere(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()), 0.02))
            .collect();
        builder.build(&boxes, MortonBits::Bits30);
        let (fresh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
        assert_eq!(builder.to_bvh(), fresh, "{n} boxes after a build of another size");
        assert_eq!(fresh.validate(&boxes), Ok(()));
    }
}

/// A key too narrow for the codes is refused, not a wrong tree: 63-bit codes need a u128 key.
#[test]
#[should_panic(expected = "63-bit Morton codes do not fit a key of 32 code bits")]
fn a_u64_key_refuses_63_bit_codes() {
    let boxes = [Aabb::around_sphere(Vec3::ZERO, 1.0), Aabb::around_sphere(Vec3::X, 1.0)];
    LbvhBuilder::<u64>::new().build(&boxes, MortonBits::Bits63);
}

type Traversal = fn(&PackedBvh, &Primitives, &Ray, Hit, bool) -> Hit;

const TRAVERSALS: [(&str, Traversal); 4] = [
    ("stack", |t, p, ray, best, shadow| {
        traverse_stack(t.threaded_tree(), p, ray, best, shadow)
    }),
    ("stackless", |t, p, ray, best, shadow| {
        traverse_stackless(&t.nodes, p, ray, best, shadow)
    }),
    ("threaded", |t, p, ray, best, shadow| {
        traverse_threaded(t.threaded_tree(), p, ray, best, shadow)
    }),
    ("wide", |t, p, ray, best, shadow| {
        traverse_wide(t.wide_tree(), p, ray, best, shadow)
    }),
];

fn random_triangle(rng: &mut SplitMix64, material: u32) -> GpuTriangle {
    let mut point = |scale: f32| Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5) * scale;
    let v0 = point(4.0);
    let (e1, e2) = (point(0.4), point(0.4));
    GpuTriangle {
        v0: v0.to_array(),
        material,
        v1: (v0 + e1).to_array(),
        normals: u32::MAX,
        v2: (v0 + e2).to_array(),
        attributes: u32::MAX,
    }
}

/// Random rays from random points: every traversal finds exactly brute force's hit (t and
/// primitive) and the same shadow answer, among spheres and triangles, coincident ones included.
#[test]
fn traversals_equal_brute_force() {
    let mut rng = SplitMix64::new(99);
    let mut spheres: Vec<GpuSphere> = (0..3000)
        .map(|i| GpuSphere {
            center: [
                rng.next_f32() * 4.0 - 2.0,
                rng.next_f32() * 4.0 - 2.0,
                rng.next_f32() * 4.0 - 2.0,
            ],
            radius: 0.02 + 0.1 * rng.next_f32(),
            material: i % 7,
            _pad: [0; 3],
        })
        .collect();
    let mut triangles: Vec<GpuTriangle> = (0..2000).map(|i| random_triangle(&mut rng, i % 7)).collect();
    // Duplicates of a tenth of them, each with another material: ties must resolve by index.
    for i in 0..300 {
        let mut copy = spheres[i * 10];
        copy.material += 1;
        spheres.push(copy);
    }
    for i in 0..200 {
        let mut copy = triangles[i * 10];
        copy.material += 1;
        triangles.push(copy);
    }
    let primitives = Primitives {
        spheres: &spheres,
        triangles: &triangles,
        query: None,
    };
    let (bvh, _) = Bvh::build_lbvh(&primitive_boxes(&spheres, &triangles), MortonBits::Bits30);
    let trees = PackedBvh::new(bvh);
    let mut triangle_hits = 0;
    let mut hits = 0;
    for _ in 0..20_000 {
        let origin = Vec3::new(
            rng.next_f32() * 6.0 - 3.0,
            rng.next_f32() * 6.0 - 3.0,
            rng.next_f32() * 6.0 - 3.0,
        );
        let dir = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5).normalize();
        let ray = Ray::new(origin, dir);
        let brute = brute_closest(&primitives, &ray, Hit::none(1e30));
        hits += (brute.kind == HitKind::Primitive) as u32;
        triangle_hits += (brute.kind == HitKind::Primitive && brute.index as usize >= spheres.len()) as u32;
        for (name, traverse) in TRAVERSALS {
            assert_eq!(
                traverse(&trees, &primitives, &ray, Hit::none(1e30), false),
                brute,
                "{name}, ray {ray:?}"
            );
            for t_max in [0.5, 2.0] {
                let blocked = traverse(&trees, &primitives, &ray, Hit::none(t_max), true).kind != HitKind::None;
                assert_eq!(
                    blocked,
                    brute_occluded(&primitives, &ray, t_max),
                    "{name}, shadow ray {ray:?} to {t_max}"
                );
            }
        }
    }
    assert!(hits > 5000, "the test rays should hit often ({hits} hits)");
    assert!(triangle_hits > 1000, "and hit triangles often ({triangle_hits} hits)");
}

/// Scenes that strain the threaded walk's 16-bit boxes: small spheres in a frame millions of times
/// their size (their boxes many times too big), and a small scene far from the origin (the ray's move into
/// the frame loses the most there). Every walk still finds brute force's hit.
#[test]
fn traversals_equal_brute_force_in_coarse_and_far_frames() {
    let mut rng = SplitMix64::new(5);
    let sphere = |center: Vec3, radius: f32| GpuSphere {
        center: center.to_array(),
        radius,
        material: 0,
        _pad: [0; 3],
    };
    let mut point = |scale: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale;
    // A cluster of small spheres in a unit cube, and a few spheres 1e5 away that stretch the frame:
    // a quantum is then several units, wider than the whole cluster.
    let mut coarse: Vec<GpuSphere> = (0..2000).map(|_| sphere(point(1.0), 0.02)).collect();
    coarse.extend((0..5).map(|_| sphere(point(1e5), 1.0)));
    let far: Vec<GpuSphere> = (0..2000).map(|_| sphere(Vec3::splat(3e5) + point(4.0), 0.05)).collect();
    for (name, spheres, centre, spread) in [
        ("coarse frame", coarse, Vec3::splat(0.5), 1.0),
        ("far frame", far, Vec3::splat(3e5 + 2.0), 4.0),
    ] {
        let boxes: Vec<Aabb> = spheres.iter().map(GpuSphere::bounds).collect();
        let trees = PackedBvh::new(Bvh::build_lbvh(&boxes, MortonBits::Bits30).0);
        assert_eq!(
            threaded::validate(&trees.frame, &trees.threaded_nodes, &boxes),
            Ok(()),
            "{name}"
        );
        let primitives = Primitives {
            spheres: &spheres,
            triangles: &[],
            query: None,
        };
        let mut hits = 0;
        for _ in 0..3000 {
            let origin = centre + (point(2.0) - Vec3::ONE) * spread;
            let dir = (point(2.0) - Vec3::ONE).normalize();
            let ray = Ray::new(origin, dir);
            let brute = brute_closest(&primitives, &ray, Hit::none(1e30));
            hits += (brute.kind == HitKind::Primitive) as u32;
            for (walk, traverse) in TRAVERSALS {
                assert_eq!(
                    traverse(&trees, &primitives, &ray, Hit::none(1e30), false),
                    brute,
                    "{name}, {walk}, ray {ray:?}"
                );
            }
        }
        assert!(hits > 300, "{name}: the test rays should hit often ({hits} hits)");
    }
}

#[test]
fn traversals_handle_one_and_two_spheres() {
    for n in [1usize, 2] {
        let spheres: Vec<GpuSphere> = (0..n)
            .map(|i| GpuSphere {
                center: [i as f32 * 3.0, 0.0, 0.0],
                radius: 1.0,
                material: 0,
                _pad: [0; 3],
            })
            .collect();
        let boxes: Vec<Aabb> = spheres.iter().map(GpuSphere::bounds).collect();
        let (bvh, _) = Bvh::build_lbvh(&boxes, MortonBits::Bits30);
        let trees = PackedBvh::new(bvh);
        let primitives = Primitives {
            spheres: &spheres,
            triangles: &[],
            query: None,
        };
        for x in [-3.0f32, 0.0, 0.5, 3.0, 6.0] {
            let ray = Ray::new(Vec3::new(x, 0.2, -5.0), Vec3::Z);
            let brute = brute_closest(&primitives, &ray, Hit::none(1e30));
            for (name, traverse) in TRAVERSALS {
                assert_eq!(
                    traverse(&trees, &primitives, &ray, Hit::none(1e30), false),
                    brute,
                    "{name}, {n} spheres, x {x}"
                );
            }
        }
    }
}
