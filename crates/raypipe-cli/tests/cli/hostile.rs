//! Hostile input and failing outputs: counts that would overflow, files that are not files, outputs
//! that cannot be written or are written by several renders at once, a closed or full standard
//! output. Each ends in exit 0 with a whole file, or exit 2 with one short line; never a panic.

use crate::common::test_dir;
use crate::common::{assert_clean_error, raypipe, raypipe_on_a_terminal, render_on_cpu};
use raypipe_cli::io;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_raypipe")
}

fn path_str(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// whitted at `width` x `height` on the CPU, written to `path`.
fn tiny_render(path: &Path, width: u32, height: u32) {
    render_on_cpu("whitted", path, width, height);
}

/// A tiny OFF model (one triangle), for the model flags.
fn triangle_model(dir: &Path) -> PathBuf {
    let path = dir.join("triangle.off");
    std::fs::write(&path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    path
}

#[test]
fn counts_beyond_what_a_render_takes_are_one_line() {
    let dir = test_dir("hostile-counts");
    let model = triangle_model(&dir);
    for spheres in ["1000000000000", "18446744073709551615", "99999999999999999999999"] {
        let output = raypipe(&["render", path_str(&model), "--spheres", spheres, "--device", "cpu"]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    let scene = dir.join("many.toml");
    std::fs::write(
        &scene,
        format!(
            "[[mesh]]\nfile = \"{}\"\nas = \"spheres\"\nspheres = 9223372036854775807\n",
            path_str(&model)
        ),
    )
    .unwrap();
    assert_clean_error(
        &raypipe(&["render", path_str(&scene), "--device", "cpu"]),
        &["many.toml:1: mesh 0: spheres must be at most 16777215"],
    );
    assert_clean_error(
        &raypipe(&[
            "render",
            "random:16777216",
            "--width",
            "8",
            "--height",
            "8",
            "--device",
            "cpu",
        ]),
        &["16777216 primitives: a render takes at most 16777215"],
    );
    assert_clean_error(
        &raypipe(&["render", "random:99999999999999"]),
        &["count must be an integer in 1..=67108864 (renders take up to 16777215)"],
    );
    let depth = raypipe(&["render", "whitted", "--depth=-1"]);
    assert!(String::from_utf8_lossy(&depth.stderr).contains("0..=32"));
}

#[test]
fn special_files_are_not_read_as_scenes_or_models() {
    let dir = test_dir("hostile-special");
    let link = dir.join("zero.off");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    assert_clean_error(
        &raypipe(&["render", path_str(&link), "--device", "cpu"]),
        &["zero.off: cannot read model file: not a regular file"],
    );
    assert_clean_error(
        &raypipe(&["render", "/dev/zero", "--device", "cpu"]),
        &["/dev/zero: cannot read scene file: not a regular file"],
    );
    let fifo = dir.join("scene.toml");
    let _ = std::fs::remove_file(&fifo);
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    // Opened for reading, a FIFO without a writer would block forever.
    assert_clean_error(
        &raypipe(&["render", path_str(&fifo), "--device", "cpu"]),
        &["scene.toml: cannot read scene file: not a regular file"],
    );
}

/// A zero-filled model gives a line that names the file and quotes a little of it, not all of it.
#[test]
fn errors_never_echo_the_input() {
    let dir = test_dir("hostile-echo");
    let zeros = dir.join("zeros.off");
    std::fs::write(&zeros, vec![0u8; 100_000]).unwrap();
    let output = raypipe(&["render", path_str(&zeros), "--device", "cpu"]);
    assert_clean_error(&output, &["zeros.off:1: expected the keyword OFF"]);
    assert!(output.stderr.len() < 400, "{} bytes of error", output.stderr.len());
    let ply = dir.join("bad.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 0 zz\n",
    )
    .unwrap();
    let output = raypipe(&["render", path_str(&ply), "--device", "cpu"]);
    assert_clean_error(&output, &["bad.ply:11:"]);
    assert!(!String::from_utf8_lossy(&output.stderr).contains("String:"));
}

#[test]
fn outputs_that_cannot_be_written_fail_before_the_render() {
    let dir = test_dir("hostile-outputs");
    let missing = dir.join("no-such-folder").join("out.png");
    assert_clean_error(
        &raypipe(&["render", "whitted", "--device", "cpu", "-o", path_str(&missing)]),
        &["out.png: cannot write: no folder"],
    );
    assert_clean_error(
        &raypipe(&["render", "whitted", "--device", "cpu", "-o", "/dev/full"]),
        &["/dev/full: cannot write: No space left on device"],
    );
    assert_clean_error(
        &raypipe(&[
            "render",
            "bounce:50",
            "--frames",
            "2",
            "--device",
            "cpu",
            "-o",
            "f_%65536d.png",
        ]),
        &["a frame number 65536 digits wide; at most 10"],
    );
    // A device is written in place, not replaced.
    let output = raypipe(&[
        "render",
        "whitted",
        "--width",
        "16",
        "--height",
        "12",
        "--device",
        "cpu",
        "-o",
        "/dev/null",
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
    // Writes into `dir` that succeed (a PNG, an EXR, two frames) and one that fails (over a folder):
    // each probes the folder and writes beside its target first; none may leave that behind.
    let folder = dir.join("a-folder");
    std::fs::create_dir_all(folder.join("inside")).unwrap();
    for (output, frames) in [("ok.png", None), ("ok.exr", None), ("f_%02d.png", Some("2"))] {
        let target = dir.join(output);
        let mut args = vec![
            "render",
            "bounce:20",
            "--width",
            "16",
            "--height",
            "12",
            "--device",
            "cpu",
        ];
        if let Some(frames) = frames {
            args.extend(["--frames", frames]);
        }
        args.extend(["-o", path_str(&target)]);
        let output = raypipe(&args);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    }
    assert!(dir.join("ok.png").is_file() && dir.join("ok.exr").is_file() && dir.join("f_01.png").is_file());
    let over_folder = raypipe(&["render", "whitted", "--device", "cpu", "-o", path_str(&folder)]);
    assert_eq!(over_folder.status.code(), Some(2));
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(leftovers.is_empty(), "partial files left behind: {leftovers:?}");
}

/// Four renders of different sizes writing one path at once leave one whole file, of one of them;
/// and an EXR is the same bytes every time.
#[test]
fn concurrent_writers_leave_one_whole_file_and_exr_bytes_repeat() {
    let dir = test_dir("hostile-concurrent");
    for name in ["same.png", "same.exr"] {
        let target = dir.join(name);
        let sizes = [(40, 30), (48, 36), (56, 42), (64, 48)];
        let children: Vec<_> = sizes
            .iter()
            .map(|(w, h)| {
                Command::new(bin())
                    .args([
                        "render",
                        "whitted",
                        "--device",
                        "cpu",
                        "--width",
                        &w.to_string(),
                        "--height",
                    ])
                    .args([&h.to_string(), "-o", path_str(&target)])
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for child in children {
            assert!(child.wait_with_output().unwrap().status.success());
        }
        let image = io::read(&target).unwrap_or_else(|e| panic!("{name} is not a whole image: {e}"));
        assert!(
            sizes.contains(&(image.width, image.height)),
            "{name}: {}x{}",
            image.width,
            image.height
        );
    }
    let [a, b] = ["a.exr", "b.exr"].map(|name| {
        let path = dir.join(name);
        let output = raypipe(&[
            "render",
            "whitted",
            "--device",
            "cpu",
            "--width",
            "96",
            "--height",
            "72",
            "-o",
            path_str(&path),
        ]);
        assert!(output.status.success());
        std::fs::read(path).unwrap()
    });
    assert!(a == b, "two EXR files of one render differ");
}

/// A reader that leaves (`| true`) ends the command quietly; a full standard output is one line.
#[test]
fn a_closed_or_full_standard_output_is_no_panic() {
    let script = format!("'{}' bvh random:200000 | true", bin());
    let output = Command::new("sh").args(["-c", &script]).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    let dir = test_dir("hostile-stdout");
    let image = dir.join("a.png");
    tiny_render(&image, 8, 6);
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let output = Command::new(bin())
        .args(["diff", path_str(&image), path_str(&image)])
        .stdout(full)
        .output()
        .unwrap();
    assert_clean_error(&output, &["standard output: No space left on device"]);
}

#[test]
fn thresholds_that_are_not_numbers_or_below_zero_are_refused() {
    let dir = test_dir("hostile-threshold");
    let image = dir.join("a.png");
    tiny_render(&image, 8, 6);
    for threshold in ["nan", "inf", "-1", "-0.5", "many"] {
        let flag = format!("--threshold={threshold}");
        let output = raypipe(&["diff", path_str(&image), path_str(&image), &flag]);
        assert_eq!(output.status.code(), Some(2), "--threshold {threshold} was taken");
        assert!(String::from_utf8_lossy(&output.stderr).contains("--threshold"));
    }
}

#[test]
fn messages_name_the_files_and_the_backend() {
    let dir = test_dir("hostile-messages");
    let [small, large] = [(8, 6), (16, 12)].map(|(w, h)| {
        let path = dir.join(format!("{w}x{h}.png"));
        tiny_render(&path, w, h);
        path
    });
    assert_clean_error(
        &raypipe(&["diff", path_str(&small), path_str(&large)]),
        &["8x6.png and ", "16x12.png: images differ in size"],
    );
    assert_clean_error(
        &raypipe(&["diff", path_str(&small), path_str(&small), "--out", "x.jpg"]),
        &["x.jpg: --out writes a .png or .exr file"],
    );
    let output = Command::new(bin())
        .args([
            "render",
            "whitted",
            "--width",
            "8",
            "--height",
            "6",
            "-o",
            path_str(&dir.join("b.png")),
        ])
        .env("WGPU_BACKEND", "vulkn")
        .output()
        .unwrap();
    assert_clean_error(&output, &["WGPU_BACKEND=\"vulkn\" names no backend"]);
}

/// Legal but probably unmeant scenes render, with one warning line; a render says where it wrote
/// unless -q.
#[test]
fn empty_scenes_warn_and_renders_say_where_they_wrote() {
    let dir = test_dir("hostile-empty");
    let out = dir.join("out.png");
    for (name, text, warning) in [
        ("empty.toml", "", "holds nothing to hit"),
        (
            "dark.toml",
            "[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n",
            "has no lights",
        ),
    ] {
        let scene = dir.join(name);
        std::fs::write(&scene, text).unwrap();
        let output = raypipe(&[
            "render",
            path_str(&scene),
            "--device",
            "cpu",
            "--width",
            "8",
            "--height",
            "6",
            "-o",
            path_str(&out),
        ]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{stderr}");
        let warnings: Vec<_> = stderr.lines().filter(|l| l.starts_with("warning:")).collect();
        assert!(warnings.len() == 1 && warnings[0].contains(warning), "{stderr}");
        assert!(stderr.contains(&format!("wrote {}", out.display())), "{stderr}");
    }
    let quiet = raypipe(&[
        "render",
        "whitted",
        "--device",
        "cpu",
        "--width",
        "8",
        "--height",
        "6",
        "-q",
        "-o",
        path_str(&out),
    ]);
    assert!(
        quiet.status.success() && quiet.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&quiet.stderr)
    );
}

/// A scene of one triangle model, lit, with every length times `scale`.
fn scaled_mesh_scene(model: &Path, scale: f32) -> String {
    let s = |v: f32| format!("{:e}", v * scale);
    format!(
        "[camera]\neye = [{}, {}, {}]\ntarget = [{}, {}, 0]\n\
         [[light]]\nposition = [{}, {}, {}]\n\
         [[mesh]]\nfile = \"{}\"\nnormalize = false\nscale = {scale:e}\n",
        s(0.3),
        s(0.3),
        s(-3.0),
        s(0.3),
        s(0.3),
        s(1.0),
        s(2.0),
        s(-4.0),
        model.display()
    )
}

/// Near the numeric limits, scenes either render as they do at unit size or are refused with the
/// limit that applies (not a false reason).
#[test]
fn numbers_near_the_limits_render_right_or_say_which_limit() {
    let dir = test_dir("hostile-range");
    let model = triangle_model(&dir);
    let render = |name: &str, text: &str| {
        let scene = dir.join(name);
        std::fs::write(&scene, text).unwrap();
        let out = dir.join(format!("{name}.png"));
        let args = [
            "render",
            path_str(&scene),
            "--device",
            "cpu",
            "--width",
            "24",
            "--height",
            "16",
            "-q",
            "-o",
        ];
        (raypipe(&[&args[..], &[path_str(&out)]].concat()), out)
    };
    // A mesh at 1e10 renders as it does at 1: lit, not shadowed, not lost.
    let (unit, unit_png) = render("unit.toml", &scaled_mesh_scene(&model, 1.0));
    assert!(unit.status.success(), "{}", String::from_utf8_lossy(&unit.stderr));
    let (big, big_png) = render("big.toml", &scaled_mesh_scene(&model, 1e10));
    assert!(big.status.success(), "{}", String::from_utf8_lossy(&big.stderr));
    let pixels = image::open(&unit_png).unwrap().to_rgb8();
    let lit = pixels.pixels().filter(|p| p.0.iter().any(|&c| c > 100)).count();
    assert!(lit > 20, "the lit triangle covers {lit} pixels at unit size");
    let same = raypipe(&["diff", path_str(&unit_png), path_str(&big_png)]);
    assert!(same.status.success(), "{}", String::from_utf8_lossy(&same.stdout));
    // Past the limit, the message names it.
    assert_clean_error(
        &render("huge.toml", &scaled_mesh_scene(&model, 1e19)).0,
        &["must lie within 1e17 of the origin"],
    );
    let light = "[[light]]\nposition = [0, 5, -5]\n";
    let sphere = "[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n";
    for (name, text, needle) in [
        (
            "far-eye.toml",
            format!("[camera]\neye = [1e20, 0, 0]\ntarget = [0, 0, 0]\n{light}{sphere}"),
            "camera: eye must lie within 1e17",
        ),
        (
            "far-light.toml",
            format!("[[light]]\nposition = [1e20, 0, 0]\n{sphere}"),
            "light 0: position must lie within 1e17",
        ),
        (
            "big-sphere.toml",
            format!("{light}[[sphere]]\ncenter = [2e20, 0, 0]\nradius = 1e20\n"),
            "sphere 0: the sphere must lie within 1e17",
        ),
        (
            "tiny-sphere.toml",
            format!("{light}[[sphere]]\ncenter = [0, 0, 0]\nradius = 1e-13\n"),
            "radius must be finite and at least 1e-12",
        ),
    ] {
        assert_clean_error(&render(name, &text).0, &[needle]);
    }
    // A plane normal whose length overflows f32 is still a direction: normalized, accepted.
    let plane = format!("{light}[[plane]]\npoint = [0, -1, 0]\nnormal = [0, 3e38, 3e38]\n");
    let (output, _) = render("plane.toml", &plane);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

/// A sequence of frames shows its progress on a terminal, and says where it wrote.
#[test]
fn frame_sequences_show_progress_on_a_terminal() {
    let out = test_dir("hostile-progress").join("last.png");
    let args = [
        "render",
        "bounce:50",
        "--frames",
        "12",
        "--device",
        "cpu",
        "--width",
        "32",
        "--height",
        "24",
        "-o",
    ];
    let (ok, shown) = raypipe_on_a_terminal(&[&args[..], &[path_str(&out)]].concat());
    assert!(ok, "{shown}");
    assert!(
        shown.contains("frames") && shown.contains("/12"),
        "no frame count shown: {shown}"
    );
    assert!(shown.contains("wrote "), "{shown}");
}

/// One triangle as a .gltf, its buffer a data URI: 3 positions, then 3 u16 indices.
const TRIANGLE_GLTF: &str = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],
"bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
"buffers":[{"byteLength":44,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}]}"#;

#[test]
fn hostile_gltf_files_are_one_line_and_exit_2() {
    let dir = test_dir("hostile-gltf");
    let good = dir.join("triangle.gltf");
    std::fs::write(&good, TRIANGLE_GLTF).unwrap();
    render_on_cpu(path_str(&good), &dir.join("triangle.png"), 16, 12);

    let link = dir.join("zero.glb");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    assert_clean_error(
        &raypipe(&["render", path_str(&link), "--device", "cpu"]),
        &["zero.glb: cannot read glTF file: not a regular file"],
    );
    let zeros = dir.join("zeros.glb");
    std::fs::write(&zeros, vec![0u8; 100_000]).unwrap();
    let output = raypipe(&["render", path_str(&zeros), "--device", "cpu"]);
    assert_clean_error(&output, &["zeros.glb: not a glTF file"]);
    assert!(output.stderr.len() < 400, "{} bytes of error", output.stderr.len());

    for (name, from, to, expected) in [
        (
            "escape.gltf",
            "data:application/octet-stream;base64,",
            "../",
            "buffer 0: URI '../",
        ),
        (
            "absolute.gltf",
            "data:application/octet-stream;base64,",
            "/etc/",
            "buffer 0: URI '/etc/",
        ),
        (
            "count.gltf",
            "\"count\":3,\"type\":\"VEC3\"",
            "\"count\":2147483648,\"type\":\"VEC3\"",
            "accessor 0: count 2147483648",
        ),
        (
            "index.gltf",
            "AAABAAIA",
            "AAABAAMA",
            "mesh 0 primitive 0: accessor 1: index 2 is 3, out of range (3 vertices)",
        ),
        (
            "draco.gltf",
            "\"asset\"",
            "\"extensionsRequired\":[\"KHR_draco_mesh_compression\"],\"asset\"",
            "extension KHR_draco_mesh_compression is required",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, TRIANGLE_GLTF.replace(from, to)).unwrap();
        let output = raypipe(&["render", path_str(&path), "--device", "cpu"]);
        assert_clean_error(&output, &[&format!("{name}: "), expected]);
    }

    // A scene file's glTF mesh: the scene file, its line and mesh table, then the glTF's own error.
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, "[[mesh]]\nfile = \"draco.gltf\"\n").unwrap();
    assert_clean_error(
        &raypipe(&["render", path_str(&scene), "--device", "cpu"]),
        &[
            "scene.toml:1: mesh 0: ",
            "draco.gltf: extension KHR_draco_mesh_compression is required",
        ],
    );
}

/// A flat (not run-length encoded) Radiance HDR of `width` x `height` texels of RGBE (m, m, m, e).
fn flat_hdr(width: u32, height: u32, rgbe: [u8; 4]) -> Vec<u8> {
    let mut bytes = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    for _ in 0..width * height {
        bytes.extend_from_slice(&rgbe);
    }
    bytes
}

#[test]
fn environments_are_read_or_refused_in_one_line() {
    let dir = test_dir("hostile-environment");
    // Mantissa 128 at exponent 129: radiance 1 (Radiance's RGBE, (m + 0.5) / 256 · 2^(e − 128) in
    // some readers: within half a percent).
    let flat = dir.join("flat.hdr");
    std::fs::write(&flat, flat_hdr(8, 4, [128, 128, 128, 129])).unwrap();
    let out = dir.join("lit.exr");
    let output = raypipe(&[
        "render",
        "whitted",
        "--device",
        "cpu",
        "--width",
        "16",
        "--height",
        "12",
        "--environment",
        path_str(&flat),
        "--environment-intensity",
        "0.5",
        "-q",
        "-o",
        path_str(&out),
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let image = io::read(&out).unwrap();
    // The top left corner sees the sky: the environment at half intensity.
    for c in 0..3 {
        assert!((image.data[c] - 0.5).abs() < 0.003, "{:?}", &image.data[..3]);
    }

    let exr = |name: &str, width: u32, height: u32, bad: Option<(u32, u32, f32)>| {
        let mut data = vec![0.25f32; (width * height * 3) as usize];
        if let Some((x, y, value)) = bad {
            data[((y * width + x) * 3 + 1) as usize] = value;
        }
        let path = dir.join(name);
        let image = raypipe::image::FloatImage {
            width,
            height,
            channels: ["R", "G", "B"].map(String::from).to_vec(),
            data,
        };
        io::write(&image, &path).unwrap();
        path
    };
    let render = |environment: &Path, extra: &[&str]| {
        let mut args = vec!["render", "whitted", "--device", "cpu", "--width", "8", "--height", "6"];
        args.extend_from_slice(&["--environment", path_str(environment)]);
        args.extend_from_slice(extra);
        let target = dir.join("never.png");
        args.extend_from_slice(&["-o", path_str(&target)]);
        let output = raypipe(&args);
        assert!(!target.exists(), "{args:?} wrote an image");
        output
    };
    assert_clean_error(
        &render(&exr("square.exr", 8, 8, None), &[]),
        &["square.exr: 8x8: an equirectangular environment is twice as wide as it is high"],
    );
    assert_clean_error(
        &render(&exr("nan.exr", 8, 4, Some((3, 1, f32::NAN))), &[]),
        &["nan.exr: texel (3, 1) is not finite"],
    );
    assert_clean_error(
        &render(&exr("inf.exr", 8, 4, Some((5, 2, f32::INFINITY))), &[]),
        &["inf.exr: texel (5, 2) is not finite"],
    );
    assert_clean_error(
        &render(&exr("negative.exr", 8, 4, Some((0, 3, -1.0))), &[]),
        &["negative.exr: texel (0, 3) is negative"],
    );
    let garbage = dir.join("garbage.hdr");
    std::fs::write(&garbage, b"#?RADIANCE\nthis is no image").unwrap();
    assert_clean_error(&render(&garbage, &[]), &["garbage.hdr: cannot decode Radiance HDR"]);
    let truncated = dir.join("truncated.exr");
    std::fs::write(&truncated, &std::fs::read(exr("whole.exr", 8, 4, None)).unwrap()[..200]).unwrap();
    assert_clean_error(&render(&truncated, &[]), &["truncated.exr: cannot decode OpenEXR"]);
    assert_clean_error(
        &render(&dir.join("missing.hdr"), &[]),
        &["missing.hdr: cannot read environment"],
    );
    let folder = dir.join("folder.hdr");
    std::fs::create_dir_all(&folder).unwrap();
    assert_clean_error(
        &render(&folder, &[]),
        &["folder.hdr: cannot read environment: not a regular file"],
    );
    assert_clean_error(&render(Path::new("/dev/zero"), &[]), &["unknown environment format"]);
    let png = dir.join("sky.png");
    tiny_render(&png, 8, 4);
    assert_clean_error(&render(&png, &[]), &["sky.png: unknown environment format"]);
    assert_clean_error(
        &render(&flat, &["--environment-intensity", "-1"]),
        &["not an intensity"],
    );
    assert_clean_error(
        &render(&flat, &["--environment-rotation", "nan"]),
        &["not a finite number"],
    );
    assert_clean_error(
        &raypipe(&["render", "whitted", "--device", "cpu", "--environment-rotation", "10"]),
        &["--environment-rotation and --environment-intensity need an environment"],
    );
}
