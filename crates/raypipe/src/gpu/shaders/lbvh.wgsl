// The LBVH build in compute passes: the phases of src/bvh/lbvh.rs, giving the same node array for
// the same Morton codes. Every kernel runs 256 invocations per workgroup; large dispatches are 2D.
//
// src/gpu/builders/lbvh/source.rs prepends the build's sizes and what depends on the code width: CELLS (grid cells per axis), the `Pair`
// type that holds a code and its primitive, and its accessors `pair`, `pair_primitive` and
// `code_word` (the code's low or high 32 bits; 30-bit codes have no high word, it reads 0).

// From the preamble (src/gpu/builders/lbvh/source.rs): GROUP invocations per workgroup; BLOCK items per block in
// the reduction kernels, ITEMS per invocation, GROUP apart; MERGE_RUN leaves per invocation of the
// merges and SIBLING_BOXES_IN_NODES (`merge`). The sort is in radix_sort.wgsl.

// BuildParams is in types.wgsl, beside the other records with a host twin.

// Layout of `scratch`: centroid bounds; from SCRATCH_BLOCKS, per-block partial centroid bounds (6
// words each). SCRATCH_BOUNDS and SCRATCH_BLOCKS come from the preamble.

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
// (Morton code, primitive) pairs; sort passes read `pairs_in` and write `pairs_out`.
@group(0) @binding(2) var<storage, read_write> pairs_in: array<Pair>;
@group(0) @binding(3) var<storage, read_write> pairs_out: array<Pair>;
@group(0) @binding(4) var<storage, read_write> scratch: array<u32>;
// The prefix length of sorted positions i and i + 1 (split_prefixes).
@group(0) @binding(5) var<storage, read_write> splits: array<i32>;
// What the merges exchange at each split: the far end of the first child to arrive, then, unless
// SIBLING_BOXES_IN_NODES, 12 words per split, the boxes of its two children. (The sort keeps its
// words here before: radix_sort.wgsl.)
@group(0) @binding(6) var<storage, read_write> climb: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> nodes: array<BvhNode>;
// Primitive sphere_count + i is triangle i.
@group(0) @binding(8) var<storage, read> triangles: array<Triangle>;

var<workgroup> shared_u32: array<u32, GROUP>;
var<workgroup> shared_lo: array<vec3<f32>, GROUP>;
var<workgroup> shared_hi: array<vec3<f32>, GROUP>;

fn flat_group(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.y * groups.x + wid.x;
}

fn block_count() -> u32 {
    return (params.count + BLOCK - 1u) / BLOCK;
}

// Where block `block`'s centroid bounds wait for bounds_final.
fn partial_bounds(block: u32) -> u32 {
    return SCRATCH_BLOCKS + block * 6u;
}

struct Box {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

// Primitive i's bounding box: PackedScene::primitive_boxes, to the bit.
fn primitive_box(i: u32) -> Box {
    if (i < params.sphere_count) {
        let s = spheres[i];
        return Box(s.center - vec3<f32>(s.radius), s.center + vec3<f32>(s.radius));
    }
    let t = triangles[i - params.sphere_count];
    return Box(min(min(t.v0, t.v1), t.v2), max(max(t.v0, t.v1), t.v2));
}

// A box in `scratch`: 6 words from `base`, the low corner first.
fn scratch_box(base: u32) -> Box {
    let lo = vec3<u32>(scratch[base], scratch[base + 1u], scratch[base + 2u]);
    let hi = vec3<u32>(scratch[base + 3u], scratch[base + 4u], scratch[base + 5u]);
    return Box(bitcast<vec3<f32>>(lo), bitcast<vec3<f32>>(hi));
}

fn store_scratch_box(base: u32, b: Box) {
    for (var a = 0u; a < 3u; a++) {
        scratch[base + a] = bitcast<u32>(b.lo[a]);
        scratch[base + 3u + a] = bitcast<u32>(b.hi[a]);
    }
}

fn centroid(i: u32) -> vec3<f32> {
    let b = primitive_box(i);
    return (b.lo + b.hi) * 0.5;
}

// Min and max over the workgroup's shared_lo / shared_hi, left in slot 0.
fn reduce_bounds(lid: u32) {
    for (var stride = GROUP / 2u; stride > 0u; stride /= 2u) {
        workgroupBarrier();
        if (lid < stride) {
            shared_lo[lid] = min(shared_lo[lid], shared_lo[lid + stride]);
            shared_hi[lid] = max(shared_hi[lid], shared_hi[lid + stride]);
        }
    }
    workgroupBarrier();
}

const BIG: f32 = 3.0e38;

// Compute the bounds of primitive centroids: per block, then over the blocks.
@compute @workgroup_size(GROUP)
fn bounds_partial(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let block = flat_group(wid, groups);
    var lo = vec3<f32>(BIG);
    var hi = vec3<f32>(-BIG);
    for (var k = 0u; k < ITEMS; k++) {
        let i = block * BLOCK + k * GROUP + lid;
        if (i < params.count) {
            let c = centroid(i);
            lo = min(lo, c);
            hi = max(hi, c);
        }
    }
    shared_lo[lid] = lo;
    shared_hi[lid] = hi;
    reduce_bounds(lid);
    if (lid == 0u && block < block_count()) {
        store_scratch_box(partial_bounds(block), Box(shared_lo[0], shared_hi[0]));
    }
}

@compute @workgroup_size(GROUP)
fn bounds_final(@builtin(local_invocation_index) lid: u32) {
    var lo = vec3<f32>(BIG);
    var hi = vec3<f32>(-BIG);
    for (var block = lid; block < block_count(); block += GROUP) {
        let b = scratch_box(partial_bounds(block));
        lo = min(lo, b.lo);
        hi = max(hi, b.hi);
    }
    shared_lo[lid] = lo;
    shared_hi[lid] = hi;
    reduce_bounds(lid);
    if (lid == 0u) {
        store_scratch_box(SCRATCH_BOUNDS, Box(shared_lo[0], shared_hi[0]));
    }
}

fn spread_bits_10(v: u32) -> u32 {
    var x = v & 0x3ffu;
    x = (x | (x << 16u)) & 0x030000ffu;
    x = (x | (x << 8u)) & 0x0300f00fu;
    x = (x | (x << 4u)) & 0x030c30c3u;
    x = (x | (x << 2u)) & 0x09249249u;
    return x;
}

// The low 21 bits of v spread so that two zero bits separate each: (bits 0-31, bits 32-63) of
// bvh::morton::spread_bits_21. Below 1024 it is spread_bits_10 in the low word.
fn spread_bits_21(v: u32) -> vec2<u32> {
    return vec2<u32>(spread_bits_10(v) | (((v >> 10u) & 1u) << 30u), spread_bits_10(v >> 11u) << 1u);
}

// A 64-bit value as (low, high) words, shifted left by s in 1..31.
fn shift_left_64(v: vec2<u32>, s: u32) -> vec2<u32> {
    return vec2<u32>(v.x << s, (v.y << s) | (v.x >> (32u - s)));
}

// Compute Morton codes of primitive centroids: the expression of bvh::morton::Grid::code.
@compute @workgroup_size(GROUP)
fn morton(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
          @builtin(local_invocation_index) lid: u32) {
    let i = flat_group(wid, groups) * GROUP + lid;
    if (i >= params.count) {
        return;
    }
    let bounds = scratch_box(SCRATCH_BOUNDS);
    let lo = bounds.lo;
    let extent = bounds.hi - lo;
    let scale = select(vec3<f32>(0.0), vec3<f32>(f32(CELLS)) / extent, extent > vec3<f32>(0.0));
    let cell = min(max((centroid(i) - lo) * scale, vec3<f32>(0.0)), vec3<f32>(f32(CELLS - 1u)));
    let q = vec3<u32>(cell);
    let code = shift_left_64(spread_bits_21(q.x), 2u) | shift_left_64(spread_bits_21(q.y), 1u) | spread_bits_21(q.z);
    pairs_in[i] = pair(code, i);
}

// Inclusive scan of shared_u32 over the workgroup (Hillis-Steele), in place.
fn scan_shared_inclusive(lid: u32) {
    workgroupBarrier();
    for (var offset = 1u; offset < GROUP; offset *= 2u) {
        var add = 0u;
        if (lid >= offset) {
            add = shared_u32[lid - offset];
        }
        workgroupBarrier();
        shared_u32[lid] += add;
        workgroupBarrier();
    }
}

// Length of the common prefix of the keys (code as 64 bits, then sorted position as 32) at sorted
// positions i and i + 1: where each node of the tree splits (Karras 2012), and so which side each
// subtree's sibling lies on. The CPU's keys hold the same bits under another number of leading
// zeros: its lengths differ from these by a constant, and every comparison of two lengths comes out
// the same on both devices.
@compute @workgroup_size(GROUP)
fn split_prefixes(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let i = flat_group(wid, groups) * GROUP + lid;
    if (i + 1u >= params.count) {
        return;
    }
    let a = pairs_in[i];
    let b = pairs_in[i + 1u];
    let high = code_word(a, true) ^ code_word(b, true);
    let low = code_word(a, false) ^ code_word(b, false);
    if (high != 0u) {
        splits[i] = i32(countLeadingZeros(high));
    } else if (low != 0u) {
        splits[i] = 32 + i32(countLeadingZeros(low));
    } else {
        splits[i] = 64 + i32(countLeadingZeros(i ^ (i + 1u)));
    }
}

// splits[i], and -1 beyond either end of the keys.
fn split_prefix(i: i32) -> i32 {
    if (i < 0 || i + 1 >= i32(params.count)) {
        return -1;
    }
    return splits[i];
}

// Where the box of the child on one side of split s waits for its sibling: 6 atomic words, after
// the n - 1 words the children exchange their far ends through.
fn box_slot(split: u32, right: bool) -> u32 {
    return params.count - 1u + split * 12u + select(0u, 6u, right);
}

// A box word holds the coordinate's bits inverted, so that 0, as the words are cleared, means not
// yet stored: no coordinate of a finite box has all bits set (that is a NaN).
fn store_box(slot: u32, lo: vec3<f32>, hi: vec3<f32>) {
    for (var a = 0u; a < 3u; a++) {
        atomicStore(&climb[slot + a], ~bitcast<u32>(lo[a]));
        atomicStore(&climb[slot + 3u + a], ~bitcast<u32>(hi[a]));
    }
}

// Reads for each word until its store shows. WGSL's atomics are relaxed: the exchange that told the
// caller it arrived second says the sibling's stores ran, not that they are visible yet.
// (BOX_SPINS bounds the wait for a word that is never stored, a NaN's.)
const BOX_SPINS: u32 = 1048576u;
fn box_word(index: u32) -> f32 {
    var word = atomicLoad(&climb[index]);
    for (var spin = 0u; spin < BOX_SPINS && word == 0u; spin++) {
        word = atomicLoad(&climb[index]);
    }
    return bitcast<f32>(~word);
}

fn load_box(slot: u32) -> Box {
    var b: Box;
    for (var a = 0u; a < 3u; a++) {
        b.lo[a] = box_word(slot + a);
        b.hi[a] = box_word(slot + 3u + a);
    }
    return b;
}

// The node of the child of split `split` on its right (or left) whose far end is `far_end`: a leaf
// where it spans one position, else numbered by its end at the split (Karras's numbering).
fn child_node(split: u32, right: bool, far_end: u32) -> u32 {
    let near_end = select(split, split + 1u, right);
    return select(near_end, params.count - 1u + near_end, far_end == near_end);
}

// The box of the child on the right (or left) of split `split` that arrived there first, whose far
// end is `far_end`: from the atomic words it stored, or where SIBLING_BOXES_IN_NODES (src/gpu/
// build.rs says where that is sound), from its node.
fn sibling_box(split: u32, right: bool, far_end: u32) -> Box {
    if (SIBLING_BOXES_IN_NODES) {
        let node = child_node(split, right, far_end);
        return Box(nodes[node].min, nodes[node].max);
    }
    return load_box(box_slot(split, right));
}

// The node after every subtree that ends at sorted position `last`, in depth-first order: the right
// child of the split after it (bvh::merge's escape). `after` is split_prefix(last).
fn escape_after(last: u32, after: i32) -> u32 {
    let next = last + 1u;
    if (next == params.count) {
        return NONE;
    }
    if (after > split_prefix(i32(next))) {
        return params.count - 1u + next;
    }
    return next;
}

// The tree's nodes, bottom-up by merges (Apetrei 2014), as bvh::merge makes them on the CPU: every
// finished subtree writes its node but for the parent, learns from the split prefixes on either
// side which side its sibling is on, leaves its box and far end at the split between them, and
// stops if it is there first. The second to arrive makes the parent: its range, number (Karras's),
// box and children, whose parent links it writes, and climbs on with it. Ends pass through atomic
// words, so the second arrival reads what the first stored; boxes too but on llvmpipe
// (`sibling_box`).
//
// Each invocation takes MERGE_RUN consecutive leaves and starts the next as soon as its climb stops,
// so invocations that run in lockstep stay busy.
@compute @workgroup_size(GROUP)
fn merge(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    let n = params.count;
    let leaf_base = n - 1u;
    let run_start = (flat_group(wid, groups) * GROUP + lid) * MERGE_RUN;
    let run_end = min(run_start + MERGE_RUN, n);
    var next_leaf = run_start;
    var climbing = false;
    // The finished subtree: sorted positions first..last, the split prefixes before and after it,
    // node number, box, the node's two links down.
    var first = 0u;
    var last = 0u;
    var before = -1;
    var after = -1;
    var node = 0u;
    var bounds: Box;
    var left = 0u;
    var right = 0u;
    loop {
        if (!climbing) {
            if (next_leaf >= run_end) {
                break;
            }
            let primitive = pair_primitive(pairs_in[next_leaf]);
            bounds = primitive_box(primitive);
            first = next_leaf;
            last = next_leaf;
            before = split_prefix(i32(first) - 1);
            after = split_prefix(i32(last));
            node = leaf_base + next_leaf;
            left = primitive;
            right = LEAF;
            next_leaf += 1u;
            climbing = true;
        }
        nodes[node].min = bounds.lo;
        nodes[node].left = left;
        nodes[node].max = bounds.hi;
        nodes[node].right = right;
        nodes[node].escape = escape_after(last, after);
        if (first == 0u && last == leaf_base) {
            nodes[node].parent = NONE;
            climbing = false;
            continue;
        }
        // A left child when the keys after it share the longer prefix with its own.
        let is_left = after > before;
        let split = select(first - 1u, last, is_left);
        if (!SIBLING_BOXES_IN_NODES) {
            store_box(box_slot(split, !is_left), bounds.lo, bounds.hi);
        }
        let sibling_end = atomicExchange(&climb[split], select(last, first, is_left) + 1u);
        if (sibling_end == 0u) {
            climbing = false;
            continue;
        }
        let sibling = sibling_box(split, is_left, sibling_end - 1u);
        if (is_left) {
            last = sibling_end - 1u;
            after = split_prefix(i32(last));
            bounds = Box(min(bounds.lo, sibling.lo), max(bounds.hi, sibling.hi));
        } else {
            first = sibling_end - 1u;
            before = split_prefix(i32(first) - 1);
            bounds = Box(min(sibling.lo, bounds.lo), max(sibling.hi, bounds.hi));
        }
        left = child_node(split, false, first);
        right = child_node(split, true, last);
        // Karras's number: the end at the parent's split. The root's prefixes are both -1 (beyond
        // the keys), so it takes its first end, 0.
        node = select(first, last, after > before);
        nodes[left].parent = node;
        nodes[right].parent = node;
    }
}

// The tree's boxes anew over primitives that moved, its topology kept (a refit): every leaf takes
// its primitive's box and climbs by the parent links; at each node the first child to arrive
// leaves its box and stops, the second makes the node's box from both and climbs on. Boxes pass as
// in `merge` (`sibling_box`): through atomic words, or on llvmpipe through the nodes. The node's
// split number is its index among the internal nodes, so its children's slots are `box_slot`'s.
@compute @workgroup_size(GROUP)
fn refit(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    let n = params.count;
    let leaf_base = n - 1u;
    let run_start = (flat_group(wid, groups) * GROUP + lid) * MERGE_RUN;
    let run_end = min(run_start + MERGE_RUN, n);
    for (var leaf = run_start; leaf < run_end; leaf++) {
        var node = leaf_base + leaf;
        var bounds = primitive_box(nodes[node].left);
        loop {
            nodes[node].min = bounds.lo;
            nodes[node].max = bounds.hi;
            let parent = nodes[node].parent;
            if (parent == NONE) {
                break;
            }
            let is_right = nodes[parent].right == node;
            if (!SIBLING_BOXES_IN_NODES) {
                store_box(box_slot(parent, is_right), bounds.lo, bounds.hi);
            }
            if (atomicAdd(&climb[parent], 1u) == 0u) {
                break;
            }
            var sibling: Box;
            if (SIBLING_BOXES_IN_NODES) {
                let other = select(nodes[parent].right, nodes[parent].left, is_right);
                sibling = Box(nodes[other].min, nodes[other].max);
            } else {
                sibling = load_box(box_slot(parent, !is_right));
            }
            bounds = Box(min(bounds.lo, sibling.lo), max(bounds.hi, sibling.hi));
            node = parent;
        }
    }
}
