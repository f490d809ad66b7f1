//! Copying a render target back to the host: rows are padded to 256 bytes in the copy buffer.

/// Bytes per row in a texture-to-buffer copy: `unpadded` rounded up to wgpu's 256-byte alignment.
pub fn padded_bytes_per_row(unpadded: u32) -> u32 {
    unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// A buffer that receives a copy of a `width` x `height` texture with `bytes_per_pixel`.
pub struct Readback {
    pub buffer: wgpu::Buffer,
    width: u32,
    height: u32,
    bytes_per_pixel: u32,
}

impl Readback {
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

    pub fn copy_from(&self, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) {
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

    /// Maps the buffer (after the copy was submitted) and returns the rows without their padding.
    pub fn read(&self, device: &wgpu::Device) -> anyhow::Result<Vec<u8>> {
        let padded = padded_bytes_per_row(self.width * self.bytes_per_pixel) as usize;
        let row = (self.width * self.bytes_per_pixel) as usize;
        map_read(device, &self.buffer, |data| {
            let mut out = Vec::with_capacity(row * self.height as usize);
            for chunk in data.chunks(padded) {
                out.extend_from_slice(&chunk[..row]);
            }
            out
        })
    }
}

/// Maps a MAP_READ buffer whose copies were submitted, waits for them, hands its bytes to `f`, and
/// unmaps it again so the buffer can receive the next copy.
pub fn map_read<T>(device: &wgpu::Device, buffer: &wgpu::Buffer, f: impl FnOnce(&[u8]) -> T) -> anyhow::Result<T> {
    let slice = buffer.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = sender.send(result);
    });
    device.poll(wgpu::PollType::wait_indefinitely())?;
    receiver.recv()??;
    let result = f(&slice.get_mapped_range()?);
    buffer.unmap();
    Ok(result)
}

/// Copies the first `size` bytes of `source` (COPY_SRC) to the host.
pub fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    source: &wgpu::Buffer,
    size: u64,
) -> anyhow::Result<Vec<u8>> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
    queue.submit([encoder.finish()]);
    map_read(device, &staging, <[u8]>::to_vec)
}
