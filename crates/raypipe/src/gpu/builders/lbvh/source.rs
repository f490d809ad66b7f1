//! What the LBVH kernels are compiled with: their sizes, the variant an adapter gets (how a sort
//! tile is ranked, how a merge finds its sibling's box), the preamble that carries both and the
//! key width, and the parameters record the kernels read.

use crate::bvh::morton::MortonBits;
use crate::gpu::GpuContext;
use crate::gpu::preamble::records_source;

const LBVH: &str = include_str!("../../shaders/lbvh.wgsl");
const RADIX_SORT: &str = include_str!("../../shaders/radix_sort.wgsl");

/// Invocations per workgroup.
pub const GROUP: u32 = 256;
/// Items per block of the reduction kernels: `BLOCK / GROUP` per invocation. Fewer, longer blocks
/// spare CPU adapters barriers: on lavapipe the morton phase of 1M took 35 to 44 ms with blocks of
/// 1,024, 21 to 24 ms with 8,192.
pub(super) const BLOCK: u32 = 8192;
/// Where `scratch` holds the centroid bounds (6 words), and where the per-block words start.
const SCRATCH_BOUNDS: u32 = 0;
pub(super) const SCRATCH_BLOCKS: u32 = 8;
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
pub(super) const HISTOGRAM_ITEMS: u32 = 16;
/// Lane groups per sort workgroup, at most: their digit counts fill 8 KiB of workgroup memory.
const LANE_GROUPS: u32 = 8;
/// The lane group of the path without subgroups.
const SHARED_LANE_WIDTH: u32 = 16;

/// Passes of the radix sort over codes of each width: even numbers, so that the sorted pairs end
/// where they started, in pairs A.
pub(super) const fn sort_passes(bits: MortonBits) -> u32 {
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

    pub(super) fn entry_point(self) -> &'static str {
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
    pub(super) fn words_per_split(self) -> u64 {
        match self {
            SiblingBoxes::Atomics => 13,
            SiblingBoxes::Nodes => 1,
        }
    }
}

/// What the build's kernels do where adapters differ: how the sort ranks and how the merges meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildVariant {
    /// How the radix sort ranks keys within a workgroup.
    pub ranking: SortRanking,
    /// How the bottom-up merges read a sibling's box.
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
    pub(super) fn merge_run(self) -> u32 {
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
        "// Generated: the build's sizes (src/gpu/builders/lbvh/source.rs) and {}-bit Morton codes.
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
pub(super) fn pair_bytes(bits: MortonBits) -> u64 {
    match bits {
        MortonBits::Bits30 => 8,
        MortonBits::Bits63 => 16,
    }
}

/// Words of `scratch` per block: its centroid bounds.
pub(super) const SCRATCH_WORDS_PER_BLOCK: u64 = 6;

/// Words of `climb` the sort uses (radix_sort.wgsl): every pass's digit starts and tile ticket, and
/// two passes' look-back words.
pub(super) fn sort_words(bits: MortonBits, ranking: SortRanking, count: u64) -> u64 {
    let passes = sort_passes(bits) as u64;
    passes * (DIGITS + 1) + 2 * count.div_ceil(ranking.tile() as u64) * DIGITS
}
/// Uniform offsets must be multiples of 256 bytes.
pub(super) const PARAMS_STRIDE: u64 = 256;
pub(super) const PHASES: usize = 3;

/// The kernels' parameters (`BuildParams` in types.wgsl), one per sort pass at `PARAMS_STRIDE`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BuildParams {
    /// Primitives: spheres, then triangles.
    pub count: u32,
    /// The lowest key bit of the digit a sort pass orders by.
    pub shift: u32,
    /// Spheres: primitives below this are spheres, the rest triangles.
    pub sphere_count: u32,
}

/// The build's records with a WGSL twin, for the layout test.
#[cfg(feature = "internals")]
pub const LAYOUTS: &[crate::records::layouts::StructLayout] = &[crate::records::layouts::struct_layout!(
    BuildParams,
    "BuildParams",
    [count, shift, sphere_count]
)];
