//! KHR_lights_punctual: a light of the file where its node puts it.

use crate::error::InputError;
use crate::scene::{Light, LightKind};
use glam::{Mat4, Vec3};

/// A KHR_lights_punctual light where its node puts it: at the node's origin, pointing along the
/// node's -z, in the extension's units (candela for point and spot, lux for directional).
pub(super) fn punctual_light(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Result<Light, InputError> {
    use gltf::khr_lights_punctual::Kind;
    let color = Vec3::from(light.color()) * light.intensity();
    if !(color.is_finite() && color.min_element() >= 0.0) {
        return Err(InputError::new(
            "colour times intensity must be finite and not negative",
        ));
    }
    let range = light.range();
    if range.is_some_and(|r| !(r > 0.0 && r.is_finite())) {
        return Err(InputError::new(format!(
            "range must be positive and finite (got {})",
            range.unwrap_or(0.0)
        )));
    }
    let direction = || {
        crate::scene::unit_vector(world.transform_vector3(Vec3::NEG_Z))
            .ok_or_else(|| InputError::new("its node's transform collapses its direction"))
    };
    let kind = match light.kind() {
        Kind::Directional => LightKind::Directional {
            direction: direction()?,
        },
        Kind::Point => LightKind::Point { range },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            direction: direction()?,
            inner_cone: inner_cone_angle,
            outer_cone: outer_cone_angle,
            range,
        },
    };
    kind.check()?;
    Ok(Light {
        position: world.transform_point3(Vec3::ZERO),
        color,
        kind,
    })
}
