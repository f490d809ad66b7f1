//! Renders whose answer is known in closed form: a sphere's silhouette area and its distance.

mod common;
use common::*;
use raypipe::gpu::upload::MemoryMode;
use raypipe::image::Frame;
use raypipe::render::Accel;
use raypipe::scene::packed::PackedScene;

const WIDTH: u32 = 121;
const HEIGHT: u32 = 81;
const FOV_DEGREES: f32 = 40.0;
const DISTANCE: f32 = 5.0;
const RADIUS: f32 = 1.0;

/// One sphere straight ahead of the camera; odd image sides put a pixel centre on the axis.
fn one_sphere() -> PackedScene {
    let text = format!(
        "[camera]\neye = [0, 0, -{DISTANCE}]\ntarget = [0, 0, 0]\nfov = {FOV_DEGREES}\n\
         [render]\nwidth = {WIDTH}\nheight = {HEIGHT}\n\
         [[light]]\nposition = [0, 5, -5]\n[[sphere]]\ncenter = [0, 0, 0]\nradius = {RADIUS}\n"
    );
    PackedScene::new(&raypipe::scene::file::parse(&text).unwrap()).unwrap()
}

fn check_silhouette_and_depth(frame: &Frame, device: &str) {
    // The silhouette is a cone of half-angle asin(r / d); on the image plane at distance 1 it is a
    // circle of radius tan of that, and a pixel is 2 tan(fov / 2) / height on a side.
    let half_angle = (RADIUS / DISTANCE).asin() as f64;
    let pixel = 2.0 * (FOV_DEGREES as f64 / 2.0).to_radians().tan() / HEIGHT as f64;
    let radius_pixels = half_angle.tan() / pixel;
    let expected = std::f64::consts::PI * radius_pixels * radius_pixels;
    let covered = frame.surface.iter().filter(|s| s[3] >= 0.0).count() as f64;
    // Pixel-centre sampling of a circle: the count differs from the area by well under its perimeter.
    let slack = 0.25 * 2.0 * std::f64::consts::PI * radius_pixels;
    assert!(
        (covered - expected).abs() <= slack,
        "{device}: {covered} covered pixels, expected {expected:.1} ± {slack:.1}"
    );

    let centre = (HEIGHT / 2 * WIDTH + WIDTH / 2) as usize;
    let depth = frame.depth().data[centre];
    let expected_depth = DISTANCE - RADIUS;
    assert!(
        (depth - expected_depth).abs() <= 1e-5 * expected_depth,
        "{device}: depth at the centre {depth}, expected {expected_depth}"
    );
    assert_eq!(
        frame.depth().data[0],
        f32::INFINITY,
        "{device}: a corner ray misses everything"
    );
}

#[test]
fn cpu_sphere_silhouette_and_depth() {
    check_silhouette_and_depth(&raypipe::cpu::render(&one_sphere(), Accel::Brute, false), "cpu");
}

#[test]
fn gpu_sphere_silhouette_and_depth() {
    let Some(ctx) = gpu() else { return };
    let frame = render_gpu(&ctx, &one_sphere(), MemoryMode::Storage, Accel::Brute);
    check_silhouette_and_depth(&frame, &ctx.describe());
}

#[test]
fn cpu_renders_do_not_depend_on_the_thread_count() {
    let scene = packed("random:300:5", 48, 32, 5);
    let many = raypipe::cpu::render(&scene, Accel::Brute, false);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| raypipe::cpu::render(&scene, Accel::Brute, false));
    assert_eq!(many, one);
}
