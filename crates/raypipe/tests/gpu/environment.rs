//! The environment on the GPU against the CPU reference: every memory mode and pipeline, with
//! Whitted mirrors and glass, a rough glTF metal and a diffuse glTF surface in a turned, scaled
//! map; and the pixels the tracer skips (outside the scene's box) reading the same map.

use crate::common::harness::Test;
use crate::common::*;
use glam::Vec3;
use raypipe::gpu::GpuContext;
use raypipe::image::diff::Tolerance;
use raypipe::modes::Accel;
use raypipe::records::PackedScene;
use raypipe::scene::{Environment, Material, Pbr, Sphere};

/// Whitted's scene and a quad, plus a rough glTF metal and a glTF plaster sphere, lit by a map
/// with a colour for every direction (and a bright spot), turned 40 degrees and scaled by 1.5.
fn environment_scene() -> PackedScene {
    let mut scene = whitted_with_quad(64, 48);
    let gltf = |metallic: f32, roughness: f32, color: Vec3| Material {
        color,
        pbr: Some(Pbr {
            metallic,
            roughness,
            ..Pbr::default()
        }),
        ..Material::default()
    };
    let first = scene.materials.len() as u32;
    scene.materials.push(gltf(1.0, 0.3, Vec3::new(0.95, 0.8, 0.5)));
    scene.materials.push(gltf(0.0, 0.8, Vec3::new(0.3, 0.6, 0.9)));
    for (i, x) in [-2.2f32, 2.2].into_iter().enumerate() {
        scene.spheres.push(Sphere {
            center: Vec3::new(x, -0.3, 0.5),
            radius: 0.6,
            material: first + i as u32,
        });
    }
    let mut environment = Environment::from_function(256, |d| {
        let spot = (d.dot(Vec3::new(0.6, 0.6, -0.5).normalize()) > 0.97) as u32 as f32;
        Vec3::new(0.5 + 0.4 * d.x, 0.5 + 0.4 * d.y, 0.5 + 0.4 * d.z) + Vec3::splat(8.0 * spot)
    })
    .unwrap();
    environment.rotation_degrees = 40.0;
    environment.intensity = 1.5;
    scene.set_environment(Some(environment));
    let mut packed = PackedScene::new(&scene).unwrap();
    packed.build_bvh();
    packed
}

fn environment_matches_the_cpu_in_every_memory_mode_and_pipeline(ctx: &GpuContext) {
    let scene = environment_scene();
    let cpu = render_cpu(&scene, Accel::Threaded);
    each_pipeline_and_memory_mode(ctx, &scene, "environment", |name, frame| {
        assert_frames_match(name, &frame, &cpu)
    });
    // The background is the map, not the scene's background colour.
    let corner = cpu.color[0];
    assert!(
        (Vec3::new(corner[0], corner[1], corner[2]) - Vec3::new(0.3, 0.5, 0.8))
            .abs()
            .max_element()
            > 0.1,
        "{corner:?}"
    );
}

/// Pixels outside the rectangle the scene's box projects to are not traced (src/gpu/trace/region.rs):
/// they must read the environment as a traced miss does.
fn skipped_pixels_read_the_environment(ctx: &GpuContext) {
    let mut scene = raypipe::scene::Scene {
        spheres: vec![Sphere {
            center: Vec3::ZERO,
            radius: 0.3,
            material: 0,
        }],
        materials: vec![Material::default()],
        ..Default::default()
    };
    scene.settings.width = 48;
    scene.settings.height = 32;
    scene.set_environment(Some(
        Environment::from_function(128, |d| Vec3::new(0.5 + 0.4 * d.x, 0.5 + 0.4 * d.y, 0.5)).unwrap(),
    ));
    let mut packed = PackedScene::new(&scene).unwrap();
    packed.build_bvh();
    let cpu = render_cpu(&packed, Accel::Threaded);
    let gpu = render_gpu(ctx, &packed, raypipe::modes::MemoryMode::Storage, Accel::Threaded);
    assert_images_match("environment-skipped", &gpu.display(), &cpu.display(), Tolerance::COLOR);
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu environment_matches_the_cpu_in_every_memory_mode_and_pipeline,
        gpu skipped_pixels_read_the_environment,
    ]
}
