// The LBVH build in compute passes: the phases of src/bvh/lbvh.rs, giving the same node array for
// the same Morton codes. Every kernel runs 256 invocations per workgroup; large dispatches are 2D.
//
// src/gpu/build.rs prepends the build's sizes and what depends on the code width: CELLS (grid cells per axis), the `Pair`
// type that holds a code and its primitive, and its accessors `pair`, `pair_primitive` and
// `code_word` (the code's low or high 32 bits; 30-bit codes have no high word, it reads 0).

// From the preamble (src/gpu/build.rs): GROUP invocations per workgroup; BLOCK items per block in
// the reduction kernels, ITEMS consecutive ones per invocation. The sort is in radix_sort.wgsl.

// BuildParams is in types.wgsl, beside the other records with a host twin.

// Layout of `scratch`: centroid bounds; from SCRATCH_BLOCKS, per-block partial centroid bounds (6
// words each); then every node's parent. (One buffer for all of them keeps the build within 8
// storage buffers, WebGPU's default limit.) SCRATCH_BOUNDS and SCRATCH_BLOCKS come from the
// preamble.

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
// (Morton code, primitive) pairs; sort passes read `pairs_in` and write `pairs_out`.
@group(0) @binding(2) var<storage, read_write> pairs_in: array<Pair>;
@group(0) @binding(3) var<storage, read_write> pairs_out: array<Pair>;
@group(0) @binding(4) var<storage, read_write> scratch: array<u32>;
// Internal node i: (left child, right child, first, last).
@group(0) @binding(5) var<storage, read_write> ranges: array<vec4<u32>>;
// [0, n - 1): visit counters of internal nodes; then 6 words per node: its box's min and max bits.
// (The sort keeps its counts here before: radix_sort.wgsl.)
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

// Where node `node`'s parent is kept.
fn parent_slot(node: u32) -> u32 {
    return SCRATCH_BLOCKS + 6u * block_count() + node;
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
@compute @workgroup_size(256)
fn bounds_partial(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let block = flat_group(wid, groups);
    var lo = vec3<f32>(BIG);
    var hi = vec3<f32>(-BIG);
    for (var k = 0u; k < ITEMS; k++) {
        let i = block * BLOCK + lid * ITEMS + k;
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
        let base = partial_bounds(block);
        for (var a = 0u; a < 3u; a++) {
            scratch[base + a] = bitcast<u32>(shared_lo[0][a]);
            scratch[base + 3u + a] = bitcast<u32>(shared_hi[0][a]);
        }
    }
}

@compute @workgroup_size(256)
fn bounds_final(@builtin(local_invocation_index) lid: u32) {
    var lo = vec3<f32>(BIG);
    var hi = vec3<f32>(-BIG);
    for (var block = lid; block < block_count(); block += GROUP) {
        let base = partial_bounds(block);
        let b_lo = vec3<f32>(bitcast<f32>(scratch[base]), bitcast<f32>(scratch[base + 1u]), bitcast<f32>(scratch[base + 2u]));
        let b_hi = vec3<f32>(bitcast<f32>(scratch[base + 3u]), bitcast<f32>(scratch[base + 4u]), bitcast<f32>(scratch[base + 5u]));
        lo = min(lo, b_lo);
        hi = max(hi, b_hi);
    }
    shared_lo[lid] = lo;
    shared_hi[lid] = hi;
    reduce_bounds(lid);
    if (lid == 0u) {
        for (var a = 0u; a < 3u; a++) {
            scratch[SCRATCH_BOUNDS + a] = bitcast<u32>(shared_lo[0][a]);
            scratch[SCRATCH_BOUNDS + 3u + a] = bitcast<u32>(shared_hi[0][a]);
        }
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
@compute @workgroup_size(256)
fn morton(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
          @builtin(local_invocation_index) lid: u32) {
    let i = flat_group(wid, groups) * GROUP + lid;
    if (i >= params.count) {
        return;
    }
    let lo = vec3<f32>(bitcast<f32>(scratch[0]), bitcast<f32>(scratch[1]), bitcast<f32>(scratch[2]));
    let hi = vec3<f32>(bitcast<f32>(scratch[3]), bitcast<f32>(scratch[4]), bitcast<f32>(scratch[5]));
    let extent = hi - lo;
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
// positions i and j; -1 outside the array. The CPU's keys hold the same bits under another number
// of leading zeros: its lengths differ from these by a constant, and every comparison of two lengths
// comes out the same on both devices.
fn delta(i: u32, j: i32) -> i32 {
    if (j < 0 || j >= i32(params.count)) {
        return -1;
    }
    let a = pairs_in[i];
    let b = pairs_in[u32(j)];
    let high = code_word(a, true) ^ code_word(b, true);
    if (high != 0u) {
        return i32(countLeadingZeros(high));
    }
    let low = code_word(a, false) ^ code_word(b, false);
    if (low != 0u) {
        return 32 + i32(countLeadingZeros(low));
    }
    return 64 + i32(countLeadingZeros(i ^ u32(j)));
}

// Find every internal node's children and range, and every node's parent (Karras 2012).
@compute @workgroup_size(256)
fn hierarchy(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
             @builtin(local_invocation_index) lid: u32) {
    let i = flat_group(wid, groups) * GROUP + lid;
    let n = params.count;
    if (i + 1u >= n) {
        return;
    }
    let ii = i32(i);
    let leaf_base = n - 1u;
    var d = -1;
    if (delta(i, ii + 1) > delta(i, ii - 1)) {
        d = 1;
    }
    let delta_min = delta(i, ii - d);
    var l_max = 2;
    while (delta(i, ii + l_max * d) > delta_min) {
        l_max *= 2;
    }
    var l = 0;
    for (var t = l_max / 2; t >= 1; t /= 2) {
        if (delta(i, ii + (l + t) * d) > delta_min) {
            l += t;
        }
    }
    let j = ii + l * d;
    let delta_node = delta(i, j);
    var s = 0;
    var shift = 1u;
    loop {
        let t = (l + (1 << shift) - 1) >> shift;
        if (delta(i, ii + (s + t) * d) > delta_node) {
            s += t;
        }
        if (t == 1) {
            break;
        }
        shift += 1u;
    }
    let split = u32(ii + s * d + min(d, 0));
    let first = u32(min(ii, j));
    let last = u32(max(ii, j));
    var left = split;
    if (first == split) {
        left = leaf_base + split;
    }
    var right = split + 1u;
    if (last == split + 1u) {
        right = leaf_base + split + 1u;
    }
    ranges[i] = vec4<u32>(left, right, first, last);
    scratch[parent_slot(left)] = i;
    scratch[parent_slot(right)] = i;
    if (i == 0u) {
        scratch[parent_slot(0)] = NONE;
    }
}

fn box_base(node: u32) -> u32 {
    return params.count - 1u + node * 6u;
}

fn store_box(node: u32, lo: vec3<f32>, hi: vec3<f32>) {
    let base = box_base(node);
    for (var a = 0u; a < 3u; a++) {
        atomicStore(&climb[base + a], bitcast<u32>(lo[a]));
        atomicStore(&climb[base + 3u + a], bitcast<u32>(hi[a]));
    }
}

fn load_box_lo(node: u32) -> vec3<f32> {
    let base = box_base(node);
    return vec3<f32>(bitcast<f32>(atomicLoad(&climb[base])), bitcast<f32>(atomicLoad(&climb[base + 1u])),
                     bitcast<f32>(atomicLoad(&climb[base + 2u])));
}

fn load_box_hi(node: u32) -> vec3<f32> {
    let base = box_base(node) + 3u;
    return vec3<f32>(bitcast<f32>(atomicLoad(&climb[base])), bitcast<f32>(atomicLoad(&climb[base + 1u])),
                     bitcast<f32>(atomicLoad(&climb[base + 2u])));
}

// Bound leaves by their primitives, then internal nodes bottom-up: each leaf climbs; at each
// internal node an atomic visit counter stops the first child to arrive, and the second, which
// then knows both children's boxes, writes the union and climbs on. Boxes are atomic words so the
// second arrival reads what the first stored.
@compute @workgroup_size(256)
fn leaves_and_bounds(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                     @builtin(local_invocation_index) lid: u32) {
    let k = flat_group(wid, groups) * GROUP + lid;
    let n = params.count;
    if (k >= n) {
        return;
    }
    let leaf = n - 1u + k;
    let b = primitive_box(pair_primitive(pairs_in[k]));
    store_box(leaf, b.lo, b.hi);
    if (n == 1u) {
        return;
    }
    var node = scratch[parent_slot(leaf)];
    while (node != NONE) {
        if (atomicAdd(&climb[node], 1u) == 0u) {
            return;
        }
        let children = ranges[node];
        store_box(node, min(load_box_lo(children.x), load_box_lo(children.y)),
                  max(load_box_hi(children.x), load_box_hi(children.y)));
        node = scratch[parent_slot(node)];
    }
}

// Link every node to the node after its subtree in depth-first order, and write the node array.
@compute @workgroup_size(256)
fn links(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    let node = flat_group(wid, groups) * GROUP + lid;
    let n = params.count;
    if (node >= 2u * n - 1u) {
        return;
    }
    let leaf_base = n - 1u;
    var left: u32;
    var right: u32;
    var last: u32;
    if (node < leaf_base) {
        let range = ranges[node];
        left = range.x;
        right = range.y;
        last = range.w;
    } else {
        left = pair_primitive(pairs_in[node - leaf_base]);
        right = LEAF;
        last = node - leaf_base;
    }
    let next = last + 1u;
    var escape = leaf_base + next;
    if (next == n) {
        escape = NONE;
    } else if (next < leaf_base && ranges[next].z == next) {
        escape = next;
    }
    var parent = NONE;
    if (n > 1u) {
        parent = scratch[parent_slot(node)];
    }
    nodes[node] = BvhNode(load_box_lo(node), left, load_box_hi(node), right, parent, escape);
}
