// The compute entry point: the same tracer as the fragment stage's, one invocation per pixel over
// 8x8 workgroups, writing the targets as storage textures.

// The targets this sample writes (the other pair of the accumulation).
@group(1) @binding(2) var next_color: texture_storage_2d<rgba32uint, write>;
@group(1) @binding(3) var next_surface: texture_storage_2d<rgba32uint, write>;

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    // The last workgroups of a row or column reach past the image.
    if (f32(id.x) >= globals.camera.width || f32(id.y) >= globals.camera.height) {
        return;
    }
    let sums = sample_pixel(id.xy);
    textureStore(next_color, id.xy, sums.color);
    textureStore(next_surface, id.xy, sums.surface);
}
