//! The LBVH build on the GPU: `shaders/lbvh.wgsl`'s and `shaders/radix_sort.wgsl`'s kernels in
//! three compute passes (morton, sort, hierarchy: bottom-up merges that write the bounds and links
//! too, as on the CPU), each timed with timestamp queries where the adapter has them. The node array
//! stays on the GPU, ready for the fragment shader; `read_nodes` fetches it for tests and stats.
//!
//! Morton codes are 30-bit or 63-bit, as on the CPU; the width picks the key type the kernels are
//! compiled with.

use super::shared::SharedBuffers;
use crate::bvh::BuildTimings;
use crate::bvh::layout::GpuNode;
use crate::bvh::morton::MortonBits;
use crate::gpu::Capacity;
use crate::gpu::device::compute::{buffer_entry, grid, kernels, storage_buffer};
use crate::gpu::device::readback::read_buffer;
use crate::gpu::device::timing::PassTimestamps;
use crate::gpu::{GpuContext, GpuError};
use crate::modes::MemoryMode;
use crate::records::{GpuSphere, GpuTriangle, PackedScene};
use std::num::NonZeroU64;

mod source;

use source::{
    BLOCK, BuildParams, HISTOGRAM_ITEMS, PARAMS_STRIDE, PHASES, SCRATCH_BLOCKS, SCRATCH_WORDS_PER_BLOCK, pair_bytes,
    sort_passes, sort_words,
};
pub use source::{BuildVariant, Codes, SiblingBoxes, SortRanking};
#[cfg(feature = "internals")]
pub use source::{DIGIT_BITS, GROUP, LAYOUTS, shader_source};
#[cfg(not(feature = "internals"))]
use source::{DIGIT_BITS, GROUP, shader_source};

struct Kernels {
    bounds_partial: wgpu::ComputePipeline,
    bounds_final: wgpu::ComputePipeline,
    morton: wgpu::ComputePipeline,
    sort_histogram: wgpu::ComputePipeline,
    sort_digit_starts: wgpu::ComputePipeline,
    sort_pass: wgpu::ComputePipeline,
    split_prefixes: wgpu::ComputePipeline,
    merge: wgpu::ComputePipeline,
    refit: wgpu::ComputePipeline,
}

/// A GPU LBVH builder: kernels compiled once, buffers kept from build to build while the
/// primitive count stays the same.
pub struct GpuLbvhBuilder {
    ctx: GpuContext,
    bits: MortonBits,
    variant: BuildVariant,
    kernels: Kernels,
    layout: wgpu::BindGroupLayout,
    buffers: Buffers,
    timer: Option<PassTimestamps>,
    refit_timer: Option<PassTimestamps>,
}

/// The buffers of a build over `count` primitives.
pub struct Buffers {
    sphere_count: u32,
    triangle_count: u32,
    /// [pairs A in, B out], [B in, A out].
    bind_groups: [wgpu::BindGroup; 2],
    /// The spheres the build reads; write new positions here before each build.
    pub spheres: wgpu::Buffer,
    /// The triangles the build reads (primitives `sphere_count..`).
    pub triangles: wgpu::Buffer,
    pairs: wgpu::Buffer,
    climb: wgpu::Buffer,
    /// The built nodes (STORAGE | COPY_SRC), the layout of `bvh::layout`.
    pub nodes: wgpu::Buffer,
}

impl GpuLbvhBuilder {
    /// Compiles the kernels for Morton codes of `bits` and sizes the buffers for `spheres` spheres and
    /// `triangles` triangles.
    pub async fn new(ctx: &GpuContext, bits: MortonBits, spheres: usize, triangles: usize) -> Result<Self, GpuError> {
        Self::with_variant(ctx, bits, spheres, triangles, BuildVariant::best(ctx)).await
    }

    /// Like [`GpuLbvhBuilder::new`], with the kernels' variant chosen.
    pub async fn with_variant(
        ctx: &GpuContext,
        bits: MortonBits,
        spheres: usize,
        triangles: usize,
        variant: BuildVariant,
    ) -> Result<Self, GpuError> {
        ctx.checked("compiling the GPU LBVH build", || {
            let device = &ctx.device;
            let rw = wgpu::BufferBindingType::Storage { read_only: false };
            let read = wgpu::BufferBindingType::Storage { read_only: true };
            let mut entries = vec![
                buffer_entry(0, wgpu::BufferBindingType::Uniform, true),
                buffer_entry(1, read, false),
            ];
            entries.extend((2..=7).map(|b| buffer_entry(b, rw, false)));
            entries.push(buffer_entry(8, read, false));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("lbvh build"),
                entries: &entries,
            });
            let kernel = kernels(ctx, "lbvh", shader_source(bits, variant), &entries);
            let kernels = Kernels {
                bounds_partial: kernel("bounds_partial"),
                bounds_final: kernel("bounds_final"),
                morton: kernel("morton"),
                sort_histogram: kernel("sort_histogram"),
                sort_digit_starts: kernel("sort_digit_starts"),
                sort_pass: kernel(variant.ranking.entry_point()),
                split_prefixes: kernel("split_prefixes"),
                merge: kernel("merge"),
                refit: kernel("refit"),
            };
            let buffers = Buffers::new(ctx, &layout, bits, variant, spheres, triangles)?;
            Ok(Self {
                ctx: ctx.clone(),
                bits,
                variant,
                kernels,
                layout,
                buffers,
                timer: ctx
                    .timestamps
                    .then(|| PassTimestamps::new(&ctx.device, "build phases", PHASES as u32)),
                refit_timer: ctx.timestamps.then(|| PassTimestamps::new(&ctx.device, "refit", 1)),
            })
        })
        .await
    }

    /// The kernels' variant this builder runs.
    pub fn variant(&self) -> BuildVariant {
        self.variant
    }

    /// Sizes the buffers for `spheres` spheres and `triangles` triangles (a no-op when the counts are
    /// unchanged).
    pub async fn resize(&mut self, spheres: usize, triangles: usize) -> Result<(), GpuError> {
        if (spheres, triangles) != (self.buffers.sphere_count as usize, self.buffers.triangle_count as usize) {
            let ctx = &self.ctx;
            self.buffers = ctx
                .checked("sizing the GPU LBVH build", || {
                    Buffers::new(ctx, &self.layout, self.bits, self.variant, spheres, triangles)
                })
                .await?;
        }
        Ok(())
    }

    /// The device it builds on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Its buffers: the primitives, the keys, the nodes.
    pub fn buffers(&self) -> &Buffers {
        &self.buffers
    }

    /// Primitives: spheres and triangles.
    pub fn count(&self) -> usize {
        self.buffers.count() as usize
    }

    /// New sphere records for the next build, as many as it was made for.
    pub fn write_spheres(&self, spheres: &[GpuSphere]) {
        assert_eq!(spheres.len(), self.buffers.sphere_count as usize);
        self.ctx
            .queue
            .write_buffer(&self.buffers.spheres, 0, bytemuck::cast_slice(spheres));
    }

    /// New triangle records for the next build, as many as it was made for.
    pub fn write_triangles(&self, triangles: &[GpuTriangle]) {
        assert_eq!(triangles.len(), self.buffers.triangle_count as usize);
        self.ctx
            .queue
            .write_buffer(&self.buffers.triangles, 0, bytemuck::cast_slice(triangles));
    }

    /// Writes a scene's primitives, sized for them.
    pub async fn write_scene(&mut self, scene: &PackedScene) -> Result<(), GpuError> {
        self.resize(scene.spheres.len(), scene.triangles.len()).await?;
        self.write_spheres(&scene.spheres);
        self.write_triangles(&scene.triangles);
        Ok(())
    }

    /// The Morton code width the kernels were compiled for.
    pub fn bits(&self) -> MortonBits {
        self.bits
    }

    /// Replaces the Morton phase with given codes (of the builder's width), for comparisons with
    /// the CPU build.
    pub fn write_codes(&self, codes: &[u64]) {
        assert_eq!(codes.len(), self.count());
        // The words of each pair, as the preamble's `Pair` lays them out.
        let mut words = Vec::with_capacity(codes.len() * pair_bytes(self.bits) as usize / 4);
        for (i, &code) in codes.iter().enumerate() {
            match self.bits {
                MortonBits::Bits30 => words.extend([code as u32, i as u32]),
                MortonBits::Bits63 => words.extend([code as u32, (code >> 32) as u32, i as u32, 0]),
            }
        }
        self.ctx
            .queue
            .write_buffer(&self.buffers.pairs, 0, bytemuck::cast_slice(&words));
    }

    /// Records a build into `encoder`: from the spheres' codes computed here, or from the codes of
    /// `write_codes`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, codes: Codes) {
        let b = &self.buffers;
        let n = b.count();
        if n == 0 {
            return;
        }
        let sort_bytes = sort_words(self.bits, self.variant.ranking, n as u64) * 4;
        encoder.clear_buffer(&b.climb, 0, Some(sort_bytes));
        let blocks = n.div_ceil(BLOCK);
        let items = n.div_ceil(GROUP);
        let k = &self.kernels;
        let a = &b.bind_groups[0];
        let phase = |encoder: &mut wgpu::CommandEncoder,
                     index: usize,
                     steps: &[(&wgpu::ComputePipeline, &wgpu::BindGroup, u32, u32)]| {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(PHASE_NAMES[index]),
                timestamp_writes: self.timer.as_ref().map(|t| t.compute_writes(index as u32)),
            });
            // `pass_index` picks the sort pass's parameters (0 for the other kernels).
            for &(pipeline, bind_group, pass_index, groups) in steps {
                let (x, y) = grid(groups);
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind_group, &[pass_index * PARAMS_STRIDE as u32]);
                pass.dispatch_workgroups(x, y, 1);
            }
        };
        if codes == Codes::Given {
            phase(encoder, 0, &[]);
        } else {
            phase(
                encoder,
                0,
                &[
                    (&k.bounds_partial, a, 0, blocks),
                    (&k.bounds_final, a, 0, 1),
                    (&k.morton, a, 0, items),
                ],
            );
        }
        let mut sort = vec![
            (&k.sort_histogram, a, 0, n.div_ceil(GROUP * HISTOGRAM_ITEMS)),
            (&k.sort_digit_starts, a, 0, 1),
        ];
        for pass in 0..sort_passes(self.bits) {
            sort.push((
                &k.sort_pass,
                &b.bind_groups[pass as usize % 2],
                pass,
                n.div_ceil(self.variant.ranking.tile()),
            ));
        }
        phase(encoder, 1, &sort);
        // The sort's words in `climb` give way to the merges' exchange words (0: nobody arrived, no
        // box stored).
        if n > 1 {
            let words = self.variant.sibling_boxes.words_per_split() * (n as u64 - 1);
            encoder.clear_buffer(&b.climb, 0, Some(words * 4));
        }
        let invocations = n.div_ceil(self.variant.merge_run());
        phase(
            encoder,
            2,
            &[
                (&k.split_prefixes, a, 0, n.div_ceil(GROUP)),
                (&k.merge, a, 0, invocations.div_ceil(GROUP)),
            ],
        );
        if let Some(timer) = &self.timer {
            timer.resolve(encoder);
        }
    }

    /// Records a refit of the last tree built: its boxes recomputed bottom-up over the primitives as
    /// they are now, its topology and links kept. Cheaper than a build; the tree degrades as the
    /// primitives move away from where it was built.
    pub fn encode_refit(&self, encoder: &mut wgpu::CommandEncoder) {
        let n = self.buffers.count();
        if n == 0 {
            return;
        }
        if n > 1 {
            let words = self.variant.sibling_boxes.words_per_split() * (n as u64 - 1);
            encoder.clear_buffer(&self.buffers.climb, 0, Some(words * 4));
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("refit"),
            timestamp_writes: self.refit_timer.as_ref().map(|t| t.compute_writes(0)),
        });
        let (x, y) = grid(n.div_ceil(self.variant.merge_run()).div_ceil(GROUP));
        pass.set_pipeline(&self.kernels.refit);
        pass.set_bind_group(0, &self.buffers.bind_groups[0], &[0]);
        pass.dispatch_workgroups(x, y, 1);
        drop(pass);
        if let Some(timer) = &self.refit_timer {
            timer.resolve(encoder);
        }
    }

    /// GPU time of the last refit submitted and finished, where the adapter has timestamps.
    pub async fn read_refit_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.refit_timer {
            Some(timer) => Ok(Some(timer.read_ms(&self.ctx).await?[0])),
            None => Ok(None),
        }
    }

    /// Builds and waits; returns the GPU time of each phase (zeros where the adapter has no
    /// timestamp queries).
    pub async fn build(&self, codes: Codes) -> Result<BuildTimings, GpuError> {
        self.ctx
            .checked("building the LBVH on the GPU", || {
                let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
                self.encode(&mut encoder, codes);
                self.ctx.queue.submit([encoder.finish()]);
                Ok(())
            })
            .await?;
        // Without timestamps nothing below waits for the build.
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        self.read_timings().await
    }

    /// The GPU time of each phase of the last build that was submitted and finished (zeros where
    /// the adapter has no timestamp queries).
    pub async fn read_timings(&self) -> Result<BuildTimings, GpuError> {
        match &self.timer {
            Some(timer) if self.count() > 0 => {
                let ms = timer.read_ms(&self.ctx).await?;
                Ok(BuildTimings {
                    morton: ms[0],
                    sort: ms[1],
                    hierarchy: ms[2],
                    // The merges write the bounds and links with the hierarchy.
                    ..BuildTimings::default()
                })
            }
            _ => Ok(BuildTimings::default()),
        }
    }

    /// The primitives and nodes, for a renderer to read in place.
    pub fn shared_buffers(&self) -> SharedBuffers {
        SharedBuffers {
            spheres: self.buffers.spheres.clone(),
            triangles: self.buffers.triangles.clone(),
            nodes: self.buffers.nodes.clone(),
            threaded_nodes: None,
            wide: None,
            bvh_frame: None,
            triangle_normals: None,
        }
    }

    /// Copies the node array back to the host.
    pub async fn read_nodes(&self) -> Result<Vec<GpuNode>, GpuError> {
        let size = (2 * self.count() as u64).saturating_sub(1) * std::mem::size_of::<GpuNode>() as u64;
        if size == 0 {
            return Ok(Vec::new());
        }
        let bytes = read_buffer(&self.ctx.device, &self.ctx.queue, &self.buffers.nodes, size).await?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

impl Buffers {
    /// Primitives: spheres, then triangles.
    fn count(&self) -> u32 {
        self.sphere_count + self.triangle_count
    }

    fn new(
        ctx: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        bits: MortonBits,
        variant: BuildVariant,
        sphere_count: usize,
        triangle_count: usize,
    ) -> Result<Self, GpuError> {
        let count = sphere_count + triangle_count;
        let n = count as u64;
        let node_bytes = node_room(ctx, count)?;
        let device = &ctx.device;
        let blocks = n.div_ceil(BLOCK as u64);
        // A binding may not be empty: an absent kind of primitive gets room for one record.
        let record_room = |records: usize, size: usize| records.max(1) as u64 * size as u64;
        let spheres = storage_buffer(
            device,
            "build spheres",
            record_room(sphere_count, std::mem::size_of::<GpuSphere>()),
            wgpu::BufferUsages::COPY_DST,
        );
        // Ray queries build the driver's triangle structures from these records where they move
        // on the GPU (`super::rayquery`).
        let blas_input = if ctx.ray_queries {
            wgpu::BufferUsages::BLAS_INPUT
        } else {
            wgpu::BufferUsages::empty()
        };
        let triangles = storage_buffer(
            device,
            "build triangles",
            record_room(triangle_count, std::mem::size_of::<GpuTriangle>()),
            wgpu::BufferUsages::COPY_DST | blas_input,
        );
        let pairs = storage_buffer(device, "pairs A", n * pair_bytes(bits), wgpu::BufferUsages::COPY_DST);
        let pairs_b = storage_buffer(device, "pairs B", n * pair_bytes(bits), wgpu::BufferUsages::empty());
        let scratch = storage_buffer(
            device,
            "build scratch",
            (SCRATCH_BLOCKS as u64 + SCRATCH_WORDS_PER_BLOCK * blocks) * 4,
            wgpu::BufferUsages::empty(),
        );
        let splits = storage_buffer(
            device,
            "split prefixes",
            n.saturating_sub(1) * 4,
            wgpu::BufferUsages::empty(),
        );
        // Per split: the exchange word, and with atomic boxes the two children's.
        let climb_words =
            (variant.sibling_boxes.words_per_split() * n.saturating_sub(1)).max(sort_words(bits, variant.ranking, n));
        let climb = storage_buffer(device, "climb", climb_words * 4, wgpu::BufferUsages::COPY_DST);
        let nodes = storage_buffer(device, "nodes", node_bytes, wgpu::BufferUsages::COPY_SRC);
        let params = params_buffer(ctx, bits, count, sphere_count);
        let bind_group = |pairs_in: &wgpu::Buffer, pairs_out: &wgpu::Buffer| {
            let resources = [
                &spheres, pairs_in, pairs_out, &scratch, &splits, &climb, &nodes, &triangles,
            ];
            let mut entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &params,
                    offset: 0,
                    size: NonZeroU64::new(std::mem::size_of::<BuildParams>() as u64),
                }),
            }];
            entries.extend(resources.iter().enumerate().map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32 + 1,
                resource: b.as_entire_binding(),
            }));
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("lbvh build"),
                layout,
                entries: &entries,
            })
        };
        let bind_groups = [bind_group(&pairs, &pairs_b), bind_group(&pairs_b, &pairs)];
        Ok(Self {
            sphere_count: sphere_count as u32,
            triangle_count: triangle_count as u32,
            bind_groups,
            spheres,
            triangles,
            pairs,
            climb,
            nodes,
        })
    }
}

/// The bytes of the node array of `count` primitives, where a storage binding holds them.
fn node_room(ctx: &GpuContext, count: usize) -> Result<u64, GpuError> {
    let allowed = ctx.limits().max_storage_buffer_binding_size;
    let node_bytes = (2 * count as u64).saturating_sub(1) * std::mem::size_of::<GpuNode>() as u64;
    if node_bytes > allowed {
        return Err(GpuError::TooBig {
            memory: MemoryMode::Storage,
            array: "node",
            records: (2 * count).saturating_sub(1),
            needed: Capacity::Bytes(node_bytes),
            allowed: Capacity::Bytes(allowed),
        });
    }
    Ok(node_bytes)
}

/// The kernels' parameters, one [`BuildParams`] per sort pass at [`PARAMS_STRIDE`] (a dynamic
/// offset picks the pass's digit).
fn params_buffer(ctx: &GpuContext, bits: MortonBits, count: usize, sphere_count: usize) -> wgpu::Buffer {
    let params = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("build params"),
        size: PARAMS_STRIDE * sort_passes(bits) as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    for pass in 0..sort_passes(bits) {
        let p = BuildParams {
            count: count as u32,
            shift: pass * DIGIT_BITS,
            sphere_count: sphere_count as u32,
        };
        ctx.queue
            .write_buffer(&params, pass as u64 * PARAMS_STRIDE, bytemuck::bytes_of(&p));
    }
    params
}

const PHASE_NAMES: [&str; PHASES] = ["morton", "sort", "hierarchy"];
