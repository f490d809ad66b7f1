//! What a screen shows of linear radiance before it is sRGB-encoded: exposure (radiance times
//! 2^EV) and a tone map that rolls the highlights off into [0, 1]. The display pass's twin is
//! `display_transform` in shaders/display.wgsl.

use crate::scene::ToneMap;

/// The largest exposure either way, in stops: 2^64 times the brightest half float is still a
/// finite f32.
pub const MAX_EXPOSURE: f32 = 64.0;

/// Exposure and tone map together: what the display pass and PNG output apply to a pixel's mean
/// radiance before sRGB encoding. EXR output takes the exposure alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DisplayTransform {
    /// Stops: radiance is multiplied by 2^exposure.
    pub exposure: f32,
    /// The curve from radiance to display values.
    pub tone_map: ToneMap,
}

impl DisplayTransform {
    /// Radiance as it is: no exposure, clipped at 1.
    pub const IDENTITY: Self = Self {
        exposure: 0.0,
        tone_map: ToneMap::None,
    };

    /// The factor on radiance, 2^exposure.
    pub fn scale(&self) -> f32 {
        self.exposure.exp2()
    }

    /// Linear radiance to linear display values in [0, 1] (`display_transform` in display.wgsl).
    pub fn apply(&self, radiance: [f32; 3]) -> [f32; 3] {
        let exposed = radiance.map(|c| c.max(0.0) * self.scale());
        match self.tone_map {
            ToneMap::None => exposed.map(|c| c.min(1.0)),
            ToneMap::Neutral => pbr_neutral(exposed),
            ToneMap::Aces => aces_hill(exposed),
        }
    }
}

/// Khronos PBR Neutral, as its specification writes it: a toe f subtracted (x - x²/(4 F90) below
/// 2 F90, F90 = 0.04 above), then, where the peak p passes Ks = 0.8 - F90, the colour scaled to the
/// compressed peak pn = 1 - (1 - Ks)² / (p + 1 - 2 Ks) and mixed toward grey pn by 1 - g,
/// g = 1 / (Kd (p - pn) + 1), Kd = 0.15.
pub fn pbr_neutral(c: [f32; 3]) -> [f32; 3] {
    const F90: f32 = 0.04;
    const KS: f32 = 0.8 - F90;
    const KD: f32 = 0.15;
    let x = c[0].min(c[1]).min(c[2]);
    let toe = if x <= 2.0 * F90 { x - x * x / (4.0 * F90) } else { F90 };
    let c = c.map(|v| v - toe);
    let peak = c[0].max(c[1]).max(c[2]);
    if peak <= KS {
        return c;
    }
    let compressed = 1.0 - (1.0 - KS) * (1.0 - KS) / (peak + 1.0 - 2.0 * KS);
    let g = 1.0 / (KD * (peak - compressed) + 1.0);
    c.map(|v| v * (compressed / peak) * g + compressed * (1.0 - g))
}

/// sRGB to ACES AP1 with the reference transform's saturation folded in, rows.
const ACES_IN: [[f32; 3]; 3] = [
    [0.59719, 0.35458, 0.04823],
    [0.07600, 0.90834, 0.01566],
    [0.02840, 0.13383, 0.83777],
];
/// Back from the output transform's AP1 to sRGB, rows.
const ACES_OUT: [[f32; 3]; 3] = [
    [1.60475, -0.53108, -0.07367],
    [-0.10208, 1.10813, -0.00605],
    [-0.00327, -0.07276, 1.07602],
];

fn rows_times(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

/// ACES filmic in Stephen Hill's fit: into AP1, the rational fit of the RRT and ODT per channel,
/// back to sRGB primaries, clamped to [0, 1].
pub fn aces_hill(c: [f32; 3]) -> [f32; 3] {
    let fit = rows_times(&ACES_IN, c)
        .map(|v| (v * (v + 0.024_578_6) - 0.000_090_537) / (v * (0.983_729 * v + 0.432_951) + 0.238_081));
    rows_times(&ACES_OUT, fit).map(|v| v.clamp(0.0, 1.0))
}
