// The compressed wide BVH (src/bvh/wide.rs) collapsed on the GPU from a built LBVH node array, one
// level of wide nodes a dispatch, as H-PLOC's conversion kernel: each invocation makes one node of
// the level, takes room for its children from two counters, and queues its internal children for
// the next level. Nodes and leaves land in the order the counters hand out, which differs from the
// CPU's, but every node holds the children and boxes the CPU's does (wide.rs's `collapse`, mirrored
// here step for step), so the walks test the same boxes in the same order.

// CollapseParams is in types.wgsl, beside the other records with a host twin.

struct Counters {
    // Wide nodes made or queued, and leaf words written.
    nodes: atomic<u32>,
    leaves: atomic<u32>,
    // The level being made: wide nodes [level_begin, level_end).
    level_begin: u32,
    level_end: u32,
}

@group(0) @binding(0) var<uniform> params: CollapseParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
// The wide BVH's texels, word by word.
@group(0) @binding(2) var<storage, read_write> wide: array<u32>;
// The binary node each wide node is made from.
@group(0) @binding(3) var<storage, read_write> queue: array<u32>;
@group(0) @binding(4) var<storage, read_write> counters: Counters;
// The next level's dispatch: workgroups x, y, z.
@group(0) @binding(5) var<storage, read_write> dispatch: array<u32, 3>;

// GROUP (invocations per workgroup) comes from the preamble (src/gpu/builders/wide_collapse.rs); WIDE_SPAN,
// WIDE_NODE_TEXELS and TINY_EXTENT from src/bvh.
const MIN_NORMAL: f32 = 0x1p-126f;
const MAX_GROUPS_X: u32 = 65535u;
// The kernels that set up a level run alone.
const SINGLE: u32 = 1u;

// Sets the counters for the root's level.
@compute @workgroup_size(SINGLE)
fn collapse_start() {
    atomicStore(&counters.nodes, 1u);
    atomicStore(&counters.leaves, 0u);
    counters.level_begin = 0u;
    counters.level_end = 1u;
    queue[0] = 0u;
    dispatch = array<u32, 3>(1u, 1u, 1u);
}

// Moves on to the nodes the last level queued, and sizes their dispatch.
@compute @workgroup_size(SINGLE)
fn collapse_next_level() {
    counters.level_begin = counters.level_end;
    counters.level_end = atomicLoad(&counters.nodes);
    let groups = (counters.level_end - counters.level_begin + GROUP - 1u) / GROUP;
    let x = min(groups, MAX_GROUPS_X);
    dispatch = array<u32, 3>(x, select(1u, (groups + x - 1u) / x, x > 0u), 1u);
}

fn is_binary_leaf(node: BvhNode) -> bool {
    return node.right == LEAF;
}

// `Child::extent` in wide.rs: half the perimeter, adds only, x, y, then z.
fn extent_sum(node: BvhNode) -> f32 {
    return (node.max.x - node.min.x) + (node.max.y - node.min.y) + (node.max.z - node.min.z);
}

// One slot's entry of `octant_costs` in wide.rs.
fn octant_cost(offset: vec3<f32>, slot: u32) -> f32 {
    let x = select(-offset.x, offset.x, (slot & 1u) != 0u);
    let y = select(-offset.y, offset.y, (slot & 2u) != 0u);
    let z = select(-offset.z, offset.z, (slot & 4u) != 0u);
    return x + y + z;
}

fn power_of_two(exponent: i32) -> f32 {
    return bitcast<f32>(u32(exponent + 127) << 23u);
}

// `quantum_exponent` in wide.rs: the biased exponent of the smallest power of two q with
// WIDE_SPAN q >= extent (127, q = 1, for a flat or tiny extent).
fn quantum_exponent(extent: f32) -> u32 {
    if (!(extent >= TINY_EXTENT)) {
        return 127u;
    }
    var exponent = i32(bitcast<u32>(extent) >> 23u) - 127 - 7;
    if (WIDE_SPAN * power_of_two(exponent) < extent) {
        exponent += 1;
    }
    return u32(exponent + 127);
}

fn flush_subnormal(v: vec3<f32>) -> vec3<f32> {
    return select(v, vec3<f32>(0.0), v < vec3<f32>(MIN_NORMAL));
}

const NO_CHILD: u32 = 0xffffffffu;

// Makes the wide node of binary node `queue[index]`.
@compute @workgroup_size(GROUP)
fn collapse_level(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let index = counters.level_begin + (wid.y * groups.x + wid.x) * GROUP + lid;
    if (index >= counters.level_end) {
        return;
    }
    let binary = queue[index];
    let node = nodes[binary];
    // `collapse` in wide.rs: the largest internal child (the first of equals) gives way to its two.
    var children: array<u32, 8>;
    var count = 1u;
    children[0] = binary;
    if (!is_binary_leaf(node)) {
        children[0] = node.left;
        children[1] = node.right;
        count = 2u;
    }
    while (count < 8u) {
        var widest = NO_CHILD;
        var widest_extent = 0.0;
        for (var i = 0u; i < count; i++) {
            let child = nodes[children[i]];
            if (!is_binary_leaf(child) && (widest == NO_CHILD || extent_sum(child) > widest_extent)) {
                widest = i;
                widest_extent = extent_sum(child);
            }
        }
        if (widest == NO_CHILD) {
            break;
        }
        let opened = nodes[children[widest]];
        children[widest] = opened.left;
        children[count] = opened.right;
        count += 1u;
    }
    // Each child in turn takes the free slot whose octant its centre lies furthest into.
    let centre = node.min + node.max;
    var slots = array<u32, 8>(NO_CHILD, NO_CHILD, NO_CHILD, NO_CHILD, NO_CHILD, NO_CHILD, NO_CHILD, NO_CHILD);
    for (var i = 0u; i < count; i++) {
        let child = nodes[children[i]];
        let offset = (child.min + child.max) - centre;
        var best = NO_CHILD;
        var best_cost = 0.0;
        for (var slot = 0u; slot < 8u; slot++) {
            if (slots[slot] != NO_CHILD) {
                continue;
            }
            let cost = octant_cost(offset, slot);
            if (best == NO_CHILD || cost > best_cost) {
                best = slot;
                best_cost = cost;
            }
        }
        slots[best] = children[i];
    }
    var internal_count = 0u;
    for (var slot = 0u; slot < 8u; slot++) {
        if (slots[slot] != NO_CHILD && !is_binary_leaf(nodes[slots[slot]])) {
            internal_count += 1u;
        }
    }
    let first_child = atomicAdd(&counters.nodes, internal_count);
    let first_leaf = atomicAdd(&counters.leaves, count - internal_count);
    // `wide_node` in wide.rs: the children's boxes in the node's frame.
    let extent = node.max - node.min;
    let exponents = vec3<u32>(quantum_exponent(extent.x), quantum_exponent(extent.y), quantum_exponent(extent.z));
    let inverse = bitcast<vec3<f32>>((vec3<u32>(254u) - exponents) << vec3<u32>(23u));
    var lo = array<u32, 6>(0u, 0u, 0u, 0u, 0u, 0u);
    var hi = array<u32, 6>(0u, 0u, 0u, 0u, 0u, 0u);
    var occupied = 0u;
    var imask = 0u;
    var internal_rank = 0u;
    var leaf_rank = 0u;
    for (var slot = 0u; slot < 8u; slot++) {
        if (slots[slot] == NO_CHILD) {
            continue;
        }
        let child = nodes[slots[slot]];
        occupied |= 1u << slot;
        if (is_binary_leaf(child)) {
            wide[first_leaf + leaf_rank] = child.left;
            leaf_rank += 1u;
        } else {
            imask |= 1u << slot;
            queue[first_child + internal_rank] = slots[slot];
            internal_rank += 1u;
        }
        let q_lo = floor(flush_subnormal(flush_subnormal(child.min - node.min) * inverse)) - 1.0;
        let q_hi = ceil(flush_subnormal(flush_subnormal(child.max - node.min) * inverse)) + 1.0;
        let a = vec3<u32>(clamp(q_lo, vec3<f32>(0.0), vec3<f32>(255.0)));
        let b = vec3<u32>(clamp(q_hi, vec3<f32>(0.0), vec3<f32>(255.0)));
        let word = slot / 4u;
        let shift = 8u * (slot % 4u);
        lo[word] |= a.x << shift;
        lo[2u + word] |= a.y << shift;
        lo[4u + word] |= a.z << shift;
        hi[word] |= b.x << shift;
        hi[2u + word] |= b.y << shift;
        hi[4u + word] |= b.z << shift;
    }
    let at = 4u * (params.root_texel + WIDE_NODE_TEXELS * index);
    wide[at] = bitcast<u32>(node.min.x);
    wide[at + 1u] = bitcast<u32>(node.min.y);
    wide[at + 2u] = bitcast<u32>(node.min.z);
    wide[at + 3u] = exponents.x | (exponents.y << 8u) | (exponents.z << 16u) | (imask << 24u);
    wide[at + 4u] = params.root_texel + WIDE_NODE_TEXELS * first_child;
    wide[at + 5u] = first_leaf;
    wide[at + 6u] = occupied;
    wide[at + 7u] = 0u;
    for (var i = 0u; i < 6u; i++) {
        wide[at + 8u + i] = lo[i];
        wide[at + 14u + i] = hi[i];
    }
}
