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
    // The colour view's exposure, 2^EV, and tone map (TONE_MAP_* from the preamble).
    exposure_scale: f32,
    tone_map: u32,
    _pad: u32,
}

// DISPLAY_COLOR, DISPLAY_DEPTH, DISPLAY_NORMAL and DISPLAY_COST (modes::Aov's numbers),
// TONE_MAP_NONE, TONE_MAP_NEUTRAL and TONE_MAP_ACES (tonemap::ToneMap's) and HEAT_STOPS
// (heatmap.rs's STOPS) come from the preamble (src/gpu/trace/display.rs).

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

// Khronos PBR Neutral (`pbr_neutral` in src/image/tonemap.rs, which writes out its terms).
fn pbr_neutral(color: vec3<f32>) -> vec3<f32> {
    let f90 = 0.04;
    let ks = 0.8 - f90;
    let kd = 0.15;
    let x = min(color.x, min(color.y, color.z));
    let toe = select(f90, x - x * x / (4.0 * f90), x <= 2.0 * f90);
    let c = color - toe;
    let peak = max(c.x, max(c.y, c.z));
    if (peak <= ks) {
        return c;
    }
    let compressed = 1.0 - (1.0 - ks) * (1.0 - ks) / (peak + 1.0 - 2.0 * ks);
    let g = 1.0 / (kd * (peak - compressed) + 1.0);
    return c * (compressed / peak) * g + compressed * (1.0 - g);
}

// ACES filmic in Stephen Hill's fit (`aces_hill` in src/image/tonemap.rs; WGSL's matrices are
// built from columns, so these are the host's rows transposed).
fn aces_hill(color: vec3<f32>) -> vec3<f32> {
    let into_ap1 = mat3x3<f32>(
        vec3<f32>(0.59719, 0.07600, 0.02840),
        vec3<f32>(0.35458, 0.90834, 0.13383),
        vec3<f32>(0.04823, 0.01566, 0.83777));
    let out_of_ap1 = mat3x3<f32>(
        vec3<f32>(1.60475, -0.10208, -0.00327),
        vec3<f32>(-0.53108, 1.10813, -0.07276),
        vec3<f32>(-0.07367, -0.00605, 1.07602));
    let v = into_ap1 * color;
    let fit = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.432951) + 0.238081);
    return clamp(out_of_ap1 * fit, vec3<f32>(0.0), vec3<f32>(1.0));
}

// Linear radiance to linear display values in [0, 1]: exposed, then tone-mapped
// (`DisplayTransform::apply`).
fn display_transform(radiance: vec3<f32>) -> vec3<f32> {
    let exposed = max(radiance, vec3<f32>(0.0)) * params.exposure_scale;
    switch params.tone_map {
        case TONE_MAP_NEUTRAL: {
            return pbr_neutral(exposed);
        }
        case TONE_MAP_ACES: {
            return aces_hill(exposed);
        }
        default: {
            return min(exposed, vec3<f32>(1.0));
        }
    }
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
            let mapped = display_transform(color.xyz);
            shown = vec3<f32>(linear_to_srgb(mapped.x), linear_to_srgb(mapped.y), linear_to_srgb(mapped.z));
        }
    }
    if (params.target_srgb == 1u) {
        shown = vec3<f32>(srgb_to_linear(shown.x), srgb_to_linear(shown.y), srgb_to_linear(shown.z));
    }
    return vec4<f32>(shown, 1.0);
}
