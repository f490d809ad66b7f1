//! The command line: renders write files, diff exits by threshold, and bad input ends with one line
//! on stderr and exit code 2, never a panic.

mod common;
use common::{assert_clean_error, raypipe};
use std::path::{Path, PathBuf};
use std::process::Output;

fn temp(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write(name: &str, text: &str) -> PathBuf {
    let path = temp(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn render_cpu(scene: &Path) -> Output {
    let out = temp("out.png");
    raypipe(&[
        "render",
        scene.to_str().unwrap(),
        "--device",
        "cpu",
        "-o",
        out.to_str().unwrap(),
    ])
}

const GOOD: &str = "[camera]\neye = [0, 1, -6]\ntarget = [0, 0, 0]\n\n[material.red]\ncolor = [1, 0, 0]\n\n\
    [[light]]\nposition = [4, 6, -3]\n\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1.0\nmaterial = \"red\"\n";

#[test]
fn a_good_scene_renders_every_output() {
    let scene = write("good.toml", GOOD);
    for (aov, name) in [
        ("color", "c.png"),
        ("color", "c.exr"),
        ("depth", "d.exr"),
        ("normal", "n.png"),
    ] {
        let out = temp(name);
        let output = raypipe(&[
            "render",
            scene.to_str().unwrap(),
            "--device",
            "cpu",
            "--width",
            "40",
            "--height",
            "30",
            "--aov",
            aov,
            "-o",
            out.to_str().unwrap(),
            "--stats",
        ]);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let image = raypipe::image::io::read(&out).unwrap();
        assert_eq!((image.width, image.height), (40, 30));
        if aov == "depth" {
            assert_eq!(image.channels, ["Z"]);
            assert!(image.data.iter().any(|z| z.is_finite()) && image.data.contains(&f32::INFINITY));
        }
        assert!(String::from_utf8_lossy(&output.stdout).contains("Mrays/s"));
    }
}

#[test]
fn diff_exits_by_threshold_and_writes_a_difference_image() {
    let a = temp("diff-a.png");
    let b = temp("diff-b.png");
    let d = temp("diff-d.png");
    for (depth, out) in [("5", &a), ("0", &b)] {
        let output = raypipe(&[
            "render",
            "whitted",
            "--device",
            "cpu",
            "--width",
            "40",
            "--height",
            "30",
            "--depth",
            depth,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(output.status.success());
    }
    let same = raypipe(&["diff", a.to_str().unwrap(), a.to_str().unwrap()]);
    assert_eq!(same.status.code(), Some(0));
    let differ = raypipe(&[
        "diff",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        d.to_str().unwrap(),
        "--threshold",
        "0.001",
    ]);
    assert_eq!(
        differ.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&differ.stdout)
    );
    assert!(String::from_utf8_lossy(&differ.stdout).contains("p99"));
    assert!(d.exists());
}

#[test]
fn cost_aov_writes_a_heat_map_with_a_legend() {
    let out = temp("cost.png");
    let output = raypipe(&[
        "render",
        "random:500",
        "--device",
        "cpu",
        "--accel",
        "stackless",
        "--width",
        "40",
        "--height",
        "30",
        "--aov",
        "cost",
        "--stats",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8_lossy(&output.stdout).contains("cost per primary ray"));
    let image = raypipe::image::io::read(&out).unwrap();
    assert_eq!(image.width, 40);
    assert!(image.height > 30, "the legend sits under the image");
    let exr = raypipe(&[
        "render",
        "random:10",
        "--aov",
        "cost",
        "-o",
        temp("cost.exr").to_str().unwrap(),
    ]);
    assert_clean_error(&exr, &["png"]);
}

#[test]
fn missing_file() {
    assert_clean_error(&render_cpu(Path::new("no/such/scene.toml")), &["no/such/scene.toml"]);
}

#[test]
fn malformed_toml_names_the_line() {
    let path = write("malformed.toml", "[camera]\neye = [0, 1, -6]]\ntarget = [0, 0, 0]\n");
    assert_clean_error(&render_cpu(&path), &["malformed.toml:2"]);
}

#[test]
fn unknown_key_names_the_line() {
    let path = write("unknown-key.toml", &format!("{GOOD}colour = [1, 1, 1]\n"));
    assert_clean_error(&render_cpu(&path), &["unknown-key.toml:", "colour"]);
}

#[test]
fn unknown_material() {
    // Element errors name the line of the element's `[[sphere]]` header.
    let path = write(
        "unknown-material.toml",
        &GOOD.replace("material = \"red\"", "material = \"gold\""),
    );
    assert_clean_error(&render_cpu(&path), &["unknown-material.toml:11", "gold"]);
}

#[test]
fn negative_and_nan_radius() {
    let path = write("negative.toml", &GOOD.replace("radius = 1.0", "radius = -1.0"));
    assert_clean_error(&render_cpu(&path), &["negative.toml:11", "sphere 0", "radius"]);
    let path = write("nan.toml", &GOOD.replace("radius = 1.0", "radius = nan"));
    assert_clean_error(&render_cpu(&path), &["nan.toml:11", "radius"]);
}

#[test]
fn a_sphere_out_of_reach() {
    let path = write("far.toml", &GOOD.replace("radius = 1.0", "radius = 3e38"));
    assert_clean_error(&render_cpu(&path), &["far.toml:11", "sphere 0", "1e30"]);
}

#[test]
fn zero_width() {
    let output = raypipe(&[
        "render",
        "whitted",
        "--device",
        "cpu",
        "--width",
        "0",
        "-o",
        temp("z.png").to_str().unwrap(),
    ]);
    assert_clean_error(&output, &["width"]);
}

#[test]
fn unknown_scene_name() {
    assert_clean_error(&render_cpu(Path::new("wonderland")), &["wonderland", "whitted"]);
    assert_clean_error(&render_cpu(Path::new("random:abc")), &["random:abc"]);
}

#[test]
fn depth_needs_exr() {
    let output = raypipe(&[
        "render",
        "whitted",
        "--aov",
        "depth",
        "-o",
        temp("d.png").to_str().unwrap(),
    ]);
    assert_clean_error(&output, &["exr"]);
}

#[test]
fn diff_of_a_missing_image() {
    let output = raypipe(&["diff", "nope-a.png", "nope-b.png"]);
    assert_clean_error(&output, &["nope-a.png"]);
}
