//! The LBVH build on the GPU: `shaders/lbvh.wgsl`'s and `shaders/radix_sort.wgsl`'s kernels in
//! three compute passes (morton, sort, hierarchy: bottom-up merges that write the bounds and links
//! too, as on the CPU), each timed with timestamp queries where the adapter has them. The node array
//! stays on the GPU, ready for the fragment shader; `read_nodes` fetches it for tests and stats.
//!
//! Morton codes are 30-bit or 63-bit, as on the CPU; the width picks the key type the kernels are
//! compiled with.

use super::shared::SharedBuffers;
use crate::bvh::BuildTimings;
use crate::bvh::layout::GpuNode;
use crate::bvh::morton::MortonBits;
use crate::gpu::Capacity;
use crate::gpu::device::compute::{buffer_entry, grid, kernels, storage_buffer};
use crate::gpu::device::readback::read_buffer;
use crate::gpu::device::timing::PassTimestamps;
use crate::gpu::preamble::records_source;
use crate::gpu::{GpuContext, GpuError};
use crate::modes::MemoryMode;
use crate::records::{GpuSphere, GpuTriangle, PackedScene, StructLayout};
use crate::struct_layout;
use std::num::NonZeroU64;

const LBVH: &str = include_str!("../shaders/lbvh.wgsl");
const RADIX_SORT: &str = include_str!("../shaders/radix_sort.wgsl");

/// Invocations per workgroup.
pub const GROUP: u32 = 256;
/// Items per block of the reduction kernels: `BLOCK / GROUP` per invocation. Fewer, longer blocks
/// spare CPU adapters barriers: on lavapipe the morton phase of 1M took 35 to 44 ms with blocks of
/// 1,024, 21 to 24 ms with 8,192.
const BLOCK: u32 = 8192;
/// Where `scratch` holds the centroid bounds (6 words), and where the per-block words start.
const SCRATCH_BOUNDS: u32 = 0;
const SCRATCH_BLOCKS: u32 = 8;
const _: () = assert!(SCRATCH_BOUNDS + 6 <= SCRATCH_BLOCKS);

/// Where a build's Morton codes come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Codes {
    /// Computed by the build from the primitives' centroids (its first kernel).
    Computed,
    /// Written by the caller with `GpuLbvhBuilder::write_codes` (the first kernel is skipped).
    Given,
}

/// The radix sort's digit, in bits (radix_sort.wgsl's, from the preamble).
pub const DIGIT_BITS: u32 = 8;
const DIGITS: u64 = 1 << DIGIT_BITS;
/// Pairs per invocation of the kernel that counts every pass's digits.
const HISTOGRAM_ITEMS: u32 = 16;
/// Lane groups per sort workgroup, at most: their digit counts fill 8 KiB of workgroup memory.
const LANE_GROUPS: u32 = 8;
/// The lane group of the path without subgroups.
const SHARED_LANE_WIDTH: u32 = 16;

/// Passes of the radix sort over codes of each width: even numbers, so that the sorted pairs end
/// where they started, in pairs A.
const fn sort_passes(bits: MortonBits) -> u32 {
    bits.total_bits().div_ceil(DIGIT_BITS)
}
const _: () = assert!(sort_passes(MortonBits::Bits30).is_multiple_of(2));
const _: () = assert!(sort_passes(MortonBits::Bits63).is_multiple_of(2));

/// How a sort workgroup ranks its tile's pairs by digit (radix_sort.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SortRanking {
    /// Lane groups are subgroups, which find the lanes of a digit by ballots.
    Subgroups {
        /// Invocations per workgroup: whole subgroups of any size the adapter may pick.
        group: u32,
    },
    /// Lane groups of 16 invocations, which compare their digits through workgroup memory.
    Shared,
    /// Every invocation counts the digits of its own run of pairs, as a CPU sort does: for CPU
    /// adapters, whose workgroups are a few SIMD lanes and whose ballots and barriers are loops.
    /// The merges then also give each invocation a run of leaves (`BuildVariant::merge_run`).
    Runs {
        /// Invocations per workgroup, each with its own digit counts.
        group: u32,
    },
}

impl SortRanking {
    /// Runs on a CPU adapter; subgroups where the device has them and a workgroup of whole
    /// subgroups fits the lane groups' memory; the shared path otherwise.
    pub fn best(ctx: &GpuContext) -> Self {
        if ctx.info.device_type == wgpu::DeviceType::Cpu {
            Self::runs(ctx)
        } else {
            Self::subgroups(ctx).unwrap_or(SortRanking::Shared)
        }
    }

    /// Every ranking the device can run, the best first.
    pub fn all(ctx: &GpuContext) -> Vec<Self> {
        let mut all = vec![Self::best(ctx)];
        for ranking in [Some(Self::runs(ctx)), Some(SortRanking::Shared), Self::subgroups(ctx)] {
            match ranking {
                Some(ranking) if !all.contains(&ranking) => all.push(ranking),
                _ => {}
            }
        }
        all
    }

    /// Runs of one SIMD vector's width: a subgroup where the device says, else 8 (AVX2's 32-bit lanes),
    /// as many as the workgroup memory holds digit counts for (1 KiB each, beside 4 KiB of the
    /// tile's own).
    fn runs(ctx: &GpuContext) -> Self {
        let room = (ctx.limits().max_compute_workgroup_storage_size.saturating_sub(4096) / 1024).max(1);
        let group = ctx.subgroups.map_or(8, |(_, max)| max).clamp(1, room);
        SortRanking::Runs { group }
    }

    fn subgroups(ctx: &GpuContext) -> Option<Self> {
        let (min, max) = ctx.subgroups?;
        let group = (LANE_GROUPS * min).min(256);
        (min >= 4 && max <= 128 && group >= max && group.is_multiple_of(max) && LANE_TILE.is_multiple_of(group))
            .then_some(SortRanking::Subgroups { group })
    }

    /// Invocations per sort workgroup.
    fn group(self) -> u32 {
        match self {
            SortRanking::Subgroups { group } | SortRanking::Runs { group } => group,
            SortRanking::Shared => 128,
        }
    }

    /// Pairs a sort workgroup ranks and scatters at once. Runs keep no ranks, so their tiles may be
    /// larger, which makes fewer tiles to look back over.
    pub fn tile(self) -> u32 {
        match self {
            SortRanking::Subgroups { .. } | SortRanking::Shared => LANE_TILE,
            SortRanking::Runs { .. } => RUNS_TILE,
        }
    }

    fn entry_point(self) -> &'static str {
        match self {
            SortRanking::Subgroups { .. } | SortRanking::Shared => "sort_pass",
            SortRanking::Runs { .. } => "sort_pass_runs",
        }
    }

    /// The WGSL that radix_sort.wgsl asks the preamble for.
    fn source(self) -> String {
        let (group, tile) = (self.group(), self.tile());
        let (lane_groups, ranked_pairs) = match self {
            SortRanking::Runs { group } => (group, 1),
            _ => (LANE_GROUPS, tile),
        };
        let common = format!(
            "const SORT_GROUP: u32 = {group}u;
const SORT_ITEMS: u32 = {}u;
const TILE: u32 = {tile}u;
const LANE_GROUPS: u32 = {lane_groups}u;
const RANKED_PAIRS: u32 = {ranked_pairs}u;
const HISTOGRAM_ITEMS: u32 = {HISTOGRAM_ITEMS}u;
",
            tile / group
        );
        let ranking = match self {
            SortRanking::Subgroups { .. } => {
                "// Lane groups are subgroups: a digit's lanes found by one ballot per digit bit.
struct SortInvocation {
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) width: u32,
    @builtin(subgroup_id) group: u32,
}
fn lane_index(v: SortInvocation) -> u32 { return v.lane; }
fn lane_width(v: SortInvocation) -> u32 { return v.width; }
fn lane_group(v: SortInvocation) -> u32 { return v.group; }
fn same_digit(v: SortInvocation, digit: u32, valid: bool) -> vec4<u32> {
    var peers = subgroupBallot(valid);
    for (var b = 0u; b < DIGIT_BITS; b++) {
        let bit_set = ((digit >> b) & 1u) != 0u;
        let votes = subgroupBallot(bit_set);
        peers &= select(~votes, votes, bit_set);
    }
    return peers;
}
"
                .to_string()
            }
            SortRanking::Shared | SortRanking::Runs { .. } => {
                let width = if matches!(self, SortRanking::Shared) {
                    SHARED_LANE_WIDTH
                } else {
                    1
                };
                format!(
                    "// Lane groups of {width} invocations: each lane compares its digit with its group's
// through workgroup memory. (Runs use sort_pass_runs, not these.)
const LANE_WIDTH: u32 = {width}u;
struct SortInvocation {{
    @builtin(local_invocation_index) index: u32,
}}
fn lane_index(v: SortInvocation) -> u32 {{ return v.index % LANE_WIDTH; }}
fn lane_width(v: SortInvocation) -> u32 {{ return LANE_WIDTH; }}
fn lane_group(v: SortInvocation) -> u32 {{ return v.index / LANE_WIDTH; }}
var<workgroup> lane_digits: array<u32, SORT_GROUP>;
fn same_digit(v: SortInvocation, digit: u32, valid: bool) -> vec4<u32> {{
    lane_digits[v.index] = select(DIGITS, digit, valid);
    workgroupBarrier();
    let first = v.index - lane_index(v);
    var peers = 0u;
    for (var l = 0u; l < LANE_WIDTH; l++) {{
        peers |= select(0u, 1u << l, lane_digits[first + l] == digit);
    }}
    workgroupBarrier();
    return vec4<u32>(select(0u, peers, valid), 0u, 0u, 0u);
}}
"
                )
            }
        };
        common + &ranking
    }
}
const _: () = assert!(SHARED_LANE_WIDTH * LANE_GROUPS >= 128);

/// How the merges pass a finished subtree's box to its sibling (lbvh.wgsl's `merge`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SiblingBoxes {
    /// Both children store their box in atomic words at the split before they meet there, and the
    /// second to arrive reads its sibling's, waiting for each word to show: WGSL's atomics are
    /// relaxed, so the exchange orders nothing else, and only atomic words may be shared between
    /// workgroups without a race.
    Atomics,
    /// The second to arrive reads its sibling's box from the sibling's node. Only where every atomic
    /// orders the plain accesses around it: Mesa's llvmpipe makes each a sequentially consistent
    /// host atomic, so the node's stores come before the first arrival's exchange and the second
    /// arrival's loads after its own. Atomics are per-lane loops there: this spares 12 a merge.
    Nodes,
}

impl SiblingBoxes {
    /// Nodes on llvmpipe (lavapipe and its GL twin), atomics elsewhere.
    pub fn best(ctx: &GpuContext) -> Self {
        if ctx.info.device_type == wgpu::DeviceType::Cpu && ctx.info.name.starts_with("llvmpipe") {
            SiblingBoxes::Nodes
        } else {
            SiblingBoxes::Atomics
        }
    }

    /// Words of `climb` per split: the far end of the first child to arrive, and with atomics the
    /// two children's boxes.
    fn words_per_split(self) -> u64 {
        match self {
            SiblingBoxes::Atomics => 13,
            SiblingBoxes::Nodes => 1,
        }
    }
}

/// What the build's kernels do where adapters differ: how the sort ranks and how the merges meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildVariant {
    pub ranking: SortRanking,
    pub sibling_boxes: SiblingBoxes,
}

impl BuildVariant {
    /// The fastest kernels the adapter runs correctly.
    pub fn best(ctx: &GpuContext) -> Self {
        BuildVariant {
            ranking: SortRanking::best(ctx),
            sibling_boxes: SiblingBoxes::best(ctx),
        }
    }

    /// The best kernels, then each other choice the adapter runs, one at a time with the best of the
    /// rest: atomic sibling boxes run everywhere.
    pub fn variants(ctx: &GpuContext) -> Vec<Self> {
        let best = Self::best(ctx);
        let rankings = SortRanking::all(ctx)
            .into_iter()
            .skip(1)
            .map(|ranking| BuildVariant { ranking, ..best });
        let boxes = (best.sibling_boxes != SiblingBoxes::Atomics).then_some(BuildVariant {
            sibling_boxes: SiblingBoxes::Atomics,
            ..best
        });
        std::iter::once(best).chain(rankings).chain(boxes).collect()
    }

    /// In words, for reports: "sort by runs (8 invocations), sibling boxes through the nodes".
    pub fn describe(self) -> String {
        let ranking = match self.ranking {
            SortRanking::Subgroups { group } => format!("subgroup ballots ({group} invocations)"),
            SortRanking::Shared => "lane groups in workgroup memory".to_string(),
            SortRanking::Runs { group } => format!("runs ({group} invocations)"),
        };
        let boxes = match self.sibling_boxes {
            SiblingBoxes::Atomics => "in atomic words",
            SiblingBoxes::Nodes => "through the nodes",
        };
        format!("sort by {ranking}, sibling boxes {boxes}")
    }

    /// Leaves an invocation of the merges takes in turn: runs of them on CPU adapters (those whose
    /// sort ranks by runs), one elsewhere.
    fn merge_run(self) -> u32 {
        match self.ranking {
            SortRanking::Runs { .. } => MERGE_RUN,
            SortRanking::Subgroups { .. } | SortRanking::Shared => 1,
        }
    }
}

/// Leaves per invocation of the merges on CPU adapters.
const MERGE_RUN: u32 = 32;
/// The tile of lane groups, whose ranks fill 4 KiB of workgroup memory.
const LANE_TILE: u32 = 1024;
/// The tile of [`SortRanking::Runs`]: on lavapipe, the sort of 1M pairs took 86 to 92 ms with tiles
/// of 1,024, 50 to 58 with 4,096 and 49 to 52 with 8,192.
const RUNS_TILE: u32 = 8192;

/// What lbvh.wgsl needs to know of the code width: the grid, and the (code, primitive) pair.
fn key_preamble(bits: MortonBits) -> String {
    let pair = match bits {
        MortonBits::Bits30 => {
            "// A 30-bit code and its primitive.
alias Pair = vec2<u32>;
fn pair(code: vec2<u32>, primitive: u32) -> Pair { return Pair(code.x, primitive); }
fn pair_primitive(p: Pair) -> u32 { return p.y; }
fn code_word(p: Pair, high: bool) -> u32 { return select(p.x, 0u, high); }"
        }
        MortonBits::Bits63 => {
            "// A 63-bit code (low word, high word) and its primitive; w is unused.
alias Pair = vec4<u32>;
fn pair(code: vec2<u32>, primitive: u32) -> Pair { return Pair(code, primitive, 0u); }
fn pair_primitive(p: Pair) -> u32 { return p.z; }
fn code_word(p: Pair, high: bool) -> u32 { return select(p.x, p.y, high); }"
        }
    };
    format!(
        "// Generated: the build's sizes (src/gpu/builders/lbvh.rs) and {}-bit Morton codes.
const GROUP: u32 = {GROUP}u;
const DIGIT_BITS: u32 = {DIGIT_BITS}u;
const DIGITS: u32 = {DIGITS}u;
const BLOCK: u32 = {BLOCK}u;
const ITEMS: u32 = {}u;
const SCRATCH_BOUNDS: u32 = {SCRATCH_BOUNDS}u;
const SCRATCH_BLOCKS: u32 = {SCRATCH_BLOCKS}u;
const CELLS: u32 = {}u;
const SORT_PASSES: u32 = {}u;
{pair}
",
        bits.total_bits(),
        BLOCK / GROUP,
        1u32 << bits.bits_per_axis(),
        sort_passes(bits),
    )
}

/// The build kernels' WGSL for codes of `bits`, in `variant`.
pub fn shader_source(bits: MortonBits, variant: BuildVariant) -> String {
    format!(
        "{}\n{}\nconst MERGE_RUN: u32 = {}u;\nconst SIBLING_BOXES_IN_NODES: bool = {};\n{}\n{LBVH}\n{RADIX_SORT}",
        key_preamble(bits),
        variant.ranking.source(),
        variant.merge_run(),
        variant.sibling_boxes == SiblingBoxes::Nodes,
        records_source(),
    )
}

/// Bytes of one (code, primitive) pair.
fn pair_bytes(bits: MortonBits) -> u64 {
    match bits {
        MortonBits::Bits30 => 8,
        MortonBits::Bits63 => 16,
    }
}

/// Words of `scratch` per block: its centroid bounds.
const SCRATCH_WORDS_PER_BLOCK: u64 = 6;

/// Words of `climb` the sort uses (radix_sort.wgsl): every pass's digit starts and tile ticket, and
/// two passes' look-back words.
fn sort_words(bits: MortonBits, ranking: SortRanking, count: u64) -> u64 {
    let passes = sort_passes(bits) as u64;
    passes * (DIGITS + 1) + 2 * count.div_ceil(ranking.tile() as u64) * DIGITS
}
/// Uniform offsets must be multiples of 256 bytes.
const PARAMS_STRIDE: u64 = 256;
const PHASES: usize = 3;

/// The kernels' parameters (`BuildParams` in types.wgsl), one per sort pass at `PARAMS_STRIDE`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BuildParams {
    /// Primitives: spheres, then triangles.
    pub count: u32,
    /// The lowest key bit of the digit a sort pass orders by.
    pub shift: u32,
    pub sphere_count: u32,
}

/// The build's records with a WGSL twin, for the layout test.
pub const LAYOUTS: &[StructLayout] = &[struct_layout!(BuildParams, "BuildParams", [count, shift, sphere_count])];

struct Kernels {
    bounds_partial: wgpu::ComputePipeline,
    bounds_final: wgpu::ComputePipeline,
    morton: wgpu::ComputePipeline,
    sort_histogram: wgpu::ComputePipeline,
    sort_digit_starts: wgpu::ComputePipeline,
    sort_pass: wgpu::ComputePipeline,
    split_prefixes: wgpu::ComputePipeline,
    merge: wgpu::ComputePipeline,
    refit: wgpu::ComputePipeline,
}

/// A GPU LBVH builder: kernels compiled once, buffers kept from build to build while the
/// primitive count stays the same.
pub struct GpuLbvhBuilder {
    ctx: GpuContext,
    bits: MortonBits,
    variant: BuildVariant,
    kernels: Kernels,
    layout: wgpu::BindGroupLayout,
    buffers: Buffers,
    timer: Option<PassTimestamps>,
    refit_timer: Option<PassTimestamps>,
}

/// The buffers of a build over `count` primitives.
pub struct Buffers {
    sphere_count: u32,
    triangle_count: u32,
    /// [pairs A in, B out], [B in, A out].
    bind_groups: [wgpu::BindGroup; 2],
    /// The spheres the build reads; write new positions here before each build.
    pub spheres: wgpu::Buffer,
    /// The triangles the build reads (primitives `sphere_count..`).
    pub triangles: wgpu::Buffer,
    pairs: wgpu::Buffer,
    climb: wgpu::Buffer,
    /// The built nodes (STORAGE | COPY_SRC), the layout of `bvh::layout`.
    pub nodes: wgpu::Buffer,
}

impl GpuLbvhBuilder {
    /// Compiles the kernels for Morton codes of `bits` and sizes the buffers for `spheres` spheres and
    /// `triangles` triangles.
    pub async fn new(ctx: &GpuContext, bits: MortonBits, spheres: usize, triangles: usize) -> Result<Self, GpuError> {
        Self::with_variant(ctx, bits, spheres, triangles, BuildVariant::best(ctx)).await
    }

    /// Like [`GpuLbvhBuilder::new`], with the kernels' variant chosen.
    pub async fn with_variant(
        ctx: &GpuContext,
        bits: MortonBits,
        spheres: usize,
        triangles: usize,
        variant: BuildVariant,
    ) -> Result<Self, GpuError> {
        ctx.checked("compiling the GPU LBVH build", || {
            let device = &ctx.device;
            let rw = wgpu::BufferBindingType::Storage { read_only: false };
            let read = wgpu::BufferBindingType::Storage { read_only: true };
            let mut entries = vec![
                buffer_entry(0, wgpu::BufferBindingType::Uniform, true),
                buffer_entry(1, read, false),
            ];
            entries.extend((2..=7).map(|b| buffer_entry(b, rw, false)));
            entries.push(buffer_entry(8, read, false));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("lbvh build"),
                entries: &entries,
            });
            let kernel = kernels(device, "lbvh", shader_source(bits, variant), &layout);
            let kernels = Kernels {
                bounds_partial: kernel("bounds_partial"),
                bounds_final: kernel("bounds_final"),
                morton: kernel("morton"),
                sort_histogram: kernel("sort_histogram"),
                sort_digit_starts: kernel("sort_digit_starts"),
                sort_pass: kernel(variant.ranking.entry_point()),
                split_prefixes: kernel("split_prefixes"),
                merge: kernel("merge"),
                refit: kernel("refit"),
            };
            let buffers = Buffers::new(ctx, &layout, bits, variant, spheres, triangles)?;
            Ok(Self {
                ctx: ctx.clone(),
                bits,
                variant,
                kernels,
                layout,
                buffers,
                timer: ctx
                    .timestamps
                    .then(|| PassTimestamps::new(&ctx.device, "build phases", PHASES as u32)),
                refit_timer: ctx.timestamps.then(|| PassTimestamps::new(&ctx.device, "refit", 1)),
            })
        })
        .await
    }

    /// The kernels' variant this builder runs.
    pub fn variant(&self) -> BuildVariant {
        self.variant
    }

    /// Sizes the buffers for `spheres` spheres and `triangles` triangles (a no-op when the counts are
    /// unchanged).
    pub async fn resize(&mut self, spheres: usize, triangles: usize) -> Result<(), GpuError> {
        if (spheres, triangles) != (self.buffers.sphere_count as usize, self.buffers.triangle_count as usize) {
            let ctx = &self.ctx;
            self.buffers = ctx
                .checked("sizing the GPU LBVH build", || {
                    Buffers::new(ctx, &self.layout, self.bits, self.variant, spheres, triangles)
                })
                .await?;
        }
        Ok(())
    }

    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    pub fn buffers(&self) -> &Buffers {
        &self.buffers
    }

    /// Primitives: spheres and triangles.
    pub fn count(&self) -> usize {
        self.buffers.count() as usize
    }

    pub fn write_spheres(&self, spheres: &[GpuSphere]) {
        assert_eq!(spheres.len(), self.buffers.sphere_count as usize);
        self.ctx
            .queue
            .write_buffer(&self.buffers.spheres, 0, bytemuck::cast_slice(spheres));
    }

    pub fn write_triangles(&self, triangles: &[GpuTriangle]) {
        assert_eq!(triangles.len(), self.buffers.triangle_count as usize);
        self.ctx
            .queue
            .write_buffer(&self.buffers.triangles, 0, bytemuck::cast_slice(triangles));
    }

    /// Writes a scene's primitives, sized for them.
    pub async fn write_scene(&mut self, scene: &PackedScene) -> Result<(), GpuError> {
        self.resize(scene.spheres.len(), scene.triangles.len()).await?;
        self.write_spheres(&scene.spheres);
        self.write_triangles(&scene.triangles);
        Ok(())
    }

    /// The Morton code width the kernels were compiled for.
    pub fn bits(&self) -> MortonBits {
        self.bits
    }

    /// Replaces the Morton phase with given codes (of the builder's width), for comparisons with
    /// the CPU build.
    pub fn write_codes(&self, codes: &[u64]) {
        assert_eq!(codes.len(), self.count());
        // The words of each pair, as the preamble's `Pair` lays them out.
        let mut words = Vec::with_capacity(codes.len() * pair_bytes(self.bits) as usize / 4);
        for (i, &code) in codes.iter().enumerate() {
            match self.bits {
                MortonBits::Bits30 => words.extend([code as u32, i as u32]),
                MortonBits::Bits63 => words.extend([code as u32, (code >> 32) as u32, i as u32, 0]),
            }
        }
        self.ctx
            .queue
            .write_buffer(&self.buffers.pairs, 0, bytemuck::cast_slice(&words));
    }

    /// Records a build into `encoder`: from the spheres' codes computed here, or from the codes of
    /// `write_codes`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, codes: Codes) {
        let b = &self.buffers;
        let n = b.count();
        if n == 0 {
            return;
        }
        let sort_bytes = sort_words(self.bits, self.variant.ranking, n as u64) * 4;
        encoder.clear_buffer(&b.climb, 0, Some(sort_bytes));
        let blocks = n.div_ceil(BLOCK);
        let items = n.div_ceil(GROUP);
        let k = &self.kernels;
        let a = &b.bind_groups[0];
        let phase = |encoder: &mut wgpu::CommandEncoder,
                     index: usize,
                     steps: &[(&wgpu::ComputePipeline, &wgpu::BindGroup, u32, u32)]| {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(PHASE_NAMES[index]),
                timestamp_writes: self.timer.as_ref().map(|t| t.compute_writes(index as u32)),
            });
            // `pass_index` picks the sort pass's parameters (0 for the other kernels).
            for &(pipeline, bind_group, pass_index, groups) in steps {
                let (x, y) = grid(groups);
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind_group, &[pass_index * PARAMS_STRIDE as u32]);
                pass.dispatch_workgroups(x, y, 1);
            }
        };
        if codes == Codes::Given {
            phase(encoder, 0, &[]);
        } else {
            phase(
                encoder,
                0,
                &[
                    (&k.bounds_partial, a, 0, blocks),
                    (&k.bounds_final, a, 0, 1),
                    (&k.morton, a, 0, items),
                ],
            );
        }
        let mut sort = vec![
            (&k.sort_histogram, a, 0, n.div_ceil(GROUP * HISTOGRAM_ITEMS)),
            (&k.sort_digit_starts, a, 0, 1),
        ];
        for pass in 0..sort_passes(self.bits) {
            sort.push((
                &k.sort_pass,
                &b.bind_groups[pass as usize % 2],
                pass,
                n.div_ceil(self.variant.ranking.tile()),
            ));
        }
        phase(encoder, 1, &sort);
        // The sort's words in `climb` give way to the merges' exchange words (0: nobody arrived, no
        // box stored).
        if n > 1 {
            let words = self.variant.sibling_boxes.words_per_split() * (n as u64 - 1);
            encoder.clear_buffer(&b.climb, 0, Some(words * 4));
        }
        let invocations = n.div_ceil(self.variant.merge_run());
        phase(
            encoder,
            2,
            &[
                (&k.split_prefixes, a, 0, n.div_ceil(GROUP)),
                (&k.merge, a, 0, invocations.div_ceil(GROUP)),
            ],
        );
        if let Some(timer) = &self.timer {
            timer.resolve(encoder);
        }
    }

    /// Records a refit of the last tree built: its boxes recomputed bottom-up over the primitives as
    /// they are now, its topology and links kept. Cheaper than a build; the tree degrades as the
    /// primitives move away from where it was built.
    pub fn encode_refit(&self, encoder: &mut wgpu::CommandEncoder) {
        let n = self.buffers.count();
        if n == 0 {
            return;
        }
        if n > 1 {
            let words = self.variant.sibling_boxes.words_per_split() * (n as u64 - 1);
            encoder.clear_buffer(&self.buffers.climb, 0, Some(words * 4));
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("refit"),
            timestamp_writes: self.refit_timer.as_ref().map(|t| t.compute_writes(0)),
        });
        let (x, y) = grid(n.div_ceil(self.variant.merge_run()).div_ceil(GROUP));
        pass.set_pipeline(&self.kernels.refit);
        pass.set_bind_group(0, &self.buffers.bind_groups[0], &[0]);
        pass.dispatch_workgroups(x, y, 1);
        drop(pass);
        if let Some(timer) = &self.refit_timer {
            timer.resolve(encoder);
        }
    }

    /// GPU time of the last refit submitted and finished, where the adapter has timestamps.
    pub async fn read_refit_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.refit_timer {
            Some(timer) => Ok(Some(timer.read_ms(&self.ctx).await?[0])),
            None => Ok(None),
        }
    }

    /// Builds and waits; returns the GPU time of each phase (zeros where the adapter has no
    /// timestamp queries).
    pub async fn build(&self, codes: Codes) -> Result<BuildTimings, GpuError> {
        self.ctx
            .checked("building the LBVH on the GPU", || {
                let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
                self.encode(&mut encoder, codes);
                self.ctx.queue.submit([encoder.finish()]);
                Ok(())
            })
            .await?;
        // Without timestamps nothing below waits for the build.
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        self.read_timings().await
    }

    /// The GPU time of each phase of the last build that was submitted and finished (zeros where
    /// the adapter has no timestamp queries).
    pub async fn read_timings(&self) -> Result<BuildTimings, GpuError> {
        match &self.timer {
            Some(timer) if self.count() > 0 => {
                let ms = timer.read_ms(&self.ctx).await?;
                Ok(BuildTimings {
                    morton: ms[0],
                    sort: ms[1],
                    hierarchy: ms[2],
                    // The merges write the bounds and links with the hierarchy.
                    ..BuildTimings::default()
                })
            }
            _ => Ok(BuildTimings::default()),
        }
    }

    /// The primitives and nodes, for a renderer to read in place.
    pub fn shared_buffers(&self) -> SharedBuffers {
        SharedBuffers {
            spheres: self.buffers.spheres.clone(),
            triangles: self.buffers.triangles.clone(),
            nodes: self.buffers.nodes.clone(),
            threaded_nodes: None,
            wide: None,
            bvh_frame: None,
            triangle_normals: None,
        }
    }

    /// Copies the node array back to the host.
    pub async fn read_nodes(&self) -> Result<Vec<GpuNode>, GpuError> {
        let size = (2 * self.count() as u64).saturating_sub(1) * std::mem::size_of::<GpuNode>() as u64;
        if size == 0 {
            return Ok(Vec::new());
        }
        let bytes = read_buffer(&self.ctx.device, &self.ctx.queue, &self.buffers.nodes, size).await?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

impl Buffers {
    /// Primitives: spheres, then triangles.
    fn count(&self) -> u32 {
        self.sphere_count + self.triangle_count
    }

    fn new(
        ctx: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        bits: MortonBits,
        variant: BuildVariant,
        sphere_count: usize,
        triangle_count: usize,
    ) -> Result<Self, GpuError> {
        let count = sphere_count + triangle_count;
        let n = count as u64;
        let node_bytes = node_room(ctx, count)?;
        let device = &ctx.device;
        let blocks = n.div_ceil(BLOCK as u64);
        // A binding may not be empty: an absent kind of primitive gets room for one record.
        let record_room = |records: usize, size: usize| records.max(1) as u64 * size as u64;
        let spheres = storage_buffer(
            device,
            "build spheres",
            record_room(sphere_count, std::mem::size_of::<GpuSphere>()),
            wgpu::BufferUsages::COPY_DST,
        );
        // Ray queries build the driver's triangle structures from these records where they move
        // on the GPU (`super::rayquery`).
        let blas_input = if ctx.ray_queries {
            wgpu::BufferUsages::BLAS_INPUT
        } else {
            wgpu::BufferUsages::empty()
        };
        let triangles = storage_buffer(
            device,
            "build triangles",
            record_room(triangle_count, std::mem::size_of::<GpuTriangle>()),
            wgpu::BufferUsages::COPY_DST | blas_input,
        );
        let pairs = storage_buffer(device, "pairs A", n * pair_bytes(bits), wgpu::BufferUsages::COPY_DST);
        let pairs_b = storage_buffer(device, "pairs B", n * pair_bytes(bits), wgpu::BufferUsages::empty());
        let scratch = storage_buffer(
            device,
            "build scratch",
            (SCRATCH_BLOCKS as u64 + SCRATCH_WORDS_PER_BLOCK * blocks) * 4,
            wgpu::BufferUsages::empty(),
        );
        let splits = storage_buffer(
            device,
            "split prefixes",
            n.saturating_sub(1) * 4,
            wgpu::BufferUsages::empty(),
        );
        // Per split: the exchange word, and with atomic boxes the two children's.
        let climb_words =
            (variant.sibling_boxes.words_per_split() * n.saturating_sub(1)).max(sort_words(bits, variant.ranking, n));
        let climb = storage_buffer(device, "climb", climb_words * 4, wgpu::BufferUsages::COPY_DST);
        let nodes = storage_buffer(device, "nodes", node_bytes, wgpu::BufferUsages::COPY_SRC);
        let params = params_buffer(ctx, bits, count, sphere_count);
        let bind_group = |pairs_in: &wgpu::Buffer, pairs_out: &wgpu::Buffer| {
            let resources = [
                &spheres, pairs_in, pairs_out, &scratch, &splits, &climb, &nodes, &triangles,
            ];
            let mut entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &params,
                    offset: 0,
                    size: NonZeroU64::new(std::mem::size_of::<BuildParams>() as u64),
                }),
            }];
            entries.extend(resources.iter().enumerate().map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32 + 1,
                resource: b.as_entire_binding(),
            }));
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("lbvh build"),
                layout,
                entries: &entries,
            })
        };
        let bind_groups = [bind_group(&pairs, &pairs_b), bind_group(&pairs_b, &pairs)];
        Ok(Self {
            sphere_count: sphere_count as u32,
            triangle_count: triangle_count as u32,
            bind_groups,
            spheres,
            triangles,
            pairs,
            climb,
            nodes,
        })
    }
}

/// The bytes of the node array of `count` primitives, where a storage binding holds them.
fn node_room(ctx: &GpuContext, count: usize) -> Result<u64, GpuError> {
    let allowed = ctx.limits().max_storage_buffer_binding_size;
    let node_bytes = (2 * count as u64).saturating_sub(1) * std::mem::size_of::<GpuNode>() as u64;
    if node_bytes > allowed {
        return Err(GpuError::TooBig {
            memory: MemoryMode::Storage,
            array: "node",
            records: (2 * count).saturating_sub(1),
            needed: Capacity::Bytes(node_bytes),
            allowed: Capacity::Bytes(allowed),
        });
    }
    Ok(node_bytes)
}

/// The kernels' parameters, one [`BuildParams`] per sort pass at [`PARAMS_STRIDE`] (a dynamic
/// offset picks the pass's digit).
fn params_buffer(ctx: &GpuContext, bits: MortonBits, count: usize, sphere_count: usize) -> wgpu::Buffer {
    let params = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("build params"),
        size: PARAMS_STRIDE * sort_passes(bits) as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    for pass in 0..sort_passes(bits) {
        let p = BuildParams {
            count: count as u32,
            shift: pass * DIGIT_BITS,
            sphere_count: sphere_count as u32,
        };
        ctx.queue
            .write_buffer(&params, pass as u64 * PARAMS_STRIDE, bytemuck::bytes_of(&p));
    }
    params
}

/// A bound on the depth of any LBVH over `count` primitives with codes of `bits`: each level of the
/// radix tree consumes at least one bit of the (code, position) key, which has bits + ceil(log2 n)
/// bits. Renderers size their traversal stack with it when the tree is built on the GPU.
pub fn depth_bound(count: usize, bits: MortonBits) -> u32 {
    bits.total_bits() + (count.max(1) as u64).next_power_of_two().trailing_zeros()
}

const PHASE_NAMES: [&str; PHASES] = ["morton", "sort", "hierarchy"];
