//! Materials: the paper's Whitted model, and glTF's metallic-roughness model beside it.

use crate::error::InputError;
use glam::{Vec2, Vec3};

/// How a surface answers light. Two models share the record: the paper's Whitted material (Phong
/// direct light, a mirror share, a Fresnel-split transmitted share), and, where `pbr` is set,
/// glTF's metallic-roughness BRDF (docs/scene-format.md, "Materials").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Whitted: the diffuse albedo. glTF: the base colour (`baseColorFactor`'s RGB), linear.
    pub color: Vec3,
    /// Whitted: the weight of the Phong highlight. Unused by glTF materials.
    pub specular: f32,
    /// Whitted: the Phong exponent of the highlight. Unused by glTF materials.
    pub shininess: f32,
    /// Whitted: the mirror reflectance, 0..1. Unused by glTF materials, whose reflection follows
    /// from their Fresnel term.
    pub reflect: f32,
    /// Whitted: the transmittance, 0..1, split between reflection and refraction by Schlick's
    /// Fresnel term. glTF: KHR_materials_transmission's factor.
    pub transmit: f32,
    /// Index of refraction of the inside of the surface (the outside is vacuum, 1.0); glTF's
    /// KHR_materials_ior, 1.5 without it.
    pub ior: f32,
    /// Light the surface gives off itself, added to its shaded colour. glTF: `emissiveFactor`
    /// times KHR_materials_emissive_strength, times the emissive texture where there is one.
    pub emission: Vec3,
    /// A texture whose colour, at the hit's texture coordinates, multiplies `color` (on
    /// triangles that have coordinates).
    pub texture: Option<TextureMap>,
    /// glTF's metallic-roughness parameters; `None` for a Whitted material.
    pub pbr: Option<Pbr>,
    /// The coverage of the surface, 0..1 (`baseColorFactor`'s alpha), times the base colour
    /// texture's alpha where there is one; what it does follows from `alpha_mode`.
    pub alpha: f32,
    /// What the alpha does.
    pub alpha_mode: AlphaMode,
    /// Whether the back of a triangle with this material is seen (glTF's `doubleSided`); a
    /// single-sided triangle is invisible from behind to camera and reflected rays
    /// (docs/scene-format.md, "Alpha and sides"). Spheres and planes are always seen from both.
    pub double_sided: bool,
}

/// How a triangle's alpha covers what lies behind it (glTF's `alphaMode`). Spheres and planes
/// are always opaque.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// The surface is cut away where alpha is below `cutoff`, for every ray (shadow rays too), and
    /// fully there elsewhere.
    Mask {
        /// The least alpha that is surface.
        cutoff: f32,
    },
    /// The surface covers `alpha` of every ray that meets it; the rest goes on behind it, shadow
    /// rays too.
    Blend,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            color: Vec3::splat(0.8),
            specular: 0.0,
            shininess: 32.0,
            reflect: 0.0,
            transmit: 0.0,
            ior: 1.5,
            emission: Vec3::ZERO,
            texture: None,
            pbr: None,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            double_sided: true,
        }
    }
}

impl Material {
    /// What of the material only triangles carry: a single side or an alpha mode other than
    /// opaque, named for a message; `None` where a sphere or plane can wear it.
    pub fn triangle_only_part(&self) -> Option<&'static str> {
        if !self.double_sided {
            Some("one side")
        } else if self.alpha_mode != AlphaMode::Opaque {
            Some("an alpha mode other than opaque")
        } else {
            None
        }
    }

    /// The material with its maps' texture indices moved by `base`: its textures placed after
    /// `base` others in a scene's list.
    pub fn with_textures_from(&self, base: u32) -> Material {
        let shift = |map: Option<TextureMap>| {
            map.map(|m| TextureMap {
                texture: m.texture + base,
                ..m
            })
        };
        Material {
            texture: shift(self.texture),
            pbr: self.pbr.map(|p| Pbr {
                metallic_roughness_texture: shift(p.metallic_roughness_texture),
                occlusion_texture: shift(p.occlusion_texture),
                emissive_texture: shift(p.emissive_texture),
                normal_texture: shift(p.normal_texture),
                specular_texture: shift(p.specular_texture),
                specular_color_texture: shift(p.specular_color_texture),
                ..p
            }),
            ..*self
        }
    }
}

/// The parameters of glTF's metallic-roughness material (the specification's Appendix B) beyond
/// what it shares with a Whitted one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pbr {
    /// 0 (dielectric) to 1 (metal).
    pub metallic: f32,
    /// 0 (a mirror) to 1; the GGX distribution's alpha is its square.
    pub roughness: f32,
    /// KHR_materials_specular's `specularFactor`: the strength of a dielectric's specular layer,
    /// 0..1 (1 without the extension).
    pub specular_factor: f32,
    /// KHR_materials_specular's `specularColorFactor`, which tints a dielectric's reflectance at
    /// normal incidence (white without the extension).
    pub specular_color: Vec3,
    /// Linear data: alpha multiplies `specular_factor`.
    pub specular_texture: Option<TextureMap>,
    /// sRGB colour multiplying `specular_color`.
    pub specular_color_texture: Option<TextureMap>,
    /// Linear data: blue multiplies `metallic`, green `roughness`.
    pub metallic_roughness_texture: Option<TextureMap>,
    /// Linear data: red is the share of ambient light that reaches the surface.
    pub occlusion_texture: Option<TextureMap>,
    /// How much of the occlusion texture applies, 0..1.
    pub occlusion_strength: f32,
    /// sRGB colour multiplying `emission`.
    pub emissive_texture: Option<TextureMap>,
    /// Linear data: a tangent-space normal (x along the tangent, y along the bitangent, z along
    /// the vertex normal), each in 2 · value - 1, x and y scaled by `normal_scale`; on triangles
    /// with tangents.
    pub normal_texture: Option<TextureMap>,
    /// Scales the normal map's x and y.
    pub normal_scale: f32,
    /// KHR_materials_volume (with a thickness above 0): the surface bounds a volume of the
    /// transmissive medium, not a thin wall; `None`: a thin wall.
    pub volume: Option<Volume>,
    /// KHR_materials_unlit: the base colour (times its map) is the surface's radiance; lights,
    /// reflections, transmission and emission are left out.
    pub unlit: bool,
}

impl Default for Pbr {
    /// glTF's defaults: a rough metal, as a material without `pbrMetallicRoughness` is.
    fn default() -> Self {
        Self {
            metallic: 1.0,
            roughness: 1.0,
            specular_factor: 1.0,
            specular_color: Vec3::ONE,
            specular_texture: None,
            specular_color_texture: None,
            metallic_roughness_texture: None,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            volume: None,
            unlit: false,
        }
    }
}

impl Pbr {
    /// The textures the material reads besides its base colour's.
    pub fn maps(&self) -> [Option<TextureMap>; 6] {
        [
            self.metallic_roughness_texture,
            self.occlusion_texture,
            self.emissive_texture,
            self.normal_texture,
            self.specular_texture,
            self.specular_color_texture,
        ]
    }
}

/// The medium inside a KHR_materials_volume surface: rays refract where they cross the surface
/// and lose light inside by Beer-Lambert's law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Volume {
    /// The colour white light takes after `attenuation_distance` inside, linear, each channel
    /// in 0..=1.
    pub attenuation_color: Vec3,
    /// Positive; infinity for a clear medium.
    pub attenuation_distance: f32,
}

impl Volume {
    /// The absorption coefficient per unit length, -ln(colour) / distance per channel (a colour
    /// channel of 0 absorbs as one of 1e-6 does).
    pub fn absorption(&self) -> Vec3 {
        let color = self.attenuation_color.max(Vec3::splat(1e-6));
        -Vec3::new(color.x.ln(), color.y.ln(), color.z.ln()) / self.attenuation_distance
    }
}

/// A texture as a material maps it: which of the scene's textures, and how the surface's texture
/// coordinates are carried to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureMap {
    /// Index into `Scene::textures`.
    pub texture: u32,
    /// How coordinates are carried to the texture.
    pub transform: TextureTransform,
    /// Which of a triangle's texture coordinate sets it reads: 0 (`Triangle::uvs`) or 1
    /// (`Triangle::uvs1`).
    pub tex_coord: u32,
}

impl TextureMap {
    /// The texture with coordinates used as they are.
    pub fn plain(texture: u32) -> TextureMap {
        TextureMap {
            texture,
            transform: TextureTransform::default(),
            tex_coord: 0,
        }
    }
}

/// KHR_texture_transform: coordinates scaled, then rotated about the origin, then offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureTransform {
    /// Added last.
    pub offset: Vec2,
    /// Radians, turning coordinates counter-clockwise (the image clockwise).
    pub rotation: f32,
    /// Applied first.
    pub scale: Vec2,
}

impl Default for TextureTransform {
    fn default() -> Self {
        Self {
            offset: Vec2::ZERO,
            rotation: 0.0,
            scale: Vec2::ONE,
        }
    }
}

impl TextureTransform {
    /// The two rows of the 2x3 matrix T R S: (u', v') = rows · (u, v, 1). R turns counter-clockwise
    /// as one sees the image, whose v runs down: (u, v) to (cos u + sin v, -sin u + cos v), the
    /// matrix of KHR_texture_transform's errata (KhronosGroup/glTF#1563) that the Sample Viewer,
    /// Babylon.js and Blender use, not the README's listing.
    pub fn rows(&self) -> [[f32; 3]; 2] {
        let (sin, cos) = self.rotation.sin_cos();
        let Vec2 { x: sx, y: sy } = self.scale;
        [
            [cos * sx, sin * sy, self.offset.x],
            [-sin * sx, cos * sy, self.offset.y],
        ]
    }

    fn is_finite(&self) -> bool {
        self.offset.is_finite() && self.rotation.is_finite() && self.scale.is_finite()
    }
}

/// The checks `Scene::validate` makes of one material, with `texture_count` textures to name.
pub(crate) fn validate_material(m: &Material, texture_count: usize) -> Result<(), InputError> {
    if !m.color.is_finite() {
        return Err(InputError::new("color must be finite"));
    }
    if !(m.emission.is_finite() && m.emission.min_element() >= 0.0) {
        return Err(InputError::new("emission must be finite and not negative"));
    }
    let maps = m.pbr.as_ref().map(Pbr::maps).unwrap_or_default();
    for map in std::iter::once(m.texture).chain(maps).flatten() {
        if map.texture as usize >= texture_count {
            return Err(InputError::new(format!(
                "texture index {} out of range ({texture_count} textures)",
                map.texture
            )));
        }
        if !map.transform.is_finite() {
            return Err(InputError::new("texture transform must be finite"));
        }
        if map.tex_coord > 1 {
            return Err(InputError::new(format!(
                "texture coordinate set {} (sets 0 and 1 are read)",
                map.tex_coord
            )));
        }
    }
    for (name, value) in [
        ("specular", m.specular),
        ("shininess", m.shininess),
        ("reflect", m.reflect),
        ("transmit", m.transmit),
    ] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(InputError::new(format!(
                "{name} must be finite and not negative (got {value})"
            )));
        }
    }
    if m.reflect > 1.0 || m.transmit > 1.0 {
        return Err(InputError::new("reflect and transmit must be at most 1"));
    }
    if !(0.0..=1.0).contains(&m.alpha) {
        return Err(InputError::new(format!("alpha must be in 0..=1 (got {})", m.alpha)));
    }
    if let AlphaMode::Mask { cutoff } = m.alpha_mode
        && !(cutoff.is_finite() && cutoff >= 0.0)
    {
        return Err(InputError::new(format!(
            "alpha cutoff must be finite and not negative (got {cutoff})"
        )));
    }
    if !(m.ior.is_finite() && m.ior > 0.0) {
        return Err(InputError::new(format!(
            "ior must be positive and finite (got {})",
            m.ior
        )));
    }
    if let Some(pbr) = &m.pbr {
        for (name, value) in [
            ("metallic", pbr.metallic),
            ("roughness", pbr.roughness),
            ("specular factor", pbr.specular_factor),
            ("occlusion strength", pbr.occlusion_strength),
        ] {
            if !(0.0..=1.0).contains(&value) {
                return Err(InputError::new(format!("{name} must be in 0..=1 (got {value})")));
            }
        }
        if let Some(volume) = pbr.volume {
            let color = volume.attenuation_color;
            if !(color.is_finite() && color.min_element() >= 0.0 && color.max_element() <= 1.0) {
                return Err(InputError::new("attenuation colour must be in 0..=1"));
            }
            if volume.attenuation_distance.is_nan() || volume.attenuation_distance <= 0.0 {
                return Err(InputError::new(format!(
                    "attenuation distance must be positive (got {})",
                    volume.attenuation_distance
                )));
            }
        }
        if !pbr.normal_scale.is_finite() {
            return Err(InputError::new("normal scale must be finite"));
        }
        if !(pbr.specular_color.is_finite() && pbr.specular_color.min_element() >= 0.0) {
            return Err(InputError::new("specular colour must be finite and not negative"));
        }
    }
    Ok(())
}
