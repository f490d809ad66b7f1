//! Surfaces and Whitted shading: the twin of `shaders/shade.wgsl`.

use super::intersect::{Hit, HitKind, Ray, v3};
use super::trace::Tracer;
use crate::scene::packed::GpuMaterial;
use glam::Vec3;

/// Secondary rays start this far (scaled by the point's magnitude) off the surface, to escape it.
pub const RAY_BIAS: f32 = 1e-4;

#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub position: Vec3,
    /// Geometric, unit, pointing out of the primitive.
    pub normal: Vec3,
    pub material: u32,
}

/// WGSL's `reflect(e1, e2)`: e1 - 2 dot(e2, e1) e2.
pub fn reflect(incident: Vec3, normal: Vec3) -> Vec3 {
    incident - 2.0 * normal.dot(incident) * normal
}

impl Tracer<'_> {
    pub fn surface_at(&self, ray: &Ray, hit: &Hit) -> Surface {
        let position = ray.origin + hit.t * ray.dir;
        if hit.kind == HitKind::Sphere {
            let sphere = &self.scene.spheres[hit.index as usize];
            return Surface {
                position,
                normal: (position - v3(sphere.center)).normalize(),
                material: sphere.material,
            };
        }
        let plane = &self.scene.planes[hit.index as usize];
        let local = position - v3(plane.point);
        let cell = (local.dot(v3(plane.tangent)) / plane.checker_size).floor()
            + (local.dot(v3(plane.bitangent)) / plane.checker_size).floor();
        let mut material = plane.material;
        if cell - 2.0 * (cell * 0.5).floor() != 0.0 {
            material = plane.checker_material;
        }
        Surface {
            position,
            normal: v3(plane.normal),
            material,
        }
    }

    /// Ambient plus, for every light that the surface faces and that nothing blocks, Lambert and
    /// Phong. `normal` faces the viewer; `view` points from the surface to the viewer.
    pub fn direct_light(&mut self, surface: &Surface, normal: Vec3, view: Vec3, material: &GpuMaterial) -> Vec3 {
        let globals = &self.scene.globals;
        let albedo = v3(material.color);
        let mut color = globals.ambient * albedo;
        let origin = offset_origin(surface.position, normal);
        for light in &self.scene.lights {
            let to_light = v3(light.position) - surface.position;
            let distance = to_light.length();
            let l = to_light / distance;
            let n_dot_l = normal.dot(l);
            if n_dot_l <= 0.0 {
                continue;
            }
            self.ray_count += 1;
            if self.occluded(&Ray { origin, dir: l }, distance) {
                continue;
            }
            let mut highlight = 0.0;
            let r_dot_v = reflect(-l, normal).dot(view);
            if r_dot_v > 0.0 && material.specular > 0.0 {
                highlight = material.specular * r_dot_v.powf(material.shininess);
            }
            color += v3(light.color) * (albedo * n_dot_l + Vec3::splat(highlight));
        }
        color
    }
}

/// `side` points to where the new ray goes: the facing normal for reflection and shadows, its
/// opposite for refraction.
pub fn offset_origin(position: Vec3, side: Vec3) -> Vec3 {
    let magnitude = position.abs().max_element().max(1.0);
    position + side * (RAY_BIAS * magnitude)
}

/// Schlick's approximation of the Fresnel reflectance; cos_theta is taken on the less dense side.
pub fn fresnel_schlick(cos_theta: f32, ior: f32) -> f32 {
    let r = (1.0 - ior) / (1.0 + ior);
    let r0 = r * r;
    let x = 1.0 - cos_theta;
    let x2 = x * x;
    r0 + (1.0 - r0) * x2 * x2 * x
}
