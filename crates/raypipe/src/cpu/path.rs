//! The path integrator, one path per sample: the twin of `shaders/path.wgsl`, which says what it
//! does.

// `!(x > 0.0)` is true for a NaN, as the shader's tests are: the guards keep NaNs out.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::admit::RayQuery;
use super::brdf::{GltfSurface, max3};
use super::bsdf::{Lobes, path_lobes, punctual_response, reflection_brdf, reflection_pdf, sample_bsdf};
use super::environment::escaped_radiance;
use super::intersect::{Hit, HitKind, Ray, box_tests, reset_box_tests, v3};
use super::sampling::{
    emitter_chance, emitter_pdf, environment_pdf, path_random, power_heuristic, sample_emitter, sample_environment,
};
use super::shade::{
    ShadingFrame, Surface, gltf_surface, light_arrival, lit, normal_mapped, offset_origin, surface_at, surface_material,
};
use super::trace::{PixelTrace, T_FAR, Tracer, cone_reflected, pixel_spread};
use crate::bvh::layout::NONE;
use crate::constants::{MAX_BLEND_LAYERS, MIN_FOOTPRINT_COSINE};
use crate::records::GpuMaterial;
use crate::records::constants::{MODEL_GLTF, MODEL_UNLIT};
use glam::{Vec2, Vec3, Vec4};

/// Bounces before Russian roulette may end a path.
pub const ROULETTE_START: u32 = 3;

/// Shadow rays to an emitter stop this much short of it, so as not to hit it (relative to the
/// distance).
const EMITTER_SHADOW_SHORTENING: f32 = 1e-4;

/// A direction to an area light, the radiance it brings, how far its shadow ray runs, and its
/// density in solid angle (`LightSample`).
struct LightSample {
    dir: Vec3,
    radiance: Vec3,
    distance: f32,
    pdf: f32,
}

impl Tracer<'_> {
    /// The current sample's four numbers of `group` (`path_random`).
    fn path_numbers(&self, group: u32) -> Vec4 {
        path_random(self.path_seed, self.path_sample, group)
    }

    /// The punctual lights' and one environment sample's light at a vertex (`path_direct_light`);
    /// `weighed`: the path goes on, so the environment's light is shared with the BSDF's sample by
    /// the power heuristic.
    #[allow(clippy::too_many_arguments)]
    fn path_direct_light(
        &mut self,
        surface: &Surface,
        frame: ShadingFrame,
        (material, s): (&GpuMaterial, &GltfSurface),
        lobes: &Lobes,
        u: Vec4,
        weighed: bool,
    ) -> Vec3 {
        let scene = self.scene;
        let mut color = Vec3::ZERO;
        let origin = offset_origin(surface, frame.normal);
        for light in &scene.lights {
            let arrival = light_arrival(light, surface.position);
            let l = arrival.dir;
            if frame.shading.dot(l) <= 0.0 || !lit(light, &arrival) {
                continue;
            }
            self.ray_count += 1;
            let Some(share) = self.shadow_ray(&Ray::new(origin, l), arrival.distance) else {
                continue;
            };
            color += arrival.irradiance * share * punctual_response(material, s, frame, l);
        }
        let share = scene.path.globals.environment_share;
        let environment = scene.globals.scene.environment_map != NONE;
        let drawn = if environment && u.x < share {
            let (dir, pdf) = sample_environment(scene, Vec2::new(u.y, u.z));
            Some(LightSample {
                dir,
                radiance: escaped_radiance(scene, dir, 0.0),
                distance: T_FAR,
                pdf: pdf * share,
            })
        } else if !scene.triangles.is_empty() && scene.path.globals.emitter_count > 0 {
            self.emitter_light(origin, Vec3::new((u.x - share) / (1.0 - share), u.y, u.z), 1.0 - share)
        } else {
            None
        };
        let Some(drawn) = drawn else {
            return color;
        };
        let l = drawn.dir;
        let n_dot_l = frame.shading.dot(l);
        if !(drawn.pdf > 0.0) || n_dot_l <= 0.0 || frame.normal.dot(l) <= 0.0 || max3(drawn.radiance) <= 0.0 {
            return color;
        }
        let f = reflection_brdf(material, s, lobes, frame.shading, frame.view, l);
        if max3(f) <= 0.0 {
            return color;
        }
        self.ray_count += 1;
        let Some(share) = self.shadow_ray(&Ray::new(origin, l), drawn.distance) else {
            return color;
        };
        let weight = if weighed {
            power_heuristic(drawn.pdf, reflection_pdf(s, lobes, frame.shading, frame.view, l))
        } else {
            1.0
        };
        color + drawn.radiance * share * f * (n_dot_l * weight / drawn.pdf)
    }

    /// The light of a point drawn on an emitter with `u`, seen from `origin` (offset from the
    /// surface, as the shadow ray and a BSDF sample's ray start), the emitters drawn with `chance`
    /// (`emitter_light`).
    fn emitter_light(&self, origin: Vec3, u: Vec3, chance: f32) -> Option<LightSample> {
        let scene = self.scene;
        let drawn = sample_emitter(scene, u);
        let to_light = drawn.point - origin;
        let distance = to_light.length();
        if !(distance > 0.0) {
            return None;
        }
        let l = to_light / distance;
        let towards = Ray::new(origin, l);
        let query = RayQuery {
            scene,
            culls_back_faces: true,
            shadow_light: None,
        };
        let index = scene.spheres.len() as u32 + drawn.index;
        if !self.primitives(query).stops_ray(index, &towards) {
            return None;
        }
        let hit = Hit {
            t: distance,
            kind: HitKind::Primitive,
            index,
        };
        let emitter = surface_at(scene, &towards, &hit);
        let cos_light = emitter.normal.dot(l).abs();
        let pdf = chance * emitter_pdf(scene, drawn.index, drawn.chance, distance, cos_light);
        Some(LightSample {
            dir: l,
            radiance: v3(surface_material(scene, &emitter).emission),
            distance: distance * (1.0 - EMITTER_SHADOW_SHORTENING),
            pdf,
        })
    }

    /// How much of an emitter's light that a BSDF sample of density `bsdf_pdf` found at `hit`
    /// counts beside the emitter's own sampling (`emission_weight`).
    fn emission_weight(&self, hit: &Hit, surface: &Surface, ray: &Ray, bsdf_pdf: f32) -> f32 {
        let scene = self.scene;
        let spheres = scene.spheres.len() as u32;
        if !(bsdf_pdf > 0.0)
            || scene.path.globals.emitter_count == 0
            || hit.kind != HitKind::Primitive
            || hit.index < spheres
        {
            return 1.0;
        }
        let index = hit.index - spheres;
        let chance = emitter_chance(scene, index);
        if !(chance > 0.0) {
            return 1.0;
        }
        let share = 1.0 - scene.path.globals.environment_share;
        let light_pdf = share * emitter_pdf(scene, index, chance, hit.t, surface.normal.dot(ray.dir).abs());
        power_heuristic(bsdf_pdf, light_pdf)
    }

    /// One path from `primary` (`trace_pixel` in path.wgsl).
    pub(crate) fn trace_path(&mut self, primary: Ray) -> PixelTrace {
        let scene = self.scene;
        let mut result = PixelTrace::default();
        reset_box_tests();
        let environment = scene.globals.scene.environment_map != NONE;
        let mut ray = primary;
        let mut culls = true;
        let mut throughput = Vec3::ONE;
        let mut cone = Vec2::new(0.0, pixel_spread(scene));
        let mut bsdf_pdf = 0.0;
        let mut bounce = 0;
        loop {
            self.ray_count += 1;
            let hit = self.closest_hit(&ray, T_FAR, culls);
            if bounce == 0 && result.depth.is_none() {
                result.cost = box_tests();
            }
            if hit.kind == HitKind::None {
                let weight = if environment && bsdf_pdf > 0.0 && scene.path.globals.table_width > 0 {
                    power_heuristic(
                        bsdf_pdf,
                        scene.path.globals.environment_share * environment_pdf(scene, ray.dir),
                    )
                } else {
                    1.0
                };
                result.color += throughput * escaped_radiance(scene, ray.dir, cone.y) * weight;
                break;
            }
            let mut surface = surface_at(scene, &ray, &hit);
            cone = Vec2::new(cone.x + cone.y * hit.t, cone.y);
            surface.attributes.footprint = cone.x.abs() / surface.normal.dot(ray.dir).abs().max(MIN_FOOTPRINT_COSINE);
            let material = surface_material(scene, &surface);
            surface.shading = normal_mapped(scene, &surface, &material);
            if bounce == 0 && result.depth.is_none() {
                result.normal = surface.shading;
                result.depth = Some(hit.t);
            }
            let entering = surface.normal.dot(ray.dir) < 0.0;
            let flip = |v: Vec3| if entering { v } else { -v };
            let (normal, shading) = (flip(surface.normal), flip(surface.shading));
            let curvature = if entering {
                surface.curvature
            } else {
                -surface.curvature
            };
            let frame = ShadingFrame {
                normal,
                shading,
                view: -ray.dir,
            };
            let volume = material.model == MODEL_GLTF && material.volume != 0;
            if volume && !entering {
                let optical_depth = -v3(material.absorption) * hit.t;
                throughput *= Vec3::new(optical_depth.x.exp(), optical_depth.y.exp(), optical_depth.z.exp());
            }
            // A blended surface stops the path with the chance of its alpha; else the path goes
            // on behind it, at the same bounce.
            if surface.blend && self.blend_layers < MAX_BLEND_LAYERS {
                self.blend_layers += 1;
                let group = 2 * (scene.max_depth + 1) + self.blend_layers;
                if self.path_numbers(group).x >= material.alpha {
                    ray = Ray::new(offset_origin(&surface, -normal), ray.dir);
                    continue;
                }
            }
            if material.model == MODEL_UNLIT {
                result.color += throughput * v3(material.color);
                break;
            }
            if max3(v3(material.emission)) > 0.0 {
                let weight = self.emission_weight(&hit, &surface, &ray, bsdf_pdf);
                result.color += throughput * v3(material.emission) * weight;
            }
            let s = gltf_surface(&material);
            let lobes = path_lobes(&material, &s, shading.dot(frame.view).max(0.0));
            let goes_on = bounce < scene.max_depth;
            let u = self.path_numbers(2 * bounce + 1);
            result.color += throughput * self.path_direct_light(&surface, frame, (&material, &s), &lobes, u, goes_on);
            if !goes_on {
                break;
            }
            let u = self.path_numbers(2 * bounce);
            let sample = sample_bsdf(&material, &s, &lobes, frame, entering, u.truncate());
            let largest = max3(sample.weight);
            if !(largest > 0.0) || largest > 3.0e38 {
                break;
            }
            throughput *= sample.weight;
            bsdf_pdf = sample.pdf;
            if bounce >= ROULETTE_START {
                let survival = max3(throughput).min(1.0);
                if !(u.w < survival) {
                    break;
                }
                throughput /= survival;
            }
            let side = if sample.through { -normal } else { normal };
            ray = Ray::new(offset_origin(&surface, side), sample.dir);
            // Back faces hide from rays outside: reflected from outside or refracted out of a
            // volume; a thin wall's transmitted ray sees them, as the Whitted integrator's does.
            culls = if volume {
                entering != sample.through
            } else {
                !sample.through
            };
            cone = cone_reflected(cone, curvature);
            bounce += 1;
        }
        result.color = finite_or_zero(result.color);
        result.rays = self.ray_count;
        result
    }
}

/// Zero for a NaN or an infinite sum (`finite_or_zero`): the last guard against a sample that
/// would poison the accumulation.
fn finite_or_zero(color: Vec3) -> Vec3 {
    let finite = !color.is_nan() && max3(color.abs()) <= 3.0e38;
    if finite { color } else { Vec3::ZERO }
}
