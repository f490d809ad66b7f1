// Both targets are rgba32uint holding f32 bits: integer targets are colour-renderable everywhere
// (float targets are not on GLES/WebGL2 without an extension), and bits read back exactly. They hold
// sums over the samples so far: each sample reads the previous pair and writes the other one.
struct PixelSums {
    // rgb: linear radiance; a: rays traced for this pixel (its cost, with WRITE_COST); summed.
    color: vec4<u32>,
    // xyz: first-hit normal; w: first-hit distance or DEPTH_MISS; the centre sample's.
    surface: vec4<u32>,
}

// The targets the previous sample wrote; unread by sample 0.
@group(1) @binding(0) var previous_color: texture_2d<u32>;
@group(1) @binding(1) var previous_surface: texture_2d<u32>;

// The pixel's next sample, added to the sums of those before it: what either entry point writes
// (fs_main in fullscreen.wgsl, cs_main in compute.wgsl).
fn sample_pixel(pixel: vec2<u32>) -> PixelSums {
    ray_count = 0u;
    box_tests = 0u;
    let sample = globals.camera.sample;
    start_sample(pixel, sample);
    let traced = trace_pixel(camera_ray(vec2<f32>(pixel) + sample_offset(pixel, sample)));
    let count = select(ray_count, primary_cost, WRITE_COST);
    return summed(pixel, vec4<f32>(traced.color, f32(count)), vec4<f32>(traced.normal, traced.depth));
}

// A sample's colour and count added to the pixel's sums so far; its surface kept only where it is
// the first (the centre sample's).
fn summed(pixel: vec2<u32>, sample_color: vec4<f32>, sample_surface: vec4<f32>) -> PixelSums {
    var color = sample_color;
    var surface = sample_surface;
    if (globals.camera.sample > 0u) {
        let texel = vec2<i32>(pixel);
        color = bitcast<vec4<f32>>(textureLoad(previous_color, texel, 0)) + color;
        surface = bitcast<vec4<f32>>(textureLoad(previous_surface, texel, 0));
    }
    return PixelSums(bitcast<vec4<u32>>(color), bitcast<vec4<u32>>(surface));
}

// The sums of a pixel whose primary ray misses the box around the scene's primitives (outside the
// rectangle it projects to, src/gpu/trace/region.rs; the tracer never runs there): what sample_pixel
// gives such a ray, what it escapes to and one ray, without tracing it.
fn miss_pixel(pixel: vec2<u32>) -> PixelSums {
    // Added to zero, as trace_task adds it to the pixel's colour.
    var color = vec3<f32>(0.0) + globals.scene.background;
    if (HAS_ENVIRONMENT) {
        let primary = camera_ray(vec2<f32>(pixel) + sample_offset(pixel, globals.camera.sample));
        color = vec3<f32>(0.0) + escaped_radiance(primary.dir, pixel_spread());
    }
    return summed(pixel, vec4<f32>(color, 1.0), vec4<f32>(vec3<f32>(0.0), DEPTH_MISS));
}
