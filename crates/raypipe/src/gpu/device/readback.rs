//! Copying GPU results back to the host, for the callers that need pixels or numbers: files, tests,
//! benchmarks. A window or a canvas never reads back. Texture rows are padded to 256 bytes in the
//! copy buffer; every wait is a future (a browser cannot block).

use super::context::{map_future, wait_mapped};
use crate::gpu::GpuError;

/// Bytes per row in a texture-to-buffer copy: `unpadded` rounded up to wgpu's 256-byte alignment.
pub(crate) fn padded_bytes_per_row(unpadded: u32) -> u32 {
    unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// A buffer that receives copies of a `width` x `height` texture with `bytes_per_pixel`. A clone
/// is a handle on the same buffer.
#[derive(Clone)]
pub struct TextureReadback {
    buffer: wgpu::Buffer,
    width: u32,
    height: u32,
    bytes_per_pixel: u32,
}

impl TextureReadback {
    /// A buffer that holds a `width` x `height` texture of `bytes_per_pixel`, rows padded as copies
    /// need.
    pub fn new(device: &wgpu::Device, width: u32, height: u32, bytes_per_pixel: u32) -> Self {
        let size = padded_bytes_per_row(width * bytes_per_pixel) as u64 * height as u64;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Self {
            buffer,
            width,
            height,
            bytes_per_pixel,
        }
    }

    /// Whether this readback fits `texture`.
    #[cfg(feature = "internals")]
    pub fn fits(&self, texture: &wgpu::Texture) -> bool {
        (texture.width(), texture.height()) == (self.width, self.height)
    }

    /// Records the copy of `texture` into the buffer.
    pub fn encode_copy(&self, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) {
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_bytes_per_row(self.width * self.bytes_per_pixel)),
                    rows_per_image: Some(self.height),
                },
            },
            texture.size(),
        );
    }

    /// The rows without their padding, once the copy's submission has finished.
    pub async fn read(&self, device: &wgpu::Device) -> Result<Vec<u8>, GpuError> {
        let padded = padded_bytes_per_row(self.width * self.bytes_per_pixel) as usize;
        let row = (self.width * self.bytes_per_pixel) as usize;
        map_read(device, &self.buffer, |data| {
            let mut out = Vec::with_capacity(row * self.height as usize);
            for chunk in data.chunks(padded) {
                out.extend_from_slice(&chunk[..row]);
            }
            out
        })
        .await
    }
}

/// Maps a MAP_READ buffer whose copies were submitted, waits for them, hands its bytes to `f`, and
/// unmaps it again so the buffer can receive the next copy.
pub(crate) async fn map_read<T>(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T, GpuError> {
    let slice = buffer.slice(..);
    let mapped = map_future(slice, wgpu::MapMode::Read);
    wait_mapped(device, mapped).await?;
    let result = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        f(&view)
    };
    buffer.unmap();
    Ok(result)
}

/// Copies the first `size` bytes of `source` (COPY_SRC) to the host.
pub(crate) async fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    source: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>, GpuError> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
    queue.submit([encoder.finish()]);
    map_read(device, &staging, <[u8]>::to_vec).await
}
