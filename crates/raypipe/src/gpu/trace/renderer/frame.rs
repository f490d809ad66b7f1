//! Encoding a frame and reading it back: each sample's passes recorded into a caller's encoder
//! ([`Renderer::encode`]), and the one route from samples to a frame in memory
//! ([`Renderer::render_samples`]; [`Renderer::read_frame`] is one sample of it).

use super::pipelines::TracePipeline;
use super::{Renderer, TimedFrame};
use crate::gpu::GpuError;
use crate::gpu::builders::threaded_layout::encode_frame_copy;
use crate::gpu::trace::shader::COMPUTE_TILE;
use crate::image::Frame;
use crate::records::{GpuCamera, GpuGlobals};
use std::future::Future;

impl Renderer {
    /// Records the next sample per pixel (the first after a restart) into the targets: the trace
    /// pass, and before it, where a rebuild feeds the walks, the copy of its quantization frame into
    /// the globals; with ray queries, the build of the driver's structures where they are new or
    /// their records were rewritten, and with the first sample after a restart where a rebuild
    /// poses their triangles. The sample's index reaches the shader through a queue write, as a
    /// camera does: submit each frame before encoding the next.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(frame) = &self.bvh_frame {
            encode_frame_copy(encoder, frame, &self.globals_buffer);
        }
        if let Some(structures) = &self.structures
            && (self.structures_stale || (structures.follows_gpu() && self.samples() == 0))
        {
            // New or rewritten records, or the triangles a rebuild posed (recorded before, with
            // the first sample after a restart).
            structures.encode_build(encoder);
            self.structures_stale = false;
        }
        let sample = self.samples();
        self.globals.camera.sample = sample;
        let offset = (std::mem::offset_of!(GpuGlobals, camera) + std::mem::offset_of!(GpuCamera, sample)) as u64;
        self.ctx
            .queue
            .write_buffer(&self.globals_buffer, offset, bytemuck::bytes_of(&sample));
        let read = self.accumulation.current;
        let written = &self.accumulation.targets[1 - read];
        let previous = &self.accumulation.reads[read];
        match &self.pipeline {
            TracePipeline::Fragment {
                pipeline,
                miss,
                vertices,
            } => {
                let attachments = [&written.color_view, &written.surface_view].map(|view| {
                    Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                });
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("trace"),
                    color_attachments: &attachments,
                    depth_stencil_attachment: None,
                    timestamp_writes: self.timer.as_ref().map(|t| t.render_writes(0)),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_bind_group(1, previous, &[]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                let (width, height) = written.size();
                match (&self.confinement, miss) {
                    (Some(confinement), Some(miss)) if !confinement.pixels.is_whole(width, height) => {
                        // Every pixel the misses' way first (a shader that traces nothing), then
                        // the tracer over the boxes' pixels, a scissored draw a rectangle.
                        pass.set_pipeline(miss);
                        pass.draw(0..3, 0..1);
                        pass.set_pipeline(pipeline);
                        for rect in &confinement.pixels.rects {
                            pass.set_scissor_rect(rect.x, rect.y, rect.width, rect.height);
                            pass.draw(0..3, 0..1);
                        }
                    }
                    _ => {
                        pass.set_pipeline(pipeline);
                        pass.draw(0..3, 0..1);
                    }
                }
            }
            TracePipeline::Compute(pipeline) => {
                let (width, height) = written.size();
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("trace"),
                    timestamp_writes: self.timer.as_ref().map(|t| t.compute_writes(0)),
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_bind_group(1, previous, &[]);
                pass.dispatch_workgroups(width.div_ceil(COMPUTE_TILE), height.div_ceil(COMPUTE_TILE), 1);
            }
        }
        if let Some(timer) = &self.timer {
            timer.resolve(encoder);
        }
        let accumulation = &mut self.accumulation;
        accumulation.current = 1 - read;
        accumulation.targets[1 - read].samples = sample + 1;
        accumulation.restarted = false;
    }

    /// GPU milliseconds of the last trace pass submitted and finished, where the adapter has
    /// timestamp queries.
    pub async fn read_gpu_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.timer {
            Some(timer) => Ok(Some(timer.read_ms(&self.ctx).await?[0])),
            None => Ok(None),
        }
    }

    /// With ray queries: builds the driver's acceleration structures again before the next sample,
    /// over the records as they are (as a moving scene's are every frame); for benchmarks that time
    /// the build.
    pub fn rebuild_structures(&mut self) {
        self.structures_stale = self.structures.is_some();
    }

    /// GPU milliseconds of the last build of the driver's acceleration structures submitted and
    /// finished, with ray queries, where the device times work between passes.
    pub async fn read_structures_build_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.structures {
            Some(structures) => structures.read_build_ms(&self.ctx).await,
            None => Ok(None),
        }
    }

    /// Traces one frame, one sample per pixel at the centres, and reads both targets back.
    pub async fn read_frame(&mut self) -> Result<TimedFrame, GpuError> {
        self.render_samples(1, |_| {}, |_| {}).await
    }

    /// The one route from samples to a frame in memory: traces `samples` samples per pixel from the
    /// start (at least 1), one submission each so that no submission runs long, with `prepare` (a
    /// BVH rebuild, say) recorded before the first in its command buffer, so that the GPU runs both
    /// without a round trip to the host; calls `sample_done` with the count finished after each
    /// (for progress bars); reads the average back (as [`crate::image::sample_mean`] computes it,
    /// for the CPU reference too). The GPU time is the sum of the trace passes'.
    pub async fn render_samples(
        &mut self,
        samples: u32,
        prepare: impl FnOnce(&mut wgpu::CommandEncoder),
        mut sample_done: impl FnMut(u32),
    ) -> Result<TimedFrame, GpuError> {
        self.ctx.live()?;
        self.restart();
        let mut prepare = Some(prepare);
        let mut gpu_ms = self.timer.as_ref().map(|_| 0.0);
        let ctx = self.ctx.clone();
        for sample in 0..samples.max(1) {
            ctx.checked("rendering", || {
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                if let Some(prepare) = prepare.take() {
                    prepare(&mut encoder);
                }
                self.encode(&mut encoder);
                ctx.queue.submit([encoder.finish()]);
                Ok(())
            })
            .await?;
            let ms = self.read_gpu_ms().await.map_err(|e| ctx.explain(e))?;
            if let (Some(total), Some(ms)) = (gpu_ms.as_mut(), ms) {
                *total += ms;
            }
            sample_done(sample + 1);
        }
        Ok(TimedFrame {
            frame: self.read_back().await?,
            gpu_ms,
        })
    }

    /// Reads the targets' sums back as a frame: mean radiance, the count's total (rays) or mean
    /// (cost), the centre sample's normal and depth. The future borrows nothing: the copies are
    /// recorded and submitted here, so that a host that draws on meanwhile (a web page) reads the
    /// frame shown now.
    pub fn read_back(&self) -> impl Future<Output = Result<Frame, GpuError>> + 'static {
        let ctx = self.ctx.clone();
        let targets = self.targets();
        let [color, surface] = self.readbacks.clone();
        let scopes = ctx.error_scopes("reading the frame back");
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        color.encode_copy(&mut encoder, &targets.color);
        surface.encode_copy(&mut encoder, &targets.surface);
        ctx.queue.submit([encoder.finish()]);
        let copied = scopes.pop();
        let (width, height) = self.size();
        let samples = targets.samples().max(1);
        let count = self.options.count;
        async move {
            let read = async {
                copied.await?;
                let mut frame = Frame::new(width, height);
                let sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&color.read(&ctx.device).await?);
                frame.color = sums
                    .into_iter()
                    .map(|sum| crate::image::sample_mean(glam::Vec4::from_array(sum), samples, count))
                    .collect();
                frame.surface = bytemuck::pod_collect_to_vec(&surface.read(&ctx.device).await?);
                Ok(frame)
            };
            read.await.map_err(|e| ctx.explain(e))
        }
    }
}
