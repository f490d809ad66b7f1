//! `raypipe bench`: every point is timed and reported with the documented keys, in CSV and JSON.

use crate::common::harness::Test;
use raypipe::gpu::GpuContext;
use std::process::Command;

fn bench_reports_every_point_with_the_documented_keys(_: &GpuContext) {
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench");
    let output = Command::new(env!("CARGO_BIN_EXE_raypipe"))
        .args([
            "bench",
            "random",
            "--counts",
            "200,400",
            "--accel",
            "brute,stack,stackless,threaded",
        ])
        .args([
            "--width", "32", "--height", "24", "--frames", "2", "--warmup", "1", "--json", "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(rows.len(), 16, "two counts times two pipelines times four modes");
    let keys = [
        "count",
        "pipeline",
        "accel",
        "memory",
        "width",
        "height",
        "frames",
        "ms_median",
        "ms_min",
        "ms_max",
        "fps",
        "mrays_per_s",
        "adapter",
        "backend",
    ];
    for row in &rows {
        for key in keys {
            assert!(row.get(key).is_some(), "{key} missing from {row}");
        }
        let (min, median, max) = (
            row["ms_min"].as_f64().unwrap(),
            row["ms_median"].as_f64().unwrap(),
            row["ms_max"].as_f64().unwrap(),
        );
        assert!(0.0 < min && min <= median && median <= max, "{row}");
        assert!(row["mrays_per_s"].as_f64().unwrap() > 0.0);
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 17, "a header and sixteen rows");
    assert!(csv.starts_with("count,pipeline,accel,"), "{csv}");
    for pipeline in ["fragment", "compute"] {
        let rows_of = rows.iter().filter(|r| r["pipeline"] == pipeline).count();
        assert_eq!(rows_of, 8, "{pipeline}: a row per count and mode");
    }
    assert!(out.join("results.json").exists());
    let plot = image::open(out.join("fps.png")).unwrap();
    assert!(plot.width() > 100 && plot.height() > 100);
    let svg = std::fs::read_to_string(out.join("fps.svg")).unwrap();
    assert!(
        svg.contains("<svg") && svg.contains("stackless, compute") && svg.contains("stackless, fragment"),
        "the SVG names its lines, one per pipeline"
    );
}

/// A model's triangles are one point whose count is the mesh's; with --rebuild every row has the
/// build's phases; the results are written as each point finishes.
fn bench_times_a_models_triangles_with_build_phases(ctx: &GpuContext) {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-triangles");
    std::fs::create_dir_all(&dir).unwrap();
    // An octahedron: eight triangles.
    let model = dir.join("octahedron.off");
    std::fs::write(
        &model,
        "OFF\n6 8 0\n1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n\
         3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n",
    )
    .unwrap();
    let out = dir.join("results");
    let output = Command::new(env!("CARGO_BIN_EXE_raypipe"))
        .arg("bench")
        .arg(&model)
        .args([
            "--as",
            "triangles",
            "--accel",
            "brute,threaded",
            "--rebuild",
            "--width",
            "32",
        ])
        .args(["--height", "24", "--frames", "2", "--warmup", "1", "--json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(rows.len(), 4, "one point: two pipelines times two modes");
    for row in &rows {
        assert_eq!(row["count"], 8, "{row}");
        let phases = &row["build_phases_ms"];
        if row["accel"] == "brute" {
            assert!(phases.is_null(), "brute force builds nothing: {row}");
        } else {
            for phase in ["morton", "sort", "hierarchy", "bounds", "links", "layout"] {
                assert!(phases[phase].as_f64().is_some_and(|ms| ms >= 0.0), "{phase} in {row}");
            }
            // The threaded walk's 16-byte layout is timed as its own phase.
            assert_eq!(phases["layout"].as_f64().unwrap() > 0.0, ctx.timestamps, "{row}");
        }
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("build_phases_ms.sort"), "{csv}");
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("build_phases_ms.links,build_phases_ms.layout,"),
        "{csv}"
    );
    assert_eq!(csv.lines().count(), 5, "{csv}");
}

/// `bench --motion --refit` on a skinned mesh from scripts/skinned-mesh.py: every point split into
/// its parts, skinning and the build on the GPU in storage memory and on the CPU in texture
/// memory, and a refit row per timed frame where a tree is refitted. Without timestamp queries
/// the GPU's phases cannot be told apart: it refuses, exit 2.
fn bench_splits_an_animated_frame_and_compares_refits(ctx: &GpuContext) {
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-motion");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap();
    let mesh = out.join("skinned.glb");
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scripts/skinned-mesh.py");
    let made = Command::new("python3")
        .arg(script)
        .args(["--triangles", "3000", "-o"])
        .arg(&mesh)
        .output()
        .expect("python3 runs scripts/skinned-mesh.py");
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    let output = Command::new(env!("CARGO_BIN_EXE_raypipe"))
        .arg("bench")
        .arg(&mesh)
        .args([
            "--motion",
            "--refit",
            "--memory",
            "storage,texture",
            "--accel",
            "threaded,brute",
        ])
        .args([
            "--width", "48", "--height", "32", "--frames", "2", "--warmup", "1", "--json", "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    if !ctx.timestamps {
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("timestamp queries"), "{stderr}");
        return;
    }
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 8, "two memories, two pipelines, two walks: {report}");
    for point in points {
        let ms = |key: &str| {
            point[key]
                .as_f64()
                .unwrap_or_else(|| panic!("{key} missing from {point}"))
        };
        let on_gpu = point["memory"] == "storage";
        assert_eq!(point["moved_on"], if on_gpu { "gpu" } else { "cpu" }, "{point}");
        assert!(point["triangles"].as_u64().unwrap() >= 3000, "{point}");
        assert!(
            ms("skin_ms") > 0.0 && ms("trace_ms") > 0.0 && ms("eval_ms") >= 0.0,
            "{point}"
        );
        let builds = point["accel"] == "threaded";
        assert_eq!(ms("build_ms") > 0.0, builds, "{point}");
        let total = ms("eval_ms") + ms("skin_ms") + ms("build_ms") + ms("upload_ms") + ms("trace_ms");
        assert!((ms("frame_ms") - total).abs() < 1e-6 * total.max(1.0), "{point}");
        assert_eq!(point["refit_ms"].is_number(), on_gpu && builds, "{point}");
    }
    let refits = report["refit"].as_array().unwrap();
    assert_eq!(refits.len(), 4, "two pipelines, two timed frames: {report}");
    for refit in refits {
        assert!(refit["frame"].as_u64().unwrap() >= 1, "{refit}");
        assert!(refit["refit_ms"].as_f64().unwrap() > 0.0, "{refit}");
    }
    let csv = std::fs::read_to_string(out.join("motion.csv")).unwrap();
    assert_eq!(csv.lines().count(), 9, "{csv}");
    assert_eq!(
        std::fs::read_to_string(out.join("refit.csv")).unwrap().lines().count(),
        5
    );
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu bench_splits_an_animated_frame_and_compares_refits,
        gpu bench_reports_every_point_with_the_documented_keys,
        gpu bench_times_a_models_triangles_with_build_phases,
    ]
}
