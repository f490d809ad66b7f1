//! The frame targets and their accumulation: two pairs of rgba32uint textures (f32 bits) that
//! take turns, a draw reading the sums in one pair and writing the next sample's sums into the
//! other; and the checks and read-backs sized with them.

use crate::gpu::GpuError;
use crate::gpu::device::readback::TextureReadback;
use crate::modes::Pipeline;

/// The shader stage that runs the tracer: what its bindings are visible to.
pub(super) fn tracer_stage(pipeline: Pipeline) -> wgpu::ShaderStages {
    match pipeline {
        Pipeline::Fragment => wgpu::ShaderStages::FRAGMENT,
        Pipeline::Compute => wgpu::ShaderStages::COMPUTE,
    }
}

/// f32 bits in an integer format: colour-renderable on every backend, read back bit for bit.
pub const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
const TARGET_BYTES_PER_PIXEL: u32 = 16;

/// The tracer's outputs, one texel per pixel: colour (rgb linear radiance, a the count, both summed
/// over the samples so far) and surface (xyz first-hit normal, w its distance or `DEPTH_MISS`, of
/// the centre sample), both f32 bits.
pub struct FrameTargets {
    /// Linear radiance and the count, summed over the samples (rgba32uint of f32 bits).
    pub color: wgpu::Texture,
    /// The centre sample's first-hit normal and distance (rgba32uint of f32 bits).
    pub surface: wgpu::Texture,
    /// A view of `color`, as the display pass reads it.
    pub color_view: wgpu::TextureView,
    /// A view of `surface`.
    pub surface_view: wgpu::TextureView,
    /// Samples per pixel summed in the colour target (0 before the first draw).
    pub(super) samples: u32,
}

impl FrameTargets {
    pub(super) fn new(device: &wgpu::Device, width: u32, height: u32, pipeline: Pipeline) -> Self {
        let written_as = match pipeline {
            Pipeline::Fragment => wgpu::TextureUsages::RENDER_ATTACHMENT,
            Pipeline::Compute => wgpu::TextureUsages::STORAGE_BINDING,
        };
        let [color, surface] = ["color target", "surface target"].map(|label| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: TARGET_FORMAT,
                usage: written_as | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        });
        Self {
            color_view: color.create_view(&Default::default()),
            surface_view: surface.create_view(&Default::default()),
            color,
            surface,
            samples: 0,
        }
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.color.width(), self.color.height())
    }

    /// Samples per pixel summed in the colour target (0 before the first draw).
    pub fn samples(&self) -> u32 {
        self.samples
    }
}

/// Two pairs of targets that take turns: a draw reads the sums in one and writes the other.
pub(super) struct Accumulation {
    pub(super) targets: [FrameTargets; 2],
    /// `reads[k]` binds `targets[k]` as the previous sample's, for a draw into `targets[1 - k]`
    /// (which a compute kernel finds bound beside them).
    pub(super) reads: [wgpu::BindGroup; 2],
    /// The pair holding the latest sums.
    pub(super) current: usize,
    /// The next draw starts the sums again.
    pub(super) restarted: bool,
}

impl Accumulation {
    pub(super) fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        width: u32,
        height: u32,
        pipeline: Pipeline,
    ) -> Self {
        let targets = [0, 1].map(|_| FrameTargets::new(device, width, height, pipeline));
        let reads = [0, 1].map(|k| {
            let view = |binding, view| wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(view),
            };
            let (read, written) = (&targets[k], &targets[1 - k]);
            let mut entries = vec![view(0, &read.color_view), view(1, &read.surface_view)];
            if pipeline == Pipeline::Compute {
                entries.extend([view(2, &written.color_view), view(3, &written.surface_view)]);
            }
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("previous sample"),
                layout,
                entries: &entries,
            })
        });
        Self {
            targets,
            reads,
            current: 0,
            restarted: true,
        }
    }
}

/// Whether a renderer of `width` x `height` fits a device of `limits`: within its largest texture,
/// and each frame target's read-back buffer within its largest buffer. Checked before anything is
/// allocated: past the adapter's limits wgpu would fail later, with its own words, after the other
/// targets took their memory.
pub fn check_frame_size(limits: &wgpu::Limits, width: u32, height: u32) -> Result<(), GpuError> {
    let max = limits.max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(GpuError::ImageTooLarge { width, height, max });
    }
    // Each target texture, and its read-back buffer (rows padded), is one allocation; wgpu's largest
    // buffer stands for the adapter's largest allocation.
    let bytes =
        crate::gpu::device::readback::padded_bytes_per_row(width * TARGET_BYTES_PER_PIXEL) as u64 * height as u64;
    if bytes > limits.max_buffer_size {
        return Err(GpuError::FrameTooLarge {
            width,
            height,
            bytes,
            max: limits.max_buffer_size,
            max_pixels: limits.max_buffer_size / TARGET_BYTES_PER_PIXEL as u64,
        });
    }
    Ok(())
}

pub(super) fn readbacks(device: &wgpu::Device, width: u32, height: u32) -> [TextureReadback; 2] {
    [0, 1].map(|_| TextureReadback::new(device, width, height, TARGET_BYTES_PER_PIXEL))
}

/// A frame target read by a shader stage (`texture_2d<u32>`) at `binding`.
pub(crate) fn target_entry(binding: u32, stage: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stage,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Group 1: the previous sample's colour and surface targets; for the compute kernel, the targets
/// it writes too, as storage textures.
pub(super) fn previous_sample_layout(device: &wgpu::Device, pipeline: Pipeline) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("previous sample"),
        entries: &previous_sample_entries(pipeline),
    })
}

/// The entries of [`previous_sample_layout`].
pub(super) fn previous_sample_entries(pipeline: Pipeline) -> Vec<wgpu::BindGroupLayoutEntry> {
    let stage = tracer_stage(pipeline);
    let mut entries = vec![target_entry(0, stage), target_entry(1, stage)];
    if pipeline == Pipeline::Compute {
        entries.extend([2, 3].map(|binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: stage,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: TARGET_FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        }));
    }
    entries
}
