//! The display pass (`shaders/display.wgsl`): a renderer's frame targets drawn into any colour
//! target, a window's surface texture or an offscreen one, as a screen shows them. The frame lands
//! at the target's top-left corner, one fragment per pixel; the rest of the target is cleared.

use super::renderer::{FrameTargets, target_entry};
use crate::Choice;
use crate::gpu::GpuContext;
use crate::image::tonemap::DisplayTransform;
use crate::modes::Aov;
use crate::scene::ToneMap;

const DISPLAY: &str = include_str!("../shaders/display.wgsl");

/// The pass's parameters (`DisplayParams` in display.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct DisplayParams {
    pub view: u32,
    pub target_srgb: u32,
    pub depth_far: f32,
    pub cost_max: f32,
    /// Samples summed in the colour target: the pass shows their mean.
    pub samples: u32,
    /// The colour view's [`DisplayTransform`]: 2^exposure, and the tone map's number.
    pub exposure_scale: f32,
    pub tone_map: u32,
    pub _pad: u32,
}

/// The display pass's records with a WGSL twin, for the layout test.
#[cfg(feature = "internals")]
pub const LAYOUTS: &[crate::records::layouts::StructLayout] = &[crate::records::layouts::struct_layout!(
    DisplayParams,
    "DisplayParams",
    [
        view,
        target_srgb,
        depth_far,
        cost_max,
        samples,
        exposure_scale,
        tone_map,
        _pad
    ]
)];

/// The display pass's WGSL: its numbers from Rust (the views' and tone maps' numbering, the heat
/// map's stops), then display.wgsl.
#[cfg_attr(feature = "internals", visibility::make(pub))]
pub(crate) fn shader_source() -> String {
    use std::fmt::Write;
    let mut out = String::from("// Generated: src/gpu/trace/display.rs.\n");
    let names = Aov::ALL
        .iter()
        .map(|&view| ("DISPLAY", view.name(), view as u32))
        .chain(ToneMap::ALL.iter().map(|&t| ("TONE_MAP", t.name(), t as u32)));
    for (prefix, name, number) in names {
        writeln!(out, "const {prefix}_{}: u32 = {number}u;", name.to_uppercase()).unwrap();
    }
    let stops = crate::image::heatmap::STOPS;
    let vectors: Vec<String> = stops
        .iter()
        .map(|s| {
            format!(
                "vec3<f32>({})",
                s.map(crate::records::constants::float_literal).join(", ")
            )
        })
        .collect();
    writeln!(out, "const HEAT_STOP_COUNT: u32 = {}u;", stops.len()).unwrap();
    writeln!(
        out,
        "const HEAT_STOPS = array<vec3<f32>, {}>({});",
        stops.len(),
        vectors.join(", ")
    )
    .unwrap();
    out + DISPLAY
}

/// What the display pass shows of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shown {
    /// Which of the frame's outputs.
    pub aov: Aov,
    /// The depth view: distances up to this fade from white to black.
    pub depth_far: f32,
    /// The cost view: the count at the top of the heat map's scale.
    pub cost_max: f32,
    /// The colour view: exposure and tone map before sRGB encoding.
    pub transform: DisplayTransform,
}

/// The display pass for targets of one format.
pub struct Display {
    ctx: GpuContext,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    target_srgb: bool,
}

impl Display {
    /// The display pass, drawing into targets of `format`.
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Self {
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("display"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                target_entry(1, wgpu::ShaderStages::FRAGMENT),
                target_entry(2, wgpu::ShaderStages::FRAGMENT),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_display"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_display"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display params"),
            size: std::mem::size_of::<DisplayParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            ctx: ctx.clone(),
            pipeline,
            layout,
            params,
            target_srgb: format.is_srgb(),
        }
    }

    /// Records the pass: `frame` (the mean of its samples) drawn into `view` (at least the frame's
    /// size) as `shown` says.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameTargets,
        view: &wgpu::TextureView,
        shown: &Shown,
    ) {
        let params = DisplayParams {
            view: shown.aov as u32,
            target_srgb: self.target_srgb as u32,
            depth_far: shown.depth_far,
            cost_max: shown.cost_max,
            samples: frame.samples().max(1),
            exposure_scale: shown.transform.scale(),
            tone_map: shown.transform.tone_map as u32,
            _pad: 0,
        };
        self.ctx
            .queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let bind_group = self.ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&frame.color_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&frame.surface_view),
                },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("display"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let (width, height) = frame.size();
        pass.set_viewport(0.0, 0.0, width as f32, height as f32, 0.0, 1.0);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
