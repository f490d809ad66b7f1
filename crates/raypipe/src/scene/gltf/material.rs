//! glTF materials as Whitted materials, and their base-colour images as textures.
//!
//! The mapping (docs/scene-format.md, "glTF"):
//! - colour: baseColorFactor's RGB, times the base-colour texture (sRGB, decoded to linear);
//! - smoothness s = (1 - roughness)^2; mirror reflectance = metallic x s, and the diffuse colour
//!   keeps the rest, (1 - reflectance);
//! - highlight weight = s / 2, with the Phong exponent 2 / roughness^4 - 2 (the Blinn-Phong
//!   exponent of the same lobe width as GGX's alpha = roughness^2), between 1 and 10,000;
//! - KHR_materials_transmission's factor is the transmittance, taken from the diffuse colour's
//!   share, with KHR_materials_ior's index (1.5 without it);
//! - emissiveFactor, times KHR_materials_emissive_strength, is the emission.

use super::data::{Files, MAX_IMAGE_BYTES, read_uri, view_bytes};
use crate::scene::texture::{MAX_TEXELS, MAX_TEXTURE_SIDE};
use crate::scene::{Material, Texture, Wrap};
use glam::Vec3;
use gltf::texture::WrappingMode;
use std::collections::HashMap;

/// The document's materials and the textures they use, built once each.
pub struct Materials {
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    /// The material of primitives without one (glTF's default material), added on first use.
    default: Option<u32>,
    texels: u64,
    /// (image, wrap) to texture index.
    by_image: HashMap<(usize, [Wrap; 2]), u32>,
}

impl Materials {
    pub fn new() -> Self {
        Self {
            materials: Vec::new(),
            textures: Vec::new(),
            default: None,
            texels: 0,
            by_image: HashMap::new(),
        }
    }

    /// Reads every material of the document, in its order.
    pub fn read(
        &mut self,
        document: &gltf::Document,
        buffers: &[Vec<u8>],
        files: Files,
        notices: &mut Vec<String>,
    ) -> Result<(), String> {
        let mut ignored_maps = false;
        let mut alpha = false;
        for material in document.materials() {
            let what = format!("material {}", material.index().unwrap_or(0));
            let pbr = material.pbr_metallic_roughness();
            let [r, g, b, _] = pbr.base_color_factor();
            let texture = match pbr.base_color_texture() {
                Some(info) if info.tex_coord() != 0 => {
                    notices.push(format!(
                        "{what}: base-colour texture on TEXCOORD_{}: only TEXCOORD_0 is read, so it is left out",
                        info.tex_coord()
                    ));
                    None
                }
                Some(info) => Some(
                    self.texture(document.as_json(), &info.texture(), buffers, files)
                        .map_err(|e| format!("{what}: {e}"))?,
                ),
                None => None,
            };
            ignored_maps |= material.normal_texture().is_some()
                || material.occlusion_texture().is_some()
                || material.emissive_texture().is_some()
                || pbr.metallic_roughness_texture().is_some();
            alpha |= material.alpha_mode() != gltf::material::AlphaMode::Opaque;
            let emission = Vec3::from(material.emissive_factor()) * material.emissive_strength().unwrap_or(1.0);
            let transmission = material.transmission().map_or(0.0, |t| t.transmission_factor());
            let ior = material.ior().unwrap_or(1.5);
            let mapped = whitted(
                Vec3::new(r, g, b),
                pbr.metallic_factor(),
                pbr.roughness_factor(),
                transmission,
                ior,
                emission,
                texture,
            );
            crate::scene::validate_material(&mapped, self.textures.len()).map_err(|e| format!("{what}: {e}"))?;
            self.materials.push(mapped);
        }
        if ignored_maps {
            notices.push("normal, occlusion, emissive and metallic-roughness textures are not used".into());
        }
        if alpha {
            notices.push("alpha modes BLEND and MASK are rendered opaque".into());
        }
        Ok(())
    }

    /// The index of a primitive's material: the document's, or the default material.
    pub fn index_of(&mut self, material: Option<usize>) -> u32 {
        match material {
            Some(index) => index as u32,
            None => *self.default.get_or_insert_with(|| {
                self.materials
                    .push(whitted(Vec3::ONE, 1.0, 1.0, 0.0, 1.5, Vec3::ZERO, None));
                self.materials.len() as u32 - 1
            }),
        }
    }

    fn texture(
        &mut self,
        root: &gltf::json::Root,
        texture: &gltf::Texture,
        buffers: &[Vec<u8>],
        files: Files,
    ) -> Result<u32, String> {
        let sampler = texture.sampler();
        let wrap = [sampler.wrap_s(), sampler.wrap_t()].map(|mode| match mode {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::ClampToEdge => Wrap::Clamp,
            WrappingMode::MirroredRepeat => Wrap::Mirror,
        });
        let image = texture.source().index();
        if let Some(&index) = self.by_image.get(&(image, wrap)) {
            return Ok(index);
        }
        let what = format!("image {image}");
        // Read from the JSON: gltf's `Image::source` unwraps a missing uri and a view's missing
        // mimeType, which no validation checks (found by the fuzz target).
        let json = &root.images[image];
        let mime = json.mime_type.as_ref().map(|m| m.0.as_str());
        let bytes = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => view_bytes(root, buffers, view.value())
                .map_err(|e| format!("{what}: {e}"))?
                .to_vec(),
            (None, Some(uri)) => read_uri(uri, files, MAX_IMAGE_BYTES, &what)?,
            (None, None) => return Err(format!("{what}: neither a bufferView nor a uri")),
        };
        let budget = MAX_TEXELS - self.texels;
        let (width, height, rgba) = decode_image(&bytes, mime, budget).map_err(|e| format!("{what}: {e}"))?;
        self.texels += width as u64 * height as u64;
        self.textures.push(Texture::from_srgb8(width, height, &rgba, wrap));
        let index = self.textures.len() as u32 - 1;
        self.by_image.insert((image, wrap), index);
        Ok(index)
    }
}

/// A metallic-roughness material as a Whitted one (the module's comment gives the mapping).
pub fn whitted(
    base: Vec3,
    metallic: f32,
    roughness: f32,
    transmission: f32,
    ior: f32,
    emission: Vec3,
    texture: Option<u32>,
) -> Material {
    let metallic = metallic.clamp(0.0, 1.0);
    let roughness = roughness.clamp(0.0, 1.0);
    let transmission = transmission.clamp(0.0, 1.0);
    let smoothness = (1.0 - roughness) * (1.0 - roughness);
    let reflect = metallic * smoothness;
    let transmit = transmission * (1.0 - reflect);
    let alpha_squared = (roughness * roughness * roughness * roughness).max(1e-12);
    Material {
        color: base * (1.0 - reflect - transmit),
        specular: smoothness * 0.5,
        shininess: (2.0 / alpha_squared - 2.0).clamp(1.0, 10_000.0),
        reflect,
        transmit,
        ior,
        emission,
        texture,
    }
}

/// An image file's pixels as 8-bit RGBA, by its MIME type or, without one, its first bytes. Its
/// size is checked from the header, before the pixels are decoded: each side at most
/// MAX_TEXTURE_SIDE, and at most `budget` texels.
fn decode_image(bytes: &[u8], mime: Option<&str>, budget: u64) -> Result<(u32, u32, Vec<u8>), String> {
    let png = match mime {
        Some("image/png") => true,
        Some("image/jpeg") => false,
        Some(other) => return Err(format!("images of type {other} are not read (PNG and JPEG are)")),
        None if bytes.starts_with(b"\x89PNG") => true,
        None if bytes.starts_with(&[0xff, 0xd8]) => false,
        None => return Err("not a PNG or JPEG image".into()),
    };
    let check = |width: u32, height: u32| {
        if width == 0 || height == 0 || width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
            return Err(format!(
                "{width}x{height} pixels: each side must be in 1..={MAX_TEXTURE_SIDE}"
            ));
        }
        if width as u64 * height as u64 > budget {
            return Err(format!(
                "{width}x{height} pixels: the scene's textures would hold more than {MAX_TEXELS} texels"
            ));
        }
        Ok(())
    };
    if png {
        decode_png(bytes, check)
    } else {
        decode_jpeg(bytes, check)
    }
}

fn decode_png(bytes: &[u8], check: impl Fn(u32, u32) -> Result<(), String>) -> Result<(u32, u32, Vec<u8>), String> {
    // The size stands at a fixed place in the first chunk, IHDR, which every PNG has: checked
    // before the decoder reads on (a file without it is one the decoder refuses).
    if bytes.len() >= 24 && &bytes[12..16] == b"IHDR" {
        let number = |at: usize| u32::from_be_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
        check(number(16), number(20))?;
    }
    let fail = |e: png::DecodingError| format!("PNG: {e}");
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(fail)?;
    let (width, height) = (reader.info().width, reader.info().height);
    let size = reader.output_buffer_size().ok_or("PNG: image too large")?;
    let mut pixels = vec![0; size];
    let frame = reader.next_frame(&mut pixels).map_err(fail)?;
    pixels.truncate(frame.buffer_size());
    let rgba = match frame.color_type {
        png::ColorType::Rgba => pixels,
        png::ColorType::Rgb => pixels.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect(),
        png::ColorType::GrayscaleAlpha => pixels.chunks_exact(2).flat_map(|p| [p[0], p[0], p[0], p[1]]).collect(),
        png::ColorType::Grayscale => pixels.iter().flat_map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::Indexed => return Err("PNG: palette not expanded".into()),
    };
    Ok((width, height, rgba))
}

fn decode_jpeg(bytes: &[u8], check: impl Fn(u32, u32) -> Result<(), String>) -> Result<(u32, u32, Vec<u8>), String> {
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGBA)
        .set_max_width(MAX_TEXTURE_SIDE as usize)
        .set_max_height(MAX_TEXTURE_SIDE as usize);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(bytes), options);
    decoder.decode_headers().map_err(|e| format!("JPEG: {e:?}"))?;
    let info = decoder.info().ok_or("JPEG: no header")?;
    let (width, height) = (info.width as u32, info.height as u32);
    check(width, height)?;
    let pixels = decoder.decode().map_err(|e| format!("JPEG: {e:?}"))?;
    if pixels.len() != width as usize * height as usize * 4 {
        return Err("JPEG: decoded to the wrong size".into());
    }
    Ok((width, height, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rough_dielectrics_are_diffuse_and_smooth_metals_mirrors() {
        let clay = whitted(Vec3::new(0.8, 0.5, 0.2), 0.0, 1.0, 0.0, 1.5, Vec3::ZERO, None);
        assert_eq!((clay.reflect, clay.transmit, clay.specular), (0.0, 0.0, 0.0));
        assert_eq!(clay.color, Vec3::new(0.8, 0.5, 0.2));
        let chrome = whitted(Vec3::ONE, 1.0, 0.0, 0.0, 1.5, Vec3::ZERO, None);
        assert_eq!((chrome.reflect, chrome.color), (1.0, Vec3::ZERO));
        assert_eq!(chrome.shininess, 10_000.0);
        let glass = whitted(Vec3::ONE, 0.0, 0.0, 1.0, 1.45, Vec3::ZERO, None);
        assert_eq!((glass.transmit, glass.ior, glass.color), (1.0, 1.45, Vec3::ZERO));
        // Half rough: the exponent of alpha = 0.25, 2 / 0.0625 - 2 = 30.
        assert_eq!(whitted(Vec3::ONE, 0.0, 0.5, 0.0, 1.5, Vec3::ZERO, None).shininess, 30.0);
    }

    #[test]
    fn images_that_are_neither_png_nor_jpeg_are_refused() {
        // The size check before decoding is in tests/gltf.rs (a_huge_texture_is_refused_...).
        assert!(
            decode_image(b"GIF89a", None, MAX_TEXELS)
                .unwrap_err()
                .contains("not a PNG or JPEG")
        );
        assert!(
            decode_image(b"", Some("image/webp"), MAX_TEXELS)
                .unwrap_err()
                .contains("image/webp")
        );
    }
}
