//! Watertight ray-triangle intersection in the fragment shader: from inside closed, finely
//! tessellated meshes, rotated and far from the origin, every one of a million primary rays hits, as
//! on the CPU (tests/cpu/watertight.rs).

use crate::common::closed::{cases, misses};
use crate::common::harness::Test;
use crate::common::render_gpu;
use raypipe::gpu::GpuContext;
use raypipe::modes::{Accel, MemoryMode};

fn no_ray_slips_between_triangles_on_the_gpu(ctx: &GpuContext) {
    let mut leaks = Vec::new();
    for (name, scene) in cases(1024) {
        let frame = render_gpu(ctx, &scene, MemoryMode::Storage, Accel::Threaded);
        let missed = misses(&frame);
        if missed > 0 {
            leaks.push(format!("{name}: {missed} of {} rays", frame.color.len()));
        }
    }
    assert!(leaks.is_empty(), "rays slipped through the mesh: {leaks:?}");
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![gpu no_ray_slips_between_triangles_on_the_gpu]
}
