//! The tracer for one pixel: the twin of `shaders/trace.wgsl`, loop for loop.

use super::accel::{
    brute_closest, brute_occluded, traverse_stack, traverse_stackless, traverse_threaded, traverse_wide,
};
use super::admit::{Primitives, RayQuery};
use super::brdf::sample_specular;
use super::environment::escaped_radiance;
use super::intersect::{Hit, HitKind, Ray, any_plane, box_tests, closest_plane, reset_box_tests, v3};
use super::shade::{
    ShadingFrame, Surface, ambient_share, direct_light, fresnel_schlick, gltf_direct_light, gltf_surface,
    normal_mapped, offset_origin, reflect, refracted_direction, surface_at, surface_material,
};
pub use crate::constants::T_FAR;
use crate::constants::{MAX_BLEND_LAYERS, MIN_FOOTPRINT_COSINE, MIN_WEIGHT, R2_STEP, ray_stack_size};
use crate::error::MissingBvh;
use crate::modes::{Accel, Integrator};
use crate::records::GpuMaterial;
use crate::records::constants::{MODEL_GLTF, MODEL_UNLIT};
use crate::records::{PackedBvh, PackedScene};
use glam::{UVec2, Vec2, Vec3};
use std::cell::Cell;

#[derive(Clone, Copy, Debug, Default)]
struct RayTask {
    origin: Vec3,
    dir: Vec3,
    weight: Vec3,
    depth: u32,
    /// Whether single-sided triangles hide their backs from the ray: camera and reflected rays,
    /// not rays transmitted through a surface (which may be inside a volume).
    culls: bool,
    /// The ray cone around it: its width where the ray starts, and its spread angle (radians).
    cone: Vec2,
}

/// The rays a hit sends on; a weight that is not worth tracing means none. `through` goes on
/// behind a blended surface: not a bounce, at the same depth.
#[derive(Clone, Copy, Debug, Default)]
struct Branches {
    reflected: RayTask,
    refracted: RayTask,
    through: RayTask,
}

/// What one pixel's trace yields: the fragment shader's two outputs. The default is a trace
/// before its first ray: no light, no surface, no rays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelTrace {
    /// Linear radiance.
    pub color: Vec3,
    /// First-hit shading normal; zero where the primary ray escapes.
    pub normal: Vec3,
    /// First-hit distance; `None` where the primary ray escapes.
    pub depth: Option<f32>,
    /// Primary, shadow and secondary rays traced for this pixel.
    pub rays: u32,
    /// Nodes the primary ray tested (box tests of internal nodes, sphere tests of leaves; spheres
    /// tested for brute force).
    pub cost: u32,
}

/// The per-pixel state the shader keeps in private variables.
pub struct Tracer<'a> {
    /// The scene traced.
    pub scene: &'a PackedScene,
    /// The walk.
    pub accel: Accel,
    /// The scene's BVH; the BVH walks need it.
    bvh: Option<&'a PackedBvh>,
    /// Rays traced for the pixel so far.
    pub ray_count: u32,
    /// The sample's random sequence: its seed and the draws so far.
    seed: u32,
    draws: u32,
    /// Surfaces of blended triangles the pixel's rays went on behind, at most MAX_BLEND_LAYERS.
    pub(crate) blend_layers: u32,
    /// The path integrator's pixel seed for the epoch, and the sample's index (`path_seed`,
    /// `path_sample`).
    pub(crate) path_seed: u32,
    pub(crate) path_sample: u32,
}

impl<'a> Tracer<'a> {
    /// A tracer for one pixel. The BVH walks need the scene's BVH, unless it has no primitives.
    pub fn new(scene: &'a PackedScene, accel: Accel) -> Result<Self, MissingBvh> {
        let bvh = scene.bvh.as_ref();
        if accel.uses_bvh() && bvh.is_none() && scene.primitive_count() > 0 {
            return Err(MissingBvh { accel });
        }
        Ok(Self {
            scene,
            accel,
            bvh,
            ray_count: 0,
            seed: 0,
            draws: 0,
            blend_layers: 0,
            path_seed: 0,
            path_sample: 0,
        })
    }

    /// The primitives in the BVH's order, as a ray that asks `query` of them meets them.
    pub fn primitives(&self, query: RayQuery<'a>) -> Primitives<'a> {
        Primitives {
            spheres: &self.scene.spheres,
            triangles: &self.scene.triangles,
            query: Some(query),
        }
    }

    /// The acceleration mode's closest primitive hit (the shader's `accel_closest`).
    fn accel_closest(&self, ray: &Ray, best: Hit, culls: bool) -> Hit {
        let primitives = self.primitives(RayQuery {
            scene: self.scene,
            culls_back_faces: culls,
            shadow_light: None,
        });
        let Some(bvh) = self.bvh.filter(|_| self.accel.uses_bvh()) else {
            // Brute force, or a BVH walk over no primitives.
            return brute_closest(&primitives, ray, best);
        };
        match self.accel {
            // The driver's walk has no CPU twin: it finds the closest hit that brute force finds.
            Accel::Brute | Accel::RayQuery => brute_closest(&primitives, ray, best),
            Accel::Stack => traverse_stack(bvh.threaded_tree(), &primitives, ray, best, false),
            Accel::Stackless => traverse_stackless(&bvh.nodes, &primitives, ray, best, false),
            Accel::Threaded => traverse_threaded(bvh.threaded_tree(), &primitives, ray, best, false),
            Accel::Wide => traverse_wide(bvh.wide_tree(), &primitives, ray, best, false),
        }
    }

    /// The acceleration mode's shadow query (the shader's `accel_occluded`); `shadow_light` keeps
    /// the share of light that blended triangles let through.
    fn accel_occluded(&self, ray: &Ray, t_max: f32, shadow_light: &Cell<f32>) -> bool {
        let primitives = self.primitives(RayQuery {
            scene: self.scene,
            culls_back_faces: false,
            shadow_light: Some(shadow_light),
        });
        let Some(bvh) = self.bvh.filter(|_| self.accel.uses_bvh()) else {
            return brute_occluded(&primitives, ray, t_max);
        };
        let none = Hit::none(t_max);
        let hit = match self.accel {
            Accel::Brute | Accel::RayQuery => return brute_occluded(&primitives, ray, t_max),
            Accel::Stack => traverse_stack(bvh.threaded_tree(), &primitives, ray, none, true),
            Accel::Stackless => traverse_stackless(&bvh.nodes, &primitives, ray, none, true),
            Accel::Threaded => traverse_threaded(bvh.threaded_tree(), &primitives, ray, none, true),
            Accel::Wide => traverse_wide(bvh.wide_tree(), &primitives, ray, none, true),
        };
        hit.kind != HitKind::None
    }

    /// The ray through a pixel position (pixel centres at +0.5, row 0 at the top).
    pub fn camera_ray(&self, pixel: Vec2) -> Ray {
        let g = &self.scene.globals.camera;
        let x = (2.0 * pixel.x / g.width - 1.0) * g.tan_half_fov * g.aspect;
        let y = (1.0 - 2.0 * pixel.y / g.height) * g.tan_half_fov;
        let dir = (v3(g.forward) + x * v3(g.right) + y * v3(g.up)).normalize();
        Ray::new(v3(g.eye), dir)
    }

    /// The closest hit, single-sided triangles hiding their backs where `culls` says so.
    pub fn closest_hit(&self, ray: &Ray, t_max: f32, culls: bool) -> Hit {
        let planes = closest_plane(&self.scene.planes, ray, Hit::none(t_max));
        self.accel_closest(ray, planes, culls)
    }

    /// A shadow ray (`occluded`, then `shadowed`): `None` where something blocks it before t_max,
    /// else the share of the light that its blended triangles let through. Shadow rays see both
    /// sides of triangles.
    pub fn shadow_ray(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let shadow_light = Cell::new(1.0);
        let blocked = any_plane(&self.scene.planes, ray, t_max) || self.accel_occluded(ray, t_max, &shadow_light);
        (!blocked).then(|| shadow_light.get())
    }

    /// Traces one ray of the tree (`trace_task`): adds its light to the pixel and says where it
    /// branches.
    fn trace_task(&mut self, task: &RayTask, result: &mut PixelTrace) -> Branches {
        let mut branches = Branches::default();
        let ray = Ray::new(task.origin, task.dir);
        self.ray_count += 1;
        let hit = self.closest_hit(&ray, T_FAR, task.culls);
        if task.depth == 0 {
            result.cost = box_tests();
        }
        if hit.kind == HitKind::None {
            result.color += task.weight * escaped_radiance(self.scene, ray.dir, task.cone.y);
            return branches;
        }
        let mut surface = surface_at(self.scene, &ray, &hit);
        // The cone where it meets the surface: its width there, and its spread.
        let cone = Vec2::new(task.cone.x + task.cone.y * hit.t, task.cone.y);
        surface.attributes.footprint = cone.x.abs() / surface.normal.dot(ray.dir).abs().max(MIN_FOOTPRINT_COSINE);
        let material = surface_material(self.scene, &surface);
        surface.shading = normal_mapped(self.scene, &surface, &material);
        // The first surface the camera ray meets, blended or not.
        if task.depth == 0 && result.depth.is_none() {
            result.normal = surface.shading;
            result.depth = Some(hit.t);
        }
        let entering = surface.normal.dot(ray.dir) < 0.0;
        // The geometric normal picks the side new rays start on; the shading normal bends them.
        let normal = if entering { surface.normal } else { -surface.normal };
        let shading = if entering { surface.shading } else { -surface.shading };
        let curvature = if entering {
            surface.curvature
        } else {
            -surface.curvature
        };
        let view = -ray.dir;
        let frame = ShadingFrame { normal, shading, view };
        // A ray that leaves a volume lost light on its way through it (Beer-Lambert).
        let mut arrived = *task;
        if material.model == MODEL_GLTF && material.volume != 0 && !entering {
            let optical_depth = -v3(material.absorption) * hit.t;
            arrived.weight *= Vec3::new(optical_depth.x.exp(), optical_depth.y.exp(), optical_depth.z.exp());
        }
        // A blended surface covers its alpha of the ray; the rest goes on behind it.
        let mut covered = arrived;
        if surface.blend {
            covered.weight *= material.alpha;
            if self.blend_layers < MAX_BLEND_LAYERS {
                self.blend_layers += 1;
                branches.through = RayTask {
                    origin: offset_origin(&surface, -normal),
                    dir: ray.dir,
                    weight: arrived.weight * (1.0 - material.alpha),
                    cone,
                    ..*task
                };
            }
        }
        // KHR_materials_unlit: the base colour is what the surface shows, and all it sends on.
        if material.model == MODEL_UNLIT {
            result.color += covered.weight * v3(material.color);
            return branches;
        }
        let scene = self.scene;
        let gltf = material.model == MODEL_GLTF;
        let mut shadow_ray = |ray: &Ray, t_max: f32| {
            self.ray_count += 1;
            self.shadow_ray(ray, t_max)
        };
        let light = if gltf {
            let share = ambient_share(scene, &surface, &material);
            gltf_direct_light(scene, &surface, frame, &material, share, &mut shadow_ray)
        } else {
            direct_light(scene, &surface, frame, &material, &mut shadow_ray)
        };
        result.color += covered.weight * (light + v3(material.emission));
        if task.depth >= self.scene.max_depth {
            return branches;
        }
        if gltf {
            let sent = self.gltf_branches(&covered, &surface, frame, &material, (entering, cone, curvature));
            return Branches {
                through: branches.through,
                ..sent
            };
        }

        // Split the transmitted share by Fresnel; all of it reflects past the critical angle.
        let mut reflect_share = material.reflect;
        let mut transmit_share = material.transmit;
        let mut refracted = Vec3::ZERO;
        let mut refracted_cone = cone;
        if transmit_share > 0.0 {
            let eta = if entering { 1.0 / material.ior } else { material.ior };
            let cos_i = view.dot(shading);
            let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
            if k < 0.0 {
                reflect_share += transmit_share;
                transmit_share = 0.0;
            } else {
                let cos_t = k.sqrt();
                refracted = (eta * ray.dir + (eta * cos_i - cos_t) * shading).normalize();
                refracted_cone = cone_refracted(cone, curvature, eta, cos_i, cos_t);
                let fresnel = fresnel_schlick(if entering { cos_i } else { cos_t }, material.ior);
                reflect_share += transmit_share * fresnel;
                transmit_share *= 1.0 - fresnel;
            }
        }
        let depth = task.depth + 1;
        branches.refracted = RayTask {
            origin: offset_origin(&surface, -normal),
            dir: refracted,
            weight: covered.weight * transmit_share,
            depth,
            culls: false,
            cone: refracted_cone,
        };
        branches.reflected = RayTask {
            origin: offset_origin(&surface, normal),
            dir: reflect(ray.dir, shading),
            weight: covered.weight * reflect_share,
            depth,
            culls: true,
            cone: cone_reflected(cone, curvature),
        };
        branches
    }

    /// A glTF surface's rays (`gltf_branches`): the reflected one weighted by the Fresnel term (drawn
    /// from the GGX lobe where the surface is rough), and the transmitted one of
    /// KHR_materials_transmission. A thin wall's transmitted ray goes on in the incoming direction,
    /// or, rough, in the reflected ray's mirror image through the surface; across a volume's
    /// surface (KHR_materials_volume) it refracts about the sampled microfacet normal, and reflects
    /// where it cannot (total internal reflection). A ray inside a volume sees the back faces of
    /// single-sided triangles. `frame` is the hit's, facing the ray; `arrival` whether the ray
    /// enters, and its cone and the surface's curvature where it meets it.
    fn gltf_branches(
        &mut self,
        task: &RayTask,
        surface: &Surface,
        frame: ShadingFrame,
        material: &GpuMaterial,
        (entering, cone, curvature): (bool, Vec2, f32),
    ) -> Branches {
        let ShadingFrame { normal, shading, view } = frame;
        let s = gltf_surface(material);
        let sample = sample_specular(&s, shading, view, self.random_pair());
        let depth = task.depth + 1;
        let mut transmitted = sample.dir - 2.0 * sample.dir.dot(shading) * shading;
        let mut transmit_side = -normal;
        let mut transmit_culls = false;
        let reflected_cone = cone_reflected(cone, curvature);
        let mut transmitted_cone = cone;
        let volume = material.volume != 0;
        if volume {
            let eta = if entering { 1.0 / s.ior } else { s.ior };
            let microfacet = (sample.dir + view).normalize();
            let bent = refracted_direction(-view, microfacet, eta);
            transmitted = bent.unwrap_or(sample.dir);
            transmitted_cone = match bent {
                Some(t) => cone_refracted(cone, curvature, eta, view.dot(microfacet), -t.dot(microfacet)),
                None => reflected_cone,
            };
            transmit_side = if bent.is_some() { -normal } else { normal };
            // Outside after it, where back faces hide again: leaving and refracted, or reflected
            // from outside.
            transmit_culls = entering != bent.is_some();
        }
        let transmit_share =
            (1.0 - s.metallic) * s.transmission * (1.0 - sample.dielectric_fresnel.max_element()) * sample.share;
        Branches {
            reflected: RayTask {
                origin: offset_origin(surface, normal),
                dir: sample.dir,
                weight: task.weight * sample.weight,
                depth,
                culls: !volume || entering,
                cone: reflected_cone,
            },
            refracted: RayTask {
                origin: offset_origin(surface, transmit_side),
                dir: transmitted,
                weight: task.weight * s.base * transmit_share,
                depth,
                culls: transmit_culls,
                cone: transmitted_cone,
            },
            through: RayTask::default(),
        }
    }

    /// The next two uniform numbers in [0, 1) of the sample's sequence (`random_pair`): a hash of
    /// the sample's seed and the draw's number, the same bits as the shader's.
    fn random_pair(&mut self) -> [f32; 2] {
        self.draws += 1;
        let x = hash_u32(self.seed ^ hash_u32(self.draws));
        let y = hash_u32(x);
        [(x >> 8) as f32, (y >> 8) as f32].map(|n| n * (1.0 / 16_777_216.0))
    }

    /// Traces sample `sample` of `pixel` (the shader's `sample_pixel`) with the scene's integrator:
    /// its camera ray, and the random numbers of its sampled reflections seeded by both (and, for
    /// the path integrator, by the scene's epoch).
    pub fn trace_sample(&mut self, pixel: UVec2, sample: u32) -> PixelTrace {
        self.seed = sample_seed(pixel, sample);
        self.draws = 0;
        self.blend_layers = 0;
        self.ray_count = 0;
        let position = pixel.as_vec2() + sample_offset(pixel, sample);
        let primary = self.camera_ray(position);
        match self.scene.integrator {
            Integrator::Whitted => self.trace_pixel(primary),
            Integrator::Path => {
                self.path_seed = path_seed(pixel, self.scene.path.globals.epoch);
                self.path_sample = sample;
                self.trace_path(primary)
            }
        }
    }

    /// A reflected branch is traced next; its refracted sibling waits on the stack. A ray that goes
    /// on behind a blended surface is traced next, and both the surface's branches wait.
    pub fn trace_pixel(&mut self, primary: Ray) -> PixelTrace {
        // The shader's RAY_STACK_SIZE in a scene with blended triangles: without them the stack
        // never holds more than max_depth + 1, so the room is the same for every scene.
        let stack_size = ray_stack_size(self.scene.max_depth, true) as usize;
        let mut result = PixelTrace::default();
        reset_box_tests();
        let mut task = RayTask {
            origin: primary.origin,
            dir: primary.dir,
            weight: Vec3::ONE,
            depth: 0,
            culls: true,
            cone: Vec2::new(0.0, pixel_spread(self.scene)),
        };
        let mut waiting = Vec::with_capacity(stack_size);
        loop {
            let branches = self.trace_task(&task, &mut result);
            let reflects = worth_tracing(branches.reflected.weight);
            if worth_tracing(branches.through.weight) {
                // The ray goes on behind the blended surface; the surface's own branches wait.
                for branch in [branches.refracted, branches.reflected] {
                    if worth_tracing(branch.weight) && waiting.len() < stack_size {
                        waiting.push(branch);
                    }
                }
                task = branches.through;
                continue;
            }
            if worth_tracing(branches.refracted.weight) {
                if !reflects {
                    task = branches.refracted;
                    continue;
                }
                if waiting.len() < stack_size {
                    waiting.push(branches.refracted);
                }
            }
            if reflects {
                task = branches.reflected;
                continue;
            }
            match waiting.pop() {
                Some(next) => task = next,
                None => break,
            }
        }
        result.rays = self.ray_count;
        result
    }
}

/// A 32-bit integer hash (PCG's output permutation, after Jarzynski and Olano 2020), for the
/// per-pixel scramble of the sample sequence (`hash_u32`).
pub(crate) fn hash_u32(value: u32) -> u32 {
    let state = value.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Where in its pixel sample `index` looks, in [0, 1)^2 (`sample_offset`). Sample 0 is the centre,
/// so one sample is the unjittered image; later samples follow the R2 sequence, shifted per pixel
/// by a hash (a Cranley-Patterson rotation). Integer arithmetic in 0.32 fixed point, so the shader
/// computes the same bits.
pub fn sample_offset(pixel: UVec2, index: u32) -> Vec2 {
    if index == 0 {
        return Vec2::splat(0.5);
    }
    let scramble_x = hash_u32(pixel.x ^ hash_u32(pixel.y));
    let scramble_y = hash_u32(scramble_x);
    let x = scramble_x.wrapping_add(index.wrapping_mul(R2_STEP[0]));
    let y = scramble_y.wrapping_add(index.wrapping_mul(R2_STEP[1]));
    Vec2::new((x >> 8) as f32, (y >> 8) as f32) * (1.0 / 16_777_216.0)
}

/// The seed of a pixel's sample's random sequence (`sample_seed`).
pub(crate) fn sample_seed(pixel: UVec2, sample: u32) -> u32 {
    hash_u32(pixel.x ^ hash_u32(pixel.y ^ hash_u32(sample)))
}

/// A pixel's seed for an epoch, which scrambles the path integrator's samples (`start_sample` in
/// path.wgsl).
pub fn path_seed(pixel: UVec2, epoch: u32) -> u32 {
    hash_u32(pixel.x ^ hash_u32(pixel.y ^ hash_u32(epoch)))
}

/// The spread angle of the ray cone through a pixel (`pixel_spread`): the angle one pixel of
/// the image subtends at the eye, at its centre.
pub(crate) fn pixel_spread(scene: &PackedScene) -> f32 {
    let camera = &scene.globals.camera;
    (2.0 * camera.tan_half_fov / camera.height).atan()
}

/// A ray cone (width at the surface, spread) reflected by a surface of `curvature` (seen from the
/// ray's side; `cone_reflected`): across the cone's width the normal turns by curvature × width,
/// and the reflected rays by twice that (Akenine-Möller et al., "Improved Shader and Texture Level
/// of Detail Using Ray Cones", 2021).
pub(crate) fn cone_reflected(cone: Vec2, curvature: f32) -> Vec2 {
    Vec2::new(cone.x, cone.y + 2.0 * curvature * cone.x)
}

/// A ray cone refracted by a surface of `curvature` (`cone_refracted`), with `eta` the ratio of
/// indices and the cosines of the incident and refracted rays to the normal. Snell's law
/// differentiated: a change of the incident angle changes the refracted one ratio = η cos θi /
/// cos θt times as much, so the incoming spread scales by it, and the normal's turn across the
/// width bends the refracted rays by (ratio - 1) times that turn (a convex surface entering glass
/// focuses).
fn cone_refracted(cone: Vec2, curvature: f32, eta: f32, cos_i: f32, cos_t: f32) -> Vec2 {
    let ratio = eta * cos_i / cos_t.max(MIN_FOOTPRINT_COSINE);
    Vec2::new(cone.x, ratio * cone.y + (ratio - 1.0) * curvature * cone.x)
}

fn worth_tracing(weight: Vec3) -> bool {
    weight.max_element() >= MIN_WEIGHT
}
