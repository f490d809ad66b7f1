//! The shared scans through the command line.

use crate::common::harness::Test;
use crate::common::raypipe;
use crate::common::test_dir;
use std::path::Path;

fn the_bunny_renders_as_20k_spheres(models: &Path) {
    let bunny = models.join("bunny.ply");
    let out = test_dir("cli-bunny").join("bunny-spheres.png");
    let output = raypipe(&[
        "render",
        bunny.to_str().unwrap(),
        "--spheres",
        "20000",
        "--width",
        "96",
        "--height",
        "72",
        "--stats",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(stdout.contains("20000 spheres, 0 triangles"), "{stdout}");
    // The bunny fills a good part of the frame: clay pixels (red well above blue) are common.
    let image = image::open(&out).unwrap().to_rgb8();
    let clay = image.pixels().filter(|p| p[0] as i32 > p[2] as i32 + 40).count();
    assert!(clay > image.len() / 3 / 20, "{clay} clay pixels of {}", image.len() / 3);
}

/// A glTF sample through `bvh` (a tree over every triangle of its node hierarchy) and `bench` (its
/// triangles, each mode's image checked against brute force's before it is timed).
fn a_gltf_sample_goes_through_bvh_and_bench(models: &Path) {
    let sample = models.join("gltf/BoxAnimated.gltf");
    let sample = sample.to_str().unwrap();
    let triangles = raypipe::scene::Scene::load(sample).unwrap().triangles.len();
    let output = raypipe(&["bvh", sample, "--json"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["primitives"].as_u64(), Some(triangles as u64), "{report}");
    let out = test_dir("cli-gltf-bench");
    let output = raypipe(&[
        "bench",
        sample,
        "--as",
        "triangles",
        "--accel",
        "brute,threaded",
        "--width",
        "32",
        "--height",
        "24",
        "--frames",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(out.join("results.csv").is_file());
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        models the_bunny_renders_as_20k_spheres,
        models a_gltf_sample_goes_through_bvh_and_bench,
    ]
}
