//! Renders whose answer is known in closed form: a sphere's silhouette area and its distance, and a
//! quad's depth at every pixel.

use crate::common::harness::Test;
use crate::common::*;
use raypipe::gpu::GpuContext;
use raypipe::image::Frame;
use raypipe::modes::{Accel, MemoryMode};
use raypipe::records::PackedScene;

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

fn cpu_sphere_silhouette_and_depth() {
    check_silhouette_and_depth(&render_cpu(&one_sphere(), Accel::Brute), "cpu");
}

fn gpu_sphere_silhouette_and_depth(ctx: &GpuContext) {
    let frame = render_gpu(ctx, &one_sphere(), MemoryMode::Storage, Accel::Brute);
    check_silhouette_and_depth(&frame, &ctx.describe());
}

fn cpu_renders_do_not_depend_on_the_thread_count() {
    let scene = packed("random:300:5", 48, 32, 5);
    let many = render_cpu(&scene, Accel::Brute);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| render_cpu(&scene, Accel::Brute));
    assert_eq!(many, one);
}

/// A quad of two triangles facing the camera at distance DISTANCE, off-centre so that its diagonal
/// misses the image's symmetric pixels: x in [-1, 1.2], y in [-0.7, 0.9].
const QUAD: [[f32; 2]; 4] = [[-1.0, -0.7], [1.2, -0.7], [1.2, 0.9], [-1.0, 0.9]];

fn one_quad(accel: Accel) -> PackedScene {
    use glam::Vec3;
    use raypipe::scene::{Camera, Light, Material, Scene, Triangle};
    let corner = |k: usize| Vec3::new(QUAD[k][0], QUAD[k][1], 0.0);
    let triangle = |a, b, c| Triangle {
        vertices: [corner(a), corner(b), corner(c)],
        normals: None,
        uvs: None,
        material: 0,
        ..Default::default()
    };
    let mut scene = Scene {
        camera: Camera {
            eye: Vec3::new(0.0, 0.0, -DISTANCE),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: FOV_DEGREES,
        },
        lights: vec![Light::constant(Vec3::new(0.0, 5.0, -5.0), Vec3::ONE)],
        materials: vec![Material::default()],
        // Clockwise seen from +z, so counter-clockwise seen from the camera: the normal is -z.
        triangles: vec![triangle(0, 2, 1), triangle(0, 3, 2)],
        ..Scene::default()
    };
    scene.settings.width = WIDTH;
    scene.settings.height = HEIGHT;
    let mut packed = PackedScene::new(&scene).unwrap();
    if accel.uses_bvh() {
        packed.build_bvh();
    }
    packed
}

/// Every pixel's depth from the pinhole model in f64: the ray through the pixel centre meets z = 0
/// at eye + DISTANCE (-x, y, 1), at distance DISTANCE |(x, y, 1)|. Pixels within a hair of an edge
/// are left out, where f32 may fall either way.
fn check_quad(frame: &Frame, device: &str) {
    let tan = (FOV_DEGREES as f64 / 2.0).to_radians().tan();
    let aspect = WIDTH as f64 / HEIGHT as f64;
    let depth = frame.depth();
    let normals = &frame.surface;
    let (mut inside, mut checked) = (0, 0);
    for py in 0..HEIGHT {
        for px in 0..WIDTH {
            let x = (2.0 * (px as f64 + 0.5) / WIDTH as f64 - 1.0) * tan * aspect;
            let y = (1.0 - 2.0 * (py as f64 + 0.5) / HEIGHT as f64) * tan;
            // The camera looks along +z with y up, so its right is cross(forward, up) = -x.
            let (hx, hy) = (-DISTANCE as f64 * x, DISTANCE as f64 * y);
            let margin = [
                hx - QUAD[0][0] as f64,
                QUAD[1][0] as f64 - hx,
                hy - QUAD[0][1] as f64,
                QUAD[2][1] as f64 - hy,
            ]
            .into_iter()
            .fold(f64::INFINITY, |m, d| m.min(d.abs()));
            if margin < 1e-4 {
                continue;
            }
            checked += 1;
            let i = (py * WIDTH + px) as usize;
            let hit =
                hx > QUAD[0][0] as f64 && hx < QUAD[1][0] as f64 && hy > QUAD[0][1] as f64 && hy < QUAD[2][1] as f64;
            let got = depth.data[i] as f64;
            if hit {
                inside += 1;
                let expected = DISTANCE as f64 * (x * x + y * y + 1.0).sqrt();
                assert!(
                    (got - expected).abs() <= 2e-6 * expected,
                    "{device}: pixel ({px}, {py}) depth {got}, expected {expected}"
                );
                assert_eq!(normals[i][..3], [0.0, 0.0, -1.0], "{device}: pixel ({px}, {py}) normal");
            } else {
                assert_eq!(got, f64::INFINITY, "{device}: pixel ({px}, {py}) should miss");
            }
        }
    }
    assert!(
        inside > 500 && checked + 20 > (WIDTH * HEIGHT) as usize,
        "{inside} inside, {checked} checked"
    );
}

fn cpu_triangle_depth_is_exact() {
    for accel in [Accel::Brute, Accel::Threaded] {
        check_quad(&render_cpu(&one_quad(accel), accel), "cpu");
    }
}

fn gpu_triangle_depth_is_exact(ctx: &GpuContext) {
    for accel in [Accel::Brute, Accel::Threaded] {
        let frame = render_gpu(ctx, &one_quad(accel), MemoryMode::Storage, accel);
        check_quad(&frame, &format!("{} {accel:?}", ctx.describe()));
    }
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        plain cpu_sphere_silhouette_and_depth,
        gpu gpu_sphere_silhouette_and_depth,
        plain cpu_renders_do_not_depend_on_the_thread_count,
        plain cpu_triangle_depth_is_exact,
        gpu gpu_triangle_depth_is_exact,
    ]
}
