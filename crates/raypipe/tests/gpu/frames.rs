//! Moving scenes: the BVH rebuilt every frame, on the GPU in the same submission as the frame, must
//! give the images of the CPU path (which rebuilds with the CPU builder).

use crate::common::harness::Test;
use crate::common::*;
use glam::Vec3;
use pollster::block_on;
use raypipe::bvh::lbvh::LbvhBuilder;
use raypipe::bvh::morton::MortonBits;
use raypipe::gpu::{GpuContext, GpuError, MotionError, MovingScene, RendererOptions, SceneRebuild, TreeUpdate};
use raypipe::image::Frame;
use raypipe::modes::Pipeline;
use raypipe::modes::{Accel, MemoryMode};
use raypipe::records::PackedScene;
use raypipe::scene::gltf::{Files, parse};
use raypipe::scene::model::{ModelOptions, gltf_scene};
use raypipe::scene::{Motion, Scene};

/// Frame `k`'s time, as `render --frames` places it at its default 30 frames per second.
fn time_of(frame: u32) -> f32 {
    (frame as f64 / 30.0) as f32
}

/// `count` frames with the BVH rebuilt on the GPU before each, in the frame's submission; each
/// frame rewrites only the records that moved, as `render --frames` and the viewer do.
pub fn gpu_frames(ctx: &GpuContext, scene: &Scene, accel: Accel, count: u32) -> Vec<Frame> {
    moving_frames(ctx, scene, accel, MemoryMode::Storage, TreeUpdate::Rebuild, count)
}

/// `count` frames of the library's moving scene in `memory`: its tree rebuilt (or refitted, with
/// `update`) on the GPU in storage memory, and elsewhere built on the CPU with the moved records
/// and the nodes rewritten in place, the route of adapters without compute shaders (WebGL2).
pub fn moving_frames(
    ctx: &GpuContext,
    scene: &Scene,
    accel: Accel,
    memory: MemoryMode,
    update: TreeUpdate,
    count: u32,
) -> Vec<Frame> {
    let options = RendererOptions {
        accel,
        memory,
        ..Default::default()
    };
    let mut moving = block_on(MovingScene::new(ctx, scene, options, update)).unwrap();
    (0..count)
        .map(|frame| {
            moving.pose(time_of(frame)).unwrap();
            block_on(moving.render_samples(1, |_| {})).unwrap().frame
        })
        .collect()
}

/// The same frames on the CPU, one reusable builder rebuilding the BVH before each.
pub fn cpu_frames(scene: &Scene, accel: Accel, count: u32) -> Vec<Frame> {
    let mut builder = LbvhBuilder::<u64>::new();
    (0..count)
        .map(|frame| {
            let mut packed = PackedScene::new(&scene.at_time(time_of(frame)).unwrap()).unwrap();
            builder.build(&packed.primitive_boxes(), MortonBits::Bits30);
            packed.set_bvh(builder.to_bvh());
            render_cpu(&packed, accel)
        })
        .collect()
}

fn gpu_rebuilt_frames_match_the_cpu(ctx: &GpuContext) {
    let mut scene = Scene::load("bounce:1500:2").unwrap();
    scene.settings.width = 64;
    scene.settings.height = 48;
    let cpu = cpu_frames(&scene, Accel::Stack, 4);
    assert_ne!(cpu[0], cpu[3], "the spheres move");
    let cpu_brute = cpu_frames(&scene, Accel::Brute, 4);
    assert_frames_match("frames-cpu-stack-vs-brute", &cpu[3], &cpu_brute[3]);
    let gpu = gpu_frames(ctx, &scene, Accel::Stack, 4);
    for (k, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
        assert_frames_match(&format!("frames-gpu-vs-cpu-{k}"), g, c);
    }
}

/// Spheres flying among standing triangles, rebuilt on the GPU every frame: the CPU's frames.
fn gpu_rebuilt_frames_with_triangles_match_the_cpu(ctx: &GpuContext) {
    let mut scene = crate::common::mixed_scene(12, 6, 300);
    scene.settings.width = 48;
    scene.settings.height = 32;
    let velocities = (0..scene.spheres.len())
        .map(|i| glam::Vec3::new((i % 7) as f32 - 3.0, (i % 5) as f32 - 2.0, (i % 3) as f32 - 1.0))
        .collect();
    scene.motion = Some(raypipe::scene::Motion::Bounce(raypipe::scene::Bounce {
        velocities,
        lo: glam::Vec3::new(-2.0, -0.5, -1.0),
        hi: glam::Vec3::new(2.0, 1.0, 2.5),
    }));
    let on_gpu = gpu_frames(ctx, &scene, Accel::Threaded, 3);
    let on_cpu = cpu_frames(&scene, Accel::Threaded, 3);
    assert_ne!(on_cpu[0], on_cpu[2], "the spheres move");
    for (k, (g, c)) in on_gpu.iter().zip(&on_cpu).enumerate() {
        assert_frames_match(&format!("frames-triangles-{k}"), g, c);
    }
}

/// A moving scene's records rewritten in texture memory, its BVH rebuilt on the CPU, gives the
/// frames of the GPU rebuild in storage memory.
fn rewritten_texture_frames_match_the_gpu_rebuild(ctx: &GpuContext) {
    let mut scene = Scene::load("bounce:1200:3").unwrap();
    scene.settings.width = 64;
    scene.settings.height = 48;
    for accel in [Accel::Threaded, Accel::Stackless, Accel::Wide] {
        let on_gpu = gpu_frames(ctx, &scene, accel, 3);
        let rewritten = moving_frames(ctx, &scene, accel, MemoryMode::Texture, TreeUpdate::Rebuild, 3);
        assert_ne!(rewritten[0], rewritten[2], "the spheres move");
        for (k, (r, g)) in rewritten.iter().zip(&on_gpu).enumerate() {
            assert_frames_match(&format!("frames-rewritten-{accel:?}-{k}"), r, g);
        }
    }
}

/// The test support's two-bone cylinder of 12 rings as a scene, loaded from its glTF: its second
/// joint bends 90 degrees over its one-second clip.
fn bending_cylinder() -> Scene {
    let (builder, _, _) = gltf_file::skinned_cylinder(12);
    let file = parse(&builder.gltf(), Files::None, &mut Vec::new()).unwrap();
    gltf_scene(&file, "cylinder.gltf", &ModelOptions::default()).unwrap()
}

/// A skinned cylinder bending (a glTF clip): its triangles and normals rewritten in place and the
/// BVH rebuilt on the GPU every frame give the CPU's frames.
fn gpu_rebuilt_animated_frames_match_the_cpu(ctx: &GpuContext) {
    let mut scene = bending_cylinder();
    scene.settings.width = 48;
    scene.settings.height = 40;
    for accel in [Accel::Threaded, Accel::Stackless, Accel::Wide] {
        let on_gpu = gpu_frames(ctx, &scene, accel, 4);
        let on_cpu = cpu_frames(&scene, accel, 4);
        assert_ne!(on_cpu[0], on_cpu[3], "the cylinder bends");
        for (k, (g, c)) in on_gpu.iter().zip(&on_cpu).enumerate() {
            assert_frames_match(&format!("frames-animated-{accel:?}-{k}"), g, c);
        }
        let rewritten = moving_frames(ctx, &scene, accel, MemoryMode::Texture, TreeUpdate::Rebuild, 4);
        for (k, (r, c)) in rewritten.iter().zip(&on_cpu).enumerate() {
            assert_frames_match(&format!("frames-animated-texture-{accel:?}-{k}"), r, c);
        }
    }
}

/// The bending cylinder's tree built at the first frame and only refitted after, for the walks
/// of either layout: the CPU's frames, whose trees are built anew.
fn gpu_refitted_animated_frames_match_the_cpu(ctx: &GpuContext) {
    let mut scene = bending_cylinder();
    scene.settings.width = 48;
    scene.settings.height = 40;
    for accel in [Accel::Threaded, Accel::Stackless, Accel::Wide] {
        let refitted = moving_frames(ctx, &scene, accel, MemoryMode::Storage, TreeUpdate::Refit, 4);
        let on_cpu = cpu_frames(&scene, accel, 4);
        for (k, (g, c)) in refitted.iter().zip(&on_cpu).enumerate() {
            assert_frames_match(&format!("frames-refitted-{accel:?}-{k}"), g, c);
        }
    }
}

/// One posed frame of the cylinder, in every memory mode and pipeline, against the CPU.
fn a_posed_frame_matches_the_cpu_in_every_mode(ctx: &GpuContext) {
    let mut posed = bending_cylinder().at_time(0.6).unwrap();
    posed.settings.width = 48;
    posed.settings.height = 40;
    let mut packed = PackedScene::new(&posed).unwrap();
    packed.build_bvh();
    let cpu = render_cpu(&packed, Accel::Threaded);
    for memory in ctx.memory_modes() {
        for pipeline in [Pipeline::Fragment, Pipeline::Compute] {
            let options = RendererOptions {
                memory,
                pipeline,
                accel: Accel::Threaded,
                ..Default::default()
            };
            let gpu = block_on(crate::common::renderer(ctx, &packed, options).read_frame())
                .unwrap()
                .frame;
            assert_frames_match(&format!("posed-{memory:?}-{pipeline:?}"), &gpu, &cpu);
        }
    }
}

/// Where the CPU poses `scene`'s animated vertices at `t`: in the order of the GPU skinning pass's
/// records (animation, placed primitive, vertex).
fn cpu_posed_vertices(scene: &Scene, t: f32) -> Vec<Vec3> {
    let Some(Motion::Animations(animations)) = &scene.motion else {
        panic!("an animated scene")
    };
    let mut out = Vec::new();
    for animated in animations {
        let pose = animated.rig.pose(Some(animated.clip), t + animated.offset);
        for placed in &animated.placed {
            let (positions, _) = animated.rig.deform(&animated.rig.instances[placed.instance], &pose);
            out.extend(positions.into_iter().map(|p| animated.place.point(p)));
        }
    }
    out
}

/// GPU skinning's vertices against the CPU's, within 1e-5 of the larger coordinate (the GPU sums
/// the weighted joint matrices before it applies them, the CPU's matrix is the same sum: only the
/// rounding of a few multiply-adds differs).
fn assert_skinned_like_the_cpu(ctx: &GpuContext, what: &str, scene: &Scene, times: &[f32]) {
    let packed = PackedScene::new(scene).unwrap();
    let rebuild = block_on(SceneRebuild::new(
        ctx,
        scene,
        &packed,
        Accel::Threaded,
        MortonBits::Bits30,
    ))
    .unwrap();
    let deform = rebuild.deform().expect("an animated scene skins on the GPU");
    for &t in times {
        deform.write_pose(t).unwrap();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        rebuild.encode(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let gpu = block_on(deform.read_positions()).unwrap();
        let cpu = cpu_posed_vertices(scene, t);
        assert_eq!(gpu.len(), cpu.len(), "{what}: vertex count");
        for (v, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
            let tolerance = 1e-5 * c.abs().max_element().max(1.0);
            assert!(
                (*g - *c).abs().max_element() <= tolerance,
                "{what} at {t} s, vertex {v}: GPU {g}, CPU {c}"
            );
        }
    }
}

/// Skinning (two joints over a cylinder) and morphing (a quad lifted by its target), posed on the
/// GPU at and between keys and past the end, against the CPU's vertices.
fn gpu_skinning_and_morphing_match_the_cpu(ctx: &GpuContext) {
    let times = [0.0, 0.3, 0.5, 1.0, 1.7];
    assert_skinned_like_the_cpu(ctx, "cylinder", &bending_cylinder(), &times);
    let file = parse(&gltf_file::morphing_quad(0.5).gltf(), Files::None, &mut Vec::new()).unwrap();
    let quad = gltf_scene(&file, "quad.gltf", &ModelOptions::default()).unwrap();
    assert_skinned_like_the_cpu(ctx, "morphing quad", &quad, &times);
}

/// The shared animated samples skinned on the GPU (the file's normals: RiggedSimple; smooth ones:
/// SimpleSkin, AnimatedTriangle; node animation: BoxAnimated), in both pipelines: their vertices
/// and their frames at three times against the CPU's.
fn gpu_skinned_samples_match_the_cpu(ctx: &GpuContext, models: &std::path::Path) {
    for name in ["RiggedSimple", "SimpleSkin", "BoxAnimated", "AnimatedTriangle"] {
        let path = models.join("gltf").join(format!("{name}.gltf"));
        let mut scene = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
        scene.settings.width = 48;
        scene.settings.height = 36;
        let duration = scene.motion.as_ref().and_then(|m| m.duration()).unwrap();
        let times: Vec<f32> = [0.2, 0.55, 0.9].iter().map(|f| f * duration).collect();
        assert_skinned_like_the_cpu(ctx, name, &scene, &times);
        for &t in &times {
            let mut cpu_packed = PackedScene::new(&scene.at_time(t).unwrap()).unwrap();
            cpu_packed.build_bvh();
            let cpu = render_cpu(&cpu_packed, Accel::Threaded);
            for pipeline in [Pipeline::Fragment, Pipeline::Compute] {
                let options = RendererOptions {
                    accel: Accel::Threaded,
                    pipeline,
                    ..Default::default()
                };
                let mut moving = block_on(MovingScene::new(ctx, &scene, options, TreeUpdate::Rebuild)).unwrap();
                moving.pose(t).unwrap();
                let gpu = block_on(moving.render_samples(1, |_| {})).unwrap().frame;
                assert_frames_match(&format!("skinned-{name}-{t}-{pipeline:?}"), &gpu, &cpu);
            }
        }
    }
}

/// A tree is refitted only where the GPU built it: in uniform or texture memory the scene is
/// refused before anything is compiled.
fn refitting_needs_storage_memory(ctx: &GpuContext) {
    let scene = Scene::load("bounce:20").unwrap();
    for memory in [MemoryMode::Uniform, MemoryMode::Texture] {
        let options = RendererOptions {
            memory,
            ..Default::default()
        };
        let made = block_on(MovingScene::new(ctx, &scene, options, TreeUpdate::Refit));
        assert!(
            matches!(made, Err(MotionError::Gpu(GpuError::RebuildNeedsStorage { memory: m })) if m == memory),
            "{memory:?}: {:?}",
            made.err()
        );
    }
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu gpu_skinning_and_morphing_match_the_cpu,
        gpu_models gpu_skinned_samples_match_the_cpu,
        gpu gpu_rebuilt_animated_frames_match_the_cpu,
        gpu gpu_refitted_animated_frames_match_the_cpu,
        gpu a_posed_frame_matches_the_cpu_in_every_mode,
        gpu gpu_rebuilt_frames_match_the_cpu,
        gpu gpu_rebuilt_frames_with_triangles_match_the_cpu,
        gpu rewritten_texture_frames_match_the_gpu_rebuild,
        gpu refitting_needs_storage_memory,
    ]
}
