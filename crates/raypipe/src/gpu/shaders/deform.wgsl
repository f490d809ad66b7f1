// Skinning and morphing on the GPU: each frame, the animated primitives' vertices posed from their
// rest pose and written into the triangle records the LBVH build and the tracer read, with their
// shading normals. The CPU twin is scene/animation.rs (`Rig::deform`, `CornerNormals::corners`);
// the host side is src/gpu/builders/deform.rs, which writes the frame's matrices and morph weights.
//
// Three kernels, one dispatch each: deform_vertices (morph, then skin or carry by the node),
// gather_triangles (corners into the records; the file's normals, or each face's normal and
// corner angles for smooth normals), smooth_normals (per corner, the angle-weighted normals of the
// faces around its position that bend less than the crease).

// From the preamble (src/gpu/builders/deform.rs): GROUP, and the normal sources NORMALS_FLAT, NORMALS_FILE,
// NORMALS_SMOOTH. Triangle, TriangleNormals and NONE are the tracer's (types.wgsl).

struct DeformParams {
    vertex_count: u32,
    triangle_count: u32,
}

// One placed primitive: where its vertices, morph offsets, matrices and weights start.
struct DeformInstance {
    vertex_first: u32,
    vertex_count: u32,
    target_first: u32,
    target_count: u32,
    // In `frame`, in matrices; a skinned vertex's joint j is matrix matrix_first + j.
    matrix_first: u32,
    skinned: u32,
    // In `frame`, in floats from its start.
    weight_first: u32,
    // NORMALS_FLAT, NORMALS_FILE or NORMALS_SMOOTH.
    normals: u32,
    // Smooth normals: the cosine of the crease angle, below which faces do not blend.
    crease_cos: f32,
}

struct DeformVertex {
    position: vec3<f32>,
    instance: u32,
    // The file's normal (zero where it has none).
    normal: vec3<f32>,
}

// Up to eight joints (16 bits each, two to a word) and their weights.
struct DeformInfluences {
    joints: vec4<u32>,
    weights_low: vec4<f32>,
    weights_high: vec4<f32>,
}

// One morph target's offsets for one vertex.
struct DeformOffset {
    position: vec4<f32>,
    normal: vec4<f32>,
}

// A placed triangle: its corners' vertices, the scene triangle it moves, and for smooth normals
// the groups of faces around each corner's position.
struct DeformTriangle {
    corners: vec3<u32>,
    triangle: u32,
    groups: vec3<u32>,
    instance: u32,
}

struct PosedVertex {
    position: vec4<f32>,
    normal: vec4<f32>,
}

// A face's normal (xyz) and its corner angles (-1 where a corner has no angle).
struct Face {
    normal: vec4<f32>,
    angles: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: DeformParams;
@group(0) @binding(1) var<storage, read> instances: array<DeformInstance>;
@group(0) @binding(2) var<storage, read> vertices: array<DeformVertex>;
@group(0) @binding(3) var<storage, read> influences: array<DeformInfluences>;
@group(0) @binding(4) var<storage, read> targets: array<DeformOffset>;
// This frame's matrices (four columns each), then its morph weights.
@group(0) @binding(5) var<storage, read> frame: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> posed: array<PosedVertex>;
@group(0) @binding(7) var<storage, read> deform_triangles: array<DeformTriangle>;
@group(0) @binding(8) var<storage, read_write> faces: array<Face>;
// Per group of faces around a position: where its entries start (group_count + 1 words), then the
// entries, a face's index times 4 plus the corner.
@group(0) @binding(9) var<storage, read> face_groups: array<u32>;
@group(0) @binding(10) var<storage, read_write> triangles: array<Triangle>;
@group(0) @binding(11) var<storage, read_write> triangle_normals: array<TriangleNormals>;

fn frame_matrix(m: u32) -> mat4x4<f32> {
    return mat4x4<f32>(frame[4u * m], frame[4u * m + 1u], frame[4u * m + 2u], frame[4u * m + 3u]);
}

fn frame_float(i: u32) -> f32 {
    return frame[i / 4u][i % 4u];
}

fn invocation(wid: vec3<u32>, groups: vec3<u32>, lid: u32) -> u32 {
    return (wid.y * groups.x + wid.x) * GROUP + lid;
}

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let length_squared = dot(v, v);
    if (length_squared > 0.0) {
        return v * inverseSqrt(length_squared);
    }
    return vec3<f32>(0.0);
}

// The normal `n` carried through `m`: by the inverse transpose of its linear part, here the
// cofactor matrix with the determinant's sign (the length goes with the normalization); unchanged
// where `m` collapses space (`normal_matrix` in scene/animation.rs).
fn carry_normal(m: mat4x4<f32>, n: vec3<f32>) -> vec3<f32> {
    let c0 = m[0].xyz;
    let c1 = m[1].xyz;
    let c2 = m[2].xyz;
    let det = dot(c0, cross(c1, c2));
    if (det == 0.0) {
        return n;
    }
    let cofactor = mat3x3<f32>(cross(c1, c2), cross(c2, c0), cross(c0, c1));
    return cofactor * n * sign(det);
}

// `sum` plus joint `joint`'s matrix times its weight `w` (nothing read where `w` is 0).
fn add_influence(sum: mat4x4<f32>, matrix_first: u32, joint: u32, w: f32) -> mat4x4<f32> {
    if (w == 0.0) {
        return sum;
    }
    return sum + frame_matrix(matrix_first + joint) * w;
}

@compute @workgroup_size(GROUP)
fn deform_vertices(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                   @builtin(local_invocation_index) lid: u32) {
    let v = invocation(wid, groups, lid);
    if (v >= params.vertex_count) {
        return;
    }
    let vertex = vertices[v];
    let instance = instances[vertex.instance];
    let local = v - instance.vertex_first;
    var position = vertex.position;
    var normal = vertex.normal;
    for (var t = 0u; t < instance.target_count; t++) {
        let w = frame_float(instance.weight_first + t);
        if (w != 0.0) {
            let offset = targets[instance.target_first + t * instance.vertex_count + local];
            position += offset.position.xyz * w;
            normal += offset.normal.xyz * w;
        }
    }
    var m: mat4x4<f32>;
    if (instance.skinned != 0u) {
        // Written out influence by influence: CPU adapters spill vectors indexed by a variable.
        let joints = influences[v].joints;
        let low = influences[v].weights_low;
        let high = influences[v].weights_high;
        let first = instance.matrix_first;
        m = add_influence(mat4x4<f32>(), first, joints.x & 0xffffu, low.x);
        m = add_influence(m, first, joints.x >> 16u, low.y);
        m = add_influence(m, first, joints.y & 0xffffu, low.z);
        m = add_influence(m, first, joints.y >> 16u, low.w);
        m = add_influence(m, first, joints.z & 0xffffu, high.x);
        m = add_influence(m, first, joints.z >> 16u, high.y);
        m = add_influence(m, first, joints.w & 0xffffu, high.z);
        m = add_influence(m, first, joints.w >> 16u, high.w);
    } else {
        m = frame_matrix(instance.matrix_first);
    }
    posed[v].position = vec4<f32>((m * vec4<f32>(position, 1.0)).xyz, 0.0);
    posed[v].normal = vec4<f32>(normalize_or_zero(carry_normal(m, normal)), 0.0);
}

// The angle at corner p between the edges to q and r; -1 where an edge has no length.
fn corner_angle(p: vec3<f32>, q: vec3<f32>, r: vec3<f32>) -> f32 {
    let a = normalize_or_zero(q - p);
    let b = normalize_or_zero(r - p);
    if (all(a == vec3<f32>(0.0)) || all(b == vec3<f32>(0.0))) {
        return -1.0;
    }
    return acos(clamp(dot(a, b), -1.0, 1.0));
}

@compute @workgroup_size(GROUP)
fn gather_triangles(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) lid: u32) {
    let i = invocation(wid, groups, lid);
    if (i >= params.triangle_count) {
        return;
    }
    let placed = deform_triangles[i];
    let instance = instances[placed.instance];
    let a = posed[placed.corners.x].position.xyz;
    let b = posed[placed.corners.y].position.xyz;
    let c = posed[placed.corners.z].position.xyz;
    triangles[placed.triangle].v0 = a;
    triangles[placed.triangle].v1 = b;
    triangles[placed.triangle].v2 = c;
    let slot = triangles[placed.triangle].normals;
    if (instance.normals == NORMALS_FILE && slot != NONE) {
        triangle_normals[slot].n0 = posed[placed.corners.x].normal.xyz;
        triangle_normals[slot].n1 = posed[placed.corners.y].normal.xyz;
        triangle_normals[slot].n2 = posed[placed.corners.z].normal.xyz;
    }
    if (instance.normals == NORMALS_SMOOTH) {
        faces[i].normal = vec4<f32>(normalize_or_zero(cross(b - a, c - a)), 0.0);
        faces[i].angles = vec4<f32>(corner_angle(a, b, c), corner_angle(b, c, a), corner_angle(c, a, b), 0.0);
    }
}

// The normal at a corner of face `own`: the faces around its position (group `group`) that bend
// from it by no more than the crease, weighted by their angle there (`Mesh::smooth_normals`).
fn blended_normal(own: vec3<f32>, group: u32, crease_cos: f32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var e = face_groups[group]; e < face_groups[group + 1u]; e++) {
        let entry = face_groups[e];
        let face = faces[entry / 4u];
        let angle = face.angles[entry % 4u];
        if (angle >= 0.0 && dot(face.normal.xyz, own) >= crease_cos) {
            sum += face.normal.xyz * angle;
        }
    }
    let normal = normalize_or_zero(sum);
    return select(normal, own, all(normal == vec3<f32>(0.0)));
}

@compute @workgroup_size(GROUP)
fn smooth_normals(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let i = invocation(wid, groups, lid);
    if (i >= params.triangle_count) {
        return;
    }
    let placed = deform_triangles[i];
    let instance = instances[placed.instance];
    let slot = triangles[placed.triangle].normals;
    if (instance.normals != NORMALS_SMOOTH || slot == NONE) {
        return;
    }
    let own = faces[i].normal.xyz;
    triangle_normals[slot].n0 = blended_normal(own, placed.groups.x, instance.crease_cos);
    triangle_normals[slot].n1 = blended_normal(own, placed.groups.y, instance.crease_cos);
    triangle_normals[slot].n2 = blended_normal(own, placed.groups.z, instance.crease_cos);
}
