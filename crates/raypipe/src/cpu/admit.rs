//! Which hits a ray takes: the twin of `shaders/admit.wgsl`. A triangle's sides and alpha (glTF's
//! doubleSided and alphaMode) decide in the walks' hit test, so that a back face or a masked hole
//! is never the closest hit and never blocks a shadow ray.

use super::intersect::{Hit, HitKind, Ray, closer_primitive, count_box_tests, intersect_sphere, intersect_triangle};
use super::maps::{surface_alpha, triangle_attributes};
use super::shade::normalize_scaled;
use crate::constants::MIN_WEIGHT;
use crate::records::constants::{
    MATERIAL_INDEX_MASK, TRIANGLE_ALPHA_BLEND, TRIANGLE_ALPHA_MASK, TRIANGLE_SINGLE_SIDED,
};
use crate::records::{GpuSphere, GpuTriangle, PackedScene};
use std::cell::Cell;

/// The primitives in the BVH's order (spheres, then triangles), and what the ray being walked asks
/// of them.
#[derive(Clone, Copy)]
pub struct Primitives<'a> {
    /// The sphere records.
    pub spheres: &'a [GpuSphere],
    /// The triangle records.
    pub triangles: &'a [GpuTriangle],
    /// What decides triangles' sides and alpha; `None`: every hit counts (the walks' own tests,
    /// over triangles whose material words carry no flags).
    pub query: Option<RayQuery<'a>>,
}

/// The shader's private `ray_culls_back_faces`, `ray_is_shadow` and `shadow_light`, with the scene
/// whose materials and maps the alpha test reads.
#[derive(Clone, Copy)]
pub struct RayQuery<'a> {
    /// The scene whose materials and texture maps decide.
    pub scene: &'a PackedScene,
    /// Whether single-sided triangles hide their backs from the ray.
    pub culls_back_faces: bool,
    /// For a shadow ray: the share of its light that the blended triangles it passed let through.
    pub shadow_light: Option<&'a Cell<f32>>,
}

impl Primitives<'_> {
    /// How many primitives there are: spheres, then triangles.
    pub fn count(&self) -> usize {
        self.spheres.len() + self.triangles.len()
    }

    /// Primitive `index`'s hit in (0, t_max], or [`NO_HIT`](super::intersect::NO_HIT)
    /// (`intersect_primitive`).
    pub fn intersect(&self, index: u32, ray: &Ray, t_max: f32) -> f32 {
        match self.spheres.get(index as usize) {
            Some(sphere) => intersect_sphere(sphere, ray, t_max),
            None => intersect_triangle(&self.triangles[index as usize - self.spheres.len()], ray, t_max),
        }
    }

    /// Whether the ray takes its hit of primitive `index` (spheres always): `primitive_stops_ray`.
    pub fn stops_ray(&self, index: u32, ray: &Ray) -> bool {
        let Some(query) = &self.query else {
            return true;
        };
        match (index as usize).checked_sub(self.spheres.len()) {
            Some(i) => triangle_stops_ray(query, &self.triangles[i], ray),
            None => true,
        }
    }
}

/// Whether the ray takes its hit of the triangle (`triangle_stops_ray`): not where it sees the back
/// of a single-sided triangle and culls back faces, not where alpha MASK cuts the triangle away. A
/// shadow ray passes a BLEND triangle, keeping (1 - alpha) of its light, until too little is left.
fn triangle_stops_ray(query: &RayQuery, triangle: &GpuTriangle, ray: &Ray) -> bool {
    let flags = triangle.material & !MATERIAL_INDEX_MASK;
    if flags == 0 {
        return true;
    }
    if flags & TRIANGLE_SINGLE_SIDED != 0 && query.culls_back_faces {
        let [v0, v1, v2] = triangle.corners();
        if normalize_scaled((v1 - v0).cross(v2 - v0)).dot(ray.dir) >= 0.0 {
            return false;
        }
    }
    if flags & (TRIANGLE_ALPHA_MASK | TRIANGLE_ALPHA_BLEND) == 0 {
        return true;
    }
    let material = &query.scene.materials[(triangle.material & MATERIAL_INDEX_MASK) as usize];
    let alpha = surface_alpha(query.scene, material, &triangle_attributes(query.scene, triangle, ray));
    if flags & TRIANGLE_ALPHA_MASK != 0 {
        return alpha >= material.alpha_cutoff;
    }
    let Some(light) = query.shadow_light else {
        return true;
    };
    light.set(light.get() * (1.0 - alpha));
    light.get() < MIN_WEIGHT
}

/// Tests a primitive of the BVH; when it beats the best hit and the ray takes it, it becomes the
/// best hit and this says so (`hit_primitive`).
pub(crate) fn hit_primitive(primitives: &Primitives, index: u32, ray: &Ray, hit: &mut Hit) -> bool {
    count_box_tests(1);
    let t = primitives.intersect(index, ray, hit.t);
    if closer_primitive(t, index, hit) && primitives.stops_ray(index, ray) {
        *hit = Hit {
            t,
            kind: HitKind::Primitive,
            index,
        };
        return true;
    }
    false
}
