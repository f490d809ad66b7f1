// The graphics pipeline's entry points: the vertex stage passes the full-screen triangle's positions
// through; all the work is per fragment, one pixel each.

@vertex
fn vs_main(@location(0) position: vec2<f32>) -> @builtin(position) vec4<f32> {
    return vec4<f32>(position, 0.0, 1.0);
}

struct FragmentOutput {
    @location(0) color: vec4<u32>,
    @location(1) surface: vec4<u32>,
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> FragmentOutput {
    let sums = sample_pixel(vec2<u32>(position.xy));
    return FragmentOutput(sums.color, sums.surface);
}

// The pixels outside the scene's projected box, drawn before the tracer's scissored draw.
@fragment
fn fs_miss(@builtin(position) position: vec4<f32>) -> FragmentOutput {
    let sums = miss_pixel(vec2<u32>(position.xy));
    return FragmentOutput(sums.color, sums.surface);
}
