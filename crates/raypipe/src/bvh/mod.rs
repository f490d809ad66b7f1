//! Bounding volume hierarchies: the linear BVH (Karras 2012) built in parallel, its GPU layout,
//! validation, SAH cost, and a binned-SAH reference builder to compare its quality with.

pub mod aabb;
pub mod key;
pub mod layout;
pub mod lbvh;
pub mod merge;
pub mod morton;
pub mod sah;
pub mod sort;
pub mod threaded;
pub mod validate;
pub mod wide;

use aabb::Aabb;
use layout::{GpuNode, NONE};
use morton::MortonBits;
pub use morton::centroid_codes;
use rayon::prelude::*;

/// A BVH over `primitive_count` primitives in the one node layout of [`layout`].
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    /// The nodes, root first.
    pub nodes: Vec<GpuNode>,
    /// Primitives the tree holds, one a leaf.
    pub primitive_count: usize,
}

/// Wall-clock time of each phase of a build, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildTimings {
    /// Computing the primitives' Morton codes.
    pub morton: f64,
    /// Sorting the codes.
    pub sort: f64,
    /// With bottom-up merges ([`lbvh::Hierarchy::Merges`], and always on the GPU), this holds the
    /// bounds and links too, which are written in the same pass; `bounds` and `links` are then zero.
    pub hierarchy: f64,
    /// Fitting the nodes' boxes.
    pub bounds: f64,
    /// Zero where the links are written with the bounds, as the CPU's climb after Karras's searches
    /// writes them; their time is then in `bounds`.
    pub links: f64,
    /// The tree laid out again as the stack and threaded walks read it (16-byte nodes in depth-first
    /// order, `gpu::builders::threaded_layout`), where a per-frame GPU rebuild does that; zero elsewhere.
    pub layout: f64,
    /// The tree collapsed into the wide walk's compressed 8-wide nodes (`bvh::wide`): on the GPU
    /// where a per-frame rebuild for the wide walk does it, on the CPU wherever the host packs a
    /// tree.
    pub collapse: f64,
}

impl BuildTimings {
    /// The whole build: every phase's milliseconds summed.
    pub fn total(&self) -> f64 {
        self.morton + self.sort + self.hierarchy + self.bounds + self.links + self.layout + self.collapse
    }
}

impl Bvh {
    /// The linear BVH of `boxes`, with the time of each phase. A per-frame rebuild should keep an
    /// [`lbvh::LbvhBuilder`] instead, whose buffers outlive each build.
    pub fn build_lbvh(boxes: &[Aabb], bits: MortonBits) -> (Bvh, BuildTimings) {
        Self::build_lbvh_with(boxes, bits, lbvh::Hierarchy::default())
    }

    /// [`Self::build_lbvh`], finding the hierarchy as `hierarchy` says.
    pub fn build_lbvh_with(boxes: &[Aabb], bits: MortonBits, hierarchy: lbvh::Hierarchy) -> (Bvh, BuildTimings) {
        match bits {
            MortonBits::Bits30 => lbvh::LbvhBuilder::<u64>::with_hierarchy(hierarchy).build_into(boxes, bits),
            MortonBits::Bits63 => lbvh::LbvhBuilder::<u128>::with_hierarchy(hierarchy).build_into(boxes, bits),
        }
    }

    /// The binned-SAH tree of `boxes` ([`sah::build_binned_sah`]) with its build time, all of it
    /// counted as the hierarchy's: the builder has none of the LBVH's other phases.
    pub fn build_binned_sah(boxes: &[Aabb]) -> (Bvh, BuildTimings) {
        let start = web_time::Instant::now();
        let bvh = sah::build_binned_sah(boxes);
        let timings = BuildTimings {
            hierarchy: start.elapsed().as_secs_f64() * 1e3,
            ..BuildTimings::default()
        };
        (bvh, timings)
    }

    /// The linear BVH of `boxes` whose Morton codes are given (so devices can be compared on
    /// identical input). `bits` says how many low bits of each code are used.
    pub fn build_from_codes(boxes: &[Aabb], codes: &[u64], bits: MortonBits) -> (Bvh, BuildTimings) {
        match bits {
            MortonBits::Bits30 => {
                let mut builder = lbvh::LbvhBuilder::<u64>::new();
                let timings = builder.build_with_codes(boxes, codes, bits);
                (builder.into_bvh(), timings)
            }
            MortonBits::Bits63 => {
                let mut builder = lbvh::LbvhBuilder::<u128>::new();
                let timings = builder.build_with_codes(boxes, codes, bits);
                (builder.into_bvh(), timings)
            }
        }
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

    /// The depth of the deepest leaf (the root is at depth 0).
    pub fn max_depth(&self) -> u32 {
        self.leaf_depths().into_iter().max().unwrap_or(0)
    }
}

pub(crate) fn node_box(node: &GpuNode) -> Aabb {
    Aabb::new(glam::Vec3::from_array(node.min), glam::Vec3::from_array(node.max))
}
