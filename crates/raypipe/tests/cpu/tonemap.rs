//! Exposure and the tone maps against their formulas written out here in f64: Khronos PBR Neutral
//! as its specification states it (toe, pass-through below 0.76, the compressed peak and the mix
//! toward white), ACES in Hill's fit, and a stop of exposure doubling radiance. The display pass
//! matches these on the GPU in tests/gpu/display.rs.

use raypipe::image::Frame;
use raypipe::image::tonemap::{DisplayTransform, aces_hill, pbr_neutral};
use raypipe::scene::ToneMap;

/// PBR Neutral by its specification: F90 = 0.04, Ks = 0.8 - F90, Kd = 0.15.
fn neutral_formula(c: [f64; 3]) -> [f64; 3] {
    let (f90, ks, kd) = (0.04, 0.76, 0.15);
    let x = c[0].min(c[1]).min(c[2]);
    let f = if x <= 2.0 * f90 { x - x * x / (4.0 * f90) } else { f90 };
    let p = (c[0] - f).max(c[1] - f).max(c[2] - f);
    if p <= ks {
        return c.map(|v| v - f);
    }
    let p_n = 1.0 - (1.0 - ks) * (1.0 - ks) / (p + 1.0 - 2.0 * ks);
    let g = 1.0 / (kd * (p - p_n) + 1.0);
    c.map(|v| (v - f) * (p_n / p) * g + p_n * (1.0 - g))
}

/// ACES in Hill's fit: M_out · fit(M_in · c), clamped, with fit(v) = (v (v + a) - b) / (v (c v + d) + e).
fn aces_formula(c: [f64; 3]) -> [f64; 3] {
    let m_in = [
        [0.59719, 0.35458, 0.04823],
        [0.07600, 0.90834, 0.01566],
        [0.02840, 0.13383, 0.83777],
    ];
    let m_out = [
        [1.60475, -0.53108, -0.07367],
        [-0.10208, 1.10813, -0.00605],
        [-0.00327, -0.07276, 1.07602],
    ];
    let times = |m: [[f64; 3]; 3], v: [f64; 3]| m.map(|r| r[0] * v[0] + r[1] * v[1] + r[2] * v[2]);
    let fit = times(m_in, c).map(|v| (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081));
    times(m_out, fit).map(|v| v.clamp(0.0, 1.0))
}

fn assert_near(got: [f32; 3], want: [f64; 3], what: &str) {
    for c in 0..3 {
        assert!(
            (got[c] as f64 - want[c]).abs() < 2e-6,
            "{what}: channel {c} is {}, the formula says {}",
            got[c],
            want[c]
        );
    }
}

const COLOURS: [[f64; 3]; 7] = [
    [0.0, 0.0, 0.0],
    [0.02, 0.05, 0.01],
    [0.5, 0.3, 0.1],
    [0.18, 0.18, 0.18],
    [0.9, 0.2, 0.1],
    [2.0, 1.0, 0.5],
    [40.0, 12.0, 3.0],
];

#[test]
fn pbr_neutral_follows_its_specification() {
    for c in COLOURS {
        assert_near(pbr_neutral(c.map(|v| v as f32)), neutral_formula(c), &format!("{c:?}"));
    }
    // Below the compression the colour only loses the toe's 0.04: base colours stay themselves.
    assert_near(pbr_neutral([0.5, 0.3, 0.1]), [0.46, 0.26, 0.06], "a mid colour");
    // A highlight's peak lands on the compressed peak, short of 1, and it whitens.
    let bright = pbr_neutral([40.0, 12.0, 3.0]);
    assert!(bright[0] < 1.0 && bright[0] > 0.99, "{bright:?}");
    assert!(bright[2] / bright[0] > 0.5, "a highlight desaturates: {bright:?}");
}

#[test]
fn aces_follows_hills_fit() {
    for c in COLOURS {
        assert_near(aces_hill(c.map(|v| v as f32)), aces_formula(c), &format!("{c:?}"));
    }
    assert_eq!(aces_hill([0.0; 3]), [0.0; 3]);
    assert_eq!(aces_hill([1e4; 3]), [1.0; 3]);
}

#[test]
fn a_stop_of_exposure_doubles_radiance_before_the_tone_map() {
    let mut frame = Frame::new(2, 1);
    frame.color = vec![[0.1, 0.2, 0.3, 1.0], [0.05, 0.4, 0.45, 1.0]];
    let mut doubled = frame.clone();
    for c in &mut doubled.color {
        for v in &mut c[..3] {
            *v *= 2.0;
        }
    }
    for tone_map in [ToneMap::None, ToneMap::Neutral, ToneMap::Aces] {
        let up = DisplayTransform {
            exposure: 1.0,
            tone_map,
        };
        let plain = DisplayTransform {
            exposure: 0.0,
            tone_map,
        };
        assert_eq!(frame.display_with(&up), doubled.display_with(&plain), "{tone_map:?}");
        let down = DisplayTransform {
            exposure: -1.0,
            tone_map,
        };
        assert_eq!(doubled.display_with(&down), frame.display_with(&plain), "{tone_map:?}");
    }
    assert_eq!(frame.exposed_radiance(1.0), doubled.radiance());
    // Without a tone map and exposure, the display is today's: clipped and sRGB-encoded.
    assert_eq!(frame.display_with(&DisplayTransform::IDENTITY), frame.display());
}
