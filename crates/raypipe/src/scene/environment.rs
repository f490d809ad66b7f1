//! Light from every direction: an equirectangular image of radiance that rays escaping the scene
//! return, and the irradiance it gives a surface, made from it once on the host so that both
//! tracers read the same numbers (`escaped_radiance` and `environment_irradiance` in
//! `shaders/environment.wgsl` and `cpu/environment.rs`).
//!
//! The convention (docs/scene-format.md): direction d maps to u = 0.5 + atan2(d.x, -d.z) / 2π,
//! v = acos(d.y) / π, u from the image's left edge and v from its top row, so the middle of the
//! image is seen looking down -z. A rotation turns the environment about +y, counter-clockwise
//! seen from above.

use super::texture::{MAX_TEXTURE_SIDE, Texture, Wrap};
use crate::error::InputError;
use glam::Vec3;
use std::f32::consts::PI;
use std::path::Path;

/// The most texels an environment keeps: larger images are halved until they fit, as a glTF's
/// textures are (half of the texels a render's textures share).
pub const MAX_ENVIRONMENT_TEXELS: u64 = 1 << 23;
/// The largest environment file read: an 8192 x 4096 float EXR, uncompressed, with room.
pub const MAX_ENVIRONMENT_BYTES: u64 = 1 << 30;
/// The irradiance map's size: irradiance varies slowly with the normal.
pub(crate) const IRRADIANCE_WIDTH: u32 = 32;
pub(crate) const IRRADIANCE_HEIGHT: u32 = 16;
/// The width the radiance is averaged down to before its irradiance is summed.
const IRRADIANCE_SOURCE_WIDTH: u32 = 128;
/// The largest radiance kept: half precision's largest finite value (brighter texels, a sun's
/// core, are clamped to it).
pub const MAX_RADIANCE: f32 = 65504.0;

/// An environment: its radiance, its irradiance, and how it is turned and scaled.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    radiance: Texture,
    irradiance: Texture,
    /// Degrees about +y.
    pub rotation_degrees: f32,
    /// Multiplies the radiance (and so the irradiance).
    pub intensity: f32,
}

/// The file formats an environment is read from.
pub const ENVIRONMENT_EXTENSIONS: [&str; 2] = ["hdr", "exr"];

/// Whether `name` ends in an environment's extension.
pub fn is_environment_file(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    ENVIRONMENT_EXTENSIONS
        .iter()
        .any(|ext| lower.ends_with(&format!(".{ext}")))
}

impl Environment {
    /// An environment from linear RGB radiance, row by row from the top (v = 0): 2:1, finite and
    /// not negative. Values above [`MAX_RADIANCE`] are clamped; an image over
    /// [`MAX_ENVIRONMENT_TEXELS`] is halved until it fits (`halvings` says how often).
    pub fn from_rgb(width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<(Environment, usize), InputError> {
        check_size(width, height)?;
        if rgb.len() as u64 != width as u64 * height as u64 {
            return Err(InputError::new(format!(
                "{} texels for a {width}x{height} environment",
                rgb.len()
            )));
        }
        if let Some(i) = rgb.iter().position(|t| t.iter().any(|c| !c.is_finite())) {
            let (x, y) = (i as u32 % width, i as u32 / width);
            return Err(InputError::new(format!("texel ({x}, {y}) is not finite")));
        }
        if let Some(i) = rgb.iter().position(|t| t.iter().any(|&c| c < 0.0)) {
            let (x, y) = (i as u32 % width, i as u32 / width);
            return Err(InputError::new(format!("texel ({x}, {y}) is negative")));
        }
        let rgba: Vec<[f32; 4]> = rgb
            .iter()
            .map(|t| {
                let [r, g, b] = t.map(|c| c.min(MAX_RADIANCE));
                [r, g, b, 1.0]
            })
            .collect();
        let mut radiance = Texture::from_linear(width, height, &rgba, [Wrap::Repeat, Wrap::Clamp]);
        let mut halvings = 0;
        while radiance.width as u64 * radiance.height as u64 > MAX_ENVIRONMENT_TEXELS {
            radiance = radiance.halved();
            halvings += 1;
        }
        Ok((Environment::with_radiance(radiance), halvings))
    }

    fn with_radiance(radiance: Texture) -> Environment {
        Environment {
            irradiance: irradiance_of(&radiance),
            radiance,
            rotation_degrees: 0.0,
            intensity: 1.0,
        }
    }

    /// The same radiance from every direction.
    pub fn uniform(radiance: Vec3) -> Environment {
        let rgb = vec![radiance.to_array(); 8 * 4];
        Environment::from_rgb(8, 4, &rgb)
            .expect("a uniform environment is valid")
            .0
    }

    /// An environment whose radiance is `radiance(direction)` at each texel's centre, `width` wide.
    pub fn from_function(width: u32, radiance: impl Fn(Vec3) -> Vec3) -> Result<Environment, InputError> {
        let height = (width / 2).max(1);
        let rgb: Vec<[f32; 3]> = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let d = texel_direction((x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32);
                radiance(d).to_array()
            })
            .collect();
        Ok(Environment::from_rgb(width, height, &rgb)?.0)
    }

    /// The built-in studio that lights glTF files bringing no lights of their own: a soft grey
    /// dome, brighter overhead, a darker ground, and two soft boxes high to the front left and
    /// right, so that metals have something to reflect.
    /// Made once (its irradiance is a few million products) and cloned for every glTF opened.
    pub fn studio() -> Environment {
        static STUDIO: std::sync::OnceLock<Environment> = std::sync::OnceLock::new();
        STUDIO
            .get_or_init(|| {
                Environment::from_function(256, studio_radiance).expect("the studio is a valid environment")
            })
            .clone()
    }

    /// Decodes a Radiance `.hdr` or an OpenEXR `.exr` (its first RGB layer) by `name`'s
    /// extension; an image halved to fit says so in a notice. Errors name no file: the caller
    /// adds it.
    pub fn decode(name: &str, bytes: &[u8]) -> Result<Environment, InputError> {
        let lower = name.to_ascii_lowercase();
        let (width, height, rgb) = if lower.ends_with(".hdr") {
            decode_hdr(bytes)?
        } else if lower.ends_with(".exr") {
            decode_exr(bytes)?
        } else {
            return Err(InputError::new(
                "unknown environment format (expected an equirectangular .hdr or .exr)",
            ));
        };
        let (environment, halvings) = Environment::from_rgb(width, height, &rgb)?;
        if halvings > 0 {
            log::warn!("{name}: halved {halvings} times to fit the texels a render holds");
        }
        Ok(environment)
    }

    /// Reads and decodes an environment file (a regular file, at most [`MAX_ENVIRONMENT_BYTES`]);
    /// errors start with its path.
    pub fn load(path: &Path) -> Result<Environment, InputError> {
        let shown = path.display().to_string();
        if !is_environment_file(&shown) {
            return Err(
                InputError::new("unknown environment format (expected an equirectangular .hdr or .exr)")
                    .in_origin(shown),
            );
        }
        let bytes = crate::input::read_regular(path, "environment", MAX_ENVIRONMENT_BYTES)?;
        Environment::decode(&shown, &bytes).map_err(|e| e.in_origin(shown))
    }

    /// Radiance, equirectangular: repeating along u, clamped along v.
    pub fn radiance(&self) -> &Texture {
        &self.radiance
    }

    /// For each normal direction (the same mapping as the radiance's), the irradiance E over π:
    /// the radiance a white Lambert surface facing that way reflects.
    pub fn irradiance(&self) -> &Texture {
        &self.irradiance
    }

    /// Rotation and intensity finite, intensity not negative.
    pub fn validate(&self) -> Result<(), InputError> {
        if !self.rotation_degrees.is_finite() {
            return Err(InputError::new("environment rotation must be finite"));
        }
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(InputError::new("environment intensity must be finite and not negative"));
        }
        self.radiance.validate()?;
        self.irradiance.validate()
    }
}

/// The unit direction at texture coordinate (u, v) of an equirectangular map: the inverse of the
/// convention.
pub(crate) fn texel_direction(u: f32, v: f32) -> Vec3 {
    let phi = 2.0 * PI * (u - 0.5);
    let theta = PI * v;
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

fn check_size(width: u32, height: u32) -> Result<(), InputError> {
    if width == 0 || height == 0 || width != 2 * height {
        return Err(InputError::new(format!(
            "{width}x{height}: an equirectangular environment is twice as wide as it is high"
        )));
    }
    if width > MAX_TEXTURE_SIDE {
        return Err(InputError::new(format!(
            "{width}x{height}: wider than the {MAX_TEXTURE_SIDE} texels a texture takes"
        )));
    }
    Ok(())
}

fn decode_hdr(bytes: &[u8]) -> Result<(u32, u32, Vec<[f32; 3]>), InputError> {
    use zune_hdr::zune_core::options::DecoderOptions;
    let fail = |e: zune_hdr::HdrDecodeErrors| InputError::new(format!("cannot decode Radiance HDR: {e:?}"));
    // Refused by the header before any pixel is decoded.
    let options = DecoderOptions::default()
        .set_max_width(2 * MAX_TEXTURE_SIDE as usize)
        .set_max_height(2 * MAX_TEXTURE_SIDE as usize);
    let mut decoder = zune_hdr::HdrDecoder::new_with_options(std::io::Cursor::new(bytes), options);
    decoder.decode_headers().map_err(fail)?;
    let (width, height) = decoder
        .dimensions()
        .ok_or_else(|| InputError::new("cannot decode Radiance HDR"))?;
    check_size(width as u32, height as u32)?;
    let floats = decoder.decode().map_err(fail)?;
    let rgb = floats.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Ok((width as u32, height as u32, rgb))
}

fn decode_exr(bytes: &[u8]) -> Result<(u32, u32, Vec<[f32; 3]>), InputError> {
    use exr::prelude::*;
    let fail = |e: exr::error::Error| InputError::new(format!("cannot decode OpenEXR: {e}"));
    // Refused by the header before any pixel is decoded.
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false).map_err(fail)?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| InputError::new("cannot decode OpenEXR: no layer"))?;
    let size = header.layer_size;
    check_size(size.width() as u32, size.height() as u32)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |resolution, _| (resolution.width(), vec![[0.0f32; 3]; resolution.area()]),
            |(width, pixels): &mut (usize, Vec<[f32; 3]>), position, (r, g, b): (f32, f32, f32)| {
                pixels[position.y() * *width + position.x()] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(fail)?;
    let layer = image.layer_data;
    let (width, height) = (layer.size.width() as u32, layer.size.height() as u32);
    check_size(width, height)?;
    Ok((width, height, layer.channel_data.pixels.1))
}

/// E/π for every direction of an IRRADIANCE_WIDTH x IRRADIANCE_HEIGHT map: a sum of L cos θ dω
/// over a grid of IRRADIANCE_SOURCE_WIDTH x half as many directions, each cell's solid angle
/// (2π / w)(π / h) sin θ, L the radiance (averaged down to that width, or bilinear between the
/// texels of a smaller image).
fn irradiance_of(radiance: &Texture) -> Texture {
    let mut source = radiance.clone();
    while source.width > IRRADIANCE_SOURCE_WIDTH {
        source = source.halved();
    }
    let (w, h) = (IRRADIANCE_SOURCE_WIDTH, IRRADIANCE_SOURCE_WIDTH / 2);
    let cell_area = (2.0 * PI / w as f32) * (PI / h as f32);
    let incoming: Vec<(Vec3, Vec3)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            (
                texel_direction(u, v),
                bilinear(&source, u, v) * (cell_area * (PI * v).sin()),
            )
        })
        .collect();
    let rgba: Vec<[f32; 4]> = (0..IRRADIANCE_HEIGHT)
        .flat_map(|y| (0..IRRADIANCE_WIDTH).map(move |x| (x, y)))
        .map(|(x, y)| {
            let n = texel_direction(
                (x as f32 + 0.5) / IRRADIANCE_WIDTH as f32,
                (y as f32 + 0.5) / IRRADIANCE_HEIGHT as f32,
            );
            let e: Vec3 = incoming.iter().map(|&(d, l)| l * n.dot(d).max(0.0)).sum();
            let [r, g, b] = (e / PI).to_array().map(|c| c.min(MAX_RADIANCE));
            [r, g, b, 1.0]
        })
        .collect();
    Texture::from_linear(IRRADIANCE_WIDTH, IRRADIANCE_HEIGHT, &rgba, [Wrap::Repeat, Wrap::Clamp])
}

/// An equirectangular texture's RGB at (u, v) in [0, 1]: bilinear, repeating along u, clamped
/// along v.
fn bilinear(texture: &Texture, u: f32, v: f32) -> Vec3 {
    let (w, h) = (texture.width as i32, texture.height as i32);
    let (x, y) = (u * w as f32 - 0.5, v * h as f32 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |i: i32, j: i32| {
        let [r, g, b, _] = texture.texel(i.rem_euclid(w) as u32, j.clamp(0, h - 1) as u32);
        Vec3::new(r, g, b)
    };
    let (i, j) = (x0 as i32, y0 as i32);
    let near = texel(i, j).lerp(texel(i + 1, j), fx);
    let far = texel(i, j + 1).lerp(texel(i + 1, j + 1), fx);
    near.lerp(far, fy)
}

/// The studio's radiance in direction `d` (unit).
fn studio_radiance(d: Vec3) -> Vec3 {
    let smoothstep = |e0: f32, e1: f32, x: f32| {
        let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let ground = Vec3::splat(0.18);
    let horizon = Vec3::new(0.55, 0.56, 0.58);
    let zenith = Vec3::new(0.75, 0.78, 0.85);
    let sky = horizon.lerp(zenith, d.y.max(0.0));
    let mut radiance = ground.lerp(sky, smoothstep(-0.05, 0.05, d.y));
    // Soft boxes: discs about 14 degrees across, their edges blurred.
    for azimuth in [-50.0f32, 55.0] {
        let (elevation, azimuth) = (35.0f32.to_radians(), azimuth.to_radians());
        let centre = Vec3::new(
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
            -elevation.cos() * azimuth.cos(),
        );
        let cos_angle = d.dot(centre);
        radiance += Vec3::splat(6.0) * smoothstep(0.9700, 0.9780, cos_angle);
    }
    radiance
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_directions_follow_the_convention() {
        // The middle of the image looks down -z, its top row up, u = 0.75 along +x.
        assert!(texel_direction(0.5, 0.5).abs_diff_eq(-Vec3::Z, 1e-6));
        assert!(texel_direction(0.75, 0.5).abs_diff_eq(Vec3::X, 1e-6));
        assert!(texel_direction(0.3, 0.0).abs_diff_eq(Vec3::Y, 1e-6));
        for (u, v) in [(0.1f32, 0.2f32), (0.6, 0.7), (0.9, 0.45)] {
            let d = texel_direction(u, v);
            let back_u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
            let back_v = d.y.clamp(-1.0, 1.0).acos() / PI;
            assert!(
                (back_u - u).abs() < 1e-5 && (back_v - v).abs() < 1e-5,
                "{u} {v}: {back_u} {back_v}"
            );
        }
    }

    #[test]
    fn a_uniform_environment_gives_its_radiance_as_irradiance_over_pi() {
        let environment = Environment::uniform(Vec3::new(0.7, 0.35, 1.4));
        let irradiance = environment.irradiance();
        for y in 0..irradiance.height {
            for x in 0..irradiance.width {
                let [r, g, b, _] = irradiance.texel(x, y);
                for (got, want) in [(r, 0.7), (g, 0.35), (b, 1.4)] {
                    assert!((got - want).abs() < 0.01 * want, "({x}, {y}): {got} for {want}");
                }
            }
        }
    }

    #[test]
    fn a_sky_over_black_ground_lights_up_facing_surfaces_fully_and_down_facing_ones_not() {
        // Radiance 1 above the horizon: E/π is 1 facing up, 1/2 facing sideways, 0 facing down.
        let environment = Environment::from_function(256, |d| Vec3::splat((d.y > 0.0) as u32 as f32)).unwrap();
        let irradiance = environment.irradiance();
        let row = |y: u32| irradiance.texel(5, y)[0];
        assert!((row(0) - 1.0).abs() < 0.03, "{}", row(0));
        assert!(row(15) < 0.03, "{}", row(15));
        let sideways = 0.5 * (row(7) + row(8));
        assert!((sideways - 0.5).abs() < 0.03, "{sideways}");
    }

    #[test]
    fn bad_environments_are_refused() {
        let texels = vec![[1.0; 3]; 8];
        assert!(Environment::from_rgb(4, 2, &texels).is_ok());
        let message = |w, h, t: &[[f32; 3]]| Environment::from_rgb(w, h, t).unwrap_err().message;
        assert!(message(8, 1, &texels).contains("twice as wide"));
        let mut nan = texels.clone();
        nan[5][1] = f32::NAN;
        assert_eq!(message(4, 2, &nan), "texel (1, 1) is not finite");
        let mut negative = texels.clone();
        negative[2][0] = -1.0;
        assert_eq!(message(4, 2, &negative), "texel (2, 0) is negative");
        assert!(message(32768, 16384, &texels).contains("wider than"));
        assert!(
            Environment::decode("sky.png", b"")
                .unwrap_err()
                .message
                .contains("unknown environment format")
        );
        assert!(Environment::decode("sky.hdr", b"#?RADIANCE\nnonsense").is_err());
        assert!(Environment::decode("sky.exr", b"not an exr").is_err());
    }

    #[test]
    fn oversized_environments_are_halved_to_fit() {
        let (width, height) = (8192u32, 4096u32);
        let texels = vec![[0.5f32; 3]; (width * height) as usize];
        let (environment, halvings) = Environment::from_rgb(width, height, &texels).unwrap();
        assert_eq!(halvings, 1);
        assert_eq!(
            (environment.radiance().width, environment.radiance().height),
            (4096, 2048)
        );
    }
}
