//! A scene built in code, no file read: a floor, two spheres (glass and a mirror), an octahedron
//! made from vectors, a material each, one light; traced on the GPU where there is one and by the
//! CPU reference otherwise, and written as a PNG.
//!
//! `cargo run --release --example scene_in_code -- scene.png`

use glam::Vec3;
use raypipe::Accel;
use raypipe::gpu::{GpuContext, Renderer, RendererOptions};
use raypipe::mesh::Mesh;
use raypipe::records::PackedScene;
use raypipe::scene::model::{Placement, add_mesh};
use raypipe::scene::{Camera, Checker, Light, Material, Plane, RenderSettings, Scene, Sphere};
use std::error::Error;

fn scene() -> Result<Scene, Box<dyn Error>> {
    let material = |color: Vec3| Material {
        color,
        ..Material::default()
    };
    let mut scene = Scene {
        camera: Camera {
            eye: Vec3::new(0.0, 1.5, -5.0),
            target: Vec3::new(0.0, 0.3, 0.0),
            up: Vec3::Y,
            fov_degrees: 45.0,
        },
        settings: RenderSettings {
            width: 320,
            height: 240,
            ..RenderSettings::default()
        },
        lights: vec![Light::constant(Vec3::new(3.0, 5.0, -4.0), Vec3::splat(0.9))],
        materials: vec![
            material(Vec3::splat(0.8)),
            material(Vec3::splat(0.3)),
            Material {
                color: Vec3::splat(0.05),
                transmit: 0.9,
                reflect: 0.05,
                ior: 1.5,
                specular: 0.5,
                ..Material::default()
            },
            Material {
                color: Vec3::splat(0.1),
                reflect: 0.85,
                ..Material::default()
            },
            Material {
                color: Vec3::new(0.85, 0.45, 0.2),
                specular: 0.3,
                ..Material::default()
            },
        ],
        planes: vec![Plane {
            point: Vec3::new(0.0, -0.5, 0.0),
            normal: Vec3::Y,
            material: 0,
            checker: Some(Checker { material: 1, size: 0.5 }),
        }],
        spheres: vec![
            Sphere {
                center: Vec3::new(-1.2, 0.2, 0.0),
                radius: 0.7,
                material: 2,
            },
            Sphere {
                center: Vec3::new(1.2, 0.2, 0.5),
                radius: 0.7,
                material: 3,
            },
        ],
        ..Scene::default()
    };
    // An octahedron from its six corners, placed behind the spheres. Without normals of its own it
    // gets smooth ones with the 60-degree crease; its faces' normals are 70.5 degrees apart, so its
    // edges stay sharp.
    let corners = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let octahedron = Mesh {
        positions: corners.to_vec(),
        normals: None,
        triangles: vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    };
    let placement = Placement {
        normalize: false,
        scale: 0.6,
        translate: Vec3::new(0.0, 0.4, 2.0),
        material: 4,
        ..Placement::default()
    };
    add_mesh(&mut scene, octahedron, &placement)?;
    scene.validate()?;
    Ok(scene)
}

fn main() -> Result<(), Box<dyn Error>> {
    let path = std::env::args().nth(1).unwrap_or_else(|| "scene.png".into());
    let mut packed = PackedScene::new(&scene()?)?;
    packed.build_bvh();
    let frame = match pollster::block_on(GpuContext::new(None))? {
        Some(ctx) => {
            let mut renderer = pollster::block_on(Renderer::new(&ctx, &packed, RendererOptions::default()))?;
            pollster::block_on(renderer.read_frame())?.frame
        }
        None => raypipe::cpu::render(&packed, Accel::Threaded)?,
    };
    let display = frame.display();
    image::save_buffer(
        &path,
        &display.to_bytes(),
        display.width,
        display.height,
        image::ColorType::Rgb8,
    )?;
    println!("{path}: {}x{}", display.width, display.height);
    Ok(())
}
