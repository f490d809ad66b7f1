//! Building the tracer's pipeline: the full-screen triangle's render pipeline (and the miss
//! shader for the pixels outside the traced region) or the compute kernel, the scene's bind group,
//! and what each needs of the adapter.

use super::targets::{TARGET_FORMAT, previous_sample_entries, tracer_stage};
use crate::gpu::builders::rayquery::AccelStructures;
use crate::gpu::device::pipelines::PipelineKey;
use crate::gpu::trace::shader::ray_query_binding;
use crate::gpu::trace::upload::SceneResources;
use crate::gpu::{GpuContext, GpuError};
use crate::modes::Pipeline;
use std::cell::OnceCell;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// A triangle whose clip-space corners cover the whole viewport.
const FULLSCREEN_TRIANGLE: [[f32; 2]; 3] = [[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]];

/// A scene uploaded and a pipeline built for it, ready to trace frames into its targets.
/// The tracer's pipeline: the full-screen triangle's, or the compute kernel's.
pub(super) enum TracePipeline {
    Fragment {
        pipeline: wgpu::RenderPipeline,
        /// Where the tracer is confined to the scene's projected box: the shader for the pixels
        /// outside it (`fs_miss`).
        miss: Option<wgpu::RenderPipeline>,
        vertices: wgpu::Buffer,
    },
    Compute(wgpu::ComputePipeline),
}

/// What the pipeline needs of the adapter beyond the fragment stage's rgba32uint targets.
pub(super) fn check_pipeline(ctx: &GpuContext, pipeline: Pipeline) -> Result<(), GpuError> {
    let usages = ctx.adapter.get_texture_format_features(TARGET_FORMAT).allowed_usages;
    let unsupported = |what| {
        Err(GpuError::PipelineUnsupported {
            adapter: ctx.describe(),
            pipeline,
            what,
        })
    };
    match pipeline {
        Pipeline::Fragment if !usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT) => {
            unsupported("render to rgba32uint targets")
        }
        Pipeline::Compute
            if !ctx
                .adapter
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS) =>
        {
            unsupported("run compute shaders")
        }
        Pipeline::Compute if !usages.contains(wgpu::TextureUsages::STORAGE_BINDING) => {
            unsupported("write rgba32uint storage textures")
        }
        _ => Ok(()),
    }
}

/// What group 0 of the tracer binds.
#[derive(Clone, Copy)]
pub(super) struct SceneBindings<'a> {
    /// At binding 0.
    pub(super) globals: &'a wgpu::Buffer,
    /// The scene's record arrays and the textures' texels.
    pub(super) resources: &'a SceneResources,
    /// With ray queries, after the texels.
    pub(super) structures: Option<&'a AccelStructures>,
}

/// Group 0 of the tracer: the globals at binding 0, then the scene's records; its layout, the
/// layout's entries and the group.
pub(super) fn scene_bind_group(
    device: &wgpu::Device,
    kind: Pipeline,
    bindings: &SceneBindings,
) -> (wgpu::BindGroupLayout, Vec<wgpu::BindGroupLayoutEntry>, wgpu::BindGroup) {
    let SceneBindings {
        globals,
        resources,
        structures,
    } = *bindings;
    let ray_queries = ray_query_binding(&resources.arrays);
    let mut layout_entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: tracer_stage(kind),
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }];
    layout_entries.extend_from_slice(&resources.layout_entries);
    if let Some(structures) = structures {
        layout_entries.extend(structures.layout_entries(ray_queries, tracer_stage(kind)));
    }
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &layout_entries,
    });
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: globals.as_entire_binding(),
    }];
    entries.extend(resources.bind_entries());
    if let Some(structures) = structures {
        entries.extend(structures.bind_entries(ray_queries));
    }
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene"),
        layout: &layout,
        entries: &entries,
    });
    (layout, layout_entries, bind_group)
}

pub(super) fn build_pipeline(
    ctx: &GpuContext,
    kind: Pipeline,
    source: String,
    bindings: &SceneBindings,
    previous_layout: &wgpu::BindGroupLayout,
    with_miss: bool,
) -> (TracePipeline, wgpu::BindGroup) {
    let device = &ctx.device;
    let (bind_group_layout, layout_entries, bind_group) = scene_bind_group(device, kind, bindings);
    // What the pipelines are compiled from besides the source and entry point; the layouts by
    // their entries, as wgpu identifies them.
    let descriptor = format!(
        "{kind:?} pipeline, groups {layout_entries:?} and {:?}, targets {TARGET_FORMAT:?}, vertex vs_main",
        previous_sample_entries(kind)
    );
    let source: Arc<str> = source.into();
    let key = |entry_point| PipelineKey::new(&source, entry_point, descriptor.clone());
    let compiled = OnceCell::new();
    let compiled = || {
        compiled.get_or_init(|| {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("trace"),
                source: wgpu::ShaderSource::Wgsl(source.to_string().into()),
            });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("trace"),
                bind_group_layouts: &[Some(&bind_group_layout), Some(previous_layout)],
                immediate_size: 0,
            });
            (module, layout)
        })
    };
    if kind == Pipeline::Compute {
        let pipeline = ctx.pipelines.compute(key("cs_main"), || {
            let (module, layout) = compiled();
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("trace"),
                layout: Some(layout),
                module,
                entry_point: Some("cs_main"),
                compilation_options: Default::default(),
                cache: None,
            })
        });
        return (TracePipeline::Compute(pipeline), bind_group);
    }
    let target = Some(wgpu::ColorTargetState {
        format: TARGET_FORMAT,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    });
    let fullscreen = |label, fragment_entry| {
        ctx.pipelines.render(key(fragment_entry), || {
            let (module, layout) = compiled();
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: 8,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x2],
                    })],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(fragment_entry),
                    compilation_options: Default::default(),
                    targets: &[target.clone(), target.clone()],
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    };
    let pipeline = fullscreen("trace", "fs_main");
    let miss = with_miss.then(|| fullscreen("trace misses", "fs_miss"));
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("fullscreen triangle"),
        contents: bytemuck::cast_slice(&FULLSCREEN_TRIANGLE),
        usage: wgpu::BufferUsages::VERTEX,
    });
    (
        TracePipeline::Fragment {
            pipeline,
            miss,
            vertices,
        },
        bind_group,
    )
}
