//! Lights: the paper's point light, and KHR_lights_punctual's three in their units.

use crate::error::InputError;
use glam::Vec3;

/// A light that casts hard shadows. What reaches a surface from it is its irradiance at normal
/// incidence, `E` (docs/scene-format.md, "Lights"); a Whitted material shows E times its Lambert
/// and Phong terms, a glTF material E times its BRDF times the cosine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Where the light is (unused by a directional light).
    pub position: Vec3,
    /// The paper's light: E itself, per channel. A glTF point or spot light: the intensity in
    /// candela (colour times intensity). A directional light: the illuminance in lux.
    pub color: Vec3,
    /// How its irradiance falls off.
    pub kind: LightKind,
}

impl Light {
    /// The paper's light at `position`: `color` reaches every surface that sees it undimmed.
    pub fn constant(position: Vec3, color: Vec3) -> Light {
        Light {
            position,
            color,
            kind: LightKind::Constant,
        }
    }
}

/// How a light's irradiance depends on where the surface is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum LightKind {
    /// The paper's: E is the colour at any distance.
    #[default]
    Constant,
    /// KHR_lights_punctual's point light: E = intensity / d², windowed to zero at `range`.
    Point {
        /// Where the light ends; `None`: nowhere.
        range: Option<f32>,
    },
    /// A point light in a cone: full strength within `inner_cone` radians of `direction`, none
    /// beyond `outer_cone`, the extension's smooth (squared linear in the cosine) step between.
    Spot {
        /// Unit, where the cone points.
        direction: Vec3,
        /// Radians from the axis of full strength.
        inner_cone: f32,
        /// Radians from the axis where the light ends.
        outer_cone: f32,
        /// Where the light ends; `None`: nowhere.
        range: Option<f32>,
    },
    /// Parallel light travelling along `direction` (unit), from infinitely far: E is the colour
    /// everywhere, and shadow rays run to infinity.
    Directional {
        /// Unit, where the light travels.
        direction: Vec3,
    },
}

impl LightKind {
    /// Why the kind's numbers cannot be rendered, if they cannot.
    pub(crate) fn check(&self) -> Result<(), InputError> {
        let range_ok = |range: &Option<f32>| range.is_none_or(|r| r > 0.0 && r.is_finite());
        let unit = |d: Vec3| d.is_finite() && (d.length() - 1.0).abs() <= 1e-4;
        match self {
            LightKind::Constant => Ok(()),
            LightKind::Point { range } if range_ok(range) => Ok(()),
            LightKind::Spot {
                direction,
                inner_cone,
                outer_cone,
                range,
            } => {
                if !range_ok(range) {
                    return Err(InputError::new("range must be positive and finite"));
                }
                if !unit(*direction) {
                    return Err(InputError::new("direction must have unit length"));
                }
                let cone_ok =
                    *inner_cone >= 0.0 && inner_cone < outer_cone && *outer_cone <= std::f32::consts::FRAC_PI_2;
                if !cone_ok {
                    return Err(InputError::new(format!(
                        "cone angles must satisfy 0 <= inner < outer <= pi/2 (got {inner_cone} and {outer_cone})"
                    )));
                }
                Ok(())
            }
            LightKind::Directional { direction } if unit(*direction) => Ok(()),
            LightKind::Directional { .. } => Err(InputError::new("direction must have unit length")),
            LightKind::Point { .. } => Err(InputError::new("range must be positive and finite")),
        }
    }
}
