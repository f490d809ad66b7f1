//! Acceleration modes: the twins of `shaders/accel_*.wgsl`. Each answers the closest sphere hit and
//! whether anything blocks a shadow ray.

use super::intersect::{Hit, HitKind, NO_HIT, Ray, closer_sphere, intersect_sphere, v3};
use crate::bvh::layout::GpuNode;
use crate::scene::packed::GpuSphere;
use glam::Vec3;

/// Brute force: every ray against every sphere (`accel_brute.wgsl`).
pub fn brute_closest(spheres: &[GpuSphere], ray: &Ray, best: Hit) -> Hit {
    let mut hit = best;
    for (i, sphere) in spheres.iter().enumerate() {
        let t = intersect_sphere(sphere, ray, hit.t);
        if closer_sphere(t, i as u32, &hit) {
            hit = Hit {
                t,
                kind: HitKind::Sphere,
                index: i as u32,
            };
        }
    }
    hit
}

pub fn brute_occluded(spheres: &[GpuSphere], ray: &Ray, t_max: f32) -> bool {
    spheres.iter().any(|sphere| {
        let t = intersect_sphere(sphere, ray, t_max);
        t > 0.0 && t < t_max
    })
}

/// 1 / dir, with near-zero components replaced so the slab test never computes 0 * inf.
pub fn safe_inverse(dir: Vec3) -> Vec3 {
    let tiny = Vec3::splat(1e-20);
    1.0 / Vec3::select(dir.abs().cmplt(tiny), tiny, dir)
}

/// Where the ray enters the box (0 if it starts inside), if it does so by t_max; else [`NO_HIT`].
pub fn intersect_box(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3, t_max: f32) -> f32 {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let near = t0.min(t1);
    let far = t0.max(t1);
    let t_enter = near.x.max(near.y).max(near.z.max(0.0));
    let t_exit = far.x.min(far.y).min(far.z.min(t_max));
    if t_enter <= t_exit { t_enter } else { NO_HIT }
}

/// The closest sphere hit that beats `best`; with `shadow`, the first hit nearer than best.t
/// (`traverse_stack` in `accel_stack.wgsl`).
pub fn traverse_stack(nodes: &[GpuNode], spheres: &[GpuSphere], ray: &Ray, best: Hit, shadow: bool) -> Hit {
    let mut hit = best;
    if spheres.is_empty() {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    let mut node = nodes[0];
    if intersect_box(v3(node.min), v3(node.max), ray.origin, inv_dir, hit.t) < 0.0 {
        return hit;
    }
    // Nodes waiting to be visited, with the distance where the ray enters them.
    let mut stack: Vec<(u32, f32)> = Vec::with_capacity(64);
    loop {
        if node.is_leaf() {
            let t = intersect_sphere(&spheres[node.left as usize], ray, hit.t);
            if closer_sphere(t, node.left, &hit) {
                hit = Hit {
                    t,
                    kind: HitKind::Sphere,
                    index: node.left,
                };
                if shadow {
                    return hit;
                }
            }
        } else {
            let left = nodes[node.left as usize];
            let right = nodes[node.right as usize];
            let t_left = intersect_box(v3(left.min), v3(left.max), ray.origin, inv_dir, hit.t);
            let t_right = intersect_box(v3(right.min), v3(right.max), ray.origin, inv_dir, hit.t);
            if t_left >= 0.0 && t_right >= 0.0 {
                // Both: go to the nearer (left on a tie), the other waits.
                if t_right < t_left {
                    stack.push((node.left, t_left));
                    node = right;
                } else {
                    stack.push((node.right, t_right));
                    node = left;
                }
                continue;
            }
            if t_left >= 0.0 {
                node = left;
                continue;
            }
            if t_right >= 0.0 {
                node = right;
                continue;
            }
        }
        // Resume at the next waiting node that the ray enters no farther than the best hit.
        match std::iter::from_fn(|| stack.pop()).find(|&(_, t)| t <= hit.t) {
            Some((index, _)) => node = nodes[index as usize],
            None => break,
        }
    }
    hit
}
