// The display pass: the tracer's linear frame turned into what a screen shows, one fragment per
// pixel of the frame. Mirrored on the host by src/image/mod.rs (`Frame::display`, `Frame::normals`)
// and src/image/heatmap.rs (`color_scale`).

struct DisplayParams {
    // DISPLAY_COLOR, DISPLAY_DEPTH, DISPLAY_NORMAL or DISPLAY_COST.
    view: u32,
    // 1 where the target encodes sRGB itself: the pass then writes linear values.
    target_srgb: u32,
    // Depth view: distances up to this fade from white to black.
    depth_far: f32,
    // Cost view: the count at the top of the scale.
    cost_max: f32,
    // Samples summed in the colour target: the pass shows their mean.
    samples: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// DISPLAY_COLOR, DISPLAY_DEPTH, DISPLAY_NORMAL and DISPLAY_COST (modes::Aov's numbers) and
// HEAT_STOPS (heatmap.rs's STOPS) come from the preamble (src/gpu/display.rs).

@group(0) @binding(0) var<uniform> params: DisplayParams;
@group(0) @binding(1) var color_target: texture_2d<u32>;
@group(0) @binding(2) var surface_target: texture_2d<u32>;

// The full-screen triangle from the vertex index alone: (-1, -1), (3, -1), (-1, 3).
@vertex
fn vs_display(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

// Linear to sRGB-encoded, the transfer function of PNG output (`linear_to_srgb` on the host).
fn linear_to_srgb(x: f32) -> f32 {
    let c = clamp(x, 0.0, 1.0);
    if (c <= 0.0031308) {
        return 12.92 * c;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

fn srgb_to_linear(x: f32) -> f32 {
    if (x <= 0.04045) {
        return x / 12.92;
    }
    return pow((x + 0.055) / 1.055, 2.4);
}

// The heat map's scale (heatmap.rs's STOPS): dark for cheap pixels, bright for expensive ones.
fn color_scale(x: f32) -> vec3<f32> {
    var stops = HEAT_STOPS;
    let last = f32(HEAT_STOP_COUNT - 1u);
    let s = clamp(x, 0.0, 1.0) * last;
    let i = min(u32(s), HEAT_STOP_COUNT - 2u);
    let f = s - f32(i);
    return stops[i] + (stops[i + 1u] - stops[i]) * f;
}

@fragment
fn fs_display(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(position.xy);
    let color = bitcast<vec4<f32>>(textureLoad(color_target, texel, 0)) / f32(params.samples);
    let surface = bitcast<vec4<f32>>(textureLoad(surface_target, texel, 0));
    let hit = surface.w >= 0.0;
    var shown = vec3<f32>(0.0);
    switch params.view {
        case DISPLAY_DEPTH: {
            if (hit) {
                shown = vec3<f32>(1.0 - clamp(surface.w / params.depth_far, 0.0, 1.0));
            }
        }
        case DISPLAY_NORMAL: {
            if (hit) {
                shown = surface.xyz * 0.5 + 0.5;
            }
        }
        case DISPLAY_COST: {
            shown = color_scale(color.w / max(params.cost_max, 1.0));
        }
        default: {
            shown = vec3<f32>(linear_to_srgb(color.x), linear_to_srgb(color.y), linear_to_srgb(color.z));
        }
    }
    if (params.target_srgb == 1u) {
        shown = vec3<f32>(srgb_to_linear(shown.x), srgb_to_linear(shown.y), srgb_to_linear(shown.z));
    }
    return vec4<f32>(shown, 1.0);
}
