//! glTF animation against known answers: samplers at keys and between them, a skinned cylinder
//! bent by hand, a morph target halfway, clamping and looping at both ends, and hostile files
//! refused with one line.

use crate::common::gltf_file::{BEND_HEIGHT, GltfBuilder, morphing_quad, skinned_cylinder};
use crate::common::harness::Test;
use glam::{Quat, Vec3};
use raypipe::modes::Accel;
use raypipe::records::packed::MovedRecords;
use raypipe::records::{PackedScene, PoseOn, PosedScene, Poses};
use raypipe::scene::animation::{Interpolation, Sampler};
use raypipe::scene::gltf::{Files, GltfScene, parse};
use raypipe::scene::model::{ModelOptions, gltf_scene};
use raypipe::scene::{Moved, Scene};
use serde_json::json;

fn sampler(interpolation: Interpolation, times: &[f32], values: &[f32], width: usize) -> Sampler {
    let sampler = Sampler {
        times: times.to_vec(),
        values: values.to_vec(),
        width,
        interpolation,
    };
    sampler.validate().unwrap();
    sampler
}

fn at(sampler: &Sampler, t: f32) -> f32 {
    let mut out = [0.0];
    sampler.sample(t, false, &mut out);
    out[0]
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-5
}

fn step_linear_and_cubic_samplers_at_keys_and_between() {
    let times = [1.0, 2.0, 4.0];
    let step = sampler(Interpolation::Step, &times, &[10.0, 20.0, 40.0], 1);
    let linear = sampler(Interpolation::Linear, &times, &[10.0, 20.0, 40.0], 1);
    for (t, stepped, lined) in [
        // Before the first key and after the last: clamped.
        (0.0, 10.0, 10.0),
        (1.0, 10.0, 10.0),
        (1.5, 10.0, 15.0),
        (2.0, 20.0, 20.0),
        (3.0, 20.0, 30.0),
        (4.0, 40.0, 40.0),
        (9.0, 40.0, 40.0),
    ] {
        assert!(close(at(&step, t), stepped), "STEP at {t}: {}", at(&step, t));
        assert!(close(at(&linear, t), lined), "LINEAR at {t}: {}", at(&linear, t));
    }
    // CUBICSPLINE keys: in-tangent, value, out-tangent. From 0 at t = 0 (out-tangent 2 per second)
    // to 1 at t = 2 (in-tangent 0): at s = 1/2 the Hermite basis gives
    // 0.5 * 0 + 0.125 * 2 * 2 + 0.5 * 1 - 0.125 * 2 * 0 = 1.0.
    let cubic = sampler(
        Interpolation::CubicSpline,
        &[0.0, 2.0],
        &[9.0, 0.0, 2.0, 0.0, 1.0, 9.0],
        1,
    );
    assert!(close(at(&cubic, 0.0), 0.0));
    assert!(close(at(&cubic, 1.0), 1.0), "{}", at(&cubic, 1.0));
    assert!(close(at(&cubic, 2.0), 1.0));
    // s = 1/4: h00 = 27/32, h10 = 9/64, h01 = 5/32, h11 = -3/64.
    let expected = 9.0 / 64.0 * 2.0 * 2.0 + 5.0 / 32.0;
    assert!(close(at(&cubic, 0.5), expected), "{}", at(&cubic, 0.5));
    assert!(close(at(&cubic, -1.0), 0.0) && close(at(&cubic, 5.0), 1.0));
}

fn rotations_are_slerped_and_normalized() {
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let linear = sampler(
        Interpolation::Linear,
        &[0.0, 1.0],
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, half, half],
        4,
    );
    let mut out = [0.0; 4];
    linear.sample(0.5, true, &mut out);
    let expected = Quat::from_rotation_z(std::f32::consts::FRAC_PI_4);
    assert!(Quat::from_slice(&out).abs_diff_eq(expected, 1e-6), "{out:?}");
    // A cubic spline's rotation comes out at unit length whatever its tangents.
    let cubic = sampler(
        Interpolation::CubicSpline,
        &[0.0, 1.0],
        &[
            [1.0; 4],
            [0.0, 0.0, 0.0, 1.0],
            [1.0; 4],
            [1.0; 4],
            [0.0, 0.0, half, half],
            [1.0; 4],
        ]
        .concat(),
        4,
    );
    cubic.sample(0.3, true, &mut out);
    assert!((Quat::from_slice(&out).length() - 1.0).abs() < 1e-6);
}

/// The cylinder as the file poses it, against the same vertices bent by hand: each vertex is
/// (1 - w) of itself plus w of itself turned about z around (0, BEND_HEIGHT, 0).
fn a_two_bone_cylinder_bends_as_posed_by_hand() {
    let (builder, rest, weights) = skinned_cylinder(9);
    let file = parse(&builder.gltf(), Files::None, &mut Vec::new()).unwrap();
    let rig = file.rig.clone().expect("a skinned file has a rig");
    assert_eq!(rig.clip(None), Ok(Some(0)));
    for (t, degrees) in [(0.0f32, 0.0f32), (0.5, 45.0), (1.0, 90.0), (3.0, 90.0)] {
        let posed = file.posed(Some(0), t);
        let turn = Quat::from_rotation_z(degrees.to_radians());
        let pivot = Vec3::new(0.0, BEND_HEIGHT, 0.0);
        for (v, (&p, &w)) in rest.iter().zip(&weights).enumerate() {
            let p = Vec3::from(p);
            let by_hand = p * (1.0 - w) + (pivot + turn * (p - pivot)) * w;
            let got = posed.primitives[0].positions[v];
            assert!(
                got.abs_diff_eq(by_hand, 1e-5),
                "t = {t}, vertex {v}: {got} against {by_hand}"
            );
        }
    }
}

fn a_morph_target_at_weight_one_half_is_halfway() {
    let file = parse(&morphing_quad(0.8).gltf(), Files::None, &mut Vec::new()).unwrap();
    for (t, z) in [(-1.0, 0.0), (0.0, 0.0), (0.5, 0.4), (1.0, 0.8), (2.0, 0.8)] {
        let posed = file.posed(Some(0), t);
        for p in &posed.primitives[0].positions {
            assert!(close(p.z, z), "t = {t}: {p}");
        }
    }
}

/// A scene places the file and plays it: the moving triangles at a time equal the file posed at
/// that time; looping wraps, clamping holds.
fn scenes_play_the_clip_clamped_or_looped() {
    let (builder, _, _) = skinned_cylinder(5);
    let file = parse(&builder.gltf(), Files::None, &mut Vec::new()).unwrap();
    let scene = gltf_scene(&file, "cylinder.gltf", &ModelOptions::default()).unwrap();
    let motion = scene.motion.clone().expect("the clip moves the cylinder");
    assert_eq!(motion.duration(), Some(1.0));
    assert!(close(motion.looped(2.25), 0.25) && close(motion.looped(-0.25), 0.75));
    let quarter = scene.at_time(0.25).unwrap();
    let wrapped = scene.at_time(motion.looped(1.25)).unwrap();
    assert_eq!(quarter.triangles, wrapped.triangles);
    assert_eq!(
        scene.at_time(1.0).unwrap().triangles,
        scene.at_time(7.0).unwrap().triangles
    );
    assert_ne!(quarter.triangles, scene.triangles);
    let Moved::Triangles(runs) = motion.moved(&scene, 0.0).unwrap() else {
        panic!("an animation moves triangles")
    };
    assert_eq!(
        runs.iter().map(|r| r.vertices.len()).sum::<usize>(),
        scene.triangles.len()
    );
    let posed = scene.at_time(0.0).unwrap();
    assert_eq!(posed.triangles, scene.triangles, "the scene as loaded is its time 0");
}

fn clips_are_chosen_by_name_or_index() {
    let (mut builder, _, _) = skinned_cylinder(5);
    builder.animations[0]["name"] = json!("Bend");
    let bytes = builder.gltf();
    let file = parse(&bytes, Files::None, &mut Vec::new()).unwrap();
    for choice in ["Bend", "0"] {
        let options = ModelOptions {
            animation: Some(raypipe::scene::animation::ClipChoice::parse(choice)),
            ..ModelOptions::default()
        };
        assert!(gltf_scene(&file, "c.gltf", &options).unwrap().motion.is_some());
    }
    let options = ModelOptions {
        animation: Some(raypipe::scene::animation::ClipChoice::parse("Walk")),
        ..ModelOptions::default()
    };
    let error = gltf_scene(&file, "c.gltf", &options).unwrap_err().to_string();
    assert!(
        error.contains("no animation named \"Walk\"") && error.contains("0 (Bend)"),
        "{error}"
    );
}

fn refusal(builder: &GltfBuilder) -> String {
    let error = parse(&builder.gltf(), Files::None, &mut Vec::new())
        .unwrap_err()
        .to_string();
    assert!(!error.contains('\n'), "{error}");
    error
}

fn hostile_animations_and_skins_are_refused_with_one_line() {
    // Key times that do not increase.
    let (mut b, _, _) = skinned_cylinder(3);
    let times = b.floats(&[0.0, 1.0, 1.0], 1);
    b.animations[0]["samplers"][0]["input"] = json!(times);
    let output = b.floats(&[0.0, 0.0, 0.0, 1.0].repeat(3), 4);
    b.animations[0]["samplers"][0]["output"] = json!(output);
    let error = refusal(&b);
    assert!(error.contains("key times must increase"), "{error}");
    // NaN keys.
    let (mut b, _, _) = skinned_cylinder(3);
    let output = b.floats(&[0.0, 0.0, 0.0, 1.0, f32::NAN, 0.0, 0.0, 1.0], 4);
    b.animations[0]["samplers"][0]["output"] = json!(output);
    assert!(refusal(&b).contains("not finite"));
    // An accessor of the wrong type for its path: VEC3 rotations.
    let (mut b, _, _) = skinned_cylinder(3);
    let output = b.floats(&[0.0; 6], 3);
    b.animations[0]["samplers"][0]["output"] = json!(output);
    let error = refusal(&b);
    assert!(
        error.contains("animation 0: channel 0") && error.contains("Vec3"),
        "{error}"
    );
    // A joint index beyond the skin.
    let (mut b, rest, _) = skinned_cylinder(3);
    let joints = b.joints(&vec![[0, 2, 0, 0]; rest.len()]);
    b.meshes[0]["primitives"][0]["attributes"]["JOINTS_0"] = json!(joints);
    let error = refusal(&b);
    assert!(error.contains("joint 2") && error.contains("skin 0 has 2"), "{error}");
    // A skin of 100,000 joints.
    let (mut b, _, _) = skinned_cylinder(3);
    let first = b.nodes.len();
    b.nodes.extend((0..100_000).map(|_| json!({})));
    b.roots.extend(first..first + 100_000);
    b.skins[0] = json!({ "joints": (first..first + 100_000).collect::<Vec<_>>() });
    let error = refusal(&b);
    assert!(error.contains("skin 0: 100000 joints, more than the 4096"), "{error}");
}

fn weights_that_do_not_sum_to_one_are_normalized_with_a_notice() {
    let (mut b, rest, weights) = skinned_cylinder(5);
    // Twice the file's weights, whose first is the only one where a vertex has one joint.
    let doubled: Vec<f32> = weights
        .iter()
        .flat_map(|&w| match w {
            0.0 | 1.0 => [2.0, 0.0, 0.0, 0.0],
            w => [2.0 * (1.0 - w), 2.0 * w, 0.0, 0.0],
        })
        .collect();
    let accessor = b.floats(&doubled, 4);
    b.meshes[0]["primitives"][0]["attributes"]["WEIGHTS_0"] = json!(accessor);
    let mut notices = Vec::new();
    let doubled_file = parse(&b.gltf(), Files::None, &mut notices).unwrap();
    assert!(
        notices.iter().any(|n| n
            == &format!(
                "{} vertices have joint weights that do not sum to one: normalized",
                rest.len()
            )),
        "{notices:?}"
    );
    let (b, _, _) = skinned_cylinder(5);
    let file = parse(&b.gltf(), Files::None, &mut Vec::new()).unwrap();
    let same = |a: &GltfScene, b: &GltfScene| {
        a.posed(Some(0), 0.7).primitives[0]
            .positions
            .iter()
            .zip(&b.posed(Some(0), 0.7).primitives[0].positions)
            .all(|(p, q)| p.abs_diff_eq(*q, 1e-5))
    };
    assert!(same(&doubled_file, &file));
}

/// Every sample model that animates moves between its start and a later time, and stays within
/// reach.
fn the_animated_samples_move(models: &std::path::Path) {
    let dir = models.join("gltf");
    for name in ["RiggedSimple", "BoxAnimated", "SimpleSkin", "AnimatedTriangle"] {
        let path = dir.join(format!("{name}.gltf"));
        let scene = Scene::load(path.to_str().unwrap()).unwrap();
        let motion = scene.motion.as_ref().unwrap_or_else(|| panic!("{name} moves"));
        let duration = motion.duration().unwrap();
        assert!(duration > 0.9, "{name}: {duration}");
        let later = scene.at_time(duration * 0.4).unwrap();
        assert_ne!(later.triangles, scene.triangles, "{name}");
        later.validate().unwrap();
    }
}

/// Rewriting only the records that move gives the records of the scene packed anew at that time.
fn moving_records_in_place_equals_packing_anew() {
    let (builder, _, _) = skinned_cylinder(6);
    let file = parse(&builder.gltf(), Files::None, &mut Vec::new()).unwrap();
    let scene = gltf_scene(&file, "cylinder.gltf", &ModelOptions::default()).unwrap();
    let motion = scene.motion.as_ref().unwrap();
    let mut packed = raypipe::records::PackedScene::new(&scene).unwrap();
    for t in [0.1, 0.5, 0.2, 1.0] {
        packed.apply(&motion.moved(&scene, t).unwrap());
        assert_eq!(
            packed,
            raypipe::records::PackedScene::new(&scene.at_time(t).unwrap()).unwrap(),
            "t = {t}"
        );
    }
    let bounce = Scene::load("bounce:30").unwrap();
    let mut packed = raypipe::records::PackedScene::new(&bounce).unwrap();
    packed.apply(&bounce.motion.as_ref().unwrap().moved(&bounce, 2.0).unwrap());
    assert_eq!(
        packed,
        raypipe::records::PackedScene::new(&bounce.at_time(2.0).unwrap()).unwrap()
    );
}

/// A posed scene keeps the last two poses' times; its records and tree at each pose are those of
/// the scene packed and built anew at that time; a time it cannot pose changes nothing. Posed for
/// the GPU, an animation keeps its loaded records (the GPU skins them) while bounce's spheres move.
fn a_posed_scene_keeps_its_last_two_poses_and_builds_as_packed_anew() {
    let (builder, _, _) = skinned_cylinder(6);
    let file = parse(&builder.gltf(), Files::None, &mut Vec::new()).unwrap();
    let cylinder = gltf_scene(&file, "cylinder.gltf", &ModelOptions::default()).unwrap();
    let mut posed = PosedScene::new(&cylinder, Accel::Threaded, PoseOn::Cpu).unwrap();
    assert_eq!(posed.poses(), Poses::default());
    for (t, previous) in [(0.25, None), (0.75, Some(0.25)), (0.5, Some(0.75))] {
        let step = posed.pose(t).unwrap();
        assert_eq!(
            posed.poses(),
            Poses {
                current: Some(t),
                previous
            },
            "t = {t}"
        );
        assert_eq!(step.moved, Some(MovedRecords::Triangles));
        assert!(step.build.is_some());
        let mut anew = PackedScene::new(&cylinder.at_time(t).unwrap()).unwrap();
        anew.build_bvh();
        // Not assert_eq: a scene's records print as thousands of lines.
        assert!(posed.packed() == &anew, "t = {t}: the records or the tree differ");
    }
    let before = posed.packed().clone();
    assert!(posed.pose(f32::NAN).is_err());
    assert_eq!(posed.poses().current, Some(0.5), "a refused time is not a pose");
    assert!(posed.packed() == &before, "a refused time moved the records");

    let mut on_gpu = PosedScene::new(&cylinder, Accel::Threaded, PoseOn::Gpu).unwrap();
    let step = on_gpu.pose(0.5).unwrap();
    assert_eq!((step.moved, step.build), (None, None));
    assert!(
        on_gpu.packed() == &PackedScene::new(&cylinder).unwrap(),
        "the GPU skins them"
    );
    let bounce = Scene::load("bounce:30").unwrap();
    let mut on_gpu = PosedScene::new(&bounce, Accel::Threaded, PoseOn::Gpu).unwrap();
    assert_eq!(on_gpu.pose(2.0).unwrap().moved, Some(MovedRecords::Spheres));
    assert!(on_gpu.packed() == &PackedScene::new(&bounce.at_time(2.0).unwrap()).unwrap());
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        plain step_linear_and_cubic_samplers_at_keys_and_between,
        plain rotations_are_slerped_and_normalized,
        plain a_two_bone_cylinder_bends_as_posed_by_hand,
        plain a_morph_target_at_weight_one_half_is_halfway,
        plain scenes_play_the_clip_clamped_or_looped,
        plain clips_are_chosen_by_name_or_index,
        plain hostile_animations_and_skins_are_refused_with_one_line,
        plain weights_that_do_not_sum_to_one_are_normalized_with_a_notice,
        models the_animated_samples_move,
        plain moving_records_in_place_equals_packing_anew,
        plain a_posed_scene_keeps_its_last_two_poses_and_builds_as_packed_anew,
    ]
}
