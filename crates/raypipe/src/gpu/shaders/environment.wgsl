// The environment: the radiance that rays escaping the scene return, and the light it gives a
// glTF surface's diffuse share. Both are equirectangular maps (src/scene/environment.rs states the
// convention) sampled through texture maps like any other. Mirrored by src/cpu/environment.rs.

// Where direction d (unit) reads an equirectangular map of the environment: d turned back by the
// environment's rotation about +y, then u = 0.5 + atan2(x, -z) / 2π, v = acos(y) / π. Straight up
// or down any u is the pole; u = 0.5 there, since atan2(0, ±0) differs between devices.
fn environment_uv(d: vec3<f32>) -> vec2<f32> {
    let turn = globals.scene.environment_turn;
    let x = turn.x * d.x - turn.y * d.z;
    let z = turn.y * d.x + turn.x * d.z;
    let u = select(0.5 + atan2(x, -z) * (0.5 / PI), 0.5, x == 0.0 && z == 0.0);
    return vec2<f32>(u, acos(clamp(d.y, -1.0, 1.0)) * (1.0 / PI));
}

// What a ray leaving the scene along `dir` brings back: the environment's radiance, or the
// background colour where the scene has none. The map is read at the level where a texel spans the
// ray cone's `spread` (radians; a row of the map spans π / height).
fn escaped_radiance(dir: vec3<f32>, spread: f32) -> vec3<f32> {
    if (!HAS_ENVIRONMENT) {
        return globals.scene.background;
    }
    let map = load_texture_map(globals.scene.environment_map);
    let lod = lod_of(abs(spread) * f32(map.height) * (1.0 / PI));
    return globals.scene.environment_intensity * sample_texture(map, environment_uv(dir), lod).rgb;
}

// The environment's irradiance over π on a surface facing `normal`: what a white Lambert surface
// there reflects.
fn environment_irradiance(normal: vec3<f32>) -> vec3<f32> {
    let map = load_texture_map(globals.scene.irradiance_map);
    return globals.scene.environment_intensity * sample_texture(map, environment_uv(normal), -1.0).rgb;
}
