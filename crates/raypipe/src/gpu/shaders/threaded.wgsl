// The threaded BVH (src/bvh/threaded.rs) laid out on the GPU from a built LBVH node array, node for
// node and bit for bit as the CPU lays it out. Both kernels run GROUP invocations per workgroup,
// one per node, in a 2D grid of workgroups.

// LayoutParams is in types.wgsl, beside the other records with a host twin.

@group(0) @binding(0) var<uniform> params: LayoutParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
// Each node's position in depth-first order.
@group(0) @binding(2) var<storage, read_write> order: array<u32>;
@group(0) @binding(3) var<storage, read_write> threaded: array<ThreadedNode>;
// The quantization frame, as the globals hold it.
@group(0) @binding(4) var<storage, read_write> frame: BvhFrame;

// GROUP (invocations per workgroup) comes from the preamble (src/gpu/builders/threaded_layout.rs); MAX_QUANTUM
// and TINY_EXTENT (below which an extent gets a quantum of 1) from src/bvh/threaded.rs.
const MIN_NORMAL: f32 = 0x1p-126f;

fn node_index(wid: vec3<u32>, groups: vec3<u32>, lid: u32) -> u32 {
    return (wid.y * groups.x + wid.x) * GROUP + lid;
}

// A node's depth-first position: before it come its ancestors and the whole subtrees to its left,
// which is twice its first leaf's position plus the left turns on the way down from the root. In
// Karras's numbering a right child's index is its first leaf's (its position, for a leaf), and a
// left child shares its parent's first leaf, so one climb to the root finds both.
@compute @workgroup_size(GROUP)
fn depth_first_order(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                     @builtin(local_invocation_index) lid: u32) {
    let index = node_index(wid, groups, lid);
    if (index >= params.node_count) {
        return;
    }
    let leaf_base = params.node_count / 2u;
    var first = 0u;
    var found_first = false;
    var left_turns = 0u;
    var child = index;
    var parent = nodes[child].parent;
    while (parent != NONE) {
        if (nodes[parent].left == child) {
            left_turns += 1u;
        } else if (!found_first) {
            found_first = true;
            first = select(child, child - leaf_base, child >= leaf_base);
        }
        child = parent;
        parent = nodes[child].parent;
    }
    order[index] = 2u * first + left_turns;
}

fn power_of_two(exponent: i32) -> f32 {
    return bitcast<f32>(u32(exponent + 127) << 23u);
}

// The exponent of the smallest power of two q with 65534 q >= extent (0 for a flat or tiny extent),
// from the float's exponent bits: `quantum_for` in threaded.rs.
fn quantum_exponent(extent: f32) -> i32 {
    if (!(extent >= TINY_EXTENT)) {
        return 0;
    }
    var exponent = i32(bitcast<u32>(extent) >> 23u) - 127 - 15;
    if ((MAX_QUANTUM - 1.0) * power_of_two(exponent) < extent) {
        exponent += 1;
    }
    return exponent;
}

fn flush_subnormal(v: vec3<f32>) -> vec3<f32> {
    return select(v, vec3<f32>(0.0), v < vec3<f32>(MIN_NORMAL));
}

// `QuantizationFrame::quantize`: corners in quanta, one unit further out than rounding needs.
fn quantize(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inverse: vec3<f32>) -> vec3<u32> {
    let q_lo = floor(flush_subnormal(flush_subnormal(lo - origin) * inverse)) - 1.0;
    let q_hi = ceil(flush_subnormal(flush_subnormal(hi - origin) * inverse)) + 1.0;
    let a = vec3<u32>(clamp(q_lo, vec3<f32>(0.0), vec3<f32>(MAX_QUANTUM)));
    let b = vec3<u32>(clamp(q_hi, vec3<f32>(0.0), vec3<f32>(MAX_QUANTUM)));
    return vec3<u32>(a.x | (a.y << 16u), a.z | (b.x << 16u), b.y | (b.z << 16u));
}

// Writes every node to its depth-first position, its escape link renumbered; node 0 also writes
// the frame.
@compute @workgroup_size(GROUP)
fn threaded_nodes(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let index = node_index(wid, groups, lid);
    if (index >= params.node_count) {
        return;
    }
    let root = nodes[0];
    let extent = root.max - root.min;
    let exponent = vec3<i32>(quantum_exponent(extent.x), quantum_exponent(extent.y), quantum_exponent(extent.z));
    let quantum = vec3<f32>(power_of_two(exponent.x), power_of_two(exponent.y), power_of_two(exponent.z));
    let inverse = vec3<f32>(power_of_two(-exponent.x), power_of_two(-exponent.y), power_of_two(-exponent.z));
    if (index == 0u) {
        frame.origin = root.min;
        frame.quantum = quantum;
        frame.inverse_quantum = inverse;
    }
    let node = nodes[index];
    var link: u32;
    if (node.right == LEAF) {
        link = LEAF_BIT | node.left;
    } else if (node.escape == NONE) {
        link = params.node_count;
    } else {
        link = order[node.escape];
    }
    threaded[order[index]] = ThreadedNode(quantize(node.min, node.max, root.min, inverse), link);
}
