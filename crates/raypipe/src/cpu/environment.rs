//! The environment's radiance for escaping rays and its light on glTF surfaces: the twin of
//! `shaders/environment.wgsl`.

use super::intersect::v3;
use super::maps::{lod_of, sample_texture};
use crate::bvh::layout::NONE;
use crate::records::PackedScene;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Where direction `d` (unit) reads an equirectangular map of the environment: `d` turned back by
/// the environment's rotation about +y, then u = 0.5 + atan2(x, -z) / 2π, v = acos(y) / π.
/// Straight up or down any u is the pole; u = 0.5 there, since atan2(0, ±0) differs between
/// devices.
pub(crate) fn environment_uv(scene: &PackedScene, d: Vec3) -> Vec2 {
    let [cos, sin] = scene.globals.scene.environment_turn;
    let x = cos * d.x - sin * d.z;
    let z = sin * d.x + cos * d.z;
    let u = if x == 0.0 && z == 0.0 {
        0.5
    } else {
        0.5 + x.atan2(-z) * (0.5 / PI)
    };
    Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() * (1.0 / PI))
}

/// What a ray leaving the scene along `dir` brings back (`escaped_radiance`): the environment's
/// radiance, or the background colour where the scene has none. The map is read at the level
/// where a texel spans the ray cone's `spread` (radians; a row of the map spans π / height).
pub(crate) fn escaped_radiance(scene: &PackedScene, dir: Vec3, spread: f32) -> Vec3 {
    let info = &scene.globals.scene;
    if info.environment_map == NONE {
        return v3(info.background);
    }
    let map = &scene.texture_maps[info.environment_map as usize];
    let lod = lod_of(spread.abs() * map.height as f32 * (1.0 / PI));
    info.environment_intensity * sample_texture(scene, map, environment_uv(scene, dir), lod).truncate()
}

/// The environment's irradiance over π on a surface facing `normal`: what a white Lambert surface
/// there reflects.
pub(crate) fn environment_irradiance(scene: &PackedScene, normal: Vec3) -> Vec3 {
    let info = &scene.globals.scene;
    let map = &scene.texture_maps[info.irradiance_map as usize];
    info.environment_intensity * sample_texture(scene, map, environment_uv(scene, normal), -1.0).truncate()
}
