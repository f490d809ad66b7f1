//! Images: the frame both tracers produce, its AOVs, and their comparison. Files are the caller's.

pub mod diff;
pub mod heatmap;
pub mod tonemap;

pub use crate::constants::DEPTH_MISS;

use crate::modes::{Aov, Count};
use glam::Vec4;
use tonemap::DisplayTransform;

/// What a render produces: the fragment shader's two outputs per pixel, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Pixels in a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// rgb: linear radiance; a: rays traced for the pixel (primary, shadow, secondary).
    pub color: Vec<[f32; 4]>,
    /// xyz: first-hit geometric normal; w: first-hit distance, or [`DEPTH_MISS`].
    pub surface: Vec<[f32; 4]>,
}

/// A float image of any channel count, rows top to bottom, channels interleaved.
#[derive(Clone, Debug, PartialEq)]
pub struct FloatImage {
    /// Pixels in a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Channel names, as an EXR file would name them.
    pub channels: Vec<String>,
    /// The values, `channels.len()` a pixel.
    pub data: Vec<f32>,
}

impl FloatImage {
    /// Pixel `index`'s channels.
    pub fn pixel(&self, index: usize) -> &[f32] {
        let n = self.channels.len();
        &self.data[index * n..(index + 1) * n]
    }

    /// Pixels in the image.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Every value clamped to [0, 1] and rounded to 8 bits, as a PNG holds a display-encoded
    /// image ([`Frame::display`]).
    pub fn to_bytes(&self) -> Vec<u8> {
        self.data
            .iter()
            .map(|&v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect()
    }
}

impl FloatImage {
    /// The image as an 8-bit PNG ([`FloatImage::to_bytes`]): one channel grey, three RGB.
    pub fn to_png(&self) -> Result<Vec<u8>, String> {
        let color = match self.channels.len() {
            1 => png::ColorType::Grayscale,
            3 => png::ColorType::Rgb,
            n => return Err(format!("cannot write a {n}-channel image as PNG")),
        };
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, self.width, self.height);
        encoder.set_color(color);
        encoder.set_depth(png::BitDepth::Eight);
        let encoded = encoder
            .write_header()
            .and_then(|mut writer| writer.write_image_data(&self.to_bytes()).and(writer.finish()));
        encoded.map_err(|e| format!("cannot encode PNG: {e}"))?;
        Ok(out)
    }
}

/// Linear to sRGB-encoded, the transfer function of PNG output.
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

fn rgb_names() -> Vec<String> {
    ["R", "G", "B"].map(String::from).to_vec()
}

impl Frame {
    /// A black frame of `width` x `height`: no ray counted, every depth a miss.
    pub fn new(width: u32, height: u32) -> Self {
        let pixels = width as usize * height as usize;
        Self {
            width,
            height,
            color: vec![[0.0; 4]; pixels],
            surface: vec![[0.0, 0.0, 0.0, DEPTH_MISS]; pixels],
        }
    }

    /// Rays traced for the whole image, as the tracer counted them.
    pub fn rays(&self) -> u64 {
        self.color.iter().map(|c| c[3] as u64).sum()
    }

    /// Colour as it is displayed: clamped and sRGB-encoded, in [0, 1]. This is what PNG files hold
    /// (before 8-bit rounding) and what colour comparisons measure.
    pub fn display(&self) -> FloatImage {
        self.display_with(&DisplayTransform::IDENTITY)
    }

    /// Colour exposed, tone-mapped by `transform` and sRGB-encoded, in [0, 1]: what the display
    /// pass shows with the same transform.
    pub fn display_with(&self, transform: &DisplayTransform) -> FloatImage {
        let data = self
            .color
            .iter()
            .flat_map(|c| transform.apply([c[0], c[1], c[2]]).map(linear_to_srgb))
            .collect();
        self.image(rgb_names(), data)
    }

    /// The image `aov` makes of the frame: colour through `transform` for a PNG, or exposed linear
    /// radiance for a float file (`float`); depth, normals, or the cost's heat map.
    pub fn aov_image(&self, aov: Aov, float: bool, transform: &DisplayTransform) -> FloatImage {
        match (aov, float) {
            (Aov::Color, false) => self.display_with(transform),
            (Aov::Color, true) => self.exposed_radiance(transform.exposure),
            (Aov::Depth, _) => self.depth(),
            (Aov::Normal, _) => self.normals(),
            (Aov::Cost, _) => heatmap::heatmap(&self.counts(), self.width, self.height),
        }
    }

    /// Linear radiance, for EXR output.
    pub fn radiance(&self) -> FloatImage {
        self.exposed_radiance(0.0)
    }

    /// Linear radiance times 2^`exposure`: EXR output with an exposure (before any tone map).
    pub fn exposed_radiance(&self, exposure: f32) -> FloatImage {
        let scale = exposure.exp2();
        let data = self
            .color
            .iter()
            .flat_map(|c| [c[0], c[1], c[2]].map(|v| v * scale))
            .collect();
        self.image(rgb_names(), data)
    }

    /// Distance from the eye to the first hit along the unit primary ray; +inf where it escapes.
    pub fn depth(&self) -> FloatImage {
        let data = self
            .surface
            .iter()
            .map(|s| if s[3] < 0.0 { f32::INFINITY } else { s[3] })
            .collect();
        self.image(vec!["Z".into()], data)
    }

    /// The fourth colour channel (rays per pixel, or cost in a cost render) as counts.
    pub fn counts(&self) -> Vec<u32> {
        self.color.iter().map(|c| c[3] as u32).collect()
    }

    /// First-hit normals mapped from [-1, 1] to [0, 1]; black where the primary ray escapes.
    pub fn normals(&self) -> FloatImage {
        let data = self
            .surface
            .iter()
            .flat_map(|s| {
                if s[3] < 0.0 {
                    [0.0; 3]
                } else {
                    [s[0], s[1], s[2]].map(|v| v * 0.5 + 0.5)
                }
            })
            .collect();
        self.image(rgb_names(), data)
    }

    fn image(&self, channels: Vec<String>, data: Vec<f32>) -> FloatImage {
        FloatImage {
            width: self.width,
            height: self.height,
            channels,
            data,
        }
    }
}

/// A pixel's colour sums over `samples` samples as a frame holds them: the mean radiance, and the
/// count's total (rays) or mean (cost per primary ray). The CPU reference and the GPU's readback both divide here.
pub fn sample_mean(sum: Vec4, samples: u32, count: Count) -> [f32; 4] {
    let n = samples as f32;
    let counted = match count {
        Count::Rays => sum.w,
        Count::Cost => sum.w / n,
    };
    [sum.x / n, sum.y / n, sum.z / n, counted]
}
