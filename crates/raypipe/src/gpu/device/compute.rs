//! What the compute passes share: storage buffers, their bindings, kernels of one module under one layout, and
//! workgroup grids.

use crate::gpu::GpuContext;
use crate::gpu::device::pipelines::PipelineKey;
use std::cell::OnceCell;
use std::sync::Arc;

/// A storage buffer with `extra` usages, at least 16 bytes (a binding may not be empty).
pub(crate) fn storage_buffer(device: &wgpu::Device, label: &str, size: u64, extra: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | extra,
        mapped_at_creation: false,
    })
}

/// A buffer binding of the compute stage.
pub(crate) fn buffer_entry(
    binding: u32,
    ty: wgpu::BufferBindingType,
    dynamic_offset: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic_offset,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A bind group of whole buffers, bound at 0, 1, 2, ... in the order given.
pub(crate) fn buffers_bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(i, buffer)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// The kernels of `source` by entry point, all bound by a layout of `entries`: a maker that takes
/// each from the device's compiled pipelines, compiling the module the first time one is missing.
///
/// Workgroup memory is not zeroed first: every kernel writes its slots before it reads them. Where
/// the driver cannot zero it (GL), naga writes the zeroing into the shader as one invocation
/// assigning whole array constructors of 256 elements, which llvmpipe took minutes to compile at
/// the first dispatch (110 s for the bounds kernels, 195 s for the sort's; now seconds).
pub(crate) fn kernels<'a>(
    ctx: &'a GpuContext,
    label: &'a str,
    source: String,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> impl Fn(&str) -> wgpu::ComputePipeline + 'a {
    let device = &ctx.device;
    let source: Arc<str> = source.into();
    let descriptor = format!("{entries:?}, workgroup memory not zeroed");
    let entries = entries.to_vec();
    let compiled = OnceCell::new();
    move |entry_point| {
        let key = PipelineKey::new(&source, entry_point, descriptor.clone());
        ctx.pipelines.compute(key, || {
            let (module, pipeline_layout) = compiled.get_or_init(|| {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(label),
                    source: wgpu::ShaderSource::Wgsl(source.to_string().into()),
                });
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries: &entries,
                });
                let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(label),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                });
                (module, pipeline_layout)
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry_point),
                layout: Some(pipeline_layout),
                module,
                entry_point: Some(entry_point),
                compilation_options: wgpu::PipelineCompilationOptions {
                    zero_initialize_workgroup_memory: false,
                    ..Default::default()
                },
                cache: None,
            })
        })
    }
}

/// One dimension of a dispatch holds at most 65,535 workgroups.
const MAX_GROUPS_X: u32 = 65535;

/// `groups` workgroups (at least one) as a 2D grid; kernels flatten it as `wid.y * groups.x + wid.x`.
pub fn grid(groups: u32) -> (u32, u32) {
    let x = groups.clamp(1, MAX_GROUPS_X);
    (x, groups.div_ceil(x).max(1))
}
