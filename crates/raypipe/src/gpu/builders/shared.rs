//! What the GPU builders hand the tracer: buffers they write every frame, which a renderer binds in
//! place of the scene's own.

/// Buffers that already live on the GPU and replace the scene's own in storage memory: the
/// primitives and nodes of a [`GpuLbvhBuilder`](crate::gpu::builders::lbvh::GpuLbvhBuilder)
/// (a [`MovingScene`](crate::gpu::MovingScene)'s, rebuilt there every frame), and the threaded nodes
/// and their quantization frame laid out from them.
#[derive(Clone, Debug)]
pub struct SharedBuffers {
    /// The sphere records, in the build's order.
    pub spheres: wgpu::Buffer,
    /// The triangle records, in the build's order.
    pub triangles: wgpu::Buffer,
    /// The binary nodes.
    pub nodes: wgpu::Buffer,
    /// For the stack and threaded walks.
    pub threaded_nodes: Option<wgpu::Buffer>,
    /// For the wide walk: the compressed wide nodes' texels.
    pub wide: Option<wgpu::Buffer>,
    /// The threaded nodes' frame, a `GpuBvhFrame` the renderer copies into its globals.
    pub bvh_frame: Option<wgpu::Buffer>,
    /// Where skinning on the GPU rewrites the triangles' shading normals.
    pub triangle_normals: Option<wgpu::Buffer>,
}
