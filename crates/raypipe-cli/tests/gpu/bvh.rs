//! `raypipe bvh --json`: one object with the documented keys, for every device and code width, and
//! the same tree statistics from the CPU and the GPU build of one scene; the GPU build names the
//! kernels it ran.

use crate::common::harness::Test;
use crate::common::raypipe;
use raypipe::gpu::GpuContext;
use raypipe::gpu::builders::lbvh::BuildVariant;
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

fn bvh_reports_the_documented_keys_on_the_cpu() {
    let cpu30 = bvh_json(&[]);
    bvh_json(&["--morton-bits", "63"]);
    let sah = bvh_json(&["--builder", "sah"]);
    let cost = |r: &Value| r["sah_cost"].as_f64().expect("sah_cost is a number");
    assert!(
        cost(&sah) <= cost(&cpu30),
        "the SAH builder's tree ({}) costs more than the LBVH's ({})",
        cost(&sah),
        cost(&cpu30)
    );
}

/// The GPU builds from its own Morton codes: it may round the grid's scale differently and so
/// build another valid tree (the CLI validates every tree it reports), but not a worse one.
fn bvh_reports_the_documented_keys_on_the_gpu(ctx: &GpuContext) {
    let variant = BuildVariant::best(ctx).describe();
    for bits in ["30", "63"] {
        let cpu = bvh_json(&["--morton-bits", bits]);
        let gpu = bvh_json(&["--device", "gpu", "--morton-bits", bits]);
        let builder = gpu["builder"].as_str().unwrap_or_default();
        assert!(
            builder.contains(&variant),
            "{builder} does not name the kernels ({variant})"
        );
        let depth = |r: &Value| r["max_depth"].as_i64().unwrap();
        let sah = |r: &Value| r["sah_cost"].as_f64().unwrap();
        assert!(
            (depth(&gpu) - depth(&cpu)).abs() <= 2 && (sah(&gpu) - sah(&cpu)).abs() <= 0.05 * sah(&cpu),
            "{bits}-bit codes: the GPU's tree (depth {}, SAH {}) is not the CPU's (depth {}, SAH {})",
            depth(&gpu),
            sah(&gpu),
            depth(&cpu),
            sah(&cpu)
        );
    }
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        plain bvh_reports_the_documented_keys_on_the_cpu,
        gpu bvh_reports_the_documented_keys_on_the_gpu,
    ]
}
