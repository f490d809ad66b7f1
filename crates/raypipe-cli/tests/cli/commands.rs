//! The command line: renders write files, diff exits by threshold, and bad input ends with one line
//! on stderr and exit code 2, never a panic.

use crate::common::{assert_clean_error, raypipe};
use crate::common::{models, test_dir};
// The binary's own image reader, to read back what it wrote.
use raypipe_cli::io;
use std::path::{Path, PathBuf};
use std::process::Output;

fn temp(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write_in(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
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

/// `raypipe render SCENE --device cpu` at 40x30 into `out`, with `extra` flags.
fn render_40x30(scene: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["render", scene, "--device", "cpu", "--width", "40", "--height", "30"];
    args.extend(extra);
    args.extend(["-o", out.to_str().unwrap()]);
    raypipe(&args)
}

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
        let output = render_40x30(scene.to_str().unwrap(), &out, &["--aov", aov, "--stats"]);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let image = io::read(&out).unwrap();
        assert_eq!((image.width, image.height), (40, 30));
        if aov == "depth" {
            assert_eq!(image.channels, ["Z"]);
            assert!(image.data.iter().any(|z| z.is_finite()) && image.data.contains(&f32::INFINITY));
        }
        assert!(String::from_utf8_lossy(&output.stdout).contains("Mrays/s"));
    }
}

/// `--exposure` scales the EXR's radiance by 2^EV and nothing more; the PNG is the tone map of
/// that EXR, sRGB-encoded.
#[test]
fn the_png_is_the_tone_map_of_the_exposed_exr() {
    use raypipe::image::linear_to_srgb;
    use raypipe::image::tonemap::DisplayTransform;
    let scene = write("tonemapped.toml", GOOD);
    let render = |name: &str, extra: &[&str]| {
        let out = temp(name);
        let output = render_40x30(scene.to_str().unwrap(), &out, extra);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        io::read(&out).unwrap()
    };
    let plain = render("plain.exr", &[]);
    let exposed = render("exposed.exr", &["--exposure", "1.5", "--tonemap", "aces"]);
    let scale = 1.5f32.exp2();
    for (a, b) in plain.data.iter().zip(&exposed.data) {
        assert!(
            (b - a * scale).abs() <= 2e-3 * b.abs().max(1e-3),
            "{b} is not 2^1.5 x {a}"
        );
    }
    for tone_map in ["none", "neutral", "aces"] {
        let png = render(
            &format!("{tone_map}.png"),
            &["--exposure", "1.5", "--tonemap", tone_map],
        );
        let transform = DisplayTransform {
            exposure: 0.0,
            tone_map: raypipe::Choice::from_name(tone_map).unwrap(),
        };
        // EXR files list their channels by name: B, G, R.
        let at = |name: &str| exposed.channels.iter().position(|c| c == name).unwrap();
        let (r, g, b) = (at("R"), at("G"), at("B"));
        for (i, pixel) in exposed.data.chunks(3).enumerate() {
            let want = transform.apply([pixel[r], pixel[g], pixel[b]]).map(linear_to_srgb);
            for c in 0..3 {
                let (got, want) = (png.data[i * 3 + c] * 255.0, (want[c] * 255.0).round());
                assert!(
                    (got - want).abs() <= 1.0,
                    "{tone_map}: pixel {i} channel {c}: {got} against {want}"
                );
            }
        }
    }
    // The tone maps differ where the scene is bright.
    assert_ne!(
        render("n.png", &["--tonemap", "neutral"]).data,
        render("c.png", &[]).data
    );
}

#[test]
fn diff_exits_by_threshold_and_writes_a_difference_image() {
    let a = temp("diff-a.png");
    let b = temp("diff-b.png");
    let d = temp("diff-d.png");
    for (depth, out) in [("5", &a), ("0", &b)] {
        let output = render_40x30("whitted", out, &["--depth", depth]);
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
    // The tests' own pass marks by name: the images are equal to themselves, and depth 1 against
    // depth 5 is beyond the colour tolerance.
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    assert_eq!(raypipe(&["diff", a, a, "--tolerance", "exact"]).status.code(), Some(0));
    let beyond = raypipe(&["diff", a, b, "--tolerance", "color"]);
    assert_eq!(
        beyond.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&beyond.stdout)
    );
    assert!(String::from_utf8_lossy(&beyond.stdout).contains("FAIL: "));
    let both = raypipe(&["diff", a, b, "--tolerance", "color", "--metric", "p99"]);
    assert_eq!(
        both.status.code(),
        Some(2),
        "--tolerance and --metric together are refused"
    );
}

/// A grey ramp, and the same ramp with a white 16x16 square: images whose FLIP is known.
fn ramps() -> (PathBuf, PathBuf) {
    let ramp = |patch: bool| raypipe::image::FloatImage {
        width: 64,
        height: 64,
        channels: ["R", "G", "B"].map(String::from).to_vec(),
        data: (0..64 * 64)
            .flat_map(|i| {
                let (x, y) = (i % 64, i / 64);
                let inside = patch && (24..40).contains(&x) && (24..40).contains(&y);
                [if inside { 1.0 } else { x as f32 / 63.0 }; 3]
            })
            .collect(),
    };
    let (a, b) = (temp("ramp.png"), temp("ramp-patched.png"));
    io::write(&ramp(false), &a).unwrap();
    io::write(&ramp(true), &b).unwrap();
    (a, b)
}

/// The FLIP figure printed with the rest, and what `--metric flip` does with it.
fn flip_mean(output: &Output) -> f64 {
    let stdout = String::from_utf8_lossy(&output.stdout);
    let after = stdout
        .split("FLIP mean ")
        .nth(1)
        .unwrap_or_else(|| panic!("no FLIP in {stdout}"));
    after.split_whitespace().next().unwrap().parse().unwrap()
}

/// An image against itself is FLIP 0; the ramp against the patched ramp is FLIP 0.081 (measured
/// with nv-flip 0.1.2: the patch is 6 % of the pixels, plainly visible on the dark half); the
/// threshold applies to the metric asked for, and `--out` writes FLIP's error map.
#[test]
fn diff_reports_flip_and_can_pass_on_it() {
    let (a, b) = ramps();
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    let same = raypipe(&["diff", a, a, "--metric", "flip"]);
    assert_eq!(same.status.code(), Some(0));
    assert_eq!(flip_mean(&same), 0.0);
    let map = temp("flip-map.png");
    let differ = raypipe(&["diff", a, b, "--metric", "flip", "--out", map.to_str().unwrap()]);
    assert_eq!(differ.status.code(), Some(1));
    let flip = flip_mean(&differ);
    assert!((flip - FLIP_OF_THE_PATCH).abs() < 0.005, "FLIP {flip}");
    let written = io::read(&map).unwrap();
    assert_eq!((written.width, written.height), (64, 64));
    let loose = raypipe(&["diff", a, b, "--metric", "flip", "--threshold", "0.2"]);
    assert_eq!(
        loose.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&loose.stdout)
    );
    // The per-pixel p99 of the same pair: the patch covers more than 1 % of the pixels.
    let p99 = raypipe(&["diff", a, b, "--metric", "p99", "--threshold", "0.2"]);
    assert_eq!(p99.status.code(), Some(1));
}

const FLIP_OF_THE_PATCH: f64 = 0.081;

#[test]
fn flip_of_a_depth_image_is_one_line() {
    let depth = temp("flip-depth.exr");
    let output = raypipe(&[
        "render",
        "whitted",
        "--device",
        "cpu",
        "--width",
        "16",
        "--height",
        "12",
        "--aov",
        "depth",
        "-o",
        depth.to_str().unwrap(),
    ]);
    assert!(output.status.success());
    let depth = depth.to_str().unwrap();
    let output = raypipe(&["diff", depth, depth, "--metric", "flip"]);
    assert_clean_error(&output, &["--metric flip compares colour images"]);
}

#[test]
fn model_flags_on_a_scene_that_is_no_model_are_one_line() {
    for flag in [&["--normals", "flat"][..], &["--crease", "30"][..]] {
        let mut args = vec!["render", "whitted", "--device", "cpu"];
        args.extend_from_slice(flag);
        assert_clean_error(&raypipe(&args), &["apply to model files"]);
    }
}

/// `--floor none` leaves a framed model's floor out and `--background` sets what escaping rays
/// see: a torus framed without its floor shows the red background around it, and below it.
#[test]
fn floor_none_and_background_set_what_a_model_stands_in() {
    let dir = test_dir("cli-floor");
    let model = write_in(&dir, "torus.off", &models::off(&models::torus(12, 6)));
    let out = dir.join("floating.png");
    let args = |floor: &str| {
        vec![
            "render".to_string(),
            model.to_str().unwrap().to_string(),
            "--device".into(),
            "cpu".into(),
            "--width".into(),
            "32".into(),
            "--height".into(),
            "24".into(),
            "--background".into(),
            "1,0,0".into(),
            "--floor".into(),
            floor.into(),
            "-o".into(),
            out.to_str().unwrap().into(),
        ]
    };
    let bottom_row_red = |floor: &str| {
        let argv = args(floor);
        let argv: Vec<&str> = argv.iter().map(String::as_str).collect();
        let output = raypipe(&argv);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let image = io::read(&out).unwrap();
        let channels = image.channels.len();
        let row = (image.height - 1) as usize * image.width as usize * channels;
        image.data[row..row + image.width as usize * channels]
            .chunks(channels)
            .all(|p| p[0] > 0.99 && p[1] < 0.01 && p[2] < 0.01)
    };
    assert!(
        bottom_row_red("none"),
        "without its floor the model floats in the background"
    );
    assert!(!bottom_row_red("checker"), "the floor fills the bottom row");
    assert_clean_error(
        &raypipe(&["render", "whitted", "--device", "cpu", "--floor", "none"]),
        &["--floor", "apply to model files"],
    );
    for bad in ["1,0", "1,x,0", "-1,0,0", "nan,0,0"] {
        let output = raypipe(&["render", "whitted", "--device", "cpu", "--background", bad]);
        assert_eq!(output.status.code(), Some(2), "--background {bad}");
    }
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
    let stats = String::from_utf8_lossy(&output.stdout);
    assert!(stats.contains("cost per primary ray"));
    // The process's peak memory, where the system says it.
    if cfg!(target_os = "linux") {
        let peak = stats
            .lines()
            .find_map(|line| line.strip_prefix("memory: peak host "))
            .and_then(|rest| rest.split(' ').next()?.parse::<f64>().ok());
        assert!(peak.is_some_and(|mib| mib > 1.0), "{stats}");
    }
    let image = io::read(&out).unwrap();
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
    assert_clean_error(&render_cpu(&path), &["far.toml:11", "sphere 0", "must lie within 1e17"]);
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

#[test]
fn broken_models_give_one_line_and_exit_code_2() {
    let dir = test_dir("meshes-broken");
    let model = models::torus(6, 4);
    let render = |path: &Path| {
        let out = dir.join("out.png");
        raypipe(&[
            "render",
            path.to_str().unwrap(),
            "--device",
            "cpu",
            "--width",
            "16",
            "--height",
            "12",
            "-o",
            out.to_str().unwrap(),
        ])
    };

    let binary = models::binary_ply(&model, true);
    let truncated = write_in(&dir, "truncated.ply", &binary[..binary.len() - 7]);
    assert_clean_error(&render(&truncated), &["truncated.ply", "face"]);

    let text = String::from_utf8(models::off(&model)).unwrap();
    let bad_index = write_in(
        &dir,
        "bad-index.off",
        text.replace("4 0 1 5 4", "4 0 1 99 4").as_bytes(),
    );
    assert_clean_error(
        &render(&bad_index),
        &["bad-index.off:", "face 0", "vertex index 99 out of range"],
    );

    let text = String::from_utf8(models::ascii_ply(&model)).unwrap();
    let lying = write_in(
        &dir,
        "lying.ply",
        text.replace("element face 24", "element face 30").as_bytes(),
    );
    assert_clean_error(&render(&lying), &["lying.ply", "face"]);

    // The first vertex line, "nx ny nz x y z confidence", gets a NaN x.
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let first_vertex = lines.iter().position(|l| l == "end_header").unwrap() + 1;
    let mut fields: Vec<String> = lines[first_vertex].split(' ').map(String::from).collect();
    fields[3] = "nan".into();
    lines[first_vertex] = fields.join(" ");
    let nan = write_in(&dir, "nan.ply", (lines.join("\n") + "\n").as_bytes());
    assert_clean_error(&render(&nan), &["nan.ply:15:", "nan"]);
    let text = String::from_utf8(models::off(&model)).unwrap();
    let first_vertex = text.lines().nth(3).unwrap();
    let nan = text.replacen(first_vertex, "nan 0 0 0 0 1", 1);
    let nan = write_in(&dir, "nan.off", nan.as_bytes());
    assert_clean_error(&render(&nan), &["nan.off", "vertex 0", "must be finite"]);

    let empty = write_in(&dir, "empty.off", b"OFF\n0 0 0\n");
    assert_clean_error(&render(&empty), &["empty.off", "empty mesh"]);

    let obj = String::from_utf8(models::obj(&model)).unwrap();
    let obj_index = write_in(&dir, "bad-index.obj", format!("{obj}f 1 2 300\n").as_bytes());
    assert_clean_error(&render(&obj_index), &["bad-index.obj:", "out of bounds"]);

    let unknown = write_in(&dir, "model.stl", b"solid x\n");
    assert_clean_error(&render(&unknown), &["model.stl", "unknown model format"]);

    let model_file = write_in(&dir, "torus.off", &models::off(&model));
    let scene = write_in(
        &dir,
        "zero.toml",
        format!(
            "[[mesh]]\nfile = \"{}\"\nas = \"spheres\"\nspheres = 0\n",
            model_file.file_name().unwrap().to_str().unwrap()
        )
        .as_bytes(),
    );
    assert_clean_error(
        &render(&scene),
        &["zero.toml:1:", "mesh 0", "spheres must be at least 1"],
    );
    let scene = write_in(&dir, "missing.toml", b"[[mesh]]\nfile = \"nowhere.ply\"\n");
    assert_clean_error(&render(&scene), &["missing.toml:1:", "nowhere.ply", "cannot read"]);
}

#[test]
fn view_without_a_display_is_one_line() {
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_raypipe"))
        .args(["view", "whitted", "--frames", "1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_clean_error(&output, &["no display"]);
}

/// The frames of `spec` in `ranges` (each an A..B of --frames), written as frame_%03d.png into one
/// folder per call; returns that folder's files by name.
fn sequence(spec: &str, dir_name: &str, ranges: &[&str]) -> Vec<(String, Vec<u8>)> {
    let dir = test_dir(dir_name);
    let pattern = dir.join("frame_%03d.png");
    for range in ranges {
        let out = raypipe(&[
            "render",
            spec,
            "--device",
            "cpu",
            "--width",
            "32",
            "--height",
            "24",
            "--frames",
            range,
            "--time",
            "0.2",
            "-q",
            "-o",
            pattern.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            (
                path.file_name().unwrap().to_string_lossy().to_string(),
                std::fs::read(&path).unwrap(),
            )
        })
        .collect();
    files.sort();
    files
}

/// A sequence split into two runs (as a batch scheduler splits it) writes the files of one whole
/// run, byte for byte; frames differ as the scene moves.
#[test]
fn a_split_sequence_equals_one_run_byte_for_byte() {
    let mut specs = vec!["bounce:40".to_string()];
    if let Some(models) = crate::common::harness::models_dir() {
        specs.push(models.join("gltf/RiggedSimple.gltf").to_string_lossy().to_string());
    }
    for (k, spec) in specs.iter().enumerate() {
        let whole = sequence(spec, &format!("sequence-whole-{k}"), &["0..10"]);
        let split = sequence(spec, &format!("sequence-split-{k}"), &["0..4", "4..10"]);
        assert_eq!(whole.len(), 10, "{spec}");
        assert_eq!(whole, split, "{spec}");
        assert_ne!(whole[0].1, whole[9].1, "{spec}: the scene moves");
        assert_eq!(whole[3].0, "frame_003.png");
    }
}

/// Binned SAH builds another tree, which must not change a pixel: the closest hit does not depend
/// on the order a walk meets primitives in (ties go to the lower index). Where the scene moves, the
/// tree is rebuilt every frame by the LBVH, so `--builder sah` is refused there.
#[test]
fn the_sah_builder_renders_the_same_image_and_refuses_motion() {
    let dir = test_dir("builder");
    let image = |builder: &str| {
        let path = dir.join(format!("{builder}.png"));
        let out = raypipe(&[
            "render",
            "random:300",
            "--device",
            "cpu",
            "--width",
            "64",
            "--height",
            "48",
            "--accel",
            "stack",
            "--builder",
            builder,
            "--stats",
            "-o",
            path.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let said = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(said.contains(&format!("bvh: {builder} on the CPU in ")), "{said}");
        std::fs::read(path).unwrap()
    };
    assert_eq!(image("sah"), image("lbvh"));
    let out = raypipe(&[
        "render",
        "bounce:10",
        "--device",
        "cpu",
        "--builder",
        "sah",
        "--frames",
        "0..2",
        "-o",
        "f_%03d.png",
    ]);
    assert_clean_error(&out, &["--builder sah builds a still scene's tree once"]);
}

#[test]
fn time_and_frames_need_a_moving_scene_and_good_ranges() {
    let out = raypipe(&["render", "whitted", "--device", "cpu", "--time", "1", "-o", "/dev/null"]);
    assert_clean_error(&out, &["--time and --loop apply to moving scenes"]);
    for bad in ["5..5", "x", "3..1"] {
        let out = raypipe(&[
            "render",
            "bounce:10",
            "--device",
            "cpu",
            "--frames",
            bad,
            "-o",
            "/dev/null",
        ]);
        assert_eq!(out.status.code(), Some(2), "--frames {bad}");
    }
    let out = raypipe(&[
        "render",
        "bounce:10",
        "--device",
        "cpu",
        "--fps",
        "0",
        "-o",
        "/dev/null",
    ]);
    assert_eq!(out.status.code(), Some(2));
}
