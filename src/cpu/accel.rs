//! Acceleration modes: the twins of `shaders/accel_*.wgsl`. Each answers the closest sphere hit and
//! whether anything blocks a shadow ray.

use super::intersect::{Hit, HitKind, Ray, intersect_sphere};
use crate::scene::packed::GpuSphere;

/// Brute force: every ray against every sphere (`accel_brute.wgsl`).
pub fn accel_closest(spheres: &[GpuSphere], ray: &Ray, best: Hit) -> Hit {
    let mut hit = best;
    for (i, sphere) in spheres.iter().enumerate() {
        let t = intersect_sphere(sphere, ray, hit.t);
        if t < hit.t {
            hit = Hit {
                t,
                kind: HitKind::Sphere,
                index: i as u32,
            };
        }
    }
    hit
}

pub fn accel_occluded(spheres: &[GpuSphere], ray: &Ray, t_max: f32) -> bool {
    spheres
        .iter()
        .any(|sphere| intersect_sphere(sphere, ray, t_max) < t_max)
}
