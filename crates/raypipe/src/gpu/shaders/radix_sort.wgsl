// The build's sort: a stable least-significant-digit radix sort of (Morton code, primitive) pairs
// by 8-bit digits, one pass per digit, after Onesweep (Adinets and Merrill 2022). One kernel counts
// every pass's digits at once; then each pass is one kernel over tiles of TILE pairs, in which a
// workgroup ranks its tile's pairs by digit, learns how many pairs of each digit the tiles before
// it hold by decoupled look-back, and scatters.
//
// The preamble (src/gpu/builders/lbvh/source.rs) chooses how a tile is ranked (`SortRanking`): in sort_pass, with
// subgroup ballots where the adapter has them, or with "lane groups" of 16 invocations that compare
// digits through workgroup memory; or in sort_pass_runs, where each invocation counts its own run
// (CPU adapters). Either way it defines SORT_GROUP (invocations per workgroup), SORT_ITEMS (pairs per
// invocation, TILE = SORT_GROUP * SORT_ITEMS), LANE_GROUPS (lane groups per workgroup, at most),
// the entry point's `SortInvocation`, its accessors `lane_index`, `lane_width`, `lane_group`, and
// `same_digit`, the lanes of the caller's lane group that hold a pair of the caller's digit.
//
// While the sort runs, `climb` holds its words (the merges use it afterwards): each pass's digit
// starts; each pass's tile ticket; then the look-back words of two passes, a pass's tile by tile.

// DIGIT_BITS and DIGITS (1 << DIGIT_BITS) come from the preamble (src/gpu/builders/lbvh/source.rs).

// A look-back word: a flag in the top two bits, a count of pairs below.
const NOT_READY: u32 = 0u;
const AGGREGATE: u32 = 0x40000000u; // the count of this tile alone
const INCLUSIVE: u32 = 0x80000000u; // the count of this tile and every tile before it
const COUNT_MASK: u32 = 0x3fffffffu;
// Reads of a word that is not ready before the workgroup counts that tile's digits itself. Waiting
// for ever would rely on the tile's workgroup running meanwhile, which not every adapter promises.
const SPINS: u32 = 1024u;

fn tile_count() -> u32 {
    return (params.count + TILE - 1u) / TILE;
}

fn digit_start_slot(sweep: u32, digit: u32) -> u32 {
    return sweep * DIGITS + digit;
}

fn ticket_slot(sweep: u32) -> u32 {
    return SORT_PASSES * DIGITS + sweep;
}

// Passes alternate between two sets of look-back words; a pass clears the other set for the next.
fn look_back_slot(sweep: u32, tile: u32, digit: u32) -> u32 {
    return SORT_PASSES * (DIGITS + 1u) + ((sweep & 1u) * tile_count() + tile) * DIGITS + digit;
}

fn digit_of(p: Pair, sweep: u32) -> u32 {
    let shift = sweep * DIGIT_BITS;
    return (code_word(p, shift >= 32u) >> (shift & 31u)) & (DIGITS - 1u);
}

// Every pass's digit counts over a sort_histogram block, added into the digit starts.
var<workgroup> pass_digit_counts: array<atomic<u32>, SORT_PASSES * DIGITS>;

// Count the digits of every pass, HISTOGRAM_ITEMS pairs per invocation.
@compute @workgroup_size(GROUP)
fn sort_histogram(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let block = flat_group(wid, groups);
    for (var s = lid; s < SORT_PASSES * DIGITS; s += GROUP) {
        atomicStore(&pass_digit_counts[s], 0u);
    }
    workgroupBarrier();
    for (var k = 0u; k < HISTOGRAM_ITEMS; k++) {
        let i = (block * HISTOGRAM_ITEMS + k) * GROUP + lid;
        if (i < params.count) {
            let p = pairs_in[i];
            for (var sweep = 0u; sweep < SORT_PASSES; sweep++) {
                atomicAdd(&pass_digit_counts[sweep * DIGITS + digit_of(p, sweep)], 1u);
            }
        }
    }
    workgroupBarrier();
    for (var s = lid; s < SORT_PASSES * DIGITS; s += GROUP) {
        let count = atomicLoad(&pass_digit_counts[s]);
        if (count != 0u) {
            atomicAdd(&climb[s], count);
        }
    }
}

// Turn every pass's digit counts into the digit starts: an exclusive scan per pass.
@compute @workgroup_size(GROUP)
fn sort_digit_starts(@builtin(local_invocation_index) lid: u32) {
    for (var sweep = 0u; sweep < SORT_PASSES; sweep++) {
        let count = atomicLoad(&climb[digit_start_slot(sweep, lid)]);
        shared_u32[lid] = count;
        scan_shared_inclusive(lid);
        atomicStore(&climb[digit_start_slot(sweep, lid)], shared_u32[lid] - count);
    }
}

// The tile this workgroup sorts: tiles are handed out in the order workgroups start, so every tile
// before this one has a workgroup that has started.
var<workgroup> tile_ticket: u32;
// Per lane group and digit: first the count of pairs so far, then where the group's pairs of that
// digit start among the tile's.
var<workgroup> lane_group_digits: array<u32, LANE_GROUPS * DIGITS>;
// Each pair's rank among the pairs of its digit in its lane group, by position in the tile
// (RANKED_PAIRS is TILE, or 1 where no ranks are kept).
var<workgroup> pair_ranks: array<u32, RANKED_PAIRS>;
// The tile's count of each digit.
var<workgroup> tile_digits: array<u32, DIGITS>;
// Per digit: during the look-back, the pairs of that digit in earlier tiles (with the flags below);
// then where the tile's pairs of that digit go.
var<workgroup> digit_base: array<u32, DIGITS>;
const DONE: u32 = 0x80000000u; // every earlier tile is counted
const STUCK: u32 = 0x40000000u; // the tile looked at was not ready
var<workgroup> look_back_flags: atomic<u32>;
var<workgroup> look_back_state: u32;
const ANY_PENDING: u32 = 1u;
const ANY_STUCK: u32 = 2u;
var<workgroup> stuck_tile_digits: array<atomic<u32>, DIGITS>;

// Mask of the lanes below `lane` in a ballot.
fn lanes_below(lane: u32) -> vec4<u32> {
    let first = vec4<u32>(0u, 32u, 64u, 96u);
    let partial = (vec4<u32>(1u) << (vec4<u32>(lane) - first)) - vec4<u32>(1u);
    return select(select(vec4<u32>(0u), partial, vec4<u32>(lane) > first), vec4<u32>(0xffffffffu),
                  vec4<u32>(lane) >= first + vec4<u32>(32u));
}

fn lane_count(mask: vec4<u32>) -> u32 {
    return dot(countOneBits(mask), vec4<u32>(1u));
}

fn lowest_lane(mask: vec4<u32>) -> u32 {
    let lowest = countTrailingZeros(mask) + vec4<u32>(0u, 32u, 64u, 96u);
    return select(select(select(lowest.w, lowest.z, mask.z != 0u), lowest.y, mask.y != 0u), lowest.x, mask.x != 0u);
}

// Counts of each digit in the tiles before `tile`, in digit_base: read from their look-back words,
// walking back tile by tile until every digit meets an inclusive count. Where a tile's word is not
// ready, the whole workgroup counts that tile's digits itself and walks on.
fn look_back(lid: u32, sweep: u32, tile: u32) {
    var look = tile;
    loop {
        look -= 1u;
        if (lid == 0u) {
            atomicStore(&look_back_flags, 0u);
        }
        workgroupBarrier();
        for (var d = lid; d < DIGITS; d += SORT_GROUP) {
            if ((digit_base[d] & DONE) != 0u) {
                continue;
            }
            var word = NOT_READY;
            for (var spin = 0u; spin < SPINS && word == NOT_READY; spin++) {
                word = atomicLoad(&climb[look_back_slot(sweep, look, d)]);
            }
            if (word == NOT_READY) {
                digit_base[d] |= STUCK;
                atomicOr(&look_back_flags, ANY_STUCK | ANY_PENDING);
            } else {
                digit_base[d] += word & COUNT_MASK;
                if ((word & INCLUSIVE) != 0u) {
                    digit_base[d] |= DONE;
                } else {
                    atomicOr(&look_back_flags, ANY_PENDING);
                }
            }
        }
        workgroupBarrier();
        if (lid == 0u) {
            look_back_state = atomicLoad(&look_back_flags);
        }
        let state = workgroupUniformLoad(&look_back_state);
        if ((state & ANY_STUCK) != 0u) {
            for (var d = lid; d < DIGITS; d += SORT_GROUP) {
                atomicStore(&stuck_tile_digits[d], 0u);
            }
            workgroupBarrier();
            for (var k = 0u; k < SORT_ITEMS; k++) {
                let i = look * TILE + k * SORT_GROUP + lid;
                if (i < params.count) {
                    atomicAdd(&stuck_tile_digits[digit_of(pairs_in[i], sweep)], 1u);
                }
            }
            workgroupBarrier();
            for (var d = lid; d < DIGITS; d += SORT_GROUP) {
                if ((digit_base[d] & STUCK) != 0u) {
                    digit_base[d] = (digit_base[d] & ~STUCK) + atomicLoad(&stuck_tile_digits[d]);
                }
            }
        }
        // Tile 0 has no tiles before it: whatever is not done there is complete.
        if ((state & ANY_PENDING) == 0u || look == 0u) {
            break;
        }
    }
}

// A pass's tile: lane group counts zeroed, the tile's ticket taken.
fn start_tile(lid: u32, sweep: u32) -> u32 {
    for (var s = lid; s < LANE_GROUPS * DIGITS; s += SORT_GROUP) {
        lane_group_digits[s] = 0u;
    }
    if (lid == 0u) {
        tile_ticket = atomicAdd(&climb[ticket_slot(sweep)], 1u);
    }
    return workgroupUniformLoad(&tile_ticket);
}

// From the lane groups' counts, where each group's pairs of each digit start in the tile, and where
// the tile's pairs of each digit go, after the look-back.
fn place_tile(lid: u32, sweep: u32, tile: u32) {
    for (var d = lid; d < DIGITS; d += SORT_GROUP) {
        var running = 0u;
        for (var g = 0u; g < LANE_GROUPS; g++) {
            let count = lane_group_digits[g * DIGITS + d];
            lane_group_digits[g * DIGITS + d] = running;
            running += count;
        }
        tile_digits[d] = running;
        atomicStore(&climb[look_back_slot(sweep, tile, d)], select(AGGREGATE, INCLUSIVE, tile == 0u) | running);
        digit_base[d] = 0u;
    }
    if (tile > 0u) {
        look_back(lid, sweep, tile);
    }
    for (var d = lid; d < DIGITS; d += SORT_GROUP) {
        let before = digit_base[d] & COUNT_MASK;
        if (tile > 0u) {
            atomicStore(&climb[look_back_slot(sweep, tile, d)], INCLUSIVE | (before + tile_digits[d]));
        }
        digit_base[d] = atomicLoad(&climb[digit_start_slot(sweep, d)]) + before;
        // The previous pass's words of this tile, cleared for the next pass.
        atomicStore(&climb[look_back_slot(sweep + 1u, tile, d)], NOT_READY);
    }
    workgroupBarrier();
}

// One pass of the sort (`sweep`, from params.shift), by its digit, from pairs_in to pairs_out: lane
// groups rank their pairs a lane group's width at a time.
@compute @workgroup_size(SORT_GROUP)
fn sort_pass(invocation: SortInvocation) {
    let lid = invocation.index;
    let sweep = params.shift / DIGIT_BITS;
    let tile = start_tile(lid, sweep);
    let lane = lane_index(invocation);
    let width = lane_width(invocation);
    let group = lane_group(invocation);
    // Each lane group ranks a run of width * SORT_ITEMS pairs, width at a time, in order.
    let run = group * width * SORT_ITEMS;
    for (var k = 0u; k < SORT_ITEMS; k++) {
        let slot = run + k * width + lane;
        let i = tile * TILE + slot;
        let valid = i < params.count;
        var d = 0u;
        if (valid) {
            d = digit_of(pairs_in[i], sweep);
        }
        let peers = same_digit(invocation, d, valid);
        var before = 0u;
        if (valid) {
            before = lane_group_digits[group * DIGITS + d];
        }
        workgroupBarrier();
        if (valid) {
            pair_ranks[slot] = before + lane_count(peers & lanes_below(lane));
            if (lane == lowest_lane(peers)) {
                lane_group_digits[group * DIGITS + d] = before + lane_count(peers);
            }
        }
        workgroupBarrier();
    }
    place_tile(lid, sweep, tile);
    for (var k = 0u; k < SORT_ITEMS; k++) {
        let slot = run + k * width + lane;
        let i = tile * TILE + slot;
        if (i < params.count) {
            let p = pairs_in[i];
            let d = digit_of(p, sweep);
            pairs_out[digit_base[d] + lane_group_digits[group * DIGITS + d] + pair_ranks[slot]] = p;
        }
    }
}

// The same pass where every invocation is a lane group of its own (CPU adapters, whose workgroups
// are a few SIMD lanes): each counts the digits of its run of SORT_ITEMS consecutive pairs, then
// counts them again as it scatters them. No ranks are kept and no ballots cast.
@compute @workgroup_size(SORT_GROUP)
fn sort_pass_runs(@builtin(local_invocation_index) lid: u32) {
    let sweep = params.shift / DIGIT_BITS;
    let tile = start_tile(lid, sweep);
    let first = tile * TILE + lid * SORT_ITEMS;
    let end = min(first + SORT_ITEMS, params.count);
    let row = lid * DIGITS;
    for (var i = first; i < end; i++) {
        lane_group_digits[row + digit_of(pairs_in[i], sweep)] += 1u;
    }
    workgroupBarrier();
    place_tile(lid, sweep, tile);
    for (var i = first; i < end; i++) {
        let p = pairs_in[i];
        let d = digit_of(p, sweep);
        pairs_out[digit_base[d] + lane_group_digits[row + d]] = p;
        lane_group_digits[row + d] += 1u;
    }
}
