//! glTF scenes on the GPU and the CPU: a file's camera gives the pinhole's depth at every pixel, a
//! checker texture shows its texels where the UVs say under every wrap mode, in every memory mode
//! and pipeline, and the same file packed three ways renders the same image.

use crate::common::gltf_file::{
    CHECKER, CLAMP_TO_EDGE, GltfBuilder, MIRRORED_REPEAT, Packing, REPEAT, attribute_quad, framed_textured_quad, quad,
};
use crate::common::harness::Test;
use crate::common::*;
use raypipe::gpu::{GpuContext, RendererOptions};
use raypipe::image::Frame;
use raypipe::image::diff::Tolerance;
use raypipe::modes::{Accel, Integrator, MemoryMode, Pipeline};
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use raypipe::scene::gltf::{Files, parse};
use raypipe::scene::model::{ModelOptions, gltf_scene};

/// 36 pixels a side: with the UVs doubled, every ninth pixel from the fifth looks at a texel's
/// centre, where bilinear filtering gives the texel itself.
const SIZE: u32 = 36;

/// The scene of a builder's file at SIZE x SIZE, lit by the Whitted integrator's ambient light
/// alone at full strength and with no bounces, so that a pixel's colour is its (dielectric)
/// surface's albedo.
fn albedo_scene(builder: &GltfBuilder) -> PackedScene {
    let file = parse(&builder.gltf(), Files::None, &mut Vec::new()).unwrap();
    let mut scene = gltf_scene(&file, "test.gltf", &ModelOptions::default()).unwrap();
    scene.settings.integrator = Integrator::Whitted;
    scene.settings.width = SIZE;
    scene.settings.height = SIZE;
    scene.settings.ambient = 1.0;
    scene.settings.max_depth = 0;
    scene.lights.clear();
    scene.set_environment(None);
    let mut packed = PackedScene::new(&scene).unwrap();
    packed.build_bvh();
    packed
}

/// The texel each texel-centre pixel must show along one axis, by wrap mode: the UVs run over
/// [0, 2], so the second half repeats, clamps to the last texel, or mirrors.
fn texel_along(wrap: u32, n: usize) -> usize {
    match wrap {
        REPEAT => n % 2,
        CLAMP_TO_EDGE => n.min(1),
        MIRRORED_REPEAT => [0, 1, 1, 0][n],
        _ => unreachable!(),
    }
}

fn check_texels(frame: &Frame, wrap: [u32; 2], device: &str) {
    for nv in 0..4 {
        for nu in 0..4 {
            let (px, py) = (9 * nu + 4, 9 * nv + 4);
            let texel = texel_along(wrap[1], nv) * 2 + texel_along(wrap[0], nu);
            let expected = CHECKER[texel].map(|c| c as f32 / 255.0);
            let got = frame.color[(py * SIZE as usize) + px];
            for c in 0..3 {
                assert!(
                    (got[c] - expected[c]).abs() < 1e-3,
                    "{device}, wrap {wrap:?}: pixel ({px}, {py}) is {got:?}, texel {texel} is {expected:?}"
                );
            }
        }
    }
}

fn cpu_checker_texels_land_where_the_uvs_say() {
    for wrap in [
        [REPEAT, CLAMP_TO_EDGE],
        [MIRRORED_REPEAT, REPEAT],
        [CLAMP_TO_EDGE, MIRRORED_REPEAT],
    ] {
        let scene = albedo_scene(&framed_textured_quad(2.0, wrap));
        check_texels(&render_cpu(&scene, Accel::Threaded), wrap, "cpu");
    }
}

/// Every memory mode and pipeline against the CPU, texel by texel and image by image; the memory
/// modes and pipelines against each other bit for bit.
fn gpu_checker_texels_in_every_memory_mode_and_pipeline(ctx: &GpuContext) {
    for wrap in [[REPEAT, CLAMP_TO_EDGE], [MIRRORED_REPEAT, REPEAT]] {
        let scene = albedo_scene(&framed_textured_quad(2.0, wrap));
        let cpu = render_cpu(&scene, Accel::Threaded);
        let mut first: Option<Frame> = None;
        let prefix = format!("gltf-texture-{}-{}", wrap[0], wrap[1]);
        each_pipeline_and_memory_mode(ctx, &scene, &prefix, |name, frame| {
            check_texels(&frame, wrap, name);
            assert_frames_match(name, &frame, &cpu);
            match &first {
                None => first = Some(frame),
                Some(first) => assert_images_match(name, &frame.display(), &first.display(), Tolerance::EXACT),
            }
        });
    }
}

/// A file's camera is a pinhole: the quad it fills is at the depth the pinhole model gives at every
/// pixel, on both devices.
fn the_file_camera_gives_the_pinhole_depth(ctx: &GpuContext) {
    let scene = albedo_scene(&framed_textured_quad(1.0, [REPEAT, REPEAT]));
    let tan = 0.5f64;
    let cpu = render_cpu(&scene, Accel::Threaded);
    let gpu = render_gpu(ctx, &scene, MemoryMode::Storage, Accel::Threaded);
    for (device, frame) in [("cpu", &cpu), ("gpu", &gpu)] {
        let depth = frame.depth();
        for py in 0..SIZE {
            for px in 0..SIZE {
                let x = (2.0 * (px as f64 + 0.5) / SIZE as f64 - 1.0) * tan;
                let y = (1.0 - 2.0 * (py as f64 + 0.5) / SIZE as f64) * tan;
                let expected = (x * x + y * y + 1.0).sqrt();
                let got = depth.data[(py * SIZE + px) as usize] as f64;
                assert!(
                    (got - expected).abs() <= 2e-6 * expected,
                    "{device}: pixel ({px}, {py}) depth {got}, expected {expected}"
                );
            }
        }
    }
}

/// One file as a .gltf with data: URIs, a .gltf beside its .bin and PNG, and a .glb: one image.
fn every_packing_renders_the_same_image(ctx: &GpuContext) {
    let dir = test_dir("gltf-gpu-packings");
    let builder = framed_textured_quad(3.0, [REPEAT, MIRRORED_REPEAT]);
    let frames: Vec<Frame> = [Packing::DataUris, Packing::ExternalFiles, Packing::Glb]
        .into_iter()
        .map(|packing| {
            let path = builder.write(&dir, &format!("{packing:?}"), packing);
            let mut scene = Scene::load(path.to_str().unwrap()).unwrap();
            scene.settings.width = 48;
            scene.settings.height = 40;
            let mut packed = PackedScene::new(&scene).unwrap();
            packed.build_bvh();
            render_gpu(ctx, &packed, MemoryMode::Storage, Accel::Threaded)
        })
        .collect();
    for (packing, frame) in ["external files", "glb"].iter().zip(&frames[1..]) {
        assert_images_match(packing, &frame.display(), &frames[0].display(), Tolerance::EXACT);
    }
}

/// glTF's materials trace on the GPU as on the CPU: glass (thin-walled transmission), a mirror, a
/// rough metal (its reflections drawn from the GGX lobe), a dielectric, under a point, a spot and
/// a directional light; and the glass shows what lies behind it, the mirror what lies before it.
fn gltf_materials_match_the_cpu(ctx: &GpuContext) {
    use serde_json::json;
    let mut b = GltfBuilder::default();
    let glass = b.material(json!({
        "doubleSided": true,
        "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0 },
        "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 }, "KHR_materials_ior": { "ior": 1.5 } }
    }));
    let mirror = b.material(json!({
        "doubleSided": true,
        "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1, "roughnessFactor": 0 }
    }));
    let gold = b.material(json!({
        "doubleSided": true,
        "pbrMetallicRoughness": { "baseColorFactor": [1, 0.78, 0.34, 1], "metallicFactor": 1, "roughnessFactor": 0.4 }
    }));
    let red = b.material(json!({
        "doubleSided": true,
        "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.1, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 0.6 }
    }));
    // Tinted glass that bounds a volume: rays refract in and out, and are absorbed inside.
    let tinted = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0.05 },
        "extensions": {
            "KHR_materials_transmission": { "transmissionFactor": 1 },
            "KHR_materials_volume": { "thicknessFactor": 1, "attenuationDistance": 0.5, "attenuationColor": [0.2, 0.8, 0.5] }
        }
    }));
    b.extensions_used = vec![
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_volume",
        "KHR_lights_punctual",
    ];
    let cube = closed_cube(&mut b, tinted, [0.2, -0.9, -1.6], 0.8);
    let quad = |b: &mut GltfBuilder, material, x0: f32, z: f32| {
        let positions = [[x0, -1.0, z], [x0 + 1.5, -1.0, z], [x0 + 1.5, 1.0, z], [x0, 1.0, z]];
        b.mesh(&positions, None, &[0, 1, 2, 0, 2, 3], Some(material))
    };
    let meshes = [
        cube,
        quad(&mut b, glass, -1.6, 0.0),
        quad(&mut b, mirror, 0.1, 0.5),
        quad(&mut b, gold, 1.8, 0.2),
        quad(&mut b, red, -3.0, 3.0),
    ];
    for mesh in meshes {
        let node = b.node(json!({ "mesh": mesh }));
        b.roots.push(node);
    }
    b.cameras = vec![json!({ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.01 } })];
    let camera = b.node(json!({ "camera": 0, "translation": [0, 0.3, -5], "rotation": [0, 1, 0, 0] }));
    b.lights = vec![
        json!({ "type": "point", "intensity": 30 }),
        json!({ "type": "spot", "intensity": 40, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } }),
        json!({ "type": "directional", "intensity": 2 }),
    ];
    let point = b.node(json!({ "translation": [2, 4, -4], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    // At -z, looking along +z (its node turned half about y) at the quads.
    let spot = b.node(json!({
        "translation": [0, 0, -4], "rotation": [0, 1, 0, 0], "extensions": { "KHR_lights_punctual": { "light": 1 } }
    }));
    let sun = b.node(json!({
        "rotation": [0.2, 0.9, 0, 0.4], "extensions": { "KHR_lights_punctual": { "light": 2 } }
    }));
    b.roots.extend([camera, point, spot, sun]);
    let file = parse(&b.gltf(), Files::None, &mut Vec::new()).unwrap();
    let mut scene = gltf_scene(&file, "materials.gltf", &ModelOptions::default()).unwrap();
    scene.settings.width = 64;
    scene.settings.height = 48;
    assert_eq!(scene.lights.len(), 3);
    gpu_matches_cpu(ctx, &scene, "gltf-materials");
    let mut packed = PackedScene::new(&scene).unwrap();
    packed.build_bvh();
    let frame = render_cpu(&packed, Accel::Threaded);
    // The quads (double-sided: the camera sees their backs) and the cube show in an eighth of the
    // view and more (the mirror shows much of the background): the glass shows the red quad
    // behind it, and the mirror the scene before it.
    let background = scene.settings.background;
    let hit = frame
        .color
        .iter()
        .filter(|c| (glam::Vec3::new(c[0], c[1], c[2]) - background).abs().max_element() > 0.01)
        .count();
    assert!(hit > frame.color.len() / 8, "only {hit} pixels show something");
}

/// A cube of side `size` with its lowest corner at `corner`, its triangles wound to face out.
fn closed_cube(b: &mut GltfBuilder, material: usize, corner: [f32; 3], size: f32) -> usize {
    let positions: Vec<[f32; 3]> = (0..8)
        .map(|i| [0, 1, 2].map(|axis| corner[axis] + size * ((i >> axis) & 1) as f32))
        .collect();
    let centre = glam::Vec3::from(corner) + glam::Vec3::splat(size / 2.0);
    let mut indices = Vec::new();
    // Each face: the corners with one axis fixed, in a loop around it.
    for axis in 0..3 {
        for side in [0, 1] {
            let (a, b2) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner_at = |i: u16, j: u16| (side << axis) | (i << a) | (j << b2);
            let quad = [corner_at(0, 0), corner_at(1, 0), corner_at(1, 1), corner_at(0, 1)];
            let p = |k: u16| glam::Vec3::from(positions[k as usize]);
            let normal = (p(quad[1]) - p(quad[0])).cross(p(quad[2]) - p(quad[0]));
            let outward = normal.dot(p(quad[0]) - centre) > 0.0;
            let order = if outward {
                [0, 1, 2, 0, 2, 3]
            } else {
                [0, 2, 1, 0, 3, 2]
            };
            indices.extend(order.map(|k| quad[k]));
        }
    }
    b.mesh(&positions, None, &indices, Some(material))
}

/// `scene`, its BVH built on the CPU, traced by the threaded walk on the GPU in storage and in
/// texture memory, each frame matching the CPU's (images named `name-MEMORY`); returns how many of
/// the CPU frame's pixels hit something.
fn gpu_matches_cpu(ctx: &GpuContext, scene: &Scene, name: &str) -> usize {
    gpu_matches_cpu_in(ctx, scene, name, &[MemoryMode::Storage, MemoryMode::Texture])
}

/// `gpu_matches_cpu` in the `memory` modes given.
fn gpu_matches_cpu_in(ctx: &GpuContext, scene: &Scene, name: &str, memory_modes: &[MemoryMode]) -> usize {
    let mut packed = PackedScene::new(scene).unwrap();
    packed.build_bvh();
    let cpu = render_cpu(&packed, Accel::Threaded);
    for &memory in memory_modes {
        let gpu = render_gpu(ctx, &packed, memory, Accel::Threaded);
        assert!(
            gpu.color.iter().flatten().all(|c| c.is_finite()),
            "{name}-{memory:?}: a pixel that is not finite"
        );
        assert_frames_match(&format!("{name}-{memory:?}"), &gpu, &cpu);
    }
    cpu.depth().data.iter().filter(|d| d.is_finite()).count()
}

/// The shared glTF samples (a texture, node animation, skins), posed 40 % into their animation,
/// on the GPU in storage and texture memory against the CPU.
fn gltf_samples_match_the_cpu(ctx: &GpuContext, models: &std::path::Path) {
    for name in [
        "BoxTextured",
        "BoxAnimated",
        "RiggedSimple",
        "SimpleSkin",
        "AnimatedTriangle",
    ] {
        let path = models.join("gltf").join(format!("{name}.gltf"));
        let loaded = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
        let time = loaded.motion.as_ref().and_then(|m| m.duration()).unwrap_or(0.0) * 0.4;
        let mut scene = loaded.at_time(time).unwrap();
        scene.settings.width = 64;
        scene.settings.height = 48;
        let hits = gpu_matches_cpu(ctx, &scene, &format!("gltf-sample-{name}"));
        assert!(
            hits > 64 * 48 / 10,
            "{name}: the model is out of view ({hits} pixels hit)"
        );
    }
}

/// Khronos samples that rest on their lowest plane stand apart from the floor a framed model gets,
/// so GPU and CPU agree on which surface each pixel sees (TwoSidedPlane's 99th-percentile error
/// was 119 of 255 when the floor touched it); SimpleInstancing places all 125 of its cubes.
fn khronos_models_on_the_floor_match_the_cpu(ctx: &GpuContext, models: &std::path::Path) {
    for (file, triangles) in [
        ("TwoSidedPlane/TwoSidedPlane.gltf", None),
        ("MorphPrimitivesTest/MorphPrimitivesTest.glb", None),
        ("SimpleInstancing/SimpleInstancing.glb", Some(125 * 12)),
    ] {
        let path = models.join("khronos").join(file);
        let mut scene = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
        if let Some(triangles) = triangles {
            assert_eq!(scene.triangles.len(), triangles, "{file}");
        }
        let lowest = scene
            .triangles
            .iter()
            .flat_map(|t| t.vertices)
            .map(|v| v.y)
            .fold(f32::INFINITY, f32::min);
        let floor = scene
            .planes
            .last()
            .unwrap_or_else(|| panic!("{file}: framed on a floor"));
        assert!(
            floor.point.y < lowest,
            "{file}: the floor at {} touches {lowest}",
            floor.point.y
        );
        scene.settings.width = 96;
        scene.settings.height = 72;
        gpu_matches_cpu(ctx, &scene, &format!("khronos-{file}").replace('/', "-"));
    }
}

/// A glTF scene of alpha and sides: a masked quad whose texture has holes, a blended quad, a
/// single-sided quad turned away from the camera, over a glossy floor (whose reflected rays cull back
/// faces too), lit by a point and a directional light. What its materials read back, and its image
/// in every memory mode, walk and pipeline against the CPU's; the CPU's own answers are worked out
/// in tests/cpu/alpha.rs.
fn alpha_and_sides_match_the_cpu(ctx: &GpuContext) {
    use serde_json::json;
    let mut b = GltfBuilder::default();
    // The checker with its green and blue texels transparent.
    let mut texels = CHECKER;
    texels[1][3] = 0;
    texels[2][3] = 0;
    let texture = b.texture(texels.as_flattened(), 2, 2, [REPEAT; 2]);
    let masked = b.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": texture }, "metallicFactor": 0 },
        "alphaMode": "MASK", "alphaCutoff": 0.4
    }));
    let blended = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.2, 0.1, 0.35], "metallicFactor": 0 },
        "alphaMode": "BLEND", "doubleSided": true
    }));
    let one_sided = b.material(json!({ "pbrMetallicRoughness": { "metallicFactor": 0 } }));
    let floor = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0.5, "roughnessFactor": 0.15 },
        "doubleSided": true
    }));
    let (positions, uvs, indices) = quad(3.0);
    let quad_mesh = |b: &mut GltfBuilder, material, flip: bool| {
        let indices = if flip { [0, 2, 1, 0, 3, 2] } else { indices };
        b.mesh(&positions, Some(&uvs), &indices, Some(material))
    };
    let meshes = [
        (quad_mesh(&mut b, masked, false), [-1.7, 0.3, 0.0]),
        (quad_mesh(&mut b, blended, false), [-0.5, 0.2, 0.6]),
        (quad_mesh(&mut b, one_sided, true), [0.7, 0.3, 0.2]),
    ];
    for (mesh, translation) in meshes {
        let node = b.node(json!({ "mesh": mesh, "translation": translation }));
        b.roots.push(node);
    }
    // The floor: the unit quad turned to face +y, stretched under the others.
    let floor_mesh = b.mesh(&positions, Some(&uvs), &indices, Some(floor));
    // A quarter turn about -x: (sin 45°, cos 45°).
    let sin_45 = std::f32::consts::FRAC_1_SQRT_2;
    let floor_node = b.node(json!({
        "mesh": floor_mesh, "translation": [-4, -0.2, 4], "scale": [8, 8, 1],
        "rotation": [-sin_45, 0, 0, sin_45]
    }));
    b.roots.push(floor_node);
    b.cameras = vec![json!({ "type": "perspective", "perspective": { "yfov": 0.9, "znear": 0.01 } })];
    // At (0.2, 1.6, 4), looking down 20 degrees toward -z.
    let camera =
        b.node(json!({ "camera": 0, "translation": [0.2, 1.6, 4], "rotation": [-0.17364818, 0, 0, 0.98480775] }));
    b.lights = vec![
        json!({ "type": "point", "intensity": 25 }),
        json!({ "type": "directional", "intensity": 1.5 }),
    ];
    let point = b.node(json!({ "translation": [1, 3, 2], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    let sun = b.node(json!({
        "rotation": [-0.5, 0.3, 0.1, 0.8], "extensions": { "KHR_lights_punctual": { "light": 1 } }
    }));
    b.roots.extend([camera, point, sun]);
    b.extensions_used = vec!["KHR_lights_punctual"];
    let file = parse(&b.gltf(), Files::None, &mut Vec::new()).unwrap();
    let mut scene = gltf_scene(&file, "alpha.gltf", &ModelOptions::default()).unwrap();
    use raypipe::scene::AlphaMode;
    let modes: Vec<_> = scene.materials.iter().map(|m| (m.alpha_mode, m.double_sided)).collect();
    // The file's four, after those of the placement.
    assert_eq!(
        modes[modes.len() - 4..],
        [
            (AlphaMode::Mask { cutoff: 0.4 }, false),
            (AlphaMode::Blend, true),
            (AlphaMode::Opaque, false),
            (AlphaMode::Opaque, true),
        ]
    );
    assert_eq!(scene.materials[modes.len() - 3].alpha, 0.35);
    scene.settings.width = 64;
    scene.settings.height = 48;
    scene.settings.max_depth = 3;
    let mut packed = PackedScene::new(&scene).unwrap();
    packed.build_bvh();
    let cpu = render_cpu(&packed, Accel::Brute);
    for accel in ctx.accels() {
        let walked = render_cpu(&packed, accel);
        assert_frames_match(&format!("alpha-cpu-{accel:?}"), &walked, &cpu);
        for memory in ctx.memory_modes() {
            let gpu = render_gpu(ctx, &packed, memory, accel);
            assert_frames_match(&format!("alpha-{accel:?}-{memory:?}"), &gpu, &cpu);
        }
    }
    let options = RendererOptions {
        pipeline: Pipeline::Compute,
        ..Default::default()
    };
    let compute = pollster::block_on(renderer(ctx, &packed, options).read_frame()).unwrap();
    assert_frames_match("alpha-compute", &compute.frame, &cpu);
}

/// A quad with vertex colours, a base colour map on its second coordinate set and a normal map
/// on MikkTSpace's tangents, lit by a point light: GPU against CPU (the CPU's answers for each
/// are worked out in tests/cpu/materials.rs).
fn vertex_attributes_match_the_cpu(ctx: &GpuContext) {
    let file = parse(&attribute_quad().gltf(), Files::None, &mut Vec::new()).unwrap();
    let mut scene = gltf_scene(&file, "attributes.gltf", &ModelOptions::default()).unwrap();
    scene.settings.width = 48;
    scene.settings.height = 48;
    let hits = gpu_matches_cpu(ctx, &scene, "vertex-attributes");
    assert!(hits > 48 * 48 / 2, "the quad fills the view ({hits} pixels hit)");
}

/// The Khronos samples that require an extension raypipe does not read, with it.
const REFUSED_KHRONOS: [(&str, &str); 2] = [
    ("ClearCoatCarPaint", "KHR_materials_clearcoat"),
    ("IridescenceSuzanne", "KHR_materials_iridescence"),
];

/// The Khronos samples whose shared copy lacks files they name (the folder of EnvironmentTest's
/// images is a placeholder there): refused, naming the file.
const INCOMPLETE_KHRONOS: [(&str, &str); 1] = [("EnvironmentTest", "EnvironmentTest_images/roughness_metallic_0.jpg")];

/// Every Khronos sample in `../shared/models/khronos/` (its .glb, else its .gltf) renders on the
/// GPU as on the CPU, in storage or texture memory (half the samples in each, the halves swapped
/// between Vulkan and GL), with something of it in view; the two that
/// require an extension raypipe does not read are refused with the line naming it.
fn every_khronos_sample_matches_the_cpu(ctx: &GpuContext, models: &std::path::Path) {
    let mut folders: Vec<_> = std::fs::read_dir(models.join("khronos"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.is_dir())
        .collect();
    folders.sort();
    assert_eq!(folders.len(), 70, "the shared Khronos samples");
    let backend_parity = (ctx.info.backend == wgpu::Backend::Gl) as usize;
    for (index, folder) in folders.into_iter().enumerate() {
        let name = folder.file_name().unwrap().to_str().unwrap().to_string();
        let file = ["glb", "gltf"]
            .iter()
            .map(|ext| folder.join(format!("{name}.{ext}")))
            .find(|path| path.is_file())
            .unwrap_or_else(|| panic!("{name}: no {name}.glb or {name}.gltf"));
        let loaded = Scene::load(file.to_str().unwrap());
        if let Some((_, missing)) = INCOMPLETE_KHRONOS.iter().find(|(model, _)| *model == name) {
            let error = loaded.expect_err(&name).to_string();
            assert!(
                error.contains(&format!("cannot read '{missing}': no such file")),
                "{name}: {error}"
            );
            continue;
        }
        let refused = REFUSED_KHRONOS.iter().find(|(model, _)| *model == name);
        let mut scene = match (loaded, refused) {
            (Ok(scene), None) => scene,
            (Err(error), Some((_, extension))) => {
                let error = error.to_string();
                assert!(
                    error.contains(&format!("extension {extension} is required")),
                    "{name}: {error}"
                );
                continue;
            }
            (Ok(_), Some((_, extension))) => panic!("{name} loads: it requires {extension}"),
            (Err(error), None) => panic!("{name}: {error}"),
        };
        scene.settings.width = 48;
        scene.settings.height = 36;
        // One memory mode and one integrator a model, alternating, and the others on the other
        // backend: CI's Vulkan and GL runs together trace every sample in both memory modes and
        // both integrators (each model's shader is a variant of its own, and compiling two a
        // model on a software adapter took most of the GPU tests' time).
        let memory = [MemoryMode::Storage, MemoryMode::Texture][(index + backend_parity) % 2];
        scene.settings.integrator = [Integrator::Path, Integrator::Whitted][(index / 2 + backend_parity) % 2];
        let hits = gpu_matches_cpu_in(ctx, &scene, &format!("khronos-{name}"), &[memory]);
        assert!(hits > 0, "{name}: nothing in view");
    }
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        plain cpu_checker_texels_land_where_the_uvs_say,
        gpu gpu_checker_texels_in_every_memory_mode_and_pipeline,
        gpu the_file_camera_gives_the_pinhole_depth,
        gpu every_packing_renders_the_same_image,
        gpu gltf_materials_match_the_cpu,
        gpu alpha_and_sides_match_the_cpu,
        gpu vertex_attributes_match_the_cpu,
        gpu_models gltf_samples_match_the_cpu,
        gpu_models khronos_models_on_the_floor_match_the_cpu,
        gpu_models every_khronos_sample_matches_the_cpu,
    ]
}
