//! The tests that need a GPU, on one shared device (see `common::harness`): the fragment shader
//! against the CPU reference, memory modes against each other, the environment, texture filtering, closed-form answers, the GPU LBVH
//! build against the CPU's, per-frame rebuilds, the driver's structures walked by ray queries, a lost device, the
//! display pass, watertight triangles, and scenes
//! at the ends of the accepted numeric range; and the tests of the shared
//! models.

#[path = "../common/mod.rs"]
mod common;

mod analytic;
mod display;
mod environment;
mod filtering;
mod frames;
mod gltf;
mod gpu_build;
mod gpu_vs_cpu;
mod lost;
mod memory_modes;
mod pipelines;
mod rayquery;
mod scale;
mod scans;
mod watertight;

fn main() -> std::process::ExitCode {
    let tests = [
        analytic::tests(),
        display::tests(),
        environment::tests(),
        filtering::tests(),
        frames::tests(),
        gpu_build::tests(),
        gltf::tests(),
        gpu_vs_cpu::tests(),
        lost::tests(),
        memory_modes::tests(),
        pipelines::tests(),
        rayquery::tests(),
        scale::tests(),
        scans::tests(),
        watertight::tests(),
    ];
    common::harness::run(tests.into_iter().flatten().collect())
}
