use raypipe::gpu::device::context::{describe, instance};
use std::process::ExitCode;

pub fn run() -> anyhow::Result<ExitCode> {
    let instance = instance(wgpu::Backends::all());
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    if adapters.is_empty() {
        crate::say!("no GPU adapters found; `render --device auto` will use the CPU reference tracer");
    }
    for adapter in adapters {
        let limits = adapter.limits();
        let renders_to = |format| {
            adapter
                .get_texture_format_features(format)
                .allowed_usages
                .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        };
        let info = adapter.get_info();
        crate::say!("{}", describe(&info));
        crate::say!("  max texture 2D:             {}", limits.max_texture_dimension_2d);
        crate::say!(
            "  max uniform binding:        {} bytes",
            limits.max_uniform_buffer_binding_size
        );
        crate::say!(
            "  max storage binding:        {} bytes",
            limits.max_storage_buffer_binding_size
        );
        crate::say!("  max buffer size:            {} bytes", limits.max_buffer_size);
        crate::say!(
            "  storage buffers per stage:  {}",
            limits.max_storage_buffers_per_shader_stage
        );
        crate::say!(
            "  sampled textures per stage: {}",
            limits.max_sampled_textures_per_shader_stage
        );
        crate::say!(
            "  timestamp queries:          {}",
            adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY)
        );
        // What `--accel rayquery` needs.
        crate::say!(
            "  ray queries:                {}",
            adapter.features().contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
        );
        if adapter.features().contains(wgpu::Features::SUBGROUP) {
            crate::say!(
                "  subgroups:                  {} to {} invocations",
                info.subgroup_min_size,
                info.subgroup_max_size
            );
        } else {
            crate::say!("  subgroups:                  none");
        }
        crate::say!(
            "  rgba32uint render target:   {}",
            renders_to(wgpu::TextureFormat::Rgba32Uint)
        );
        crate::say!(
            "  rgba32float render target:  {}",
            renders_to(wgpu::TextureFormat::Rgba32Float)
        );
    }
    Ok(ExitCode::SUCCESS)
}
