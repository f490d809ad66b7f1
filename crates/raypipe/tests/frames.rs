//! Moving scenes: the BVH rebuilt every frame, on the GPU in the same submission as the frame, must
//! give the images of the CPU path (which rebuilds with the CPU builder).

mod common;
use common::*;
use raypipe::image::Frame;
use raypipe::render::{Accel, DeviceChoice, RenderOptions, render_frames};
use raypipe::scene::Scene;

fn frames(scene: &Scene, device: DeviceChoice, accel: Accel, count: u32) -> Vec<Frame> {
    let options = RenderOptions {
        device,
        accel,
        ..RenderOptions::default()
    };
    let mut out = Vec::new();
    let outcome = render_frames(scene, &options, count, |_, frame| {
        out.push(frame.clone());
        Ok(())
    })
    .unwrap();
    assert_eq!(outcome.render_ms.len(), count as usize);
    assert_eq!(outcome.builds.len(), if accel.uses_bvh() { count as usize } else { 0 });
    out
}

#[test]
fn gpu_rebuilt_frames_match_the_cpu() {
    let mut scene = Scene::load("bounce:1500:2").unwrap();
    scene.settings.width = 64;
    scene.settings.height = 48;
    let cpu = frames(&scene, DeviceChoice::Cpu, Accel::Stack, 4);
    assert_ne!(cpu[0], cpu[3], "the spheres move");
    let cpu_brute = frames(&scene, DeviceChoice::Cpu, Accel::Brute, 4);
    assert_frames_match("frames-cpu-stack-vs-brute", &cpu[3], &cpu_brute[3]);
    if gpu().is_none() {
        return;
    }
    let gpu = frames(&scene, DeviceChoice::Gpu, Accel::Stack, 4);
    for (k, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
        assert_frames_match(&format!("frames-gpu-vs-cpu-{k}"), g, c);
    }
}

#[test]
fn frame_names_follow_printf_patterns() {
    use raypipe::cli::numbered;
    assert_eq!(numbered("frame_%04d.png", 7).as_deref(), Some("frame_0007.png"));
    assert_eq!(numbered("f%d.exr", 12).as_deref(), Some("f12.exr"));
    assert_eq!(numbered("plain.png", 3), None);
    assert_eq!(numbered("odd%x.png", 3), None);
}

/// Spheres flying among standing triangles, rebuilt on the GPU every frame: the CPU's frames.
#[test]
fn gpu_rebuilt_frames_with_triangles_match_the_cpu() {
    let mut scene = models::mixed_scene(12, 6, 300);
    scene.settings.width = 48;
    scene.settings.height = 32;
    let velocities = (0..scene.spheres.len())
        .map(|i| glam::Vec3::new((i % 7) as f32 - 3.0, (i % 5) as f32 - 2.0, (i % 3) as f32 - 1.0))
        .collect();
    scene.motion = Some(raypipe::scene::Motion {
        velocities,
        lo: glam::Vec3::new(-2.0, -0.5, -1.0),
        hi: glam::Vec3::new(2.0, 1.0, 2.5),
        frame_time: 1.0 / 30.0,
    });
    if gpu().is_none() {
        return;
    }
    let on_gpu = frames(&scene, DeviceChoice::Gpu, Accel::Threaded, 3);
    let on_cpu = frames(&scene, DeviceChoice::Cpu, Accel::Threaded, 3);
    assert_ne!(on_cpu[0], on_cpu[2], "the spheres move");
    for (k, (g, c)) in on_gpu.iter().zip(&on_cpu).enumerate() {
        assert_frames_match(&format!("frames-triangles-{k}"), g, c);
    }
}
