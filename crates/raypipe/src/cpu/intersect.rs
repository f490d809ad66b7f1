//! Ray-primitive intersection: the twin of `shaders/intersect.wgsl`.

pub use crate::constants::NO_HIT;
use crate::constants::{PARALLEL_EPSILON, TINY_DIRECTION};
use crate::records::{GpuPlane, GpuSphere, GpuTriangle};
use glam::{Vec3, Vec3Swizzles};

/// A ray: its origin and unit direction, with its shear for the watertight triangle test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Unit length: t is a distance.
    pub dir: Vec3,
    /// For the triangle test, worked out once per ray.
    pub shear: RayShear,
}

impl Ray {
    /// The shader's `make_ray`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            shear: ray_shear(dir),
        }
    }
}

/// The shear that takes a ray to the frame where it starts at the origin and runs along +z (Woop,
/// Benthin and Wald 2013): the frame's z is the direction's dominant axis, its x and y the other two
/// (swapped where the ray points down that axis, which keeps the triangles' winding); `s` holds
/// (dir.x / dir.z, dir.y / dir.z, 1 / dir.z) in the frame's axes. As in the shader, the axes are
/// choices between swizzles (`shear_axes`), which GPU compilers keep in registers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayShear {
    /// The frame's z is world x (`z_is_x`), world y (`z_is_y`), or world z.
    pub z_is_x: bool,
    /// See `z_is_x`.
    pub z_is_y: bool,
    /// The frame's x and y are the remaining axes in reverse cyclic order.
    pub swap_xy: bool,
    /// (dir.x / dir.z, dir.y / dir.z, 1 / dir.z) in the frame's axes.
    pub s: Vec3,
}

/// `v`'s components in the frame's axis order: exact, a permutation.
pub(crate) fn shear_axes(v: Vec3, shear: &RayShear) -> Vec3 {
    let cyclic = if shear.z_is_x {
        v.yzx()
    } else if shear.z_is_y {
        v.zxy()
    } else {
        v
    };
    if shear.swap_xy { cyclic.yxz() } else { cyclic }
}

pub(crate) fn ray_shear(dir: Vec3) -> RayShear {
    let a = dir.abs();
    let mut shear = RayShear {
        z_is_x: a.x > a.y && a.x > a.z,
        z_is_y: false,
        swap_xy: false,
        s: Vec3::ZERO,
    };
    shear.z_is_y = !shear.z_is_x && a.y > a.z;
    // The swap leaves z where it is.
    shear.swap_xy = shear_axes(dir, &shear).z < 0.0;
    let d = shear_axes(dir, &shear);
    let sz = 1.0 / d.z;
    shear.s = Vec3::new(d.x * sz, d.y * sz, sz);
    shear
}

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    /// Nothing, before `t_max`.
    None,
    /// A sphere or a triangle: the index is the primitive's (spheres first, then triangles).
    Primitive,
    /// One of the scene's infinite planes.
    Plane,
}

/// The closest hit found so far: `t` is t_max while `kind` is `None`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The hit's distance along the ray.
    pub t: f32,
    /// What was hit.
    pub kind: HitKind,
    /// Which primitive or plane.
    pub index: u32,
}

impl Hit {
    /// No hit yet, with `t_max` the farthest a hit may lie.
    pub fn none(t_max: f32) -> Self {
        Self {
            t: t_max,
            kind: HitKind::None,
            index: 0,
        }
    }
}

pub(crate) fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

thread_local! {
    /// Nodes tested on this thread (ray-box tests of internal nodes, ray-sphere tests of leaves;
    /// spheres tested for brute force): the shader's private `box_tests`, since one pixel is traced
    /// start to end on one thread.
    static BOX_TESTS: std::cell::Cell<u32> = const { std::cell::Cell::new(0) };
}

pub(crate) fn count_box_tests(n: u32) {
    BOX_TESTS.with(|c| c.set(c.get().wrapping_add(n)));
}

pub(crate) fn box_tests() -> u32 {
    BOX_TESTS.with(|c| c.get())
}

pub(crate) fn reset_box_tests() {
    BOX_TESTS.with(|c| c.set(0));
}

/// The nearest t in (0, t_max] where the ray meets the sphere, or [`NO_HIT`]. t_max itself counts, so
/// that a sphere as near as the best hit so far can still win the tie (see [`closer_primitive`]).
pub(crate) fn intersect_sphere(sphere: &GpuSphere, ray: &Ray, t_max: f32) -> f32 {
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

/// A corner in the ray's sheared frame: xy where the ray passes through (0, 0), z scaled so that
/// the hit's t comes out of the barycentric blend of the corners' z.
pub(crate) fn sheared(corner: Vec3, ray: &Ray) -> Vec3 {
    let p = shear_axes(corner - ray.origin, &ray.shear);
    let s = ray.shear.s;
    Vec3::new(p.x - s.x * p.z, p.y - s.y * p.z, s.z * p.z)
}

/// p.x q.y - p.y q.x, with the pair taken in one fixed order: the triangle across an edge meets it
/// as (q, p) and gets exactly the negated value, as in the shader, where the compiler may fuse
/// multiply-adds.
pub(crate) fn edge_function(p: glam::Vec2, q: glam::Vec2) -> f32 {
    if p.x < q.x || (p.x == q.x && p.y < q.y) {
        p.x * q.y - p.y * q.x
    } else {
        -(q.x * p.y - q.y * p.x)
    }
}

/// The watertight ray-triangle test (Woop, Benthin and Wald 2013): (u, v, t) where
/// (1 - u - v) v0 + u v1 + v v2 = origin + t dir, or [`NO_HIT`] in every component where the ray
/// passes outside. Two triangles sharing an edge compute that edge's function from the same sheared
/// corners, so a ray through the edge hits one of them (or both), never neither. A ray in the
/// triangle's plane (or a degenerate triangle) has det 0 and misses.
pub(crate) fn triangle_uvt(triangle: &GpuTriangle, ray: &Ray) -> Vec3 {
    let [a, b, c] = triangle.corners().map(|corner| sheared(corner, ray));
    let u = edge_function(c.truncate(), b.truncate());
    let v = edge_function(a.truncate(), c.truncate());
    let w = edge_function(b.truncate(), a.truncate());
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return Vec3::splat(NO_HIT);
    }
    let det = u + v + w;
    if det == 0.0 {
        return Vec3::splat(NO_HIT);
    }
    // Weights first, then depths: an edge function is already a product of two coordinates, and
    // times a depth it would overflow near the accepted range's end (MAX_COORDINATE).
    let inv_det = 1.0 / det;
    let weights = Vec3::new(u, v, w) * inv_det;
    Vec3::new(
        weights.y,
        weights.z,
        weights.x * a.z + weights.y * b.z + weights.z * c.z,
    )
}

/// The t in (0, t_max] where the ray meets the triangle, or [`NO_HIT`]; t_max counts, as for spheres.
pub(crate) fn intersect_triangle(triangle: &GpuTriangle, ray: &Ray, t_max: f32) -> f32 {
    let t = triangle_uvt(triangle, ray).z;
    if t > 0.0 && t <= t_max { t } else { NO_HIT }
}

/// Whether primitive `index`, met at t (or [`NO_HIT`]), beats the best hit: nearer, or as near with
/// a lower index, so that coincident primitives resolve the same whatever order a traversal visits
/// them in.
pub(crate) fn closer_primitive(t: f32, index: u32, best: &Hit) -> bool {
    t > 0.0 && (t < best.t || (t == best.t && best.kind == HitKind::Primitive && index < best.index))
}

pub(crate) fn intersect_plane(plane: &GpuPlane, ray: &Ray, t_max: f32) -> f32 {
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
pub(crate) fn safe_inverse(dir: Vec3) -> Vec3 {
    let tiny = Vec3::splat(TINY_DIRECTION);
    1.0 / Vec3::select(dir.abs().cmplt(tiny), tiny, dir)
}

/// Where the ray enters the box (0 if it starts inside), if it does so by t_max; else [`NO_HIT`].
pub(crate) fn intersect_box(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3, t_max: f32) -> f32 {
    count_box_tests(1);
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let swap = t1.cmplt(t0);
    let near = Vec3::select(swap, t1, t0);
    let far = Vec3::select(swap, t0, t1);
    let t_enter = larger(larger(near.x, near.y), larger(near.z, 0.0));
    let t_exit = smaller(smaller(far.x, far.y), smaller(far.z, t_max));
    if t_enter <= t_exit { t_enter } else { NO_HIT }
}

/// The larger of two numbers that are not NaN (`larger` in the shader).
fn larger(a: f32, b: f32) -> f32 {
    if b > a { b } else { a }
}

/// The smaller of two numbers that are not NaN (`smaller` in the shader).
fn smaller(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

/// Planes are unbounded, so they stay outside any acceleration structure and are always tested.
pub(crate) fn closest_plane(planes: &[GpuPlane], ray: &Ray, best: Hit) -> Hit {
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

pub(crate) fn any_plane(planes: &[GpuPlane], ray: &Ray, t_max: f32) -> bool {
    planes.iter().any(|plane| intersect_plane(plane, ray, t_max) < t_max)
}
