//! Scenes: what is rendered, independent of how it reaches a tracer.
//!
//! A [`Scene`] comes from a TOML file ([`mod@file`]), a built-in generator ([`builtin`]), or a model
//! file read by [`mesh`](crate::mesh) or [`gltf`] and placed by [`model`]; [`Scene::load`] picks
//! between them. `records::PackedScene` turns it into the flat records that the GPU shader and the CPU
//! reference read.

pub mod animation;
pub mod builtin;
pub mod environment;
pub mod file;
pub mod gltf;
pub mod light;
mod load;
pub mod material;
pub mod model;
pub mod motion;
pub mod texture;

pub use environment::Environment;
pub use light::{Light, LightKind};
pub use load::{is_model_file, model_extension_list};
pub use material::{AlphaMode, Material, Pbr, TextureMap, TextureTransform, Volume};
pub use motion::{Bounce, Motion, Moved};
pub use texture::{Filter, TexelFilter, Texture, Wrap};

use crate::choice::impl_choice;
use crate::error::{Element, InputError};
use crate::modes::{Accel, Integrator};
use glam::{Quat, Vec2, Vec3, Vec4};
use material::validate_material;

/// A pinhole camera. The ray convention is documented in `docs/scene-format.md` and implemented in
/// `records::GpuCamera` (basis) and `camera_ray` (per pixel), identically on CPU and GPU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Where the pinhole is.
    pub eye: Vec3,
    /// The point the camera looks at: the image's centre.
    pub target: Vec3,
    /// The image's up direction (need not be perpendicular to the view).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_degrees: f32,
}

/// How exposed radiance is brought into [0, 1] for the screen and PNG files (applied by
/// [`crate::image::tonemap::DisplayTransform`] and the display pass; the traced radiance never).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ToneMap {
    /// Clipped at 1: the paper's images, and the TOML scenes' as they have always been.
    #[default]
    None,
    /// Khronos PBR Neutral: colours below 0.76 pass nearly unchanged (less a small toe), brighter
    /// ones compress toward white and desaturate.
    Neutral,
    /// ACES's reference and output transforms in Stephen Hill's fit, in and out of ACES's AP1
    /// primaries: a filmic curve that darkens mid-tones and shifts hues less than a per-channel one.
    Aces,
}

impl_choice!(
    ToneMap,
    [
        (None, "none", "radiance clipped at 1, as the paper's images are"),
        (
            Neutral,
            "neutral",
            "Khronos PBR Neutral: base colours as they are, highlights rolled off to white"
        ),
        (
            Aces,
            "aces",
            "ACES filmic (Hill's fit of the reference and output transforms)"
        ),
    ]
);

/// Render settings a scene may carry; command-line flags override them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Maximum number of bounces (reflection or refraction) after the primary ray.
    pub max_depth: u32,
    /// The radiance of rays that escape the scene.
    pub background: Vec3,
    /// Ambient light intensity, multiplied by a surface's diffuse colour.
    pub ambient: f32,
    /// How the scene asks to be traced (TOML `[render] accel`): a command line's `--accel`
    /// overrides it; with neither, the program's default.
    pub accel: Option<Accel>,
    /// How light is carried (TOML `[render] integrator`): Whitted's for the paper's scenes, the
    /// path tracer for glTF files; a command line's `--integrator` overrides it.
    pub integrator: Integrator,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            max_depth: 5,
            background: Vec3::new(0.05, 0.05, 0.1),
            ambient: 0.1,
            accel: None,
            integrator: Integrator::Whitted,
        }
    }
}

/// A sphere primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// The centre.
    pub center: Vec3,
    /// At least [`MIN_RADIUS`].
    pub radius: f32,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

/// A triangle, counter-clockwise seen from its outside (the side its geometric normal points to).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Triangle {
    /// The corners, counter-clockwise seen from outside.
    pub vertices: [Vec3; 3],
    /// Vertex normals to interpolate for shading; `None` shades with the geometric normal.
    pub normals: Option<[Vec3; 3]>,
    /// Texture coordinates of the corners, for a textured material (glTF's TEXCOORD_0).
    pub uvs: Option<[Vec2; 3]>,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// A second set of texture coordinates (glTF's TEXCOORD_1), for maps that name set 1.
    pub uvs1: Option<[Vec2; 3]>,
    /// Linear RGBA vertex colours (glTF's COLOR_0), multiplying the base colour and its alpha.
    pub colors: Option<[Vec4; 3]>,
    /// Unit tangents along increasing u of the normal map's coordinates, w (±1) the bitangent's
    /// sign: bitangent = w · cross(normal, tangent) (glTF's TANGENT, or MikkTSpace's). A normal map
    /// needs them.
    pub tangents: Option<[Vec4; 3]>,
}

/// An infinite plane, optionally a checkerboard of two materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// A point on the plane.
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Index into [`Scene::materials`]: the whole plane, or the even squares of a checker.
    pub material: u32,
    /// Squares of a second material, where the plane has them.
    pub checker: Option<Checker>,
}

/// A plane's checkerboard: squares of `size` alternating between the plane's material and this one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checker {
    /// The material of the odd squares.
    pub material: u32,
    /// Edge length of a square.
    pub size: f32,
}

/// What is rendered: the camera and settings, lights, materials, primitives (spheres and triangles
/// in the BVH, planes beside it), textures and motion. [`Scene::validate`] checks it before any
/// tracer reads it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// The pinhole the primary rays start from.
    pub camera: Camera,
    /// Size, depth, background, ambient.
    pub settings: RenderSettings,
    /// Point lights, each casting hard shadows.
    pub lights: Vec<Light>,
    /// What primitives and planes name by index.
    pub materials: Vec<Material>,
    /// Sphere primitives, in the BVH.
    pub spheres: Vec<Sphere>,
    /// Triangle primitives, in the BVH beside the spheres.
    pub triangles: Vec<Triangle>,
    /// Where each mesh (a model file's, a glTF primitive's) starts in `triangles`, ascending: its
    /// triangles run to the next start. Triangles before the first start, or in a scene that names
    /// none, are one mesh. Ray queries build a bottom-level structure per mesh.
    pub mesh_starts: Vec<u32>,
    /// Infinite planes, tested beside the BVH.
    pub planes: Vec<Plane>,
    /// The images materials are textured with.
    pub textures: Vec<Texture>,
    /// What moves, and how, as time passes; `None` for a still scene.
    pub motion: Option<Motion>,
    /// Light from every direction: what escaping rays return instead of the background, and the
    /// irradiance on glTF surfaces instead of the ambient term. Set with [`Scene::set_environment`].
    pub environment: Option<Environment>,
    /// The tone map the scene is meant to be shown with: Khronos PBR Neutral for a glTF file, as
    /// glTF viewers show one; none (radiance clipped at 1) for the paper's scenes. A viewer's or
    /// the command line's choice overrides it.
    pub tone_map: ToneMap,
}

/// A similarity transform: rotate, scale uniformly, translate; what a placement does to a file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// Applied first.
    pub rotation: Quat,
    /// Uniform scale, applied after the rotation.
    pub scale: f32,
    /// Applied last.
    pub translation: Vec3,
}

impl Similarity {
    /// A point carried by the transform.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.rotation * p * self.scale + self.translation
    }

    /// A direction turned by the rotation alone (normals, view directions).
    pub fn direction(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }

    /// As a matrix: `point` is its `transform_point3`.
    pub fn matrix(&self) -> glam::Mat4 {
        glam::Mat4::from_scale_rotation_translation(Vec3::splat(self.scale), self.rotation, self.translation)
    }
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: Vec3::new(0.0, 1.0, -6.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: 40.0,
        }
    }
}

fn finite_vec(v: Vec3) -> bool {
    v.is_finite()
}

/// The farthest anything may lie from the origin. Within it the tracers' arithmetic cannot overflow:
/// a ray-triangle edge function, the largest product, stays below about 1e36, and squared distances
/// below 1e35. Scenes render alike at any scale from [`MIN_RADIUS`] to here (tests/scale.rs).
pub const MAX_COORDINATE: f32 = 1e17;
/// The smallest sphere radius: below it the radius's square nears f32's smallest normal number,
/// which GPUs flush to zero.
pub const MIN_RADIUS: f32 = 1e-12;

fn environment_texels(environment: &Environment) -> u64 {
    environment.radiance().stored_texels() + environment.irradiance().stored_texels()
}

fn within_reach(v: Vec3) -> bool {
    v.abs().max_element() <= MAX_COORDINATE
}

fn out_of_reach(what: &str) -> String {
    format!("{what} must lie within {MAX_COORDINATE:e} of the origin")
}

/// `v` at unit length, or `None` for a zero vector; no square of a huge or tiny `v` is formed.
pub(crate) fn unit_vector(v: Vec3) -> Option<Vec3> {
    let largest = v.abs().max_element();
    (largest > 0.0 && largest.is_finite()).then(|| (v / largest).normalize())
}

impl Scene {
    /// Lights the scene with `environment` (or none), halving its largest textures where they and
    /// the environment would hold more texels than a render takes; returns how many halvings that
    /// took.
    pub fn set_environment(&mut self, environment: Option<Environment>) -> usize {
        let taken = environment.as_ref().map_or(0, environment_texels);
        self.environment = environment;
        texture::shrink_to_fit(&mut self.textures, texture::MAX_TEXELS - taken)
    }

    /// The texels of the textures and the environment together, mipmaps counted.
    pub fn texels(&self) -> u64 {
        let textures: u64 = self.textures.iter().map(Texture::stored_texels).sum();
        textures + self.environment.as_ref().map_or(0, environment_texels)
    }

    /// Checks every invariant the tracers rely on: finite numbers, positive radii, unit-length normals
    /// that exist, material indices in range, a camera that can see.
    pub fn validate(&self) -> Result<(), InputError> {
        validate_camera(&self.camera)?;
        self.settings.validate()?;
        for (i, light) in self.lights.iter().enumerate() {
            if !(finite_vec(light.position) && finite_vec(light.color)) {
                return Err(InputError::of(Element::Light(i), "position and color must be finite"));
            }
            if !within_reach(light.position) {
                return Err(InputError::of(Element::Light(i), out_of_reach("position")));
            }
            light.kind.check().map_err(|e| e.with_element(Element::Light(i)))?;
        }
        for (i, texture) in self.textures.iter().enumerate() {
            texture.validate().map_err(|e| e.with_element(Element::Texture(i)))?;
        }
        if let Some(environment) = &self.environment {
            environment.validate()?;
        }
        let ascending = self.mesh_starts.windows(2).all(|w| w[0] <= w[1]);
        if !ascending
            || self
                .mesh_starts
                .last()
                .is_some_and(|&s| s as usize > self.triangles.len())
        {
            return Err(InputError::of(
                Element::Scene,
                format!("mesh starts must ascend within the {} triangles", self.triangles.len()),
            ));
        }
        let texels = self.texels();
        if texels > texture::MAX_TEXELS {
            return Err(InputError::of(
                Element::Scene,
                format!(
                    "the textures and the environment hold {texels} texels, more than the {} a scene takes",
                    texture::MAX_TEXELS
                ),
            ));
        }
        for (i, m) in self.materials.iter().enumerate() {
            validate_material(m, self.textures.len()).map_err(|e| e.with_element(Element::Material(i)))?;
        }
        let material_count = self.materials.len() as u32;
        let check_material = |element: &dyn Fn() -> Element, index: u32| {
            if index >= material_count {
                Err(InputError::of(
                    element(),
                    format!("material index {index} out of range ({material_count} materials)"),
                ))
            } else {
                Ok(())
            }
        };
        // Spheres and planes are tested without their material; only triangles carry its sides
        // and alpha into the walks.
        let check_whole_material = |element: &dyn Fn() -> Element, index: u32| {
            check_material(element, index)?;
            match self.materials[index as usize].triangle_only_part() {
                Some(part) => Err(InputError::of(
                    element(),
                    format!("material {index} has {part}, which only triangles can have"),
                )),
                None => Ok(()),
            }
        };
        for (i, s) in self.spheres.iter().enumerate() {
            let element = || Element::Sphere(i);
            if !finite_vec(s.center) {
                return Err(InputError::of(element(), "center must be finite"));
            }
            if !(s.radius >= MIN_RADIUS && s.radius.is_finite()) {
                return Err(InputError::of(
                    element(),
                    format!("radius must be finite and at least {MIN_RADIUS:e} (got {})", s.radius),
                ));
            }
            if !within_reach(s.center.abs() + s.radius) {
                return Err(InputError::of(element(), out_of_reach("the sphere")));
            }
            check_whole_material(&element, s.material)?;
        }
        for (i, t) in self.triangles.iter().enumerate() {
            let element = || Element::Triangle(i);
            if !t.vertices.iter().all(|v| v.is_finite()) {
                return Err(InputError::of(element(), "vertices must be finite"));
            }
            if !t.vertices.iter().all(|&v| within_reach(v)) {
                return Err(InputError::of(element(), out_of_reach("vertices")));
            }
            if let Some(normals) = t.normals
                && !normals.iter().all(|n| n.is_finite())
            {
                return Err(InputError::of(element(), "normals must be finite"));
            }
            if !(t.uvs.iter().chain(&t.uvs1).flatten().all(|uv| uv.is_finite())) {
                return Err(InputError::of(element(), "texture coordinates must be finite"));
            }
            if !(t.colors.iter().chain(&t.tangents).flatten().all(|c| c.is_finite())) {
                return Err(InputError::of(element(), "colours and tangents must be finite"));
            }
            check_material(&element, t.material)?;
        }
        for (i, p) in self.planes.iter().enumerate() {
            let element = || Element::Plane(i);
            if !(finite_vec(p.point) && finite_vec(p.normal)) {
                return Err(InputError::of(element(), "point and normal must be finite"));
            }
            if !within_reach(p.point) {
                return Err(InputError::of(element(), out_of_reach("point")));
            }
            if (p.normal.length() - 1.0).abs() > 1e-4 {
                return Err(InputError::of(element(), "normal must have unit length"));
            }
            check_whole_material(&element, p.material)?;
            if let Some(checker) = p.checker {
                check_whole_material(&element, checker.material)?;
                if !(checker.size > 0.0 && checker.size.is_finite()) {
                    return Err(InputError::of(
                        element(),
                        format!("checker size must be positive and finite (got {})", checker.size),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A camera that frames something: finite, within reach, looking somewhere, with a sound field of view.
fn validate_camera(c: &Camera) -> Result<(), InputError> {
    if !(finite_vec(c.eye) && finite_vec(c.target) && finite_vec(c.up)) {
        return Err(InputError::of(Element::Camera, "eye, target and up must be finite"));
    }
    for (name, point) in [("eye", c.eye), ("target", c.target)] {
        if !within_reach(point) {
            return Err(InputError::of(Element::Camera, out_of_reach(name)));
        }
    }
    let Some(forward) = unit_vector(c.target - c.eye) else {
        return Err(InputError::of(Element::Camera, "eye and target must differ"));
    };
    let Some(up) = unit_vector(c.up) else {
        return Err(InputError::of(Element::Camera, "up must not be zero"));
    };
    if forward.cross(up).length_squared() < 1e-12 {
        return Err(InputError::of(
            Element::Camera,
            "up must not be parallel to the view direction",
        ));
    }
    if !(c.fov_degrees > 0.0 && c.fov_degrees < 180.0) {
        return Err(InputError::of(
            Element::Camera,
            format!("fov must be in (0, 180) degrees (got {})", c.fov_degrees),
        ));
    }
    Ok(())
}

/// The most records of one kind a render takes: indices up to 2^24 - 1 stay exact in the f32
/// texels of texture memory (`records::MAX_TEXEL_INTEGER`). Scenes and their loaders refuse more
/// before building them.
pub const MAX_RECORDS: usize = (1 << 24) - 1;

/// The largest image side we accept; far beyond any adapter's texture limit is a typo, not a request.
pub(crate) const MAX_IMAGE_SIDE: u32 = 16384;
/// The deepest bounce count we accept; the shader keeps a ray stack of this many entries plus one.
pub const MAX_DEPTH_LIMIT: u32 = 32;

impl RenderSettings {
    /// Sizes, depth, background and ambient within what the tracers take.
    pub fn validate(&self) -> Result<(), InputError> {
        for (name, value) in [("width", self.width), ("height", self.height)] {
            if value == 0 || value > MAX_IMAGE_SIDE {
                return Err(InputError::of(
                    Element::Render,
                    format!("{name} must be in 1..={MAX_IMAGE_SIDE} (got {value})"),
                ));
            }
        }
        if self.max_depth > MAX_DEPTH_LIMIT {
            return Err(InputError::of(
                Element::Render,
                format!("max_depth must be at most {MAX_DEPTH_LIMIT} (got {})", self.max_depth),
            ));
        }
        if !finite_vec(self.background) {
            return Err(InputError::of(Element::Render, "background must be finite"));
        }
        if !(self.ambient.is_finite() && self.ambient >= 0.0) {
            return Err(InputError::of(
                Element::Render,
                "ambient must be finite and not negative",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mesh starts ascend within the triangles, or the scene is refused in one line.
    #[test]
    fn mesh_starts_must_ascend_within_the_triangles() {
        let mut scene = Scene {
            materials: vec![Material::default()],
            triangles: vec![Triangle::default(); 4],
            ..Scene::default()
        };
        for (starts, valid) in [
            (vec![], true),
            (vec![0, 2], true),
            (vec![1, 4], true),
            (vec![2, 1], false),
            (vec![0, 5], false),
        ] {
            scene.mesh_starts = starts.clone();
            let result = scene.validate();
            assert_eq!(result.is_ok(), valid, "{starts:?}: {result:?}");
            if let Err(e) = result {
                assert_eq!(e.message, "mesh starts must ascend within the 4 triangles");
            }
        }
    }
}
