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

pub fn tests() -> Vec<Test> {
    crate::tests![gpu bench_reports_every_point_with_the_documented_keys]
}
