//! The threaded BVH laid out on the GPU (`shaders/threaded.wgsl`) from the node array a
//! [`GpuLbvhBuilder`](super::lbvh::GpuLbvhBuilder) builds there: the per-frame twin of
//! [`crate::bvh::threaded::threaded_nodes`], so a rebuilt tree reaches the stack and threaded walks
//! with no round trip to the host.

use crate::bvh::threaded::GpuThreadedNode;
use crate::gpu::device::compute::{buffer_entry, buffers_bind_group, grid, kernels, storage_buffer};
use crate::gpu::device::timing::PassTimestamps;
use crate::gpu::preamble::records_source;
use crate::gpu::{GpuContext, GpuError};
use crate::records::{GpuBvhFrame, GpuGlobals};

const LAYOUT: &str = include_str!("../shaders/threaded.wgsl");
/// Invocations per workgroup, one node each.
pub const GROUP: u32 = 256;
const FRAME_BYTES: u64 = std::mem::size_of::<GpuBvhFrame>() as u64;

/// The kernels' parameters (`LayoutParams` in types.wgsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LayoutParams {
    /// Nodes: 2n - 1 for n primitives.
    pub node_count: u32,
}

/// The layout's records with a WGSL twin, for the layout test.
#[cfg(feature = "internals")]
pub const LAYOUTS: &[crate::records::layouts::StructLayout] = &[crate::records::layouts::struct_layout!(
    LayoutParams,
    "LayoutParams",
    [node_count]
)];

/// The layout kernels' WGSL.
pub fn shader_source() -> String {
    format!(
        "// Generated: src/gpu/builders/threaded_layout.rs.\nconst GROUP: u32 = {GROUP}u;\n{}\n{LAYOUT}",
        records_source()
    )
}

/// The threaded layout on the GPU: the build's nodes renumbered depth-first into 16-byte nodes with
/// skip links, for the stack and threaded walks.
pub struct GpuThreadedLayout {
    order: wgpu::ComputePipeline,
    nodes: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    node_count: u32,
    /// The threaded nodes (STORAGE | COPY_SRC), in depth-first order.
    pub threaded: wgpu::Buffer,
    /// The quantization frame, laid out as the globals' `bvh_origin`, `bvh_quantum` and
    /// `bvh_inverse_quantum` (COPY_SRC).
    pub frame: wgpu::Buffer,
    timer: Option<PassTimestamps>,
}

impl GpuThreadedLayout {
    /// Compiles the kernels and sizes the buffers for the LBVH of `primitive_count` primitives
    /// whose nodes are in `nodes`.
    pub async fn new(ctx: &GpuContext, nodes: &wgpu::Buffer, primitive_count: usize) -> Result<Self, GpuError> {
        ctx.checked("compiling the threaded BVH layout", || {
            let device = &ctx.device;
            let node_count = (2 * primitive_count).saturating_sub(1) as u32;
            let storage = |label, size, extra| storage_buffer(device, label, size, extra);
            let order = storage("depth-first order", node_count as u64 * 4, wgpu::BufferUsages::empty());
            let threaded = storage(
                "threaded nodes",
                node_count as u64 * std::mem::size_of::<GpuThreadedNode>() as u64,
                wgpu::BufferUsages::COPY_SRC,
            );
            let frame = storage("quantization frame", FRAME_BYTES, wgpu::BufferUsages::COPY_SRC);
            let params = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("layout params"),
                size: 16,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            ctx.queue
                .write_buffer(&params, 0, bytemuck::bytes_of(&LayoutParams { node_count }));
            let read_write = wgpu::BufferBindingType::Storage { read_only: false };
            let entries = [
                buffer_entry(0, wgpu::BufferBindingType::Uniform, false),
                buffer_entry(1, wgpu::BufferBindingType::Storage { read_only: true }, false),
                buffer_entry(2, read_write, false),
                buffer_entry(3, read_write, false),
                buffer_entry(4, read_write, false),
            ];
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("threaded layout"),
                entries: &entries,
            });
            let kernel = kernels(ctx, "threaded layout", shader_source(), &entries);
            let (order_kernel, nodes_kernel) = (kernel("depth_first_order"), kernel("threaded_nodes"));
            let bind_group = buffers_bind_group(
                device,
                "threaded layout",
                &layout,
                &[&params, nodes, &order, &threaded, &frame],
            );
            Ok(Self {
                order: order_kernel,
                nodes: nodes_kernel,
                bind_group,
                node_count,
                threaded,
                frame,
                timer: ctx
                    .timestamps
                    .then(|| PassTimestamps::new(device, "threaded layout", 1)),
            })
        })
        .await
    }

    /// Records the layout of the nodes as they will be when the encoder reaches it.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        self.encode_kernels(encoder, &[&self.order, &self.nodes]);
    }

    /// Records the layout of a tree whose topology is the last one laid out's (a refit): its
    /// depth-first order stands, only the nodes' boxes are written anew.
    pub fn encode_boxes(&self, encoder: &mut wgpu::CommandEncoder) {
        self.encode_kernels(encoder, &[&self.nodes]);
    }

    fn encode_kernels(&self, encoder: &mut wgpu::CommandEncoder, kernels: &[&wgpu::ComputePipeline]) {
        if self.node_count == 0 {
            return;
        }
        let (x, y) = grid(self.node_count.div_ceil(GROUP));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("threaded layout"),
            timestamp_writes: self.timer.as_ref().map(|t| t.compute_writes(0)),
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        for kernel in kernels {
            pass.set_pipeline(kernel);
            pass.dispatch_workgroups(x, y, 1);
        }
        drop(pass);
        if let Some(timer) = &self.timer {
            timer.resolve(encoder);
        }
    }

    /// Records the copy of the frame into a globals buffer (COPY_DST), after [`Self::encode`].
    #[cfg(feature = "internals")]
    pub fn encode_frame_copy(&self, encoder: &mut wgpu::CommandEncoder, globals: &wgpu::Buffer) {
        encode_frame_copy(encoder, &self.frame, globals);
    }

    /// GPU milliseconds of the last layout submitted and finished (None without timestamp queries).
    pub async fn read_ms(&self, ctx: &GpuContext) -> Result<Option<f64>, GpuError> {
        match &self.timer {
            Some(timer) if self.node_count > 0 => Ok(Some(timer.read_ms(ctx).await?[0])),
            _ => Ok(None),
        }
    }

    /// Copies the frame and the nodes back to the host.
    #[cfg(feature = "internals")]
    pub async fn read(
        &self,
        ctx: &GpuContext,
    ) -> Result<(crate::bvh::threaded::QuantizationFrame, Vec<GpuThreadedNode>), GpuError> {
        if self.node_count == 0 {
            return Ok((Default::default(), Vec::new()));
        }
        let frame =
            crate::gpu::device::readback::read_buffer(&ctx.device, &ctx.queue, &self.frame, FRAME_BYTES).await?;
        let frame: GpuBvhFrame = bytemuck::pod_read_unaligned(&frame);
        let size = self.node_count as u64 * std::mem::size_of::<GpuThreadedNode>() as u64;
        let nodes = crate::gpu::device::readback::read_buffer(&ctx.device, &ctx.queue, &self.threaded, size).await?;
        Ok((frame.frame(), bytemuck::pod_collect_to_vec(&nodes)))
    }
}

/// Records the copy of a laid-out frame (a `GpuBvhFrame` buffer) into a globals buffer (COPY_DST).
pub(crate) fn encode_frame_copy(encoder: &mut wgpu::CommandEncoder, frame: &wgpu::Buffer, globals: &wgpu::Buffer) {
    let offset = std::mem::offset_of!(GpuGlobals, bvh_frame) as u64;
    encoder.copy_buffer_to_buffer(frame, 0, globals, offset, FRAME_BYTES);
}
