//! Bounding volume hierarchies: the linear BVH (Karras 2012) built in parallel, its GPU layout,
//! validation, SAH cost, and a binned-SAH reference builder to compare its quality with.

pub mod aabb;
pub mod layout;
pub mod lbvh;
pub mod morton;
pub mod sah;
pub mod sort;
pub mod validate;

use aabb::Aabb;
use layout::{GpuNode, NONE};
use morton::MortonBits;
use rayon::prelude::*;
use std::time::Instant;

/// A BVH over `primitive_count` primitives in the one node layout of [`layout`].
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    pub nodes: Vec<GpuNode>,
    pub primitive_count: usize,
}

/// Wall-clock time of each phase of a build, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildTimings {
    pub morton: f64,
    pub sort: f64,
    pub hierarchy: f64,
    pub bounds: f64,
    pub links: f64,
}

impl BuildTimings {
    pub fn total(&self) -> f64 {
        self.morton + self.sort + self.hierarchy + self.bounds + self.links
    }
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// Morton codes of the boxes' centroids, quantized in the centroids' bounds.
pub fn centroid_codes(boxes: &[Aabb], bits: MortonBits) -> Vec<u64> {
    let centroids: Vec<glam::Vec3> = boxes.par_iter().with_min_len(4096).map(|b| b.centroid()).collect();
    let bounds = centroids
        .par_iter()
        .with_min_len(4096)
        .fold(|| Aabb::EMPTY, |b, &c| b.grow(c))
        .reduce(|| Aabb::EMPTY, Aabb::union);
    morton::morton_codes(&centroids, bounds, bits)
}

impl Bvh {
    /// The linear BVH of `boxes`, with the time of each phase.
    pub fn build_lbvh(boxes: &[Aabb], bits: MortonBits) -> (Bvh, BuildTimings) {
        let start = Instant::now();
        let codes = centroid_codes(boxes, bits);
        let morton = ms_since(start);
        let (bvh, mut timings) = Self::build_from_codes(boxes, &codes, bits);
        timings.morton = morton;
        (bvh, timings)
    }

    /// The linear BVH of `boxes` whose Morton codes are given (so devices can be compared on
    /// identical input). `bits` says how many low bits of each code are used.
    pub fn build_from_codes(boxes: &[Aabb], codes: &[u64], bits: MortonBits) -> (Bvh, BuildTimings) {
        assert_eq!(boxes.len(), codes.len());
        let n = boxes.len();
        let mut timings = BuildTimings::default();
        if n == 0 {
            return (
                Bvh {
                    nodes: Vec::new(),
                    primitive_count: 0,
                },
                timings,
            );
        }

        // Sort (code, primitive) pairs by code, stably, so equal codes keep primitive order.
        let start = Instant::now();
        let (sorted_codes, order): (Vec<u64>, Vec<u32>) = match bits {
            MortonBits::Bits30 => {
                // One u64 per pair: the code above the index; sorting the code bits alone keeps the
                // index order of equal codes.
                let mut packed: Vec<u64> = codes
                    .par_iter()
                    .with_min_len(4096)
                    .enumerate()
                    .map(|(i, &c)| (c << 32) | i as u64)
                    .collect();
                sort::radix_sort_by_key(&mut packed, 32, 30, |&p| p);
                packed
                    .par_iter()
                    .with_min_len(4096)
                    .map(|&p| (p >> 32, p as u32))
                    .unzip()
            }
            MortonBits::Bits63 => {
                let mut pairs: Vec<(u64, u32)> = codes.iter().enumerate().map(|(i, &c)| (c, i as u32)).collect();
                sort::radix_sort_by_key(&mut pairs, 0, 63, |&(c, _)| c);
                pairs.into_iter().unzip()
            }
        };
        timings.sort = ms_since(start);

        if n == 1 {
            let b = boxes[0];
            let nodes = vec![GpuNode {
                min: b.min.to_array(),
                left: 0,
                max: b.max.to_array(),
                right: layout::LEAF,
                parent: NONE,
                escape: NONE,
                _pad: [0; 2],
            }];
            return (
                Bvh {
                    nodes,
                    primitive_count: 1,
                },
                timings,
            );
        }

        let start = Instant::now();
        let hierarchy = lbvh::hierarchy(&sorted_codes);
        timings.hierarchy = ms_since(start);

        let start = Instant::now();
        let sorted_boxes: Vec<Aabb> = order
            .par_iter()
            .with_min_len(4096)
            .map(|&p| boxes[p as usize])
            .collect();
        let node_boxes = lbvh::bounds(&hierarchy, &sorted_boxes);
        timings.bounds = ms_since(start);

        let start = Instant::now();
        let escapes = lbvh::escapes(&hierarchy, n);
        let nodes = lbvh::assemble(&hierarchy, &node_boxes, &escapes, &order);
        timings.links = ms_since(start);
        (
            Bvh {
                nodes,
                primitive_count: n,
            },
            timings,
        )
    }

    pub fn root_bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, node_box)
    }

    /// Depth of every leaf (the root is at depth 0), by climbing parent links in parallel.
    pub fn leaf_depths(&self) -> Vec<u32> {
        self.nodes
            .par_iter()
            .with_min_len(4096)
            .filter(|node| node.is_leaf())
            .map(|leaf| {
                let mut depth = 0;
                let mut parent = leaf.parent;
                while parent != NONE {
                    depth += 1;
                    parent = self.nodes[parent as usize].parent;
                }
                depth
            })
            .collect()
    }

    pub fn max_depth(&self) -> u32 {
        self.leaf_depths().into_iter().max().unwrap_or(0)
    }
}

pub fn node_box(node: &GpuNode) -> Aabb {
    Aabb::new(glam::Vec3::from_array(node.min), glam::Vec3::from_array(node.max))
}
