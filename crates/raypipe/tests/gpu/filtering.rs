//! Texture filtering on the GPU against the CPU reference, in every memory mode and pipeline: a
//! checker floor to the horizon (trilinear), seen directly, in a mirror sphere and through a
//! glass one (the cones reflected and refracted), and a wall read through NEAREST filters
//! between and within mip levels.

use crate::common::harness::Test;
use crate::common::*;
use glam::{Vec2, Vec3};
use raypipe::gpu::GpuContext;
use raypipe::modes::Accel;
use raypipe::records::PackedScene;
use raypipe::scene::{Filter, Material, Sphere, TexelFilter, TextureMap};

fn filtering_scene() -> PackedScene {
    let mut scene = checker_floor(Filter::default(), 64, 48);
    scene.settings.max_depth = 3;
    let first = scene.materials.len() as u32;
    scene.materials.push(Material {
        color: Vec3::ZERO,
        reflect: 1.0,
        ..Material::default()
    });
    scene.materials.push(Material {
        color: Vec3::ZERO,
        transmit: 1.0,
        ior: 1.5,
        ..Material::default()
    });
    for (i, x) in [-0.5f32, 1.1].into_iter().enumerate() {
        scene.spheres.push(Sphere {
            center: Vec3::new(x, 0.45, -3.0),
            radius: 0.4,
            material: first + i as u32,
        });
    }
    // A wall on the right, far off and turned away, in a 16 x 16 checker read through the nearest
    // level with the nearest texel.
    let nearest = Filter {
        magnify: TexelFilter::Nearest,
        minify: TexelFilter::Nearest,
        mipmaps: Some(TexelFilter::Nearest),
    };
    scene.textures.push(checker_texture(16, nearest));
    let mut wall = unlit_textured();
    wall.texture = Some(TextureMap::plain(1));
    scene.materials.push(wall);
    let corners = [(3.0, -4.0), (3.0, -30.0), (12.0, -30.0), (12.0, -4.0)];
    let corners = [0.0, 0.0, 3.0, 3.0]
        .iter()
        .zip(corners)
        .map(|(&y, (x, z))| Vec3::new(x, y, z))
        .collect::<Vec<_>>();
    let uv = |p: Vec3| Vec2::new(p.z, p.y) * 2.0;
    scene.triangles.extend(quad_triangles(
        [corners[0], corners[1], corners[2], corners[3]],
        first + 2,
        true,
        Some(&uv),
    ));
    let mut packed = PackedScene::new(&scene).unwrap();
    packed.build_bvh();
    packed
}

fn filtered_textures_match_the_cpu_in_every_memory_mode_and_pipeline(ctx: &GpuContext) {
    let scene = filtering_scene();
    let cpu = render_cpu(&scene, Accel::Threaded);
    each_pipeline_and_memory_mode(ctx, &scene, "filtering", |name, frame| {
        assert_frames_match(name, &frame, &cpu)
    });
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![gpu filtered_textures_match_the_cpu_in_every_memory_mode_and_pipeline]
}
