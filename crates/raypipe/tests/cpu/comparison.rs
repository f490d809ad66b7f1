//! The comparison harness itself: it must pass equal images and fail perturbed ones, or every
//! GPU-against-CPU test above proves nothing.

use crate::common::{packed, render_cpu};
use raypipe::image::FloatImage;
use raypipe::image::diff::{Tolerance, compare};
use raypipe::modes::Accel;

fn reference() -> FloatImage {
    render_cpu(&packed("whitted", 80, 60, 5), Accel::Brute).display()
}

#[test]
fn an_image_matches_itself() {
    let image = reference();
    let stats = compare(&image, &image.clone()).unwrap();
    assert_eq!(stats.differing, 0);
    Tolerance::COLOR.check(&stats).unwrap();
    Tolerance::EXACT.check(&stats).unwrap();
}

#[test]
fn a_shifted_patch_fails() {
    let image = reference();
    let mut perturbed = image.clone();
    // Brighten a 12x10 patch (2.5 % of the pixels) by 0.2.
    for y in 20..30 {
        for x in 30..42 {
            let i = (y * 80 + x) * 3;
            for c in &mut perturbed.data[i..i + 3] {
                *c = (*c + 0.2).min(1.0);
            }
        }
    }
    let stats = compare(&perturbed, &image).unwrap();
    assert!(
        Tolerance::COLOR.check(&stats).is_err(),
        "a bright patch must fail: {stats:?}"
    );
}

#[test]
fn a_small_global_bias_fails() {
    let image = reference();
    let mut perturbed = image.clone();
    for v in &mut perturbed.data {
        *v = (*v + 0.01).min(1.0);
    }
    let stats = compare(&perturbed, &image).unwrap();
    assert!(
        Tolerance::COLOR.check(&stats).is_err(),
        "a 1 % bias must fail: {stats:?}"
    );
}

#[test]
fn one_different_pixel_fails_exact_but_not_color() {
    let image = reference();
    let mut perturbed = image.clone();
    perturbed.data[0] = 1.0 - perturbed.data[0];
    let stats = compare(&perturbed, &image).unwrap();
    assert_eq!(stats.differing, 1);
    assert!(Tolerance::EXACT.check(&stats).is_err());
    Tolerance::COLOR.check(&stats).unwrap();
}

#[test]
fn a_depth_image_with_a_lost_hit_fails() {
    let depth = render_cpu(&packed("whitted", 80, 60, 0), Accel::Brute).depth();
    let mut perturbed = depth.clone();
    let hits: Vec<usize> = (0..perturbed.data.len())
        .filter(|&i| perturbed.data[i].is_finite())
        .collect();
    for &i in hits.iter().step_by(50) {
        perturbed.data[i] = f32::INFINITY;
    }
    let stats = compare(&perturbed, &depth).unwrap();
    assert!(
        Tolerance::DEPTH.check(&stats).is_err(),
        "lost hits must fail: {stats:?}"
    );
}
