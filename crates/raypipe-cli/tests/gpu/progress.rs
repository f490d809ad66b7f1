//! Long GPU work shows progress on a terminal: the tracer's compile, the samples of a render, and
//! the frames within each benchmark point.

use crate::common::harness::Test;
use crate::common::raypipe_on_a_terminal;
use raypipe::gpu::GpuContext;

fn gpu_renders_and_bench_points_show_progress(_: &GpuContext) {
    let dir = crate::common::test_dir("progress");
    let out = dir.join("spp.png");
    let (ok, shown) = raypipe_on_a_terminal(&[
        "render",
        "whitted",
        "--device",
        "gpu",
        "--spp",
        "6",
        "--width",
        "48",
        "--height",
        "32",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{shown}");
    assert!(
        shown.contains("compiling the tracer"),
        "no word of the compile: {shown}"
    );
    assert!(shown.contains("/6 samples"), "no sample count shown: {shown}");

    let bench = dir.join("bench");
    let (ok, shown) = raypipe_on_a_terminal(&[
        "bench",
        "--counts",
        "200",
        "--accel",
        "brute",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--width",
        "32",
        "--height",
        "24",
        "--out",
        bench.to_str().unwrap(),
    ]);
    assert!(ok, "{shown}");
    assert!(
        shown.contains("frame 4 of 4"),
        "no frame within the point shown: {shown}"
    );
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![gpu gpu_renders_and_bench_points_show_progress]
}
