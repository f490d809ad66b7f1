// Decoders for the texture route: each record arrives as texels written on the host by
// GpuRecord::push_texels (src/records/texels.rs): rgba32float, with integer fields as exact float
// values, or rgba32uint for records of integers only.

fn texel_coord(index: u32) -> vec2<u32> {
    return vec2<u32>(index % TEXELS_PER_ROW, index / TEXELS_PER_ROW);
}

fn sphere_from_texels(t0: vec4<f32>, t1: vec4<f32>) -> Sphere {
    return Sphere(t0.xyz, t0.w, u32(t1.x));
}

fn triangle_from_texels(t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>) -> Triangle {
    return Triangle(t0.xyz, u32(t0.w), t1.xyz, link_from_texel(t1.w), t2.xyz, link_from_texel(t2.w));
}

// The attribute blocks are texels already, in every memory mode.
fn triangle_attributes_from_texels(t0: vec4<f32>) -> vec4<f32> {
    return t0;
}


fn triangle_normals_from_texels(t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>) -> TriangleNormals {
    return TriangleNormals(t0.xyz, t1.xyz, t2.xyz);
}

fn plane_from_texels(t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>, t3: vec4<f32>) -> Plane {
    return Plane(t0.xyz, u32(t0.w), t1.xyz, u32(t1.w), t2.xyz, t2.w, t3.xyz);
}

fn light_from_texels(t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>, t3: vec4<f32>) -> Light {
    return Light(t0.xyz, u32(t0.w), t1.xyz, t1.w, t2.xyz, t2.w, t3.x);
}

// The materials-and-maps array is texels already, in every memory mode.
fn shading_from_texels(t0: vec4<f32>) -> vec4<f32> {
    return t0;
}

fn material_from_texels(t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>, t3: vec4<f32>, t4: vec4<f32>, t5: vec4<f32>, t6: vec4<f32>, t7: vec4<f32>, t8: vec4<f32>) -> Material {
    return Material(t0.xyz, t0.w, t1.x, t1.y, t1.z, t1.w, t2.xyz, u32(t2.w), t3.xyz, t3.w, t4.x, t4.y, t4.z,
        link_from_texel(t4.w), link_from_texel(t5.x), link_from_texel(t5.y), link_from_texel(t5.z), t5.w, t6.x,
        link_from_texel(t6.y), t6.z, t7.xyz, u32(t7.w), link_from_texel(t8.x), link_from_texel(t8.y));
}

fn texture_map_from_texels(t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>) -> TextureMap {
    let size = vec4<u32>(t0);
    return TextureMap(size.x, size.y, size.z, size.w, t1.xyz, u32(t1.w), t2.xyz, u32(t2.w));
}

// Node links travel as exact floats, with NONE and LEAF as -1.
fn link_from_texel(value: f32) -> u32 {
    return select(u32(value), NONE, value < 0.0);
}

fn node_from_texels(t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>) -> BvhNode {
    return BvhNode(t0.xyz, link_from_texel(t0.w), t1.xyz, link_from_texel(t1.w), link_from_texel(t2.x), link_from_texel(t2.y));
}

// Threaded nodes are integers only: one rgba32uint texel, the buffer's bytes.
fn threaded_node_from_texels(t0: vec4<u32>) -> ThreadedNode {
    return ThreadedNode(t0.xyz, t0.w);
}

// The wide BVH's texels are words already: one rgba32uint texel.
fn wide_from_texels(t0: vec4<u32>) -> WideTexel {
    return WideTexel(t0);
}
