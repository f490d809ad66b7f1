//! Images that materials are textured with: linear RGBA texels at half precision, with the wrap mode
//! of each axis and the sampler's filters. Both tracers sample them alike (`sample_texture` in
//! `shaders/maps.wgsl` and `cpu/maps.rs`): from a chain of mipmaps made on the host
//! ([`Texture::halved`] again and again), at the level a ray cone's footprint picks, trilinear by
//! default.

use crate::error::InputError;
use half::f16;

/// What a texture coordinate outside [0, 1] reads (glTF's sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles the plane (glTF's REPEAT).
    #[default]
    Repeat,
    /// The edge texels continue outwards (CLAMP_TO_EDGE).
    Clamp,
    /// The image tiles the plane, every other copy mirrored (MIRRORED_REPEAT).
    Mirror,
}

/// How texels are read within a level: the one nearest the point, or the four around it blended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TexelFilter {
    /// The nearest texel (or level).
    Nearest,
    /// Bilinear between texels (or linear between levels).
    #[default]
    Linear,
}

/// A sampler's filters (glTF's magFilter and minFilter): how a texture is read where a texel
/// covers more than the ray's footprint (magnified), and where the footprint covers more than a
/// texel (minified), within a mip level and between two.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Filter {
    /// Where a texel covers more than the footprint.
    pub magnify: TexelFilter,
    /// Where the footprint covers more than a texel.
    pub minify: TexelFilter,
    /// Between mip levels: the nearest level or the two around the footprint blended; `None`
    /// reads the full-size image only (minFilter NEAREST or LINEAR).
    pub mipmaps: Option<TexelFilter>,
}

impl Default for Filter {
    /// Trilinear: what glTF's viewers use where the sampler names no filter.
    fn default() -> Self {
        Filter {
            magnify: TexelFilter::Linear,
            minify: TexelFilter::Linear,
            mipmaps: Some(TexelFilter::Linear),
        }
    }
}

/// The most texels a scene's textures hold together, their mipmaps counted: 2^24, so that a
/// texel's index is exact in the f32 records of texture memory (a 2048 x 2048 image and its
/// mipmaps take a third of it).
pub const MAX_TEXELS: u64 = 1 << 24;
/// The most texels a file's images may decode to together: what [`shrink_to_fit`] brings down
/// to MAX_TEXELS.
pub(crate) const MAX_DECODED_TEXELS: u64 = 4 * MAX_TEXELS;
/// The longest side of a texture.
pub(crate) const MAX_TEXTURE_SIDE: u32 = 16384;

/// An image of linear RGBA texels (half floats), with how it wraps and filters.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Texels in a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Row by row from texture coordinate v = 0 (the image's first row, as glTF has it): linear
    /// RGBA as IEEE half floats (their bits), the precision the GPU texture holds.
    pub texels: Vec<[u16; 4]>,
    /// Along u, then v.
    pub wrap: [Wrap; 2],
    /// How it is read.
    pub filter: Filter,
}

impl Texture {
    /// A texture from 8-bit sRGB-encoded RGBA (an image file's pixels), decoded to linear light;
    /// alpha is linear already.
    pub fn from_srgb8(width: u32, height: u32, rgba: &[u8], wrap: [Wrap; 2]) -> Texture {
        let table: Vec<u16> = (0..=255u8)
            .map(|c| f16::from_f32(srgb_to_linear(c)).to_bits())
            .collect();
        let texels = rgba
            .chunks_exact(4)
            .map(|p| {
                [
                    table[p[0] as usize],
                    table[p[1] as usize],
                    table[p[2] as usize],
                    f16::from_f32(p[3] as f32 / 255.0).to_bits(),
                ]
            })
            .collect();
        Texture {
            width,
            height,
            texels,
            wrap,
            filter: Filter::default(),
        }
    }

    /// A texture from 8-bit RGBA that is data, not colour (metalness and roughness, occlusion):
    /// each value over 255, with no transfer curve.
    pub fn from_data8(width: u32, height: u32, rgba: &[u8], wrap: [Wrap; 2]) -> Texture {
        Texture {
            width,
            height,
            texels: rgba
                .chunks_exact(4)
                .map(|p| [p[0], p[1], p[2], p[3]].map(|c| f16::from_f32(c as f32 / 255.0).to_bits()))
                .collect(),
            wrap,
            filter: Filter::default(),
        }
    }

    /// A texture from linear RGBA values, rounded to half precision.
    pub fn from_linear(width: u32, height: u32, rgba: &[[f32; 4]], wrap: [Wrap; 2]) -> Texture {
        Texture {
            width,
            height,
            texels: rgba.iter().map(|p| p.map(|c| f16::from_f32(c).to_bits())).collect(),
            wrap,
            filter: Filter::default(),
        }
    }

    /// The texture read through `filter`.
    pub fn with_filter(self, filter: Filter) -> Texture {
        Texture { filter, ..self }
    }

    /// The texture at half its size each way (an odd side rounds up, a side of 1 stays), each
    /// texel the mean of the linear values of the texels it covers.
    pub fn halved(&self) -> Texture {
        let (width, height) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let mut texels = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                let columns = (2 * x)..(2 * x + 2).min(self.width);
                let rows = (2 * y)..(2 * y + 2).min(self.height);
                let mut sum = [0.0f32; 4];
                let mut count = 0.0;
                for row in rows {
                    for column in columns.clone() {
                        let texel = self.texel(column, row);
                        sum.iter_mut().zip(texel).for_each(|(s, t)| *s += t);
                        count += 1.0;
                    }
                }
                texels.push(sum.map(|s| f16::from_f32(s / count).to_bits()));
            }
        }
        Texture {
            width,
            height,
            texels,
            wrap: self.wrap,
            filter: self.filter,
        }
    }

    /// Appends the texture's mip chain to `out`: the image, then each level [`halved`](Self::halved)
    /// from the one before, down to a single texel. Returns the number of levels.
    pub fn push_mip_chain(&self, out: &mut Vec<[u16; 4]>) -> u32 {
        out.extend_from_slice(&self.texels);
        let levels = mip_sizes(self.width, self.height).count();
        let mut level = None::<Texture>;
        for _ in 1..levels {
            let next = level.as_ref().unwrap_or(self).halved();
            out.extend_from_slice(&next.texels);
            level = Some(next);
        }
        levels as u32
    }

    /// The texels of the image and its mipmaps together: what the texture takes of [`MAX_TEXELS`].
    pub fn stored_texels(&self) -> u64 {
        mip_sizes(self.width, self.height)
            .map(|(w, h)| w as u64 * h as u64)
            .sum()
    }

    /// The texel at column `x`, row `y`, as f32 (exact: every half is an f32).
    pub fn texel(&self, x: u32, y: u32) -> [f32; 4] {
        self.texels[(y * self.width + x) as usize].map(|bits| f16::from_bits(bits).to_f32())
    }

    /// Why the texture cannot be rendered, if it cannot: its size and texels.
    pub fn validate(&self) -> Result<(), InputError> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
            return Err(InputError::new(format!(
                "size {w}x{h}: each side must be in 1..={MAX_TEXTURE_SIDE}"
            )));
        }
        if self.texels.len() as u64 != w as u64 * h as u64 {
            return Err(InputError::new(format!(
                "{} texels for a {w}x{h} image",
                self.texels.len()
            )));
        }
        if self
            .texels
            .iter()
            .flatten()
            .any(|&bits| !f16::from_bits(bits).is_finite())
        {
            return Err(InputError::new("texels must be finite"));
        }
        Ok(())
    }
}

/// The sizes of a `width` x `height` image's mip levels, the image first: each side halved and
/// rounded up, down to 1 x 1 (what the shader's `mip_level` walks).
pub(crate) fn mip_sizes(width: u32, height: u32) -> impl Iterator<Item = (u32, u32)> {
    std::iter::successors(Some((width, height)), |&(w, h)| {
        ((w, h) != (1, 1)).then(|| (w.div_ceil(2), h.div_ceil(2)))
    })
}

/// Halves the largest of `textures` until they hold at most `budget` texels together, mipmaps
/// counted ([`MAX_TEXELS`] or less; a texture of one texel cannot shrink, and with a million of them the sum cannot exceed
/// the limit). Returns how many halvings it took.
pub(crate) fn shrink_to_fit(textures: &mut [Texture], budget: u64) -> usize {
    let size = |t: &Texture| t.stored_texels();
    let mut total: u64 = textures.iter().map(size).sum();
    let mut halvings = 0;
    while total > budget {
        let Some(largest) = textures.iter_mut().filter(|t| size(t) > 1).max_by_key(|t| size(t)) else {
            break;
        };
        let before = size(largest);
        *largest = largest.halved();
        total -= before - size(largest);
        halvings += 1;
    }
    halvings
}

/// The sRGB transfer function's inverse (IEC 61966-2-1): an 8-bit encoded value to linear light.
pub fn srgb_to_linear(encoded: u8) -> f32 {
    let c = encoded as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decodes_to_linear_light() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        // Mid-grey encodes about a fifth of the light.
        assert!((srgb_to_linear(128) - 0.2158).abs() < 1e-3);
        let texture = Texture::from_srgb8(1, 1, &[255, 128, 0, 51], [Wrap::Repeat; 2]);
        let [r, g, b, a] = texture.texel(0, 0);
        assert_eq!((r, b), (1.0, 0.0));
        assert!((g - 0.2158).abs() < 1e-3 && (a - 0.2).abs() < 1e-3, "{g} {a}");
        texture.validate().unwrap();
    }

    #[test]
    fn halving_averages_blocks_and_shrinking_stops_at_the_limit() {
        // 3x1: an odd side keeps its last texel alone.
        let texture = Texture::from_linear(3, 1, &[[0.0; 4], [1.0; 4], [0.5, 0.25, 0.0, 1.0]], [Wrap::Clamp; 2]);
        let half = texture.halved();
        assert_eq!((half.width, half.height), (2, 1));
        assert_eq!(half.texel(0, 0), [0.5; 4]);
        assert_eq!(half.texel(1, 0), [0.5, 0.25, 0.0, 1.0]);
        // Two 4096 x 4096 textures (with their mipmaps, 2.7 times the limit) and a small one: the big
        // ones halve once each.
        let big = Texture {
            width: 4096,
            height: 4096,
            texels: vec![[0; 4]; 4096 * 4096],
            wrap: [Wrap::Repeat; 2],
            filter: Filter::default(),
        };
        let small = Texture::from_linear(2, 2, &[[1.0; 4]; 4], [Wrap::Repeat; 2]);
        let mut textures = vec![big.clone(), big, small.clone()];
        assert_eq!(shrink_to_fit(&mut textures, MAX_TEXELS), 2);
        assert_eq!([textures[0].width, textures[1].width], [2048, 2048]);
        assert_eq!(textures[2], small);
    }

    #[test]
    fn mip_chains_halve_down_to_one_texel() {
        let sizes: Vec<_> = mip_sizes(5, 2).collect();
        assert_eq!(sizes, [(5, 2), (3, 1), (2, 1), (1, 1)]);
        assert_eq!(mip_sizes(1, 1).count(), 1);
        // A 4 x 4 checker of one-texel squares: its 2 x 2 level is grey, and so is its last.
        let checker: Vec<[f32; 4]> = (0..16).map(|i| [((i % 4 + i / 4) % 2) as f32; 4]).collect();
        let texture = Texture::from_linear(4, 4, &checker, [Wrap::Repeat; 2]);
        let mut chain = Vec::new();
        assert_eq!(texture.push_mip_chain(&mut chain), 3);
        assert_eq!(chain.len() as u64, texture.stored_texels());
        assert_eq!(chain.len(), 16 + 4 + 1);
        let grey = [f16::from_f32(0.5).to_bits(); 4];
        assert!(chain[16..].iter().all(|&t| t == grey));
    }

    #[test]
    fn sizes_and_texel_counts_are_checked() {
        let mut texture = Texture::from_linear(2, 1, &[[0.0; 4]; 2], [Wrap::Clamp; 2]);
        texture.validate().unwrap();
        texture.height = 2;
        assert_eq!(texture.validate().unwrap_err().message, "2 texels for a 2x2 image");
        texture.width = 0;
        assert!(texture.validate().unwrap_err().message.starts_with("size 0x2"));
        let infinite = Texture::from_linear(1, 1, &[[f32::INFINITY, 0.0, 0.0, 1.0]], [Wrap::Clamp; 2]);
        assert_eq!(infinite.validate().unwrap_err().message, "texels must be finite");
    }
}
