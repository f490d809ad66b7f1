//! Shared test support: scenes at test sizes, GPU renders, and image assertions that leave the
//! images behind for a human when they fail.
#![allow(dead_code)]

pub mod closed;
pub mod gltf_file;
// Not every test binary uses both.
#[allow(unused_imports)]
pub use raypipe_test_support::{self as harness, models};

use glam::{Vec2, Vec3};
use raypipe::Choice;
use raypipe::gpu::{GpuContext, Renderer, RendererOptions};
use raypipe::image::diff::{self, Tolerance};
use raypipe::image::{FloatImage, Frame};
use raypipe::modes::{Accel, MemoryMode, Pipeline};
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Light, Material, RenderSettings, Scene};
use std::path::{Path, PathBuf};

/// A fresh, empty folder for a test's files ([`harness::fresh_dir`]).
pub fn test_dir(name: &str) -> PathBuf {
    harness::fresh_dir(PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name))
}

/// Whitted's scene (mirror, glass, checker floor, two lights) with a quad of two triangles behind,
/// at `width` x `height`: every primitive kind in one image.
pub fn whitted_with_quad(width: u32, height: u32) -> Scene {
    let mut scene = raypipe::scene::builtin::whitted();
    scene.settings.width = width;
    scene.settings.height = height;
    let q = [(1.2, -1.0), (2.8, -1.0), (2.8, 1.0), (1.2, 1.0)].map(|(x, y)| glam::Vec3::new(x, y, 2.0));
    for [a, b, c] in [[0, 2, 1], [0, 3, 2]] {
        scene.triangles.push(raypipe::scene::Triangle {
            vertices: [q[a], q[b], q[c]],
            normals: None,
            uvs: None,
            material: 1,
            ..Default::default()
        });
    }
    scene
}

/// Two triangles over the quad `corners` (counter-clockwise seen from the side it faces when
/// `facing_front`; wound the other way round otherwise), in `material`, with texture coordinates
/// from `uv` where given.
pub fn quad_triangles(
    corners: [glam::Vec3; 4],
    material: u32,
    facing_front: bool,
    uv: Option<&dyn Fn(glam::Vec3) -> glam::Vec2>,
) -> [raypipe::scene::Triangle; 2] {
    let order = if facing_front {
        [[0, 1, 2], [0, 2, 3]]
    } else {
        [[0, 2, 1], [0, 3, 2]]
    };
    order.map(|[a, b, c]| {
        let vertices = [corners[a], corners[b], corners[c]];
        raypipe::scene::Triangle {
            vertices,
            uvs: uv.map(|uv| vertices.map(uv)),
            material,
            ..Default::default()
        }
    })
}

/// A scene at a test size and depth, packed.
pub fn packed(spec: &str, width: u32, height: u32, max_depth: u32) -> PackedScene {
    let mut scene = Scene::load(spec).unwrap();
    scene.settings.width = width;
    scene.settings.height = height;
    scene.settings.max_depth = max_depth;
    PackedScene::new(&scene).unwrap()
}

pub fn renderer(ctx: &GpuContext, scene: &PackedScene, options: RendererOptions) -> Renderer {
    pollster::block_on(Renderer::new(ctx, scene, options))
        .unwrap_or_else(|e| panic!("building the renderer failed on {}: {e}", ctx.describe()))
}

pub fn render_gpu(ctx: &GpuContext, scene: &PackedScene, memory: MemoryMode, accel: Accel) -> Frame {
    let options = RendererOptions {
        memory,
        accel,
        ..Default::default()
    };
    render_gpu_with(ctx, scene, options)
}

/// One frame of `scene` on the GPU, traced as `options` say.
pub fn render_gpu_with(ctx: &GpuContext, scene: &PackedScene, options: RendererOptions) -> Frame {
    pollster::block_on(renderer(ctx, scene, options).read_frame())
        .unwrap_or_else(|e| panic!("GPU render failed on {}: {e}", ctx.describe()))
        .frame
}

/// `scene` traced by the threaded walk in each pipeline and each memory mode the adapter has,
/// each frame handed to `check` with its name, `{prefix}-{pipeline}-{memory}`.
pub fn each_pipeline_and_memory_mode(
    ctx: &GpuContext,
    scene: &PackedScene,
    prefix: &str,
    check: impl FnMut(&str, Frame),
) {
    each_pipeline_and_memory_mode_at(ctx, scene, 1, prefix, check);
}

/// [`each_pipeline_and_memory_mode`] at `samples` samples a pixel.
pub fn each_pipeline_and_memory_mode_at(
    ctx: &GpuContext,
    scene: &PackedScene,
    samples: u32,
    prefix: &str,
    mut check: impl FnMut(&str, Frame),
) {
    for &pipeline in Pipeline::ALL {
        for memory in ctx.memory_modes() {
            let options = RendererOptions {
                pipeline,
                memory,
                accel: Accel::Threaded,
                ..Default::default()
            };
            let frame = pollster::block_on(renderer(ctx, scene, options).render_samples(samples, |_| {}, |_| {}))
                .unwrap_or_else(|e| panic!("GPU render failed on {}: {e}", ctx.describe()))
                .frame;
            check(&format!("{prefix}-{pipeline:?}-{memory:?}"), frame);
        }
    }
}

/// The CPU reference's frame.
pub fn render_cpu(scene: &PackedScene, accel: Accel) -> Frame {
    raypipe::cpu::render(scene, accel).unwrap()
}

/// [`models::mixed_scene`], its files in a test folder of its own.
pub fn mixed_scene(rings: u32, sides: u32, spheres: usize) -> Scene {
    let dir = test_dir(&format!("mixed-scene-{rings}-{sides}-{spheres}"));
    models::mixed_scene(&dir, rings, sides, spheres)
}

fn output_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("image-failures");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `image` as an 8-bit PNG for a human: display values as they are, anything else (depth) scaled
/// to [0, 1] over its finite range, +inf black.
fn write_for_viewing(image: &FloatImage, path: &Path) {
    let finite = image.data.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let display = image.data.iter().all(|v| (0.0..=1.0).contains(v));
    let to_byte = |v: f32| {
        let v = if display {
            v
        } else if v.is_finite() && hi > lo {
            1.0 - (v - lo) / (hi - lo)
        } else {
            0.0
        };
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    let channels = image.channels.len();
    let mut rgb = Vec::with_capacity(image.pixel_count() * 3);
    for i in 0..image.pixel_count() {
        let p = image.pixel(i);
        let pick = |c: usize| to_byte(p[c.min(channels - 1)]);
        rgb.extend([pick(0), pick(1), pick(2)]);
    }
    image::RgbImage::from_raw(image.width, image.height, rgb)
        .expect("sized to the image")
        .save(path)
        .unwrap();
}

/// Asserts that `actual` matches `expected` within `tolerance`. On failure writes
/// `NAME-expected.png`, `NAME-actual.png` and `NAME-difference.png` and names them in the panic.
pub fn assert_images_match(name: &str, actual: &FloatImage, expected: &FloatImage, tolerance: Tolerance) {
    let errors = diff::pixel_errors(actual, expected).unwrap();
    let stats = diff::stats(&errors);
    if let Err(message) = tolerance.check(&stats) {
        let dir = output_dir();
        write_for_viewing(actual, &dir.join(format!("{name}-actual.png")));
        write_for_viewing(expected, &dir.join(format!("{name}-expected.png")));
        let picture = diff::error_image(&errors, actual.width, actual.height, 0.1);
        write_for_viewing(&picture, &dir.join(format!("{name}-difference.png")));
        panic!("{name}: {message}; images in {}", dir.display());
    }
}

/// Colour and depth of two frames must match within the tolerances for different devices.
pub fn assert_frames_match(name: &str, actual: &Frame, expected: &Frame) {
    assert_images_match(
        &format!("{name}-color"),
        &actual.display(),
        &expected.display(),
        Tolerance::COLOR,
    );
    assert_images_match(
        &format!("{name}-depth"),
        &actual.depth(),
        &expected.depth(),
        Tolerance::DEPTH,
    );
}

/// A 9x9 image whose centre pixel's ray runs down -z onto the plane z = 0 at the origin: view
/// direction (0, 0, 1), normal (0, 0, 1).
pub const PLANE_SIZE: u32 = 9;

/// The plane z = 0 (a big quad facing +z) in `material`, seen from (0, 0, 5), with `lights`, no
/// ambient light, a black background and no bounces: a pixel is direct light alone.
pub fn plane_scene(material: Material, lights: Vec<Light>) -> Scene {
    let corners = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)].map(|(x, y)| Vec3::new(x, y, 0.0));
    let triangles = quad_triangles(corners, 0, true, Some(&|p: Vec3| Vec2::new(p.x, p.y))).to_vec();
    Scene {
        camera: Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: 20.0,
        },
        settings: RenderSettings {
            width: PLANE_SIZE,
            height: PLANE_SIZE,
            max_depth: 0,
            background: Vec3::ZERO,
            ambient: 0.0,
            accel: None,
            integrator: Default::default(),
        },
        lights,
        materials: vec![material],
        triangles,
        ..Scene::default()
    }
}

/// The centre pixel's radiance.
pub fn centre(scene: &Scene) -> Vec3 {
    let mut packed = PackedScene::new(scene).unwrap();
    packed.build_bvh();
    let frame = render_cpu(&packed, Accel::Threaded);
    let [r, g, b, _] = frame.color[(PLANE_SIZE / 2 * PLANE_SIZE + PLANE_SIZE / 2) as usize];
    Vec3::new(r, g, b)
}

/// An unlit material showing texture 0 as it is: a pixel's radiance is the filtered texel.
pub fn unlit_textured() -> Material {
    Material {
        color: Vec3::ONE,
        texture: Some(raypipe::scene::TextureMap::plain(0)),
        pbr: Some(raypipe::scene::Pbr {
            unlit: true,
            ..Default::default()
        }),
        ..Material::default()
    }
}

/// A `size` x `size` checker of one-texel squares, 1 where x + y is even and 0 elsewhere, tiling
/// the plane, read through `filter`.
pub fn checker_texture(size: u32, filter: raypipe::scene::Filter) -> raypipe::scene::Texture {
    let texels: Vec<[f32; 4]> = (0..size * size)
        .map(|i| {
            let on = (i % size + i / size).is_multiple_of(2);
            if on { [1.0; 4] } else { [0.0, 0.0, 0.0, 1.0] }
        })
        .collect();
    raypipe::scene::Texture::from_linear(size, size, &texels, [raypipe::scene::Wrap::Repeat; 2]).with_filter(filter)
}

/// The texels of [`checker_floor`]'s texture per unit of length on the floor.
pub const FLOOR_TEXELS_PER_UNIT: f32 = 10.0;

/// A floor (y = 0) to the horizon, 4 km wide and 1 km deep, in a 64 x 64 checker of one-texel
/// squares (10 to a unit of length, read through `filter`), unlit, seen at `width` x `height` from
/// 1 unit above it, looking slightly down: the near rows see a texel over several pixels, the far
/// rows hundreds of texels in a pixel.
pub fn checker_floor(filter: raypipe::scene::Filter, width: u32, height: u32) -> Scene {
    let corners =
        [(-2000.0, 10.0), (2000.0, 10.0), (2000.0, -1000.0), (-2000.0, -1000.0)].map(|(x, z)| Vec3::new(x, 0.0, z));
    let uv = |p: Vec3| Vec2::new(p.x, p.z) * (FLOOR_TEXELS_PER_UNIT / 64.0);
    Scene {
        camera: Camera {
            eye: Vec3::new(0.3, 1.0, 0.0),
            target: Vec3::new(0.3, 0.6, -4.0),
            up: Vec3::Y,
            fov_degrees: 40.0,
        },
        settings: RenderSettings {
            width,
            height,
            max_depth: 0,
            background: Vec3::ZERO,
            ambient: 0.0,
            accel: None,
            integrator: Default::default(),
        },
        materials: vec![unlit_textured()],
        textures: vec![checker_texture(64, filter)],
        triangles: quad_triangles(corners, 0, true, Some(&uv)).to_vec(),
        ..Scene::default()
    }
}

/// The rows of `frame` whose every pixel hit something, top to bottom.
pub fn hit_rows(frame: &Frame) -> Vec<u32> {
    (0..frame.height)
        .filter(|&y| (0..frame.width).all(|x| frame.surface[(y * frame.width + x) as usize][3] >= 0.0))
        .collect()
}

/// The standard deviation of the red channel over `rows` of `frame`.
pub fn red_deviation(frame: &Frame, rows: &[u32]) -> f32 {
    let values: Vec<f32> = rows
        .iter()
        .flat_map(|&y| (0..frame.width).map(move |x| (y * frame.width + x) as usize))
        .map(|i| frame.color[i][0])
        .collect();
    let mean = values.iter().sum::<f32>() / values.len() as f32;
    (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / values.len() as f32).sqrt()
}
