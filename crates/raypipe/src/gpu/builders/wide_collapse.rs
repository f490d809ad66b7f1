//! The compressed wide BVH collapsed on the GPU (`shaders/wide.wgsl`) from the node array a
//! [`GpuLbvhBuilder`](super::lbvh::GpuLbvhBuilder) builds there: the per-frame twin of
//! [`crate::bvh::wide::wide_texels`], so a rebuilt tree reaches the wide walk with no round trip to
//! the host.
//!
//! One level of wide nodes a dispatch, each sized by the level before it through an indirect
//! dispatch; the host records as many levels as the deepest tree the build can make
//! ([`crate::bvh::lbvh::depth_bound`]), those past the tree's end dispatching no workgroup.

use crate::bvh::wide::{GpuWideTexel, capacity_texels, leaf_texels, node_capacity};
use crate::gpu::device::compute::{buffer_entry, buffers_bind_group, kernels, storage_buffer};
use crate::gpu::device::readback::read_buffer;
use crate::gpu::device::timing::PassTimestamps;
use crate::gpu::preamble::records_source;
use crate::gpu::{GpuContext, GpuError};

const COLLAPSE: &str = include_str!("../shaders/wide.wgsl");
/// Invocations per workgroup, one wide node each.
#[cfg_attr(feature = "internals", visibility::make(pub))]
pub(crate) const GROUP: u32 = 64;

/// The kernels' parameters (`CollapseParams` in types.wgsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct CollapseParams {
    pub primitive_count: u32,
    /// Where the nodes start: after the leaf words.
    pub root_texel: u32,
}

/// The collapse's records with a WGSL twin, for the layout test.
#[cfg(feature = "internals")]
pub const LAYOUTS: &[crate::records::layouts::StructLayout] = &[crate::records::layouts::struct_layout!(
    CollapseParams,
    "CollapseParams",
    [primitive_count, root_texel]
)];

/// The collapse kernels' WGSL.
#[cfg_attr(feature = "internals", visibility::make(pub))]
pub(crate) fn shader_source() -> String {
    format!(
        "// Generated: src/gpu/builders/wide_collapse.rs.\nconst GROUP: u32 = {GROUP}u;\n{}\n{COLLAPSE}",
        records_source()
    )
}

/// The wide collapse on the GPU: the build's binary tree into compressed 8-wide nodes, for the wide
/// walk.
pub struct GpuWideCollapse {
    start: wgpu::ComputePipeline,
    level: wgpu::ComputePipeline,
    next_level: wgpu::ComputePipeline,
    /// Every buffer: the kernels that size a level.
    bind_group: wgpu::BindGroup,
    /// All but the dispatch: the level kernel, which the dispatch sizes.
    level_bind_group: wgpu::BindGroup,
    primitive_count: usize,
    /// Levels recorded: one more than the deepest tree's depth.
    levels: u32,
    dispatch: wgpu::Buffer,
    /// The wide BVH's texels (STORAGE | COPY_SRC): leaf words, then nodes as the counters placed them.
    pub texels: wgpu::Buffer,
    timer: Option<PassTimestamps>,
}

impl GpuWideCollapse {
    /// Compiles the kernels and sizes the buffers for the LBVH of `primitive_count` primitives
    /// whose nodes are in `nodes`, at most `depth_bound` deep.
    pub async fn new(
        ctx: &GpuContext,
        nodes: &wgpu::Buffer,
        primitive_count: usize,
        depth_bound: u32,
    ) -> Result<Self, GpuError> {
        ctx.checked("compiling the wide BVH collapse", || {
            let device = &ctx.device;
            let storage = |label, size, extra| storage_buffer(device, label, size, extra);
            let texels = storage(
                "wide BVH",
                capacity_texels(primitive_count) as u64 * std::mem::size_of::<GpuWideTexel>() as u64,
                wgpu::BufferUsages::COPY_SRC,
            );
            let queue = storage(
                "wide nodes' binary nodes",
                node_capacity(primitive_count) as u64 * 4,
                wgpu::BufferUsages::empty(),
            );
            let counters = storage("collapse counters", 16, wgpu::BufferUsages::empty());
            let dispatch = storage("collapse dispatch", 16, wgpu::BufferUsages::INDIRECT);
            let params = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("collapse params"),
                size: 16,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let root_texel = leaf_texels(primitive_count);
            ctx.queue.write_buffer(
                &params,
                0,
                bytemuck::bytes_of(&CollapseParams {
                    primitive_count: primitive_count as u32,
                    root_texel,
                }),
            );
            // A dispatch may not read its own workgroup count from a buffer it binds, so the level
            // kernel binds all but the dispatch buffer, and the kernels that size a level bind all.
            let read_write = wgpu::BufferBindingType::Storage { read_only: false };
            let buffers = [&params, nodes, &texels, &queue, &counters, &dispatch];
            let bound = |label, count: usize| {
                let mut entries = vec![
                    buffer_entry(0, wgpu::BufferBindingType::Uniform, false),
                    buffer_entry(1, wgpu::BufferBindingType::Storage { read_only: true }, false),
                ];
                entries.extend((2..count as u32).map(|binding| buffer_entry(binding, read_write, false)));
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries: &entries,
                });
                let group = buffers_bind_group(device, label, &layout, &buffers[..count]);
                (entries, group)
            };
            let (sizing_entries, bind_group) = bound("wide collapse sizing", buffers.len());
            let (level_entries, level_bind_group) = bound("wide collapse level", buffers.len() - 1);
            let sizing = kernels(ctx, "wide collapse sizing", shader_source(), &sizing_entries);
            let level = kernels(ctx, "wide collapse level", shader_source(), &level_entries);
            Ok(Self {
                start: sizing("collapse_start"),
                level: level("collapse_level"),
                next_level: sizing("collapse_next_level"),
                bind_group,
                level_bind_group,
                primitive_count,
                levels: depth_bound + 1,
                dispatch,
                texels,
                timer: ctx.timestamps.then(|| PassTimestamps::new(device, "wide collapse", 1)),
            })
        })
        .await
    }

    /// Records the collapse of the nodes as they will be when the encoder reaches it.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        if self.primitive_count == 0 {
            return;
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("wide collapse"),
            timestamp_writes: self.timer.as_ref().map(|t| t.compute_writes(0)),
        });
        for level in 0..self.levels {
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.set_pipeline(if level == 0 { &self.start } else { &self.next_level });
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_bind_group(0, &self.level_bind_group, &[]);
            pass.set_pipeline(&self.level);
            pass.dispatch_workgroups_indirect(&self.dispatch, 0);
        }
        drop(pass);
        if let Some(timer) = &self.timer {
            timer.resolve(encoder);
        }
    }

    /// GPU milliseconds of the last collapse submitted and finished (None without timestamp queries).
    pub async fn read_ms(&self, ctx: &GpuContext) -> Result<Option<f64>, GpuError> {
        match &self.timer {
            Some(timer) if self.primitive_count > 0 => Ok(Some(timer.read_ms(ctx).await?[0])),
            _ => Ok(None),
        }
    }

    /// Copies the texels back to the host, as many as the array may hold.
    pub async fn read(&self, ctx: &GpuContext) -> Result<Vec<GpuWideTexel>, GpuError> {
        let size = self.texels.size();
        let bytes = read_buffer(&ctx.device, &ctx.queue, &self.texels, size).await?;
        let texels: Vec<GpuWideTexel> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(texels[..capacity_texels(self.primitive_count) as usize].to_vec())
    }
}
