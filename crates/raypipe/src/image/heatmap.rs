//! Heat maps of per-pixel counts (`--aov cost`), with a colour-scale legend under the image.

use super::FloatImage;

/// Stops of an "inferno"-like scale: dark for cheap pixels, bright for expensive ones.
pub const STOPS: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.02],
    [0.34, 0.06, 0.43],
    [0.73, 0.21, 0.33],
    [0.98, 0.55, 0.04],
    [0.99, 1.0, 0.64],
];

/// The colour of `x` in [0, 1] on the scale.
pub fn color_scale(x: f32) -> [f32; 3] {
    let x = x.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (x as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    std::array::from_fn(|c| STOPS[i][c] + (STOPS[i + 1][c] - STOPS[i][c]) * f)
}

/// 3x5 bitmaps of the digits, one row per 3 bits (top row first).
const DIGITS: [[u8; 5]; 10] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
];

struct Canvas {
    width: usize,
    height: usize,
    data: Vec<f32>,
}

impl Canvas {
    fn set(&mut self, x: usize, y: usize, rgb: [f32; 3]) {
        if x < self.width && y < self.height {
            let i = (y * self.width + x) * 3;
            self.data[i..i + 3].copy_from_slice(&rgb);
        }
    }

    /// Draws `value` in white with its left edge at `x` (or right edge, when `align_right`).
    fn number(&mut self, value: u32, x: usize, y: usize, scale: usize, align_right: bool) {
        let text = value.to_string();
        let width = text.len() * 4 * scale - scale;
        let left = if align_right { x.saturating_sub(width) } else { x };
        for (k, digit) in text.bytes().enumerate() {
            let glyph = DIGITS[(digit - b'0') as usize];
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        for dy in 0..scale {
                            for dx in 0..scale {
                                let px = left + (k * 4 + col) * scale + dx;
                                self.set(px, y + row * scale + dy, [1.0; 3]);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// `counts` (row-major, `width` x `height`) as colours from 0 (dark) to the largest count (bright),
/// above a legend: the colour bar with 0, the middle and the largest count written under it.
pub fn heatmap(counts: &[u32], width: u32, height: u32) -> FloatImage {
    let (w, h) = (width as usize, height as usize);
    let max = counts.iter().copied().max().unwrap_or(0).max(1);
    let scale = if w >= 240 { 2 } else { 1 };
    let bar = 6 * scale;
    let legend = 2 * scale + bar + 2 * scale + 5 * scale + 2 * scale;
    let mut canvas = Canvas {
        width: w,
        height: h + legend,
        data: vec![0.0; w * (h + legend) * 3],
    };
    for (i, &c) in counts.iter().enumerate() {
        canvas.set(i % w, i / w, color_scale(c as f32 / max as f32));
    }
    let bar_top = h + 2 * scale;
    for x in 0..w {
        let rgb = color_scale(x as f32 / (w.max(2) - 1) as f32);
        for y in bar_top..bar_top + bar {
            canvas.set(x, y, rgb);
        }
    }
    let text_top = bar_top + bar + 2 * scale;
    canvas.number(0, scale, text_top, scale, false);
    canvas.number(max / 2, w / 2, text_top, scale, false);
    canvas.number(max, w - scale, text_top, scale, true);
    FloatImage {
        width,
        height: (h + legend) as u32,
        channels: ["R", "G", "B"].map(String::from).to_vec(),
        data: canvas.data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_runs_dark_to_bright() {
        let brightness = |x: f32| color_scale(x).iter().sum::<f32>();
        assert!(brightness(0.0) < brightness(0.5) && brightness(0.5) < brightness(1.0));
    }

    #[test]
    fn heatmap_keeps_the_image_and_adds_a_legend() {
        let counts: Vec<u32> = (0..64 * 48).map(|i| (i % 64) as u32).collect();
        let image = heatmap(&counts, 64, 48);
        assert_eq!(image.width, 64);
        assert!(image.height > 48);
        let pixel = |x: usize, y: usize| &image.data[(y * 64 + x) * 3..(y * 64 + x) * 3 + 3];
        assert_eq!(pixel(0, 0), color_scale(0.0));
        assert_eq!(pixel(63, 0), color_scale(1.0));
        // Somewhere in the legend's text row there are white digit pixels.
        assert!((48..image.height as usize).any(|y| (0..64).any(|x| pixel(x, y) == [1.0; 3])));
    }
}
