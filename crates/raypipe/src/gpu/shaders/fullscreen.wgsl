// The vertex stage passes the full-screen triangle's positions through; all the work is per fragment.

@vertex
fn vs_main(@location(0) position: vec2<f32>) -> @builtin(position) vec4<f32> {
    return vec4<f32>(position, 0.0, 1.0);
}
