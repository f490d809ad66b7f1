//! glTF materials, read as the specification defines them, and the images they map.
//!
//! Every glTF material is a metallic-roughness one ([`Pbr`]): base colour (factor times texture,
//! sRGB decoded to linear), metalness and roughness (factors times the texture's blue and green),
//! occlusion (its texture's red, by `strength`), emission (`emissiveFactor` times
//! KHR_materials_emissive_strength times the emissive texture), KHR_materials_transmission,
//! KHR_materials_ior, KHR_materials_volume, KHR_materials_specular (factors times the strength
//! texture's alpha and the colour texture's RGB) and KHR_materials_unlit. Every map may carry a
//! KHR_texture_transform, on TEXCOORD_0 or TEXCOORD_1; normal maps; the alpha mode, cutoff and
//! sides. What is not read yet is named in one notice: maps on TEXCOORD_2 and above.

use super::data::{Files, MAX_IMAGE_BYTES, read_uri, view_bytes};
use crate::error::{GltfPart, InputError};
use crate::scene::texture::{MAX_DECODED_TEXELS, MAX_TEXELS, MAX_TEXTURE_SIDE, shrink_to_fit};
use crate::scene::{
    AlphaMode, Filter, Material, Pbr, TexelFilter, Texture, TextureMap, TextureTransform, Volume, Wrap,
};
use glam::{Vec2, Vec3};
use gltf::texture::{MagFilter, MinFilter, WrappingMode};
use std::collections::{BTreeSet, HashMap};

/// How an image's values are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Encoding {
    /// sRGB-encoded colour (base colour, emission), decoded to linear.
    Srgb,
    /// Linear data (metalness and roughness, occlusion).
    Data,
}

/// A map as a textureInfo names it: the texture, the coordinate set, and the transform.
struct MapInfo<'a> {
    texture: gltf::Texture<'a>,
    tex_coord: u32,
    transform: Option<&'a gltf::json::Value>,
}

impl<'a> MapInfo<'a> {
    fn of(info: &'a gltf::texture::Info<'a>) -> Self {
        Self {
            texture: info.texture(),
            tex_coord: info.tex_coord(),
            transform: info.extension_value(TEXTURE_TRANSFORM),
        }
    }
}

const TEXTURE_TRANSFORM: &str = "KHR_texture_transform";

/// The [`MapInfo`] of an occlusion or normal texture, which gltf gives types of their own with
/// textureInfo's methods.
macro_rules! map_info {
    ($info:expr) => {
        MapInfo {
            texture: $info.texture(),
            tex_coord: $info.tex_coord(),
            transform: $info.extension_value(TEXTURE_TRANSFORM),
        }
    };
}

/// The document's materials and the textures they use, built once each.
pub(crate) struct Materials {
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    /// The material of primitives without one (glTF's default material), added on first use.
    default: Option<u32>,
    texels: u64,
    /// (image, wrap, filter, encoding) to texture index.
    by_image: HashMap<(usize, [Wrap; 2], Filter, Encoding), u32>,
    /// What the materials hold that is not drawn, said once each.
    left_out: BTreeSet<&'static str>,
}

impl Materials {
    pub fn new() -> Self {
        Self {
            materials: Vec::new(),
            textures: Vec::new(),
            default: None,
            texels: 0,
            by_image: HashMap::new(),
            left_out: BTreeSet::new(),
        }
    }

    /// Reads every material of the document, in its order.
    pub fn read(
        &mut self,
        document: &gltf::Document,
        buffers: &[Vec<u8>],
        files: Files,
        notices: &mut Vec<String>,
    ) -> Result<(), InputError> {
        for material in document.materials() {
            let within = |e: InputError| e.within(GltfPart::Material(material.index().unwrap_or(0)));
            let read = self
                .material(document.as_json(), &material, buffers, files)
                .map_err(within)?;
            crate::scene::material::validate_material(&read, self.textures.len()).map_err(within)?;
            self.materials.push(read);
        }
        let halvings = shrink_to_fit(&mut self.textures, MAX_TEXELS);
        if halvings > 0 {
            notices.push(format!(
                "textures halved {halvings} times to fit the {MAX_TEXELS} texels a render holds"
            ));
        }
        notices.extend(self.left_out.iter().map(|s| s.to_string()));
        Ok(())
    }

    /// One material with its maps.
    fn material(
        &mut self,
        root: &gltf::json::Root,
        material: &gltf::Material,
        buffers: &[Vec<u8>],
        files: Files,
    ) -> Result<Material, InputError> {
        let pbr = material.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let map =
            |info: Option<MapInfo>, encoding: Encoding, this: &mut Self| -> Result<Option<TextureMap>, InputError> {
                let Some(info) = info else { return Ok(None) };
                this.map(root, &info, encoding, buffers, files)
            };
        let base = map(pbr.base_color_texture().as_ref().map(MapInfo::of), Encoding::Srgb, self)?;
        let metallic_roughness = map(
            pbr.metallic_roughness_texture().as_ref().map(MapInfo::of),
            Encoding::Data,
            self,
        )?;
        let emissive = map(
            material.emissive_texture().as_ref().map(MapInfo::of),
            Encoding::Srgb,
            self,
        )?;
        let occlusion = material.occlusion_texture();
        let occlusion_map = map(occlusion.as_ref().map(|o| map_info!(o)), Encoding::Data, self)?;
        let normal = material.normal_texture();
        let normal_map = map(normal.as_ref().map(|n| map_info!(n)), Encoding::Data, self)?;
        let specular = material.specular();
        let specular_map = map(
            specular
                .as_ref()
                .and_then(|s| s.specular_texture())
                .as_ref()
                .map(MapInfo::of),
            Encoding::Data,
            self,
        )?;
        let specular_color_map = map(
            specular
                .as_ref()
                .and_then(|s| s.specular_color_texture())
                .as_ref()
                .map(MapInfo::of),
            Encoding::Srgb,
            self,
        )?;
        let emission = Vec3::from(material.emissive_factor()) * material.emissive_strength().unwrap_or(1.0);
        Ok(Material {
            color: Vec3::new(r, g, b),
            transmit: material
                .transmission()
                .map_or(0.0, |t| t.transmission_factor())
                .clamp(0.0, 1.0),
            ior: material.ior().unwrap_or(1.5),
            emission,
            texture: base,
            pbr: Some(Pbr {
                metallic: pbr.metallic_factor().clamp(0.0, 1.0),
                roughness: pbr.roughness_factor().clamp(0.0, 1.0),
                specular_factor: specular.as_ref().map_or(1.0, |s| s.specular_factor()).clamp(0.0, 1.0),
                specular_color: specular
                    .as_ref()
                    .map_or(Vec3::ONE, |s| Vec3::from(s.specular_color_factor())),
                specular_texture: specular_map,
                specular_color_texture: specular_color_map,
                metallic_roughness_texture: metallic_roughness,
                occlusion_texture: occlusion_map,
                occlusion_strength: occlusion.as_ref().map_or(1.0, |o| o.strength()).clamp(0.0, 1.0),
                emissive_texture: emissive,
                normal_texture: normal_map,
                normal_scale: normal.as_ref().map_or(1.0, |n| n.scale()),
                // A thickness of 0 is the extension's thin wall; a ray tracer measures the
                // rest from the geometry, so the thickness's value and map are not read.
                volume: material
                    .volume()
                    .filter(|v| v.thickness_factor() > 0.0)
                    .map(|v| Volume {
                        attenuation_color: Vec3::from(v.attenuation_color()),
                        attenuation_distance: v.attenuation_distance(),
                    }),
                unlit: material.unlit(),
            }),
            alpha: alpha.clamp(0.0, 1.0),
            alpha_mode: match material.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                    cutoff: material.alpha_cutoff().unwrap_or(0.5),
                },
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            double_sided: material.double_sided(),
            ..Material::default()
        })
    }

    /// A map of the material's: its texture (decoded once per image, wrap and encoding) and
    /// transform; `None`, with a notice, where it reads coordinates the tracers do not carry.
    fn map(
        &mut self,
        root: &gltf::json::Root,
        info: &MapInfo,
        encoding: Encoding,
        buffers: &[Vec<u8>],
        files: Files,
    ) -> Result<Option<TextureMap>, InputError> {
        let (transform, tex_coord) = texture_transform(info.transform, info.tex_coord)?;
        if tex_coord > 1 {
            self.left_out
                .insert("maps on TEXCOORD_2 and above are left out: TEXCOORD_0 and TEXCOORD_1 are read");
            return Ok(None);
        }
        let texture = self.texture(root, &info.texture, encoding, buffers, files)?;
        Ok(Some(TextureMap {
            texture,
            transform,
            tex_coord,
        }))
    }

    /// Checks that a primitive with material `index` has what its maps read: the coordinate set
    /// of each (`sets`: whether it has TEXCOORD_0 and TEXCOORD_1), and for a normal map its
    /// normals. Says whether the primitive needs tangents (its material has a normal map).
    pub fn check_attributes(&self, index: u32, sets: [bool; 2], has_normals: bool) -> Result<bool, InputError> {
        let material = &self.materials[index as usize];
        let pbr = material.pbr.unwrap_or_default();
        let maps = std::iter::once(material.texture).chain(pbr.maps()).flatten();
        for map in maps {
            if !sets[map.tex_coord as usize] {
                return Err(InputError::new(format!(
                    "material {index} reads TEXCOORD_{}, which the primitive lacks",
                    map.tex_coord
                )));
            }
        }
        if pbr.normal_texture.is_some() && !has_normals {
            return Err(InputError::new(format!(
                "material {index} has a normal map, and the primitive has no NORMAL"
            )));
        }
        Ok(pbr.normal_texture.is_some())
    }

    /// The coordinate set material `index`'s normal map reads.
    pub fn normal_map_set(&self, index: u32) -> u32 {
        let pbr = self.materials[index as usize].pbr.unwrap_or_default();
        pbr.normal_texture.map_or(0, |map| map.tex_coord)
    }

    /// The index of a primitive's material: the document's, or the default material.
    pub fn index_of(&mut self, material: Option<usize>) -> u32 {
        match material {
            Some(index) => index as u32,
            None => *self.default.get_or_insert_with(|| {
                // glTF's default material: white, a rough metal, opaque, single-sided.
                self.materials.push(Material {
                    color: Vec3::ONE,
                    pbr: Some(Pbr::default()),
                    double_sided: false,
                    ..Material::default()
                });
                self.materials.len() as u32 - 1
            }),
        }
    }

    fn texture(
        &mut self,
        root: &gltf::json::Root,
        texture: &gltf::Texture,
        encoding: Encoding,
        buffers: &[Vec<u8>],
        files: Files,
    ) -> Result<u32, InputError> {
        let sampler = texture.sampler();
        let wrap = [sampler.wrap_s(), sampler.wrap_t()].map(|mode| match mode {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::ClampToEdge => Wrap::Clamp,
            WrappingMode::MirroredRepeat => Wrap::Mirror,
        });
        let filter = sampler_filter(sampler.mag_filter(), sampler.min_filter());
        let image = texture.source().index();
        if let Some(&index) = self.by_image.get(&(image, wrap, filter, encoding)) {
            return Ok(index);
        }
        let within = |e: InputError| e.within(GltfPart::Image(image));
        // Read from the JSON: gltf's `Image::source` unwraps a missing uri and a view's missing
        // mimeType, which no validation checks (found by the fuzz target).
        let json = &root.images[image];
        let mime = json.mime_type.as_ref().map(|m| m.0.as_str());
        let bytes = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => view_bytes(root, buffers, view.value()).map_err(within)?.to_vec(),
            (None, Some(uri)) => read_uri(uri, files, MAX_IMAGE_BYTES, GltfPart::Image(image))?,
            (None, None) => return Err(within(InputError::new("neither a bufferView nor a uri"))),
        };
        let budget = MAX_DECODED_TEXELS - self.texels;
        let (width, height, rgba) = decode_image(&bytes, mime, budget).map_err(within)?;
        self.texels += width as u64 * height as u64;
        self.textures.push(match encoding {
            Encoding::Srgb => Texture::from_srgb8(width, height, &rgba, wrap).with_filter(filter),
            Encoding::Data => Texture::from_data8(width, height, &rgba, wrap).with_filter(filter),
        });
        let index = self.textures.len() as u32 - 1;
        self.by_image.insert((image, wrap, filter, encoding), index);
        Ok(index)
    }
}

/// A glTF sampler's filters; where it names none, trilinear (as the Khronos viewers read them).
fn sampler_filter(magnify: Option<MagFilter>, minify: Option<MinFilter>) -> Filter {
    use TexelFilter::{Linear, Nearest};
    let mut filter = Filter::default();
    if magnify == Some(MagFilter::Nearest) {
        filter.magnify = Nearest;
    }
    if let Some(minify) = minify {
        (filter.minify, filter.mipmaps) = match minify {
            MinFilter::Nearest => (Nearest, None),
            MinFilter::Linear => (Linear, None),
            MinFilter::NearestMipmapNearest => (Nearest, Some(Nearest)),
            MinFilter::LinearMipmapNearest => (Linear, Some(Nearest)),
            MinFilter::NearestMipmapLinear => (Nearest, Some(Linear)),
            MinFilter::LinearMipmapLinear => (Linear, Some(Linear)),
        };
    }
    filter
}

/// A KHR_texture_transform object's transform and texture coordinate set (`texCoord` overrides
/// the textureInfo's `tex_coord`); the identity where there is none.
fn texture_transform(json: Option<&gltf::json::Value>, tex_coord: u32) -> Result<(TextureTransform, u32), InputError> {
    let mut transform = TextureTransform::default();
    let Some(json) = json else {
        return Ok((transform, tex_coord));
    };
    let fail = |what: &str| InputError::new(format!("{TEXTURE_TRANSFORM}: {what} must be finite numbers"));
    let pair = |name: &str, default: Vec2| -> Result<Vec2, InputError> {
        match json.get(name) {
            None => Ok(default),
            Some(value) => {
                let numbers: Option<Vec<f32>> = value
                    .as_array()
                    .map(|a| {
                        a.iter()
                            .map(|n| n.as_f64().map(|n| n as f32))
                            .collect::<Option<Vec<f32>>>()
                    })
                    .unwrap_or(None);
                match numbers.as_deref() {
                    Some(&[x, y]) if x.is_finite() && y.is_finite() => Ok(Vec2::new(x, y)),
                    _ => Err(fail(&format!("{name}: two"))),
                }
            }
        }
    };
    transform.offset = pair("offset", Vec2::ZERO)?;
    transform.scale = pair("scale", Vec2::ONE)?;
    if let Some(rotation) = json.get("rotation") {
        transform.rotation = rotation
            .as_f64()
            .map(|r| r as f32)
            .filter(|r| r.is_finite())
            .ok_or_else(|| fail("rotation: one"))?;
    }
    let tex_coord = match json.get("texCoord") {
        None => tex_coord,
        Some(set) => set
            .as_u64()
            .and_then(|s| u32::try_from(s).ok())
            .ok_or_else(|| InputError::new(format!("{TEXTURE_TRANSFORM}: texCoord must be a set index")))?,
    };
    Ok((transform, tex_coord))
}

/// An image file's pixels as 8-bit RGBA, by its MIME type or, without one, its first bytes. Its
/// size is checked from the header, before the pixels are decoded: each side at most
/// MAX_TEXTURE_SIDE, and at most `budget` texels.
fn decode_image(bytes: &[u8], mime: Option<&str>, budget: u64) -> Result<(u32, u32, Vec<u8>), InputError> {
    let png = match mime {
        Some("image/png") => true,
        Some("image/jpeg") => false,
        Some(other) => {
            return Err(InputError::new(format!(
                "images of type {other} are not read (PNG and JPEG are)"
            )));
        }
        None if bytes.starts_with(b"\x89PNG") => true,
        None if bytes.starts_with(&[0xff, 0xd8]) => false,
        None => return Err(InputError::new("not a PNG or JPEG image")),
    };
    let check = |width: u32, height: u32| {
        if width == 0 || height == 0 || width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
            return Err(InputError::new(format!(
                "{width}x{height} pixels: each side must be in 1..={MAX_TEXTURE_SIDE}"
            )));
        }
        if width as u64 * height as u64 > budget {
            return Err(InputError::new(format!(
                "{width}x{height} pixels: the file's images would decode to more than {MAX_DECODED_TEXELS} texels"
            )));
        }
        Ok(())
    };
    if png {
        decode_png(bytes, check)
    } else {
        decode_jpeg(bytes, check)
    }
}

type Decoded = (u32, u32, Vec<u8>);

fn decode_png(bytes: &[u8], check: impl Fn(u32, u32) -> Result<(), InputError>) -> Result<Decoded, InputError> {
    // The size stands at a fixed place in the first chunk, IHDR, which every PNG has: checked
    // before the decoder reads on (a file without it is one the decoder refuses).
    if bytes.len() >= 24 && &bytes[12..16] == b"IHDR" {
        let number = |at: usize| u32::from_be_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
        check(number(16), number(20))?;
    }
    let fail = |e: png::DecodingError| InputError::new(format!("PNG: {e}"));
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(fail)?;
    let (width, height) = (reader.info().width, reader.info().height);
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| InputError::new("PNG: image too large"))?;
    let mut pixels = vec![0; size];
    let frame = reader.next_frame(&mut pixels).map_err(fail)?;
    pixels.truncate(frame.buffer_size());
    let rgba = match frame.color_type {
        png::ColorType::Rgba => pixels,
        png::ColorType::Rgb => pixels.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect(),
        png::ColorType::GrayscaleAlpha => pixels.chunks_exact(2).flat_map(|p| [p[0], p[0], p[0], p[1]]).collect(),
        png::ColorType::Grayscale => pixels.iter().flat_map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::Indexed => return Err(InputError::new("PNG: palette not expanded")),
    };
    Ok((width, height, rgba))
}

fn decode_jpeg(bytes: &[u8], check: impl Fn(u32, u32) -> Result<(), InputError>) -> Result<Decoded, InputError> {
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGBA)
        .set_max_width(MAX_TEXTURE_SIDE as usize)
        .set_max_height(MAX_TEXTURE_SIDE as usize);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(bytes), options);
    let fail = |e: zune_jpeg::errors::DecodeErrors| InputError::new(format!("JPEG: {e:?}"));
    decoder.decode_headers().map_err(fail)?;
    let info = decoder.info().ok_or_else(|| InputError::new("JPEG: no header"))?;
    let (width, height) = (info.width as u32, info.height as u32);
    check(width, height)?;
    let pixels = decoder.decode().map_err(fail)?;
    if pixels.len() != width as usize * height as usize * 4 {
        return Err(InputError::new("JPEG: decoded to the wrong size"));
    }
    Ok((width, height, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_transforms_are_read_with_their_defaults_and_texcoord_override() {
        let json: gltf::json::Value =
            serde_json::from_str(r#"{"offset": [0.5, 0.25], "rotation": 1.5, "texCoord": 1}"#).unwrap();
        let (transform, set) = texture_transform(Some(&json), 0).unwrap();
        assert_eq!(
            (transform.offset, transform.rotation, transform.scale, set),
            (Vec2::new(0.5, 0.25), 1.5, Vec2::ONE, 1)
        );
        assert_eq!(texture_transform(None, 0).unwrap(), (TextureTransform::default(), 0));
        let bad: gltf::json::Value = serde_json::from_str(r#"{"scale": [1]}"#).unwrap();
        assert!(texture_transform(Some(&bad), 0).unwrap_err().message.contains("scale"));
    }

    #[test]
    fn samplers_filters_are_read_and_default_to_trilinear() {
        use TexelFilter::{Linear, Nearest};
        assert_eq!(sampler_filter(None, None), Filter::default());
        assert_eq!(
            Filter::default(),
            Filter {
                magnify: Linear,
                minify: Linear,
                mipmaps: Some(Linear)
            }
        );
        let pixel_art = sampler_filter(Some(MagFilter::Nearest), Some(MinFilter::Nearest));
        assert_eq!(
            pixel_art,
            Filter {
                magnify: Nearest,
                minify: Nearest,
                mipmaps: None
            }
        );
        let cases = [
            (MinFilter::Linear, Linear, None),
            (MinFilter::NearestMipmapNearest, Nearest, Some(Nearest)),
            (MinFilter::LinearMipmapNearest, Linear, Some(Nearest)),
            (MinFilter::NearestMipmapLinear, Nearest, Some(Linear)),
            (MinFilter::LinearMipmapLinear, Linear, Some(Linear)),
        ];
        for (min, minify, mipmaps) in cases {
            let filter = sampler_filter(Some(MagFilter::Linear), Some(min));
            assert_eq!(
                (filter.magnify, filter.minify, filter.mipmaps),
                (Linear, minify, mipmaps),
                "{min:?}"
            );
        }
    }

    #[test]
    fn images_that_are_neither_png_nor_jpeg_are_refused() {
        // The size check before decoding is in tests/files/gltf.rs (a_huge_texture_is_refused_...).
        assert!(
            decode_image(b"GIF89a", None, MAX_TEXELS)
                .unwrap_err()
                .message
                .contains("not a PNG or JPEG")
        );
        assert!(
            decode_image(b"", Some("image/webp"), MAX_TEXELS)
                .unwrap_err()
                .message
                .contains("image/webp")
        );
    }
}
