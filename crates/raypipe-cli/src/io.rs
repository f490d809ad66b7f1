//! Reading and writing PNG (8-bit, display-encoded) and OpenEXR (32-bit float) images.

use anyhow::bail;
use exr::prelude::{self as exrs, ReadChannels, ReadLayers, WritableImage};
use raypipe::image::FloatImage;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

fn is_exr(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// Writes a PNG (values in [0, 1], rounded to 8 bits) or, by extension, a float EXR, whole or not
/// at all ([`write_file`]).
pub fn write(image: &FloatImage, path: &Path) -> anyhow::Result<()> {
    write_as(image, path, is_exr(path))
}

/// [`write`] as EXR or PNG whatever the extension: for a device or FIFO, which has none.
pub fn write_as(image: &FloatImage, path: &Path, exr: bool) -> anyhow::Result<()> {
    let bytes = if exr {
        encode_exr(image, path)?
    } else {
        encode_png(image, path)?
    };
    write_file(path, &bytes)
}

/// Bytes to `path`, whole or not at all: written to a temporary file beside it, synced, then
/// renamed over it, so that a reader (or another writer of the same path) never sees half a file and
/// a failed write leaves nothing behind. A path that exists and is not a regular file (a device
/// such as /dev/null, a FIFO) is written in place: renaming would replace it.
pub fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let fail = |e: std::io::Error| anyhow::anyhow!("{}: cannot write: {e}", path.display());
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        let mut file = std::fs::OpenOptions::new().write(true).open(path).map_err(fail)?;
        return file.write_all(bytes).and_then(|()| file.flush()).map_err(fail);
    }
    let temp = temporary_beside(path);
    let written = std::fs::File::create(&temp).and_then(|mut file| {
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&temp, path)
    });
    if let Err(e) = written {
        let _ = std::fs::remove_file(&temp);
        return Err(fail(e));
    }
    Ok(())
}

/// A name beside `path` that no other writer uses: hidden, with this process's id and a count.
fn temporary_beside(path: &Path) -> PathBuf {
    static COUNT: AtomicU32 = AtomicU32::new(0);
    let name = path
        .file_name()
        .map_or("output".into(), |n| n.to_string_lossy().into_owned());
    let n = COUNT.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{n}.partial", std::process::id()))
}

/// Whether `path` can be written, before the work that produces it: its folder exists and a file
/// can be created there. A device or FIFO is left to the write itself: opening a FIFO to try it
/// would hand its reader an empty stream.
pub fn check_writable(path: &Path) -> anyhow::Result<()> {
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        return Ok(());
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        bail!("{}: cannot write: no folder {}", path.display(), folder.display());
    }
    let probe = temporary_beside(path);
    std::fs::File::create(&probe).map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

fn encode_png(image: &FloatImage, path: &Path) -> anyhow::Result<Vec<u8>> {
    image
        .to_png()
        .map_err(|why| anyhow::anyhow!("{}: {why}", path.display()))
}

fn encode_exr(image: &FloatImage, path: &Path) -> anyhow::Result<Vec<u8>> {
    let n = image.channels.len();
    let channels: exrs::SmallVec<[exrs::AnyChannel<exrs::FlatSamples>; 4]> = image
        .channels
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let samples = image.data.iter().skip(c).step_by(n).copied().collect();
            exrs::AnyChannel::new(name.as_str(), exrs::FlatSamples::F32(samples))
        })
        .collect();
    // Blocks in increasing order: compressed in parallel, they would otherwise be written as they
    // finish, and the same image would give different bytes from run to run.
    let encoding = exrs::Encoding {
        line_order: exrs::LineOrder::Increasing,
        ..exrs::Encoding::FAST_LOSSLESS
    };
    let layer = exrs::Layer::new(
        (image.width as usize, image.height as usize),
        exrs::LayerAttributes::default(),
        encoding,
        exrs::AnyChannels::sort(channels),
    );
    let mut exr = std::io::Cursor::new(Vec::new());
    exrs::Image::from_layer(layer)
        .write()
        .to_buffered(&mut exr)
        .map_err(|e| anyhow::anyhow!("{}: cannot encode EXR: {e}", path.display()))?;
    Ok(exr.into_inner())
}

/// Reads a PNG (as RGB in [0, 1]) or an EXR (every channel of the first layer, as f32).
pub fn read(path: &Path) -> anyhow::Result<FloatImage> {
    if !path.exists() {
        bail!("{}: no such file", path.display());
    }
    if is_exr(path) {
        return read_exr(path);
    }
    let img = image::open(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read image: {e}", path.display()))?
        .into_rgb32f();
    Ok(FloatImage {
        width: img.width(),
        height: img.height(),
        channels: ["R", "G", "B"].map(String::from).to_vec(),
        data: img.into_raw(),
    })
}

fn read_exr(path: &Path) -> anyhow::Result<FloatImage> {
    let image = exrs::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read EXR: {e}", path.display()))?;
    let layer = image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let list = &layer.channel_data.list;
    let n = list.len();
    let mut data = vec![0.0; width * height * n];
    for (c, channel) in list.iter().enumerate() {
        for (i, v) in channel.sample_data.values_as_f32().enumerate() {
            data[i * n + c] = v;
        }
    }
    Ok(FloatImage {
        width: width as u32,
        height: height as u32,
        channels: list.iter().map(|c| c.name.to_string()).collect(),
        data,
    })
}
