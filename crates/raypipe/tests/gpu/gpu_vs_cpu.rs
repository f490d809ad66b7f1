//! The fragment shader against the CPU reference, on every built-in scene, at full depth, in every
//! acceleration mode; and every BVH mode against brute force on both devices.

use crate::common::harness::Test;
use crate::common::*;
use glam::Vec3;
use raypipe::cpu::Count;
use raypipe::gpu::{GpuContext, RendererOptions};
use raypipe::modes::{Accel, Builder, Integrator, MemoryMode};
use raypipe::records::{GpuCamera, PackedScene};
use raypipe::scene::{Camera, Environment, Scene};

fn check(ctx: &GpuContext, spec: &str, width: u32, height: u32) {
    let mut scene = packed(spec, width, height, 5);
    scene.build_bvh();
    check_scene(ctx, &spec.replace(':', "-"), &scene);
}

fn check_scene(ctx: &GpuContext, name: &str, scene: &PackedScene) {
    let cpu_brute = render_cpu(scene, Accel::Brute);
    for accel in Accel::BVH {
        let cpu = render_cpu(scene, accel);
        assert_frames_match(&format!("cpu-{accel:?}-vs-brute-{name}"), &cpu, &cpu_brute);
    }
    let gpu_brute = render_gpu(ctx, scene, MemoryMode::Storage, Accel::Brute);
    assert_frames_match(&format!("gpu-vs-cpu-{name}"), &gpu_brute, &cpu_brute);
    // The shader counts its rays; they agree but for the few pixels where devices diverge.
    let (g, c) = (gpu_brute.rays() as f64, cpu_brute.rays() as f64);
    assert!((g - c).abs() <= 0.01 * c, "{name}: GPU traced {g} rays, CPU {c}");
    for accel in Accel::BVH {
        let gpu = render_gpu(ctx, scene, MemoryMode::Storage, accel);
        assert_frames_match(&format!("gpu-{accel:?}-vs-brute-{name}"), &gpu, &gpu_brute);
        let cpu = render_cpu(scene, accel);
        assert_frames_match(&format!("gpu-vs-cpu-{accel:?}-{name}"), &gpu, &cpu);
    }
}

fn whitted(ctx: &GpuContext) {
    check(ctx, "whitted", 160, 120);
}

/// The path integrator draws the CPU's numbers: the paper's scene (mirrors, glass, Lambert) with
/// every walk against brute force and the CPU; random spheres in the studio environment, whose
/// light it samples, at four samples a pixel in every pipeline and memory mode.
fn path_traced_images_agree(ctx: &GpuContext) {
    let mut paper = packed("whitted", 96, 72, 5);
    paper.integrator = Integrator::Path;
    paper.build_bvh();
    check_scene(ctx, "path-whitted", &paper);
    let mut scene = Scene::load("random:200").unwrap();
    scene.settings.width = 64;
    scene.settings.height = 48;
    scene.settings.integrator = Integrator::Path;
    scene.set_environment(Some(Environment::studio()));
    let mut spheres = PackedScene::new(&scene).unwrap();
    spheres.build_bvh();
    let samples = 4;
    let cpu = raypipe::cpu::render_with(&spheres, Accel::Threaded, Count::Rays, samples, &|| {}).unwrap();
    each_pipeline_and_memory_mode_at(ctx, &spheres, samples, "path-random", |name, frame| {
        assert_frames_match(name, &frame, &cpu);
    });
}

/// Sixteen jittered samples per pixel: the shader's sequence is the CPU's, bit for bit, so the
/// averages agree as single samples do, in every memory mode that holds the scene; and the cost
/// view's mean per sample too.
fn sixteen_samples_agree(ctx: &GpuContext) {
    let mut scene = packed("random:300", 96, 72, 5);
    scene.build_bvh();
    for (memory, count) in [
        (MemoryMode::Storage, Count::Rays),
        (MemoryMode::Texture, Count::Rays),
        (MemoryMode::Storage, Count::Cost),
    ] {
        let options = RendererOptions {
            memory,
            accel: Accel::Threaded,
            count,
            ..Default::default()
        };
        let mut gpu = renderer(ctx, &scene, options);
        let frame = pollster::block_on(gpu.render_samples(16, |_| {}, |_| {}))
            .unwrap()
            .frame;
        assert_eq!(gpu.samples(), 16);
        let cpu = raypipe::cpu::render_with(&scene, Accel::Threaded, count, 16, &|| {}).unwrap();
        let name = format!("spp-16-{memory}-{count:?}");
        assert_frames_match(&name, &frame, &cpu);
        if count == Count::Cost {
            let total_cost = |f: &raypipe::image::Frame| f.color.iter().map(|c| c[3] as f64).sum::<f64>();
            let (g, c) = (total_cost(&frame), total_cost(&cpu));
            assert!(
                (g - c).abs() <= 1e-3 * c,
                "{name}: mean cost {g} on the GPU, {c} on the CPU"
            );
        } else {
            let (g, c) = (frame.rays() as f64, cpu.rays() as f64);
            assert!((g - c).abs() <= 0.01 * c, "{name}: GPU traced {g} rays, CPU {c}");
        }
    }
}

fn sphere_8k(ctx: &GpuContext) {
    check(ctx, "sphere-8k", 64, 48);
}

fn torus_5k(ctx: &GpuContext) {
    check(ctx, "torus-5k", 64, 48);
}

fn random_spheres(ctx: &GpuContext) {
    check(ctx, "random:1000:7", 64, 48);
}

fn odd_image_sizes_read_back_whole_rows(ctx: &GpuContext) {
    // 67 * 16 bytes is not a multiple of the 256-byte copy alignment: rows must be unpadded right.
    check(ctx, "whitted", 67, 33);
}

fn random_spheres_with_duplicates(ctx: &GpuContext) {
    // A tenth of the spheres twice, the copy in another material: ties resolve by index everywhere.
    let mut scene = raypipe::scene::builtin::random(1500, 4);
    for i in 0..150 {
        let mut copy = scene.spheres[i * 10];
        copy.material = 2 + (copy.material - 2 + 1) % 6;
        scene.spheres.push(copy);
    }
    scene.settings.width = 64;
    scene.settings.height = 48;
    let mut scene = PackedScene::new(&scene).unwrap();
    scene.build_bvh();
    check_scene(ctx, "random-duplicates", &scene);
}

fn coincident_spheres(ctx: &GpuContext) {
    let text = "[camera]\neye = [0, 0.5, -4]\ntarget = [0, 0, 0]\n[material.glass]\ntransmit = 0.9\nior = 1.5\n\
        [material.red]\ncolor = [0.9, 0.1, 0.1]\n[[light]]\nposition = [3, 5, -4]\n\
        [[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"glass\"\n\
        [[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"glass\"\n\
        [[sphere]]\ncenter = [0.5, 0, 0.5]\nradius = 0.5\nmaterial = \"red\"\n\
        [[sphere]]\ncenter = [0.5, 0, 0.5]\nradius = 0.5\nmaterial = \"red\"\n\
        [[plane]]\npoint = [0, -1, 0]\nnormal = [0, 1, 0]\n";
    let mut scene = raypipe::scene::file::parse(text).unwrap();
    scene.settings.width = 64;
    scene.settings.height = 48;
    let mut scene = PackedScene::new(&scene).unwrap();
    scene.build_bvh();
    check_scene(ctx, "coincident", &scene);
}

fn cost_aov_counts_the_same_tests_on_both_devices(ctx: &GpuContext) {
    let mut scene = packed("random:3000:9", 64, 48, 5);
    scene.build_bvh();
    let cost = |accel| raypipe::cpu::render_with(&scene, accel, Count::Cost, 1, &|| {}).unwrap();
    let brute = cost(Accel::Brute);
    assert!(
        brute.counts().iter().all(|&c| c == 3000),
        "brute force tests every sphere"
    );
    for accel in Accel::BVH {
        let cpu = cost(accel);
        let options = RendererOptions {
            memory: MemoryMode::Storage,
            accel,
            count: Count::Cost,
            ..Default::default()
        };
        let gpu = pollster::block_on(renderer(ctx, &scene, options).read_frame())
            .unwrap()
            .frame;
        let (g, c) = (gpu.counts(), cpu.counts());
        let differing = g.iter().zip(&c).filter(|(a, b)| a != b).count();
        // Devices may disagree on a grazing box test: a handful of pixels at most.
        assert!(
            differing * 100 <= g.len(),
            "{accel:?}: {differing} of {} pixel costs differ",
            g.len()
        );
        assert!(
            c.iter().any(|&x| x > 0) && c.iter().all(|&x| x < 3000),
            "{accel:?}: BVH costs are below brute force's"
        );
    }
}

/// Triangles (smooth glass, flat mirror) and spheres in one BVH.
fn spheres_and_triangles(ctx: &GpuContext) {
    let mut scene = crate::common::mixed_scene(24, 12, 1500);
    scene.settings.width = 96;
    scene.settings.height = 64;
    let mut scene = PackedScene::new(&scene).unwrap();
    assert_eq!((scene.triangles.len(), scene.spheres.len()), (1152, 1500));
    scene.build_bvh();
    check_scene(ctx, "spheres-and-triangles", &scene);
}

/// A tree built by binned SAH (`--builder sah`) instead of the LBVH: other nodes, another order
/// and depth, the same images. Triangles and spheres in one tree, every walk against brute force on
/// both devices; and the stack and threaded walks in texture memory (the page's) against the CPU.
fn sah_trees_trace_as_the_lbvh_does(ctx: &GpuContext) {
    let mut scene = crate::common::mixed_scene(24, 12, 1500);
    scene.settings.width = 96;
    scene.settings.height = 64;
    let mut scene = PackedScene::new(&scene).unwrap();
    scene.build_bvh_with(Builder::Sah);
    let mut lbvh = scene.clone();
    lbvh.build_bvh();
    let (sah_nodes, lbvh_nodes) = (&scene.bvh.as_ref().unwrap().nodes, &lbvh.bvh.as_ref().unwrap().nodes);
    assert_eq!(sah_nodes.len(), lbvh_nodes.len());
    assert_ne!(
        sah_nodes, lbvh_nodes,
        "the SAH tree must differ from the LBVH for this test to mean anything"
    );
    check_scene(ctx, "sah-spheres-and-triangles", &scene);
    for accel in [Accel::Stack, Accel::Threaded] {
        let gpu = render_gpu(ctx, &scene, MemoryMode::Texture, accel);
        let cpu = render_cpu(&scene, accel);
        assert_frames_match(&format!("gpu-texture-vs-cpu-{accel:?}-sah"), &gpu, &cpu);
    }
}

/// The fragment tracer runs only on the pixels the BVH's boxes project to
/// (`raypipe::gpu::trace::region`); a shader that traces nothing gives the others the background. A small
/// cluster (a mirror among them) off the frame's centre, four jittered samples so that the misses
/// accumulate too, every walk and both memory modes: the CPU's image and rays. Then the camera
/// moved by `set_camera`: turned away (no pixel traced), and inside the root box (its projection
/// folds there, so its children's are taken).
fn pixels_outside_the_projected_box_match_the_cpu(ctx: &GpuContext) {
    let text = "[camera]\neye = [0, 0.5, -6]\ntarget = [0, 0, 0]\n[material.mirror]\nreflect = 0.8\n\
        [material.red]\ncolor = [0.9, 0.1, 0.1]\n[[light]]\nposition = [3, 5, -4]\n\
        [[sphere]]\ncenter = [1.2, 0.6, 0]\nradius = 0.3\nmaterial = \"mirror\"\n\
        [[sphere]]\ncenter = [1.7, 0.4, 0.3]\nradius = 0.25\nmaterial = \"red\"\n\
        [[sphere]]\ncenter = [1.4, 1.0, -0.2]\nradius = 0.2\nmaterial = \"red\"\n";
    let mut scene = raypipe::scene::file::parse(text).unwrap();
    scene.settings.width = 64;
    scene.settings.height = 48;
    let mut scene = PackedScene::new(&scene).unwrap();
    scene.build_bvh();
    let pixels = 64 * 48;
    let with_camera = |eye: Vec3, target: Vec3| {
        let camera = Camera {
            eye,
            target,
            up: Vec3::Y,
            fov_degrees: 40.0,
        };
        let mut moved = scene.clone();
        moved.globals.camera = GpuCamera::new(&camera, 64, 48);
        (camera, moved)
    };
    let turned_away = with_camera(Vec3::new(0.0, 0.5, -6.0), Vec3::new(0.0, 0.5, -7.0));
    let inside = with_camera(Vec3::new(1.45, 0.7, 0.0), Vec3::new(1.45, 0.7, 1.0));
    for memory in [MemoryMode::Storage, MemoryMode::Texture] {
        for accel in Accel::BVH {
            let name = format!("outside-the-box-{memory}-{accel:?}");
            let options = RendererOptions {
                memory,
                accel,
                ..Default::default()
            };
            let mut gpu = renderer(ctx, &scene, options);
            let traced = gpu.traced_region().pixel_count();
            assert!(traced > 0 && traced * 4 < pixels, "{name}: traced {traced} pixels");
            let frame = pollster::block_on(gpu.render_samples(4, |_| {}, |_| {})).unwrap().frame;
            let cpu = raypipe::cpu::render_with(&scene, accel, Count::Rays, 4, &|| {}).unwrap();
            assert_frames_match(&name, &frame, &cpu);
            assert_eq!(frame.rays(), cpu.rays(), "{name}: rays");
            for (view, (camera, moved), any_traced) in [("turned-away", &turned_away, false), ("inside", &inside, true)]
            {
                gpu.set_camera(camera);
                let traced = gpu.traced_region().pixel_count();
                assert_eq!(traced > 0, any_traced, "{name}-{view}: traced {traced} pixels");
                let frame = pollster::block_on(gpu.render_samples(2, |_| {}, |_| {})).unwrap().frame;
                let cpu = raypipe::cpu::render_with(moved, accel, Count::Rays, 2, &|| {}).unwrap();
                assert_frames_match(&format!("{name}-{view}"), &frame, &cpu);
                assert_eq!(frame.rays(), cpu.rays(), "{name}-{view}: rays");
            }
        }
    }
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu whitted,
        gpu path_traced_images_agree,
        gpu sixteen_samples_agree,
        gpu sphere_8k,
        gpu torus_5k,
        gpu random_spheres,
        gpu odd_image_sizes_read_back_whole_rows,
        gpu random_spheres_with_duplicates,
        gpu coincident_spheres,
        gpu cost_aov_counts_the_same_tests_on_both_devices,
        gpu spheres_and_triangles,
        gpu sah_trees_trace_as_the_lbvh_does,
        gpu pixels_outside_the_projected_box_match_the_cpu,
    ]
}
