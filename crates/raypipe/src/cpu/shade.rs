//! Surfaces, their materials and maps, lights, and direct light: the twin of `shaders/shade.wgsl`.

use super::brdf::{GltfSurface, gltf_brdf};
use super::environment::environment_irradiance;
use super::intersect::{Hit, HitKind, Ray, triangle_uvt, v3};
use super::maps::{
    Attributes, has_coordinates, map_coordinates, sample_map, sample_texture, texture_lod, triangle_attributes,
};
use crate::bvh::layout::NONE;
use crate::constants::{RAY_BIAS, T_FAR};
use crate::records::constants::{
    ATTRIBUTE_COLOR, ATTRIBUTE_TANGENT, LIGHT_CONSTANT, LIGHT_DIRECTIONAL, LIGHT_SPOT, MATERIAL_INDEX_MASK, MODEL_GLTF,
    TRIANGLE_ALPHA_BLEND,
};
use crate::records::{GpuLight, GpuMaterial, GpuTriangle, PackedScene};
use glam::{Vec2, Vec3};

/// The frame a hit is shaded in, all three facing the viewer: the geometric normal (which side new
/// rays start on), the shading normal (interpolated and normal-mapped: lighting, reflection and
/// refraction use it), and the direction from the surface to the viewer. Twin of `ShadingFrame` in
/// shade.wgsl.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShadingFrame {
    pub normal: Vec3,
    pub shading: Vec3,
    pub view: Vec3,
}

/// Where a ray hit and what lies there: the point, its shading frame, material and attributes.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// The hit point.
    pub position: Vec3,
    /// Geometric, unit, pointing out of the primitive: it decides inside and outside, and which side
    /// new rays start on.
    pub normal: Vec3,
    /// Unit, on the geometric normal's side: the interpolated vertex normal of a smooth triangle, the
    /// geometric normal otherwise. Lighting, reflection and refraction use it.
    pub shading: Vec3,
    /// The material's index.
    pub material: u32,
    /// The largest coordinate of the ray's origin and of the hit: the position's rounding error is
    /// a few float steps of it.
    pub reach: f32,
    /// Texture coordinates, vertex colour and tangent at the hit, where the triangle has them.
    pub attributes: Attributes,
    /// A triangle with alpha BLEND: it covers its alpha of the ray.
    pub blend: bool,
    /// How fast the shading normal turns per unit of length across the surface, positive where it
    /// turns away from the geometric normal's side (a sphere's 1 / radius seen from outside): what
    /// widens or narrows a ray cone that the surface reflects or refracts.
    pub curvature: f32,
}

pub(crate) fn max_abs(v: Vec3) -> f32 {
    v.abs().max_element()
}

/// `v.normalize()` for any nonzero v: the squares of a big or small v would overflow or underflow.
pub(crate) fn normalize_scaled(v: Vec3) -> Vec3 {
    (v / max_abs(v)).normalize()
}

/// WGSL's `reflect(e1, e2)`: e1 - 2 dot(e2, e1) e2.
pub fn reflect(incident: Vec3, normal: Vec3) -> Vec3 {
    incident - 2.0 * normal.dot(incident) * normal
}

/// The surface a ray hit: where, its normals, its material.
pub(crate) fn surface_at(scene: &PackedScene, ray: &Ray, hit: &Hit) -> Surface {
    let position = ray.origin + hit.t * ray.dir;
    let reach = max_abs(ray.origin).max(max_abs(position));
    if hit.kind == HitKind::Primitive {
        if let Some(sphere) = scene.spheres.get(hit.index as usize) {
            let normal = (position - v3(sphere.center)).normalize();
            return Surface {
                position,
                normal,
                shading: normal,
                material: sphere.material,
                reach,
                attributes: Attributes::NONE,
                blend: false,
                curvature: 1.0 / sphere.radius,
            };
        }
        let triangle = &scene.triangles[hit.index as usize - scene.spheres.len()];
        let [v0, v1, v2] = triangle.corners();
        let normal = normalize_scaled((v1 - v0).cross(v2 - v0));
        let (shading, curvature) = triangle_shading(scene, triangle, ray, normal);
        return Surface {
            position,
            normal,
            shading,
            material: triangle.material & MATERIAL_INDEX_MASK,
            reach,
            attributes: triangle_attributes(scene, triangle, ray),
            blend: triangle.material & TRIANGLE_ALPHA_BLEND != 0,
            curvature,
        };
    }
    let plane = &scene.planes[hit.index as usize];
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
        shading: v3(plane.normal),
        material,
        reach,
        attributes: Attributes::NONE,
        blend: false,
        curvature: 0.0,
    }
}

/// The surface's material, its vertex colour and maps applied at the hit (`surface_material`): the
/// base colour's (alpha too, as `surface_alpha` computes it), and a glTF material's metalness and
/// roughness (blue and green), emission, and specular strength (alpha) and colour.
pub(crate) fn surface_material(scene: &PackedScene, surface: &Surface) -> GpuMaterial {
    let mut material = scene.materials[surface.material as usize];
    let a = &surface.attributes;
    if a.present & ATTRIBUTE_COLOR != 0 {
        material.color = (v3(material.color) * a.color.truncate()).to_array();
        material.alpha *= a.color.w;
    }
    if a.present == 0 {
        return material;
    }
    if let Some(texel) = sample_map(scene, material.base_map, a) {
        material.color = (v3(material.color) * texel.truncate()).to_array();
        material.alpha *= texel.w;
    }
    if material.model == MODEL_GLTF {
        if let Some(texel) = sample_map(scene, material.metallic_roughness_map, a) {
            material.roughness *= texel.y;
            material.metallic *= texel.z;
        }
        if let Some(texel) = sample_map(scene, material.emissive_map, a) {
            material.emission = (v3(material.emission) * texel.truncate()).to_array();
        }
        if let Some(texel) = sample_map(scene, material.specular_map, a) {
            material.specular_factor *= texel.w;
        }
        if let Some(texel) = sample_map(scene, material.specular_color_map, a) {
            material.specular_color = (v3(material.specular_color) * texel.truncate()).to_array();
        }
    }
    material
}

/// The share of ambient light that reaches a glTF surface: 1 blended toward its occlusion map's
/// red by the map's strength.
pub(crate) fn ambient_share(scene: &PackedScene, surface: &Surface, material: &GpuMaterial) -> f32 {
    if surface.attributes.present == 0 {
        return 1.0;
    }
    match sample_map(scene, material.occlusion_map, &surface.attributes) {
        Some(texel) => 1.0 + material.occlusion_strength * (texel.x - 1.0),
        None => 1.0,
    }
}

/// The shading normal bent by the material's normal map (`normal_mapped`), in the frame of the
/// triangle's tangent (made perpendicular to the shading normal n), its bitangent w cross(n,
/// tangent) and n; n itself where the triangle lacks the map's coordinates or tangents, or where
/// the bent normal would turn away from the geometric one.
pub(crate) fn normal_mapped(scene: &PackedScene, surface: &Surface, material: &GpuMaterial) -> Vec3 {
    let n = surface.shading;
    let a = &surface.attributes;
    if material.normal_map == NONE || a.present & ATTRIBUTE_TANGENT == 0 {
        return n;
    }
    let map = &scene.texture_maps[material.normal_map as usize];
    let along = a.tangent.truncate() - a.tangent.truncate().dot(n) * n;
    if !has_coordinates(map, a) || along.dot(along) == 0.0 {
        return n;
    }
    let tangent = along.normalize();
    let sign = if a.tangent.w >= 0.0 { 1.0 } else { -1.0 };
    let bitangent = sign * n.cross(tangent);
    let texel = sample_texture(scene, map, map_coordinates(map, a), texture_lod(map, a));
    let xy = (2.0 * Vec2::new(texel.x, texel.y) - 1.0) * material.normal_scale;
    let bent = xy.x * tangent + xy.y * bitangent + (2.0 * texel.z - 1.0) * n;
    if bent.dot(surface.normal) <= 0.0 {
        return n;
    }
    bent.normalize()
}

/// A smooth triangle's vertex normals interpolated at the hit, turned to the geometric normal's
/// side (the geometric normal where they cancel out), and the triangle's curvature
/// (`triangle_shading`). A flat triangle has neither.
fn triangle_shading(scene: &PackedScene, triangle: &GpuTriangle, ray: &Ray, normal: Vec3) -> (Vec3, f32) {
    if triangle.normals == NONE {
        return (normal, 0.0);
    }
    let uvt = triangle_uvt(triangle, ray);
    let n = &scene.triangle_normals[triangle.normals as usize];
    let [n0, n1, n2] = [n.n0, n.n1, n.n2].map(v3);
    let curvature = triangle_curvature(triangle, [n0, n1, n2], normal);
    let blended = (1.0 - uvt.x - uvt.y) * n0 + uvt.x * n1 + uvt.y * n2;
    if blended.dot(blended) == 0.0 {
        return (normal, curvature);
    }
    let shading = blended.normalize();
    (if shading.dot(normal) < 0.0 { -shading } else { shading }, curvature)
}

/// How fast a smooth triangle's vertex normals turn along its edges, averaged over the three
/// (`triangle_curvature`): the change of normal along an edge, over its length squared, taken
/// along it. Normals on a sphere of radius r, seen from the geometric normal's side, give 1 / r
/// outside and -1 / r inside.
fn triangle_curvature(triangle: &GpuTriangle, normals: [Vec3; 3], normal: Vec3) -> f32 {
    let corners = triangle.corners();
    // The vertex normals facing the geometric normal's side, as the shading normal does.
    let n = normals.map(|n| if n.dot(normal) < 0.0 { -n } else { n });
    let mut sum = 0.0;
    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
        let edge = corners[b] - corners[a];
        let length_squared = edge.dot(edge);
        if length_squared > 0.0 {
            sum += (n[b] - n[a]).dot(edge) / length_squared;
        }
    }
    sum / 3.0
}

/// How a light reaches a point: the unit direction to it, how far a shadow ray runs, and E, the
/// irradiance on a surface facing it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LightArrival {
    pub dir: Vec3,
    pub distance: f32,
    pub irradiance: Vec3,
}

/// KHR_lights_punctual's recommended falloff: inverse-square, windowed smoothly to zero at
/// `range` (none where it is 0).
pub(crate) fn range_attenuation(range: f32, distance: f32) -> f32 {
    let inverse_square = 1.0 / (distance * distance);
    if range <= 0.0 {
        return inverse_square;
    }
    let ratio = distance / range;
    let ratio2 = ratio * ratio;
    (1.0 - ratio2 * ratio2).clamp(0.0, 1.0) * inverse_square
}

/// What `light` gives the point `position`, by its kind (`light_arrival`).
pub(crate) fn light_arrival(light: &GpuLight, position: Vec3) -> LightArrival {
    if light.kind == LIGHT_DIRECTIONAL {
        return LightArrival {
            dir: -v3(light.direction),
            distance: T_FAR,
            irradiance: v3(light.color),
        };
    }
    let to_light = v3(light.position) - position;
    let distance = to_light.length();
    let dir = to_light / distance;
    let mut irradiance = v3(light.color);
    if light.kind != LIGHT_CONSTANT {
        irradiance *= range_attenuation(light.range, distance);
    }
    if light.kind == LIGHT_SPOT {
        let cone = (v3(light.direction).dot(-dir) * light.spot_scale + light.spot_offset).clamp(0.0, 1.0);
        irradiance *= cone * cone;
    }
    LightArrival {
        dir,
        distance,
        irradiance,
    }
}

/// Whether a light's shadow ray is worth casting: the paper's lights always are (their ray
/// counts stay), a glTF light where it gives anything.
pub(crate) fn lit(light: &GpuLight, arrival: &LightArrival) -> bool {
    light.kind == LIGHT_CONSTANT || arrival.irradiance.max_element() > 0.0
}

/// Ambient plus, for every light that the surface faces and that nothing blocks, Lambert and
/// Phong times the light's E, in the hit's `frame`. `shadow_ray` casts a shadow ray (and counts
/// it): `None` where something blocks it, else the share of the light that blended triangles let
/// through (`occluded` and `shadowed`).
pub(crate) fn direct_light(
    scene: &PackedScene,
    surface: &Surface,
    frame: ShadingFrame,
    material: &GpuMaterial,
    mut shadow_ray: impl FnMut(&Ray, f32) -> Option<f32>,
) -> Vec3 {
    let ShadingFrame { normal, shading, view } = frame;
    let globals = &scene.globals.scene;
    let albedo = v3(material.color);
    let mut color = globals.ambient * albedo;
    let origin = offset_origin(surface, normal);
    for light in &scene.lights {
        let arrival = light_arrival(light, surface.position);
        let l = arrival.dir;
        let n_dot_l = shading.dot(l);
        if n_dot_l <= 0.0 || !lit(light, &arrival) {
            continue;
        }
        let Some(share) = shadow_ray(&Ray::new(origin, l), arrival.distance) else {
            continue;
        };
        let irradiance = arrival.irradiance * share;
        let mut highlight = 0.0;
        let r_dot_v = reflect(-l, shading).dot(view);
        if r_dot_v > 0.0 && material.specular > 0.0 {
            highlight = material.specular * r_dot_v.powf(material.shininess);
        }
        color += irradiance * (albedo * n_dot_l + Vec3::splat(highlight));
    }
    color
}

/// A glTF material's parameters, as the BRDF takes them.
pub(crate) fn gltf_surface(material: &GpuMaterial) -> GltfSurface {
    GltfSurface {
        base: v3(material.color),
        metallic: material.metallic,
        roughness: material.roughness,
        transmission: material.transmit,
        ior: material.ior,
        specular_factor: material.specular_factor,
        specular_color: v3(material.specular_color),
    }
}

/// A glTF surface's direct light: the ambient light (the environment's irradiance, where the
/// scene has one) on its diffuse share, times `ambient_share`; plus, for every light that it faces
/// and that nothing blocks, E times the BRDF times the cosine. Arguments as [`direct_light`]'s.
pub(crate) fn gltf_direct_light(
    scene: &PackedScene,
    surface: &Surface,
    frame: ShadingFrame,
    material: &GpuMaterial,
    ambient_share: f32,
    mut shadow_ray: impl FnMut(&Ray, f32) -> Option<f32>,
) -> Vec3 {
    let ShadingFrame { normal, shading, view } = frame;
    let s = gltf_surface(material);
    let diffuse = s.base * ((1.0 - s.metallic) * (1.0 - s.transmission));
    let info = &scene.globals.scene;
    let ambient = if info.environment_map == NONE {
        Vec3::splat(info.ambient)
    } else {
        environment_irradiance(scene, shading)
    };
    let mut color = ambient * ambient_share * diffuse;
    let origin = offset_origin(surface, normal);
    for light in &scene.lights {
        let arrival = light_arrival(light, surface.position);
        let l = arrival.dir;
        let n_dot_l = shading.dot(l);
        if n_dot_l <= 0.0 || !lit(light, &arrival) {
            continue;
        }
        let Some(share) = shadow_ray(&Ray::new(origin, l), arrival.distance) else {
            continue;
        };
        let irradiance = arrival.irradiance * share;
        color += irradiance * n_dot_l * gltf_brdf(&s, shading, view, l);
    }
    color
}

/// `side` points to where the new ray goes: the facing normal for reflection and shadows, its
/// opposite for refraction.
pub(crate) fn offset_origin(surface: &Surface, side: Vec3) -> Vec3 {
    surface.position + side * (RAY_BIAS * surface.reach)
}

/// The unit direction of a ray along `i` refracted into the medium across `n` (unit, on i's side)
/// with `eta` the ratio of indices (from over to); `None` past the critical angle
/// (`refracted_direction`).
pub(crate) fn refracted_direction(i: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -n.dot(i);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| (eta * i + (eta * cos_i - k.sqrt()) * n).normalize())
}

/// Schlick's approximation of the Fresnel reflectance; cos_theta is taken on the less dense side.
pub(crate) fn fresnel_schlick(cos_theta: f32, ior: f32) -> f32 {
    let r = (1.0 - ior) / (1.0 + ior);
    let r0 = r * r;
    let x = 1.0 - cos_theta;
    let x2 = x * x;
    r0 + (1.0 - r0) * x2 * x2 * x
}
