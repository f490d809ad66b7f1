// Compressed wide BVH traversal (src/bvh/wide.rs, after Ylitie, Karras and Laine 2017): a node's
// eight boxes tested at once in the node's own frame, its hit leaves tested at once, its hit
// internal children visited nearest first in the order of the ray's octant, the others waiting on
// the stack as one group (a base, the hit slots as bits slot ^ octant, and the slots of their kind).
// Mirrored by src/cpu/accel.rs.

// The bits set in an 8-bit mask, and the highest of them: WebGL2's GLSL ES 3.0 has neither
// countOneBits (bitCount) nor firstLeadingBit (findMSB).
fn count_bits(mask: u32) -> u32 {
    let pairs = mask - ((mask >> 1u) & 0x55u);
    let nibbles = (pairs & 0x33u) + ((pairs >> 2u) & 0x33u);
    return (nibbles + (nibbles >> 4u)) & 0x0fu;
}

fn highest_bit(mask: u32) -> u32 {
    let four = select(0u, 4u, mask >= 16u);
    let rest = mask >> four;
    let two = select(0u, 2u, rest >= 4u);
    return four + two + select(0u, 1u, (rest >> two) >= 2u);
}

// Takes a group's nearest hit child: the texel of an internal child (stride WIDE_NODE_TEXELS), the word of a
// leaf's primitive (stride 1).
fn take_nearest(base: u32, hits: ptr<function, u32>, kind_mask: u32, octant: u32, stride: u32) -> u32 {
    let bit = highest_bit(*hits);
    *hits &= ~(1u << bit);
    let slot = bit ^ octant;
    return base + stride * count_bits(kind_mask & ((1u << slot) - 1u));
}

// The ray's octant: bit k set where its direction's component k is not negative.
fn ray_octant(dir: vec3<f32>) -> u32 {
    return u32(dir.x >= 0.0) | (u32(dir.y >= 0.0) << 1u) | (u32(dir.z >= 0.0) << 2u);
}

// A mask of slots moved to the bits slot ^ octant.
fn octant_bits(mask: u32, octant: u32) -> u32 {
    var bits = mask;
    if ((octant & 1u) != 0u) {
        bits = ((bits & 0x55u) << 1u) | ((bits >> 1u) & 0x55u);
    }
    if ((octant & 2u) != 0u) {
        bits = ((bits & 0x33u) << 2u) | ((bits >> 2u) & 0x33u);
    }
    if ((octant & 4u) != 0u) {
        bits = ((bits & 0x0fu) << 4u) | ((bits >> 4u) & 0x0fu);
    }
    return bits;
}

// A word's four bytes as floats, the lowest first.
fn bytes(word: u32) -> vec4<f32> {
    return vec4<f32>((vec4<u32>(word) >> vec4<u32>(0u, 8u, 16u, 24u)) & vec4<u32>(0xffu));
}

// One axis's slabs of four boxes whose corners are the bytes of `lo` and `hi`, as intersect_box
// computes them: where the ray enters (near) and leaves (far) each.
fn slabs(lo: u32, hi: u32, origin: f32, inv_dir: f32, near: ptr<function, vec4<f32>>, far: ptr<function, vec4<f32>>) {
    let t0 = (bytes(lo) - origin) * inv_dir;
    let t1 = (bytes(hi) - origin) * inv_dir;
    let swap = t1 < t0;
    *near = select(t0, t1, swap);
    *far = select(t1, t0, swap);
}

// `intersect_box` for four boxes at once, whose low and high corners are the bytes of `lo` and
// `hi` (x, y, z words): bit i set where the ray enters box i by t_max. Component for component the
// arithmetic of intersect_box, so the CPU's box-by-box test finds the same boxes. Written out axis by
// axis: SwiftShader keeps an array, or a vector indexed by a variable, in memory.
fn slab_hits(lo: vec3<u32>, hi: vec3<u32>, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> u32 {
    var near_x: vec4<f32>;
    var far_x: vec4<f32>;
    var near_y: vec4<f32>;
    var far_y: vec4<f32>;
    var near_z: vec4<f32>;
    var far_z: vec4<f32>;
    slabs(lo.x, hi.x, origin.x, inv_dir.x, &near_x, &far_x);
    slabs(lo.y, hi.y, origin.y, inv_dir.y, &near_y, &far_y);
    slabs(lo.z, hi.z, origin.z, inv_dir.z, &near_z, &far_z);
    // larger(larger(x, y), larger(z, 0)) and smaller(smaller(x, y), smaller(z, t_max)), as
    // intersect_box: b where it is the larger (smaller), else a.
    let zero = vec4<f32>(0.0);
    let t_far = vec4<f32>(t_max);
    let near_xy = select(near_x, near_y, near_y > near_x);
    let near_z0 = select(near_z, zero, zero > near_z);
    let t_enter = select(near_xy, near_z0, near_z0 > near_xy);
    let far_xy = select(far_x, far_y, far_y < far_x);
    let far_zt = select(far_z, t_far, t_far < far_z);
    let t_exit = select(far_xy, far_zt, far_zt < far_xy);
    let enters = vec4<u32>(t_enter <= t_exit);
    return enters.x | (enters.y << 1u) | (enters.z << 2u) | (enters.w << 3u);
}

// Word `i` of the array: a leaf's primitive. Picked by selects, not by indexing the texel with a
// variable, which SwiftShader does through memory.
fn wide_word(i: u32) -> u32 {
    let texel = wide_texel(i / 4u);
    let lane = i % 4u;
    return select(select(texel.x, texel.y, lane == 1u), select(texel.z, texel.w, lane == 3u), lane >= 2u);
}

fn wide_texel(i: u32) -> vec4<u32> {
    return load_wide(i).words;
}

fn traverse_wide(ray: Ray, best: Hit, shadow: bool) -> Hit {
    var hit = best;
    let count = primitive_count();
    if (count == 0u) {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    let octant = ray_octant(ray.dir);
    // The group being visited; first the root, as one internal child in slot 0 after the leaf words.
    var node_base = (count + 3u) / 4u;
    var node_hits = 1u << octant;
    var node_mask = 1u;
    // Waiting groups: base, and hits | kind mask << 8.
    var stack_base: array<u32, BVH_STACK_SIZE>;
    var stack_hits: array<u32, BVH_STACK_SIZE>;
    var size = 0u;
    // The hit leaves of the last node visited, nearest first.
    var leaf_base = 0u;
    var leaf_hits = 0u;
    var leaf_mask = 0u;
    // Two loops (Aila and Laine's while-while): the inner one visits nodes until the ray has
    // leaves to test, the outer one tests them. SwiftShader and llvmpipe run a loop's whole body
    // for every step any of its lanes takes, so the primitive tests are kept out of the node
    // steps, and a step that resumes a waiting group visits a node too. The nodes and primitives
    // tested, and their order, are those of one loop (src/cpu/accel.rs).
    loop {
        loop {
            if (leaf_hits != 0u) {
                break;
            }
            if (node_hits == 0u) {
                if (size == 0u) {
                    break;
                }
                size -= 1u;
                node_base = stack_base[size];
                node_hits = stack_hits[size] & 0xffu;
                node_mask = stack_hits[size] >> 8u;
            }
            let texel = take_nearest(node_base, &node_hits, node_mask, octant, WIDE_NODE_TEXELS);
            if (node_hits != 0u) {
                stack_base[size] = node_base;
                stack_hits[size] = node_hits | (node_mask << 8u);
                size += 1u;
            }
            let t0 = wide_texel(texel);
            let t1 = wide_texel(texel + 1u);
            let t2 = wide_texel(texel + 2u);
            let t3 = wide_texel(texel + 3u);
            let t4 = wide_texel(texel + 4u);
            // The ray in the node's frame, where its children's corners are whole quanta.
            let exponents = (vec3<u32>(t0.w, t0.w >> 8u, t0.w >> 16u)) & vec3<u32>(0xffu);
            let quantum = bitcast<vec3<f32>>(exponents << vec3<u32>(23u));
            let inverse_quantum = bitcast<vec3<f32>>((vec3<u32>(254u) - exponents) << vec3<u32>(23u));
            let origin = (ray.origin - bitcast<vec3<f32>>(t0.xyz)) * inverse_quantum;
            let node_inv_dir = inv_dir * quantum;
            let imask = t0.w >> 24u;
            // Slots 0-3, then 4-7: each axis's four corners in one word, tested four at a time.
            let slots = t1.z;
            box_tests += count_bits(slots);
            let low = slab_hits(vec3<u32>(t2.x, t2.z, t3.x), vec3<u32>(t3.z, t4.x, t4.z), origin, node_inv_dir, hit.t);
            let high = slab_hits(vec3<u32>(t2.y, t2.w, t3.y), vec3<u32>(t3.w, t4.y, t4.w), origin, node_inv_dir, hit.t);
            let hit_slots = (low | (high << 4u)) & slots;
            node_base = t1.x;
            node_hits = octant_bits(hit_slots & imask, octant);
            node_mask = imask;
            leaf_base = t1.y;
            leaf_mask = slots & ~imask;
            leaf_hits = octant_bits(hit_slots & leaf_mask, octant);
        }
        if (leaf_hits == 0u) {
            break;
        }
        loop {
            let word = take_nearest(leaf_base, &leaf_hits, leaf_mask, octant, 1u);
            if (hit_primitive(wide_word(word), ray, &hit) && shadow) {
                return hit;
            }
            if (leaf_hits == 0u) {
                break;
            }
        }
    }
    return hit;
}

fn accel_closest(ray: Ray, best: Hit) -> Hit {
    return traverse_wide(ray, best, false);
}

fn accel_occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_wide(ray, Hit(t_max, HIT_NONE, 0u), true).kind != HIT_NONE;
}
