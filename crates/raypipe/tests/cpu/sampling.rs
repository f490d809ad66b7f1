//! Samples per pixel on the CPU reference: the sequence the shader shares, one sample as the
//! unjittered image, and many samples as the supersampled image they estimate.

use crate::common::{assert_images_match, packed};
use glam::{UVec2, Vec2};
use raypipe::cpu::trace::{Tracer, sample_offset};
use raypipe::cpu::{Count, render_with};
use raypipe::image::diff::{Tolerance, compare};
use raypipe::image::{FloatImage, Frame};
use raypipe::modes::Accel;
use raypipe::records::PackedScene;

fn render(scene: &PackedScene, samples: u32) -> Frame {
    render_with(scene, Accel::Threaded, Count::Rays, samples, &|| {}).unwrap()
}

fn whitted(width: u32, height: u32) -> PackedScene {
    let mut scene = packed("whitted", width, height, 5);
    scene.build_bvh();
    scene
}

/// `frame`'s linear radiance averaged over `factor` x `factor` blocks: a box filter.
fn box_filtered(frame: &Frame, factor: u32) -> FloatImage {
    let (width, height) = (frame.width / factor, frame.height / factor);
    let mut data = Vec::with_capacity((width * height * 3) as usize);
    for y in 0..height {
        for x in 0..width {
            let mut sum = [0.0f64; 3];
            for dy in 0..factor {
                for dx in 0..factor {
                    let pixel = frame.color[((y * factor + dy) * frame.width + x * factor + dx) as usize];
                    for c in 0..3 {
                        sum[c] += pixel[c] as f64;
                    }
                }
            }
            let n = (factor * factor) as f64;
            data.extend(sum.map(|s| raypipe::image::linear_to_srgb((s / n) as f32)));
        }
    }
    FloatImage {
        width,
        height,
        channels: ["R", "G", "B"].map(String::from).to_vec(),
        data,
    }
}

/// The real root of g^3 = g + 1, by Newton's method from 1.3.
fn plastic_number() -> f64 {
    let mut g = 1.3f64;
    for _ in 0..20 {
        g -= (g * g * g - g - 1.0) / (3.0 * g * g - 1.0);
    }
    g
}

#[test]
fn sample_zero_is_the_pixel_centre() {
    for pixel in [UVec2::ZERO, UVec2::new(7, 3), UVec2::new(4095, 2160)] {
        assert_eq!(sample_offset(pixel, 0), Vec2::splat(0.5));
    }
}

#[test]
fn offsets_stay_inside_the_pixel_and_differ_between_pixels() {
    let a = UVec2::new(10, 20);
    let b = UVec2::new(11, 20);
    for index in 1..4096 {
        let offset = sample_offset(a, index);
        assert!(
            offset.cmpge(Vec2::ZERO).all() && offset.cmplt(Vec2::ONE).all(),
            "{offset}"
        );
        // R2 (Roberts 2018): each sample steps by (1/g, 1/g^2) modulo 1, g the plastic number
        // (g^3 = g + 1), whatever the pixel's rotation; within the 2^-24 of the fixed point.
        let step = sample_offset(a, index + 1) - offset;
        let plastic = plastic_number();
        for (got, expected) in [(step.x, 1.0 / plastic), (step.y, 1.0 / (plastic * plastic))] {
            let got = (got as f64).rem_euclid(1.0);
            let error = (got - expected).abs().min(1.0 - (got - expected).abs());
            assert!(error < 2.0f64.powi(-23), "sample {index}: step {got}, R2's {expected}");
        }
    }
    let same = (1..64).filter(|&i| sample_offset(a, i) == sample_offset(b, i)).count();
    assert_eq!(same, 0, "neighbouring pixels must not share one pattern");
}

/// R2 points fill the pixel evenly: 64 of them leave no cell of a 4x4 grid empty or crowded (16
/// random points per pixel would, about one pixel in five).
#[test]
fn sixty_four_samples_cover_the_pixel_evenly() {
    for pixel in [UVec2::new(0, 0), UVec2::new(33, 91), UVec2::new(1279, 959)] {
        let mut cells = [0u32; 16];
        for index in 0..64 {
            let offset = sample_offset(pixel, index);
            let cell = (offset * 4.0).as_uvec2();
            cells[(cell.y * 4 + cell.x) as usize] += 1;
        }
        assert!(cells.iter().all(|&n| (2..=6).contains(&n)), "{pixel}: {cells:?}");
    }
}

/// One sample per pixel is the image of rays through the pixel centres, bit for bit.
#[test]
fn one_sample_is_the_centre_image() {
    let scene = whitted(40, 30);
    let frame = render(&scene, 1);
    for (i, color) in frame.color.iter().enumerate() {
        let (x, y) = (i as u32 % 40, i as u32 / 40);
        let mut tracer = Tracer::new(&scene, Accel::Threaded).unwrap();
        let trace = tracer.trace_pixel(tracer.camera_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)));
        assert_eq!(color, &[trace.color.x, trace.color.y, trace.color.z, trace.rays as f32]);
    }
}

/// Many samples estimate the box-filtered image: 64 per pixel at 160x120 against 1280x960
/// averaged over 8x8 blocks (64 regular samples per pixel). What is left is sampling noise at edges
/// and in the checkerboard's far moiré, in display units: measured mean 5.0e-3, p99 4.9e-2. One
/// sample per pixel misses by far more (mean 4.4e-2, p99 0.34), so this cannot pass by accident.
#[test]
fn sixty_four_samples_match_a_supersampled_image() {
    let reference = box_filtered(&render(&whitted(1280, 960), 1), 8);
    let scene = whitted(160, 120);
    let tolerance = Tolerance { mean: 8e-3, p99: 8e-2 };
    assert_images_match("spp-64", &render(&scene, 64).display(), &reference, tolerance);
    let aliased = compare(&render(&scene, 1).display(), &reference).unwrap();
    assert!(tolerance.check(&aliased).is_err(), "one sample must miss: {aliased:?}");
}

/// The depth and normal outputs stay the centre sample's; the ray count adds up every sample's.
#[test]
fn surfaces_stay_the_centres_and_rays_add_up() {
    let scene = whitted(40, 30);
    let one = render(&scene, 1);
    let eight = render(&scene, 8);
    assert_eq!(one.surface, eight.surface);
    assert!(
        eight.rays() > 7 * one.rays(),
        "{} rays for 8 samples, {} for one",
        eight.rays(),
        one.rays()
    );
}
