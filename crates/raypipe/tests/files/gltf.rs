//! glTF files built here with known answers: node transforms against positions placed by hand,
//! instances, cameras, lights, materials and textures, the three ways to pack a file, and the
//! files the tests write through the Khronos validator. Hostile files: `gltf_hostile.rs`.

use crate::common::gltf_file::{GltfBuilder, Packing, textured_quad};
use crate::common::harness::Test;
use crate::common::test_dir;
use glam::Vec3;
use raypipe::scene::Scene;
use raypipe::scene::gltf::{Files, GltfScene, parse};
use raypipe::scene::{Light, LightKind, TextureMap};
use serde_json::{Value, json};

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

fn read(builder: &GltfBuilder) -> GltfScene {
    parse(&builder.gltf(), Files::None, &mut Vec::new()).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

fn assert_positions(actual: &[Vec3], expected: &[[f32; 3]]) {
    assert_eq!(actual.len(), expected.len());
    for (a, &e) in actual.iter().zip(expected) {
        assert!(close(*a, Vec3::from(e)), "{actual:?} against {expected:?}");
    }
}

/// A root translated by (1, 2, 3) whose child is translated by (0, 0, -1), turned 90 degrees about
/// z and scaled by 2, holding one triangle.
pub fn hierarchy(child: Value) -> GltfBuilder {
    let mut b = GltfBuilder::default();
    let mesh = b.mesh(&TRIANGLE, None, &[0, 1, 2], None);
    let mut child = child;
    child["mesh"] = json!(mesh);
    let child = b.node(child);
    let root = b.node(json!({ "translation": [1, 2, 3], "children": [child] }));
    b.roots = vec![root];
    b
}

fn node_hierarchy_places_triangles_as_by_hand() {
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let file = read(&hierarchy(json!({
        "translation": [0, 0, -1], "rotation": [0, 0, half, half], "scale": [2, 2, 2]
    })));
    // (x, y, z) scaled by 2, turned to (-y, x, z), moved by (0, 0, -1) and then (1, 2, 3).
    assert_eq!(file.primitives.len(), 1);
    assert_positions(
        &file.primitives[0].positions,
        &[[1.0, 2.0, 2.0], [1.0, 4.0, 2.0], [-1.0, 2.0, 2.0]],
    );
    assert_eq!(file.primitives[0].triangles, vec![[0, 1, 2]]);
}

fn a_matrix_node_equals_its_trs_twin() {
    // Column-major: the same turn, scale and translation as the test above.
    let file = read(&hierarchy(json!({
        "matrix": [0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 2, 0, 0, 0, -1, 1]
    })));
    assert_positions(
        &file.primitives[0].positions,
        &[[1.0, 2.0, 2.0], [1.0, 4.0, 2.0], [-1.0, 2.0, 2.0]],
    );
}

fn a_mirroring_node_turns_the_winding() {
    let file = read(&hierarchy(json!({ "scale": [-1, 1, 1] })));
    assert_eq!(file.primitives[0].triangles, vec![[0, 2, 1]]);
}

fn an_instanced_mesh_appears_at_every_node() {
    let mut b = GltfBuilder::default();
    let mesh = b.mesh(&TRIANGLE, None, &[0, 1, 2], None);
    let left = b.node(json!({ "mesh": mesh, "translation": [-5, 0, 0] }));
    let right = b.node(json!({ "mesh": mesh, "translation": [5, 0, 0] }));
    b.roots = vec![left, right];
    let file = read(&b);
    assert_eq!(file.primitives.len(), 2);
    assert_positions(
        &file.primitives[0].positions,
        &[[-5.0, 0.0, 0.0], [-4.0, 0.0, 0.0], [-5.0, 1.0, 0.0]],
    );
    assert_positions(
        &file.primitives[1].positions,
        &[[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]],
    );
}

/// A triangle mesh under a node that EXT_mesh_gpu_instancing places `translations.len()` times, the
/// second instance turned a quarter about z and the third scaled by 2.
fn instanced(node: Value) -> GltfBuilder {
    let mut b = GltfBuilder::default();
    let mesh = b.mesh(&TRIANGLE, None, &[0, 1, 2], None);
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let translation = b.floats(&[0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 0.0, 10.0, 0.0], 3);
    let rotation = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, half, half, 0.0, 0.0, 0.0, 1.0], 4);
    let scale = b.floats(&[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0], 3);
    let mut node = node;
    node["mesh"] = json!(mesh);
    node["extensions"] = json!({ "EXT_mesh_gpu_instancing": { "attributes": {
        "TRANSLATION": translation, "ROTATION": rotation, "SCALE": scale
    } } });
    let root = b.node(node);
    b.roots = vec![root];
    b.extensions_used.push("EXT_mesh_gpu_instancing");
    b
}

/// Every EXT_mesh_gpu_instancing instance is placed: T * R * S of its own, under the node's
/// transform, as the extension defines it.
fn gpu_instancing_places_every_instance_under_its_node() {
    let file = read(&instanced(json!({ "translation": [0, 0, -1] })));
    assert_eq!(file.primitives.len(), 3);
    // Instance 0 where it stands; 1 moved by x 10 and turned (x, y) to (-y, x); 2 moved by y 10 and
    // doubled; all moved by the node's z -1.
    let expected = [
        [[0.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 1.0, -1.0]],
        [[10.0, 0.0, -1.0], [10.0, 1.0, -1.0], [9.0, 0.0, -1.0]],
        [[0.0, 10.0, -1.0], [2.0, 10.0, -1.0], [0.0, 12.0, -1.0]],
    ];
    for (primitive, expected) in file.primitives.iter().zip(&expected) {
        assert_positions(&primitive.positions, expected);
    }
    let notices = {
        let mut notices = Vec::new();
        parse(&instanced(json!({})).gltf(), Files::None, &mut notices).unwrap();
        notices
    };
    assert!(
        !notices.iter().any(|n| n.contains("EXT_mesh_gpu_instancing")),
        "{notices:?}"
    );
}

/// Instancing accessors of the wrong type, component type or count end in one line naming the node.
fn bad_instancing_accessors_are_refused() {
    let error = |b: &GltfBuilder| parse(&b.gltf(), Files::None, &mut Vec::new()).unwrap_err().to_string();
    let mut b = instanced(json!({}));
    let two = b.floats(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], 3);
    b.nodes[0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["SCALE"] = json!(two);
    assert_eq!(
        error(&b),
        "node 0: EXT_mesh_gpu_instancing: TRANSLATION has 3 instances and SCALE 2"
    );
    let mut b = instanced(json!({}));
    let vec2 = b.floats(&[0.0; 6], 2);
    b.nodes[0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = json!(vec2);
    assert!(
        error(&b).starts_with("node 0: EXT_mesh_gpu_instancing: TRANSLATION: accessor"),
        "{}",
        error(&b)
    );
    let mut b = instanced(json!({}));
    let bytes = b.floats(&[0.0; 9], 3);
    b.accessors[bytes]["componentType"] = json!(5121);
    b.nodes[0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = json!(bytes);
    assert_eq!(
        error(&b),
        format!("node 0: EXT_mesh_gpu_instancing: TRANSLATION: accessor {bytes} must be float")
    );
    let mut b = instanced(json!({}));
    b.nodes[0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = json!({});
    assert_eq!(
        error(&b),
        "node 0: EXT_mesh_gpu_instancing: none of TRANSLATION, ROTATION and SCALE"
    );
}

fn strips_fans_and_points_by_mode() {
    let mut b = GltfBuilder::default();
    b.mesh(
        &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
        None,
        &[0, 1, 2, 3],
        None,
    );
    b.meshes[0]["primitives"][0]["mode"] = json!(5);
    let mut points = b.meshes[0]["primitives"][0].clone();
    points["mode"] = json!(0);
    b.meshes[0]["primitives"].as_array_mut().unwrap().push(points);
    let node = b.node(json!({ "mesh": 0 }));
    b.roots = vec![node];
    let mut notices = Vec::new();
    let file = parse(&b.gltf(), Files::None, &mut notices).unwrap();
    assert_eq!(file.primitives[0].triangles, vec![[0, 1, 2], [2, 1, 3]]);
    assert_eq!(file.primitives.len(), 1);
    assert!(
        notices
            .iter()
            .any(|n| n == "1 primitives of points or lines are skipped"),
        "{notices:?}"
    );
}

/// A triangle, two cameras (the first turned to look along -x), a point light and a sun.
fn cameras_and_lights() -> GltfBuilder {
    let mut b = GltfBuilder::default();
    let mesh = b.mesh(&TRIANGLE, None, &[0, 1, 2], None);
    let model = b.node(json!({ "mesh": mesh }));
    b.cameras = vec![
        json!({ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }),
        json!({ "type": "perspective", "perspective": { "yfov": 1.0, "znear": 0.1 } }),
    ];
    // Turned 90 degrees about y: the camera's -z looks along -x.
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let camera = b.node(json!({ "camera": 0, "translation": [4, 0, 0], "rotation": [0, half, 0, half] }));
    let second = b.node(json!({ "camera": 1 }));
    b.lights = vec![
        json!({ "type": "point", "color": [1, 0.5, 0.25], "intensity": 2 }),
        json!({ "type": "directional", "intensity": 0.5 }),
    ];
    b.extensions_used = vec!["KHR_lights_punctual"];
    let point = b.node(json!({ "translation": [0, 3, 0], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    let sun = b.node(json!({ "extensions": { "KHR_lights_punctual": { "light": 1 } } }));
    b.roots = vec![model, camera, second, point, sun];
    b
}

fn the_first_perspective_camera_and_the_lights_come_from_their_nodes() {
    let b = cameras_and_lights();
    let file = read(&b);
    let camera = file.camera.unwrap();
    assert!(close(camera.eye, Vec3::new(4.0, 0.0, 0.0)), "{camera:?}");
    assert!(close(camera.target - camera.eye, Vec3::NEG_X), "{camera:?}");
    assert!(close(camera.up, Vec3::Y), "{camera:?}");
    assert!((camera.fov_degrees - 0.5f32.to_degrees()).abs() < 1e-4);
    assert_eq!(
        file.lights[0],
        Light {
            position: Vec3::new(0.0, 3.0, 0.0),
            color: Vec3::new(2.0, 1.0, 0.5),
            kind: LightKind::Point { range: None },
        }
    );
    assert_eq!(
        (file.lights[1].color, file.lights[1].kind),
        (Vec3::splat(0.5), LightKind::Directional { direction: Vec3::NEG_Z })
    );

    let path = b.write(&test_dir("gltf-camera"), "scene", Packing::Glb);
    let scene = Scene::load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.camera, camera);
    assert!(scene.planes.is_empty(), "a file with a camera gets no floor");
    assert_eq!(scene.lights.len(), 2);
    // Truly directional: the light keeps its direction, placed by the file's (identity) rotation.
    assert_eq!(scene.lights[1].kind, LightKind::Directional { direction: Vec3::NEG_Z });
}

fn without_camera_and_lights_a_file_is_framed_as_a_model() {
    let mut b = GltfBuilder::default();
    let mesh = b.mesh(&TRIANGLE, None, &[0, 1, 2], None);
    b.roots = vec![b.node(json!({ "mesh": mesh }))];
    let scene = Scene::from_bytes("t.gltf", &b.gltf()).unwrap();
    assert_eq!((scene.lights.len(), scene.planes.len()), (2, 1));
    // Just below the model's lowest point (y 0), by a thousandth of its bounding sphere's radius.
    let radius = (Vec3::new(1.0, 1.0, 0.0) * 0.5).length();
    let gap = -scene.planes[0].point.y;
    assert!(
        gap > 0.0 && gap <= 1.001e-3 * radius,
        "the floor lies {gap} below the model"
    );
    // The file's one primitive has no material: glTF's default material, after the floor's.
    assert_eq!(scene.triangles[0].material, 3);
    assert_eq!(scene.materials[3].color, Vec3::ONE);
}

/// A glass triangle (transmission, ior 1.3) and a glowing one.
fn glass_and_lamp() -> GltfBuilder {
    let mut b = GltfBuilder::default();
    let glass = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0 },
        "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 }, "KHR_materials_ior": { "ior": 1.3 } }
    }));
    let lamp = b.material(json!({ "emissiveFactor": [1, 0.5, 0], "pbrMetallicRoughness": { "metallicFactor": 0 } }));
    b.extensions_used = vec!["KHR_materials_transmission", "KHR_materials_ior"];
    let a = b.mesh(&TRIANGLE, None, &[0, 1, 2], Some(glass));
    let c = b.mesh(&TRIANGLE, None, &[0, 1, 2], Some(lamp));
    b.roots = vec![b.node(json!({ "mesh": a })), b.node(json!({ "mesh": c }))];
    b
}

fn materials_map_to_whitted_ones() {
    let b = glass_and_lamp();
    let file = read(&b);
    let glass = file.materials[0];
    assert_eq!((glass.transmit, glass.ior, glass.reflect), (1.0, 1.3, 0.0));
    let lamp = file.materials[1];
    assert_eq!((lamp.emission, lamp.reflect), (Vec3::new(1.0, 0.5, 0.0), 0.0));
    assert_eq!(file.primitives[1].material, 1);
}

fn textures_keep_their_texels_and_wrap_modes() {
    let file = read(&textured_quad(2.0, [33071, 33648]));
    assert_eq!(file.textures.len(), 1);
    let texture = &file.textures[0];
    assert_eq!((texture.width, texture.height), (2, 2));
    use raypipe::scene::Wrap;
    assert_eq!(texture.wrap, [Wrap::Clamp, Wrap::Mirror]);
    // sRGB 255 and 0 decode to exactly 1 and 0.
    assert_eq!(texture.texel(0, 0), [1.0, 0.0, 0.0, 1.0]);
    assert_eq!(texture.texel(1, 1), [1.0, 1.0, 1.0, 1.0]);
    assert_eq!(file.materials[0].texture, Some(TextureMap::plain(0)));
    assert_eq!(file.primitives[0].uvs.as_ref().unwrap()[1], glam::Vec2::new(2.0, 2.0));
}

fn colours_second_coordinates_and_tangents_are_read() {
    use crate::common::gltf_file::attribute_quad;
    let file = read(&attribute_quad());
    let primitive = &file.primitives[0];
    let colors = primitive.colors.as_ref().unwrap();
    // Normalized bytes: 255 is 1, 64 is 64 / 255; alpha 128 / 255.
    assert_eq!(colors[0], glam::Vec4::new(1.0, 64.0 / 255.0, 64.0 / 255.0, 1.0));
    assert_eq!(colors[3].w, 128.0 / 255.0);
    assert_eq!(primitive.uvs1.as_ref().unwrap()[0], glam::Vec2::new(1.0, 1.0));
    let material = file.materials[0];
    assert_eq!(material.texture.unwrap().tex_coord, 1);
    let pbr = material.pbr.unwrap();
    assert_eq!((pbr.normal_texture.unwrap().tex_coord, pbr.normal_scale), (0, 0.8));
    // One image for KHR_materials_specular's two maps: its alpha read as data for the strength,
    // its colour decoded from sRGB for the colour.
    let [strength, colour] = [pbr.specular_texture, pbr.specular_color_texture].map(Option::unwrap);
    assert_eq!((strength.tex_coord, colour.tex_coord), (0, 1));
    // Texels are half floats.
    let alpha = file.textures[strength.texture as usize].texel(0, 0)[3];
    assert!((alpha - 64.0 / 255.0).abs() < 1e-3, "{alpha}");
    let [r, g, b, _] = file.textures[colour.texture as usize].texel(0, 0);
    let srgb = |c: f32| ((c / 255.0 + 0.055) / 1.055).powf(2.4);
    for (got, byte) in [(r, 188.0), (g, 255.0), (b, 128.0)] {
        assert!((got - srgb(byte)).abs() < 1e-3, "{got} against {}", srgb(byte));
    }
    // MikkTSpace's tangents: along +x (u) with v running down the image (quad's UVs), so the
    // bitangent's sign is -1.
    let tangents = primitive.tangents.as_ref().unwrap();
    assert_eq!(tangents.len(), 2);
    for t in tangents.iter().flatten() {
        assert!((t.truncate() - Vec3::X).length() < 1e-5 && t.w == -1.0, "{t}");
    }
    // A map on a set the primitive lacks, a normal map without normals: one line each.
    let without = |attribute: &str| {
        let mut b = attribute_quad();
        let attributes = b.meshes[0]["primitives"][0]["attributes"].as_object_mut().unwrap();
        attributes.remove(attribute);
        parse(&b.gltf(), Files::None, &mut Vec::new()).unwrap_err().to_string()
    };
    for (attribute, expected) in [
        ("TEXCOORD_1", "material 0 reads TEXCOORD_1, which the primitive lacks"),
        ("NORMAL", "material 0 has a normal map, and the primitive has no NORMAL"),
    ] {
        let err = without(attribute);
        assert!(err.contains(expected), "{err}");
    }
}

fn every_packing_gives_the_same_scene() {
    let dir = test_dir("gltf-packings");
    let b = textured_quad(3.0, [10497, 33071]);
    let scenes: Vec<Scene> = [Packing::DataUris, Packing::ExternalFiles, Packing::Glb]
        .into_iter()
        .map(|packing| {
            let path = b.write(&dir, &format!("{packing:?}"), packing);
            Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{packing:?}: {e}"))
        })
        .collect();
    assert_eq!(scenes[0], scenes[1]);
    assert_eq!(scenes[0], scenes[2]);
    assert_eq!(scenes[0].textures.len(), 1);
    // A page has no folder to read external files from.
    let external = std::fs::read(dir.join("ExternalFiles.gltf")).unwrap();
    let err = Scene::from_bytes("ExternalFiles.gltf", &external)
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("ExternalFiles.gltf: buffer 0: external file 'ExternalFiles.bin' cannot be read here"),
        "{err}"
    );
}

fn a_gltf_mesh_table_places_the_file_after_its_own_transforms() {
    let dir = test_dir("gltf-mesh-table");
    let b = hierarchy(json!({}));
    b.write(&dir, "tri", Packing::Glb);
    std::fs::write(
        dir.join("scene.toml"),
        "[[mesh]]\nfile = \"tri.glb\"\nnormalize = false\nscale = 2\ntranslate = [0, 0, 10]\n\
         [[mesh]]\nfile = \"tri.glb\"\nas = \"spheres\"\nradius = 0.1\n",
    )
    .unwrap();
    let scene = Scene::load(dir.join("scene.toml").to_str().unwrap()).unwrap();
    // The file puts the triangle at (1, 2, 3) + TRIANGLE; the table doubles it and moves it.
    let t = &scene.triangles[0];
    assert_eq!(
        t.vertices,
        [
            Vec3::new(2.0, 4.0, 16.0),
            Vec3::new(4.0, 4.0, 16.0),
            Vec3::new(2.0, 6.0, 16.0)
        ]
    );
    assert_eq!(scene.spheres.len(), 3);
    // glTF's default material, after the table's default one.
    assert_eq!(scene.materials[t.material as usize].color, Vec3::ONE);
}

/// A 16x8 JPEG (made with Pillow, quality 95): its left half (200, 30, 40), its right half
/// (20, 180, 60), in sRGB.
const JPEG_BASE64: &str = "/9j/4AAQSkZJRgABAQAAAQABAAD/2wBDAAIBAQEBAQIBAQECAgICAgQDAgICAgUEBAMEBgUGBgYFBgYGBwkIBgcJBwYGCAsICQoKCgoKBggLDAsKDAkKCgr/2wBDAQICAgICAgUDAwUKBwYHCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgr/wAARCAAIABADASIAAhEBAxEB/8QAHwAAAQUBAQEBAQEAAAAAAAAAAAECAwQFBgcICQoL/8QAtRAAAgEDAwIEAwUFBAQAAAF9AQIDAAQRBRIhMUEGE1FhByJxFDKBkaEII0KxwRVS0fAkM2JyggkKFhcYGRolJicoKSo0NTY3ODk6Q0RFRkdISUpTVFVWV1hZWmNkZWZnaGlqc3R1dnd4eXqDhIWGh4iJipKTlJWWl5iZmqKjpKWmp6ipqrKztLW2t7i5usLDxMXGx8jJytLT1NXW19jZ2uHi4+Tl5ufo6erx8vP09fb3+Pn6/8QAHwEAAwEBAQEBAQEBAQAAAAAAAAECAwQFBgcICQoL/8QAtREAAgECBAQDBAcFBAQAAQJ3AAECAxEEBSExBhJBUQdhcRMiMoEIFEKRobHBCSMzUvAVYnLRChYkNOEl8RcYGRomJygpKjU2Nzg5OkNERUZHSElKU1RVVldYWVpjZGVmZ2hpanN0dXZ3eHl6goOEhYaHiImKkpOUlZaXmJmaoqOkpaanqKmqsrO0tba3uLm6wsPExcbHyMnK0tPU1dbX2Nna4uPk5ebn6Onq8vP09fb3+Pn6/9oADAMBAAIRAxEAPwD5Hr6Qoor8NzD7Pz/Q9z9ov/zTH/c7/wC6h//Z";

fn jpeg_textures_decode_to_linear_texels() {
    let b = textured_quad(1.0, [10497, 10497]);
    let mut document: Value = serde_json::from_slice(&b.gltf()).unwrap();
    document["images"][0] = json!({ "uri": format!("data:image/jpeg;base64,{JPEG_BASE64}") });
    let file = parse(&serde_json::to_vec(&document).unwrap(), Files::None, &mut Vec::new()).unwrap();
    let texture = &file.textures[0];
    assert_eq!((texture.width, texture.height), (16, 8));
    use raypipe::scene::texture::srgb_to_linear;
    for ((x, y), srgb) in [((2, 2), [200u8, 30, 40]), ((13, 5), [20, 180, 60])] {
        let texel = texture.texel(x, y);
        for c in 0..3 {
            // JPEG is lossy: within a few 8-bit steps of the colour it was given.
            let (low, high) = (
                srgb_to_linear(srgb[c].saturating_sub(4)),
                srgb_to_linear(srgb[c].saturating_add(4)),
            );
            assert!(
                texel[c] >= low && texel[c] <= high,
                "texel ({x}, {y}) is {texel:?}, made from {srgb:?}"
            );
        }
        assert_eq!(texel[3], 1.0);
    }
}

/// scripts/skinned-mesh.py's animated tube of at least `triangles` triangles (the benchmarks'
/// content), written into `dir`.
fn skinned_mesh(dir: &std::path::Path, triangles: usize) -> std::path::PathBuf {
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/skinned-mesh.py");
    let path = dir.join(format!("skinned-mesh-{triangles}.glb"));
    let made = std::process::Command::new("python3")
        .arg(&script)
        .args(["--triangles", &triangles.to_string(), "-o"])
        .arg(&path)
        .output()
        .expect("python3 runs scripts/skinned-mesh.py");
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    path
}

/// The benchmarks' skinned mesh loads with the triangles asked for, and its clip moves every ring
/// but the root's: the chain bends.
fn the_generated_skinned_mesh_loads_and_bends() {
    let dir = test_dir("skinned-mesh");
    let path = skinned_mesh(&dir, 5000);
    let scene = Scene::load(path.to_str().unwrap()).unwrap();
    assert!(
        (5000..5200).contains(&scene.triangles.len()),
        "{}",
        scene.triangles.len()
    );
    let motion = scene.motion.as_ref().expect("the clip plays");
    assert_eq!(motion.duration(), Some(2.0));
    let later = scene.at_time(0.5).unwrap();
    let moved = scene
        .triangles
        .iter()
        .zip(&later.triangles)
        .filter(|(a, b)| a.vertices != b.vertices)
        .count();
    assert!(
        moved > scene.triangles.len() / 2,
        "{moved} of {} moved",
        scene.triangles.len()
    );
}

/// Every file these tests generate passes the Khronos glTF-Validator (npm gltf-validator, run by
/// web/validate-gltf.mjs), so that they test glTF and not a dialect of raypipe's own. Ignored, with
/// the reason, where Node.js or the package (`npm ci --prefix web`) is missing, unless
/// RAYPIPE_REQUIRE_VALIDATOR=1 (CI) makes that a failure.
fn generated_files_pass_the_khronos_validator(root: &std::path::Path) {
    let script = root.join("web/validate-gltf.mjs");
    let dir = test_dir("gltf-validator");
    let mut files = Vec::new();
    let builders = [
        (
            "hierarchy",
            hierarchy(json!({ "translation": [0, 0, -1], "rotation": [0, 0, 0.6, 0.8], "scale": [2, 2, 2] })),
        ),
        (
            "matrix",
            hierarchy(json!({ "matrix": [0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 2, 0, 0, 0, -1, 1] })),
        ),
        ("cameras-and-lights", cameras_and_lights()),
        ("instancing", instanced(json!({ "translation": [0, 0, -1] }))),
        ("materials", glass_and_lamp()),
        ("textured", textured_quad(2.0, [10497, 33071])),
        (
            "framed",
            crate::common::gltf_file::framed_textured_quad(2.0, [33648, 10497]),
        ),
        ("skinned", crate::common::gltf_file::skinned_cylinder(6).0),
        ("morphing", crate::common::gltf_file::morphing_quad(0.5)),
        ("attributes", crate::common::gltf_file::attribute_quad()),
    ];
    for (stem, builder) in &builders {
        for packing in [Packing::DataUris, Packing::ExternalFiles, Packing::Glb] {
            files.push(builder.write(&dir, &format!("{stem}-{packing:?}"), packing));
        }
    }
    files.push(skinned_mesh(&dir, 2000));
    let output = std::process::Command::new("node")
        .arg(&script)
        .args(&files)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{report}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_eq!(
        report
            .lines()
            .filter(|l| l.ends_with(": 0 errors, 0 warnings") || l.ends_with(": 0 errors, 1 warnings"))
            .count(),
        files.len(),
        "{report}"
    );
    // The one warning allowed: the attribute quad's normal map on a primitive without TANGENT,
    // which the specification answers with MikkTSpace tangents (the case that file tests).
    let warnings: Vec<&str> = report.lines().filter(|l| l.starts_with("  warning ")).collect();
    assert_eq!(warnings.len(), 3, "{report}");
    assert!(
        warnings
            .iter()
            .all(|l| l.starts_with("  warning MESH_PRIMITIVE_GENERATED_TANGENT_SPACE:")),
        "{report}"
    );
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        plain node_hierarchy_places_triangles_as_by_hand,
        plain a_matrix_node_equals_its_trs_twin,
        plain a_mirroring_node_turns_the_winding,
        plain an_instanced_mesh_appears_at_every_node,
        plain gpu_instancing_places_every_instance_under_its_node,
        plain bad_instancing_accessors_are_refused,
        plain strips_fans_and_points_by_mode,
        plain the_first_perspective_camera_and_the_lights_come_from_their_nodes,
        plain without_camera_and_lights_a_file_is_framed_as_a_model,
        plain materials_map_to_whitted_ones,
        plain textures_keep_their_texels_and_wrap_modes,
        plain colours_second_coordinates_and_tangents_are_read,
        plain every_packing_gives_the_same_scene,
        plain a_gltf_mesh_table_places_the_file_after_its_own_transforms,
        plain jpeg_textures_decode_to_linear_texels,
        plain the_generated_skinned_mesh_loads_and_bends,
        validator generated_files_pass_the_khronos_validator,
    ]
}
