//! Ray-primitive intersection: the twin of `shaders/intersect.wgsl`.

pub use crate::records::constants::NO_HIT;
use crate::records::constants::{PARALLEL_EPSILON, TINY_DIRECTION};
use crate::records::{GpuPlane, GpuSphere, GpuTriangle};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    /// Unit length: t is a distance.
    pub dir: Vec3,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    None,
    /// A sphere or a triangle: the index is the primitive's (spheres first, then triangles).
    Primitive,
    Plane,
}

/// The closest hit found so far: `t` is t_max while `kind` is `None`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub kind: HitKind,
    pub index: u32,
}

impl Hit {
    pub fn none(t_max: f32) -> Self {
        Self {
            t: t_max,
            kind: HitKind::None,
            index: 0,
        }
    }
}

pub fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

thread_local! {
    /// Nodes tested on this thread (ray-box tests of internal nodes, ray-sphere tests of leaves;
    /// spheres tested for brute force): the shader's private `box_tests`, since one pixel is traced
    /// start to end on one thread.
    static BOX_TESTS: std::cell::Cell<u32> = const { std::cell::Cell::new(0) };
}

pub fn count_box_tests(n: u32) {
    BOX_TESTS.with(|c| c.set(c.get().wrapping_add(n)));
}

pub fn box_tests() -> u32 {
    BOX_TESTS.with(|c| c.get())
}

pub fn reset_box_tests() {
    BOX_TESTS.with(|c| c.set(0));
}

/// The nearest t in (0, t_max] where the ray meets the sphere, or [`NO_HIT`]. t_max itself counts, so
/// that a sphere as near as the best hit so far can still win the tie (see [`closer_primitive`]).
pub fn intersect_sphere(sphere: &GpuSphere, ray: &Ray, t_max: f32) -> f32 {
    let oc = ray.origin - v3(sphere.center);
    let b = oc.dot(ray.dir);
    // Squared distance from the centre to the ray's line, without the cancellation in b*b - c.
    let off_axis = oc - b * ray.dir;
    let discriminant = sphere.radius * sphere.radius - off_axis.dot(off_axis);
    if discriminant < 0.0 {
        return NO_HIT;
    }
    let root = discriminant.sqrt();
    let t_near = -b - root;
    if t_near > 0.0 && t_near <= t_max {
        return t_near;
    }
    let t_far = -b + root;
    if t_far > 0.0 && t_far <= t_max {
        return t_far;
    }
    NO_HIT
}

/// Möller–Trumbore: (u, v, t) where v0 + u e1 + v e2 = origin + t dir. A ray in the triangle's
/// plane (or a degenerate triangle) has det 0 and gets a u that fails every test.
pub fn triangle_uvt(triangle: &GpuTriangle, ray: &Ray) -> Vec3 {
    let (e1, e2) = (v3(triangle.e1), v3(triangle.e2));
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return Vec3::splat(NO_HIT);
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - v3(triangle.v0);
    let q = s.cross(e1);
    Vec3::new(s.dot(p) * inv_det, ray.dir.dot(q) * inv_det, e2.dot(q) * inv_det)
}

/// The t in (0, t_max] where the ray meets the triangle, or [`NO_HIT`]; t_max counts, as for spheres.
pub fn intersect_triangle(triangle: &GpuTriangle, ray: &Ray, t_max: f32) -> f32 {
    let uvt = triangle_uvt(triangle, ray);
    if uvt.x >= 0.0 && uvt.y >= 0.0 && uvt.x + uvt.y <= 1.0 && uvt.z > 0.0 && uvt.z <= t_max {
        return uvt.z;
    }
    NO_HIT
}

/// The primitives in the BVH's order: spheres, then triangles.
#[derive(Clone, Copy)]
pub struct Primitives<'a> {
    pub spheres: &'a [GpuSphere],
    pub triangles: &'a [GpuTriangle],
}

impl Primitives<'_> {
    pub fn count(&self) -> usize {
        self.spheres.len() + self.triangles.len()
    }

    /// Primitive `index`'s hit in (0, t_max], or [`NO_HIT`] (`intersect_primitive`).
    pub fn intersect(&self, index: u32, ray: &Ray, t_max: f32) -> f32 {
        match self.spheres.get(index as usize) {
            Some(sphere) => intersect_sphere(sphere, ray, t_max),
            None => intersect_triangle(&self.triangles[index as usize - self.spheres.len()], ray, t_max),
        }
    }
}

/// Whether primitive `index`, met at t (or [`NO_HIT`]), beats the best hit: nearer, or as near with
/// a lower index, so that coincident primitives resolve the same whatever order a traversal visits
/// them in.
pub fn closer_primitive(t: f32, index: u32, best: &Hit) -> bool {
    t > 0.0 && (t < best.t || (t == best.t && best.kind == HitKind::Primitive && index < best.index))
}

pub fn intersect_plane(plane: &GpuPlane, ray: &Ray, t_max: f32) -> f32 {
    let normal = v3(plane.normal);
    let denom = normal.dot(ray.dir);
    if denom.abs() < PARALLEL_EPSILON {
        return t_max;
    }
    let t = (v3(plane.point) - ray.origin).dot(normal) / denom;
    if t > 0.0 && t < t_max {
        return t;
    }
    t_max
}

/// 1 / dir, with near-zero components replaced so the slab test never computes 0 * inf.
pub fn safe_inverse(dir: Vec3) -> Vec3 {
    let tiny = Vec3::splat(TINY_DIRECTION);
    1.0 / Vec3::select(dir.abs().cmplt(tiny), tiny, dir)
}

/// Where the ray enters the box (0 if it starts inside), if it does so by t_max; else [`NO_HIT`].
pub fn intersect_box(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3, t_max: f32) -> f32 {
    count_box_tests(1);
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let near = t0.min(t1);
    let far = t0.max(t1);
    let t_enter = near.x.max(near.y).max(near.z.max(0.0));
    let t_exit = far.x.min(far.y).min(far.z.min(t_max));
    if t_enter <= t_exit { t_enter } else { NO_HIT }
}

/// Tests a primitive of the BVH; when it beats the best hit, it becomes the best hit and this says
/// so (`hit_primitive`).
pub fn hit_primitive(primitives: &Primitives, index: u32, ray: &Ray, hit: &mut Hit) -> bool {
    count_box_tests(1);
    let t = primitives.intersect(index, ray, hit.t);
    if closer_primitive(t, index, hit) {
        *hit = Hit {
            t,
            kind: HitKind::Primitive,
            index,
        };
        return true;
    }
    false
}

/// Planes are unbounded, so they stay outside any acceleration structure and are always tested.
pub fn closest_plane(planes: &[GpuPlane], ray: &Ray, best: Hit) -> Hit {
    let mut hit = best;
    for (i, plane) in planes.iter().enumerate() {
        let t = intersect_plane(plane, ray, hit.t);
        if t < hit.t {
            hit = Hit {
                t,
                kind: HitKind::Plane,
                index: i as u32,
            };
        }
    }
    hit
}

pub fn any_plane(planes: &[GpuPlane], ray: &Ray, t_max: f32) -> bool {
    planes.iter().any(|plane| intersect_plane(plane, ray, t_max) < t_max)
}
