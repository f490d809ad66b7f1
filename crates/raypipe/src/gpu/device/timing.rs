//! GPU time of passes from timestamp queries: a begin and an end timestamp per pass.

use super::readback::map_read;
use crate::gpu::{GpuContext, GpuError};

/// Timestamps around `passes` render or compute passes, resolved into a buffer the host reads.
pub(crate) struct PassTimestamps {
    passes: u32,
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
}

impl PassTimestamps {
    pub fn new(device: &wgpu::Device, label: &str, passes: u32) -> Self {
        let buffer = |usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16 * passes as u64,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            passes,
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * passes,
            }),
            resolve: buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
            read: buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
        }
    }

    pub fn render_writes(&self, pass: u32) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * pass),
            end_of_pass_write_index: Some(2 * pass + 1),
        }
    }

    pub fn compute_writes(&self, pass: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * pass),
            end_of_pass_write_index: Some(2 * pass + 1),
        }
    }

    /// Records pass `pass`'s begin (`end` false) or end timestamp between commands, for work that
    /// is no pass (acceleration structure builds): where the device has
    /// `TIMESTAMP_QUERY_INSIDE_ENCODERS` ([`GpuContext::encoder_timestamps`]).
    pub fn write(&self, encoder: &mut wgpu::CommandEncoder, pass: u32, end: bool) {
        encoder.write_timestamp(&self.queries, 2 * pass + end as u32);
    }

    /// Records the copy of this submission's timestamps to the host-readable buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2 * self.passes, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, 16 * self.passes as u64);
    }

    /// Milliseconds of each pass, once the submission that resolved them has finished.
    pub async fn read_ms(&self, ctx: &GpuContext) -> Result<Vec<f64>, GpuError> {
        let ticks: Vec<u64> = map_read(&ctx.device, &self.read, bytemuck::pod_collect_to_vec).await?;
        let period_ns = ctx.queue.get_timestamp_period() as f64;
        Ok(ticks
            .chunks(2)
            .map(|t| t[1].wrapping_sub(t[0]) as f64 * period_ns / 1e6)
            .collect())
    }
}
