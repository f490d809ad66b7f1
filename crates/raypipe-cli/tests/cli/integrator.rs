//! The integrator a render takes: the scene's own (path for a glTF file, Whitted for the paper's
//! scenes) unless --integrator says, and the samples each takes by default.

use crate::common::{raypipe, test_dir};

/// A glTF file renders path traced at the samples the figures chose unless --spp says otherwise;
/// the paper's scenes at one sample with Whitted's light; --integrator swaps either.
#[test]
fn a_gltf_file_is_path_traced_at_its_default_samples() {
    let dir = test_dir("integrator-defaults");
    let out = dir.join("image.png");
    let says = |args: &[&str]| {
        let mut all = vec!["render"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--device", "cpu", "--width", "16", "--height", "12", "--stats", "-o"]);
        all.push(out.to_str().unwrap());
        let output = raypipe(&all);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        String::from_utf8_lossy(&output.stdout).to_string()
    };
    let device_line = |text: String| text.lines().find(|l| l.starts_with("device:")).unwrap().to_string();
    let whitted = device_line(says(&["whitted"]));
    assert!(
        whitted.ends_with("integrator whitted, 1 samples per pixel"),
        "{whitted}"
    );
    let path = device_line(says(&["whitted", "--integrator", "path"]));
    assert!(
        path.ends_with(&format!(
            "integrator path, {} samples per pixel",
            raypipe_cli::render::PATH_SAMPLES
        )),
        "{path}"
    );
    let Some(models) = crate::common::harness::models_dir() else {
        return;
    };
    let gltf = models.join("gltf/BoxTextured.gltf");
    let gltf = gltf.to_str().unwrap();
    let line = device_line(says(&[gltf]));
    assert!(line.contains("integrator path, 128 samples per pixel"), "{line}");
    let line = device_line(says(&[gltf, "--integrator", "whitted", "--spp", "2"]));
    assert!(line.ends_with("integrator whitted, 2 samples per pixel"), "{line}");
}
