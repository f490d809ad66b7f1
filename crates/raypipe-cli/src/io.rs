//! Reading and writing PNG (8-bit, display-encoded) and OpenEXR (32-bit float) images.

use anyhow::{Context, bail};
use exr::prelude::{self as exrs, ReadChannels, ReadLayers, WritableImage};
use raypipe::image::FloatImage;
use std::path::Path;

fn is_exr(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// Writes a PNG (values in [0, 1], rounded to 8 bits) or, by extension, a float EXR.
pub fn write(image: &FloatImage, path: &Path) -> anyhow::Result<()> {
    if is_exr(path) {
        write_exr(image, path)
    } else {
        write_png(image, path)
    }
}

pub fn write_png(image: &FloatImage, path: &Path) -> anyhow::Result<()> {
    let channels = image.channels.len();
    let to_byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let result = match channels {
        1 => image::GrayImage::from_raw(
            image.width,
            image.height,
            image.data.iter().map(|&v| to_byte(v)).collect(),
        )
        .map(|img| img.save(path)),
        3 => image::RgbImage::from_raw(
            image.width,
            image.height,
            image.data.iter().map(|&v| to_byte(v)).collect(),
        )
        .map(|img| img.save(path)),
        n => bail!("{}: cannot write a {n}-channel image as PNG", path.display()),
    };
    result
        .expect("the buffer size matches the image size")
        .with_context(|| format!("{}: cannot write PNG", path.display()))
}

pub fn write_exr(image: &FloatImage, path: &Path) -> anyhow::Result<()> {
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
    let layer = exrs::Layer::new(
        (image.width as usize, image.height as usize),
        exrs::LayerAttributes::default(),
        exrs::Encoding::FAST_LOSSLESS,
        exrs::AnyChannels::sort(channels),
    );
    exrs::Image::from_layer(layer)
        .write()
        .to_file(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot write EXR: {e}", path.display()))
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
