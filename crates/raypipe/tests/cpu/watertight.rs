//! Watertight ray-triangle intersection on the CPU reference: from inside closed, finely
//! tessellated meshes, rotated and far from the origin, every one of a million primary rays hits.
//! (The GPU's twin of this test is in the `gpu` harness.)

use crate::common::closed::{cases, misses};
use raypipe::modes::Accel;

#[test]
fn no_ray_slips_between_triangles_on_the_cpu() {
    let mut leaks = Vec::new();
    for (name, scene) in cases(1024) {
        for accel in [Accel::Threaded, Accel::Stackless] {
            let frame = raypipe::cpu::render(&scene, accel).unwrap();
            let missed = misses(&frame);
            if missed > 0 {
                leaks.push(format!("{name}, {accel}: {missed} of {} rays", frame.color.len()));
            }
        }
    }
    assert!(leaks.is_empty(), "rays slipped through the mesh: {leaks:?}");
}
