//! A material's scattering as the path integrator draws it: the twin of `shaders/bsdf.wgsl`.

// `!(x > 0.0)` is true for a NaN, as the shader's tests are: the guards keep NaNs out.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::brdf::{
    GltfSurface, MIN_ALPHA, dielectric_fresnel, ggx_distribution, gltf_brdf, max3, metal_fresnel,
    sample_visible_normal, smith_g1, smith_g2, tangent_frame,
};
use super::intersect::v3;
use super::sampling::sample_cosine;
use super::shade::{ShadingFrame, fresnel_schlick, reflect, refracted_direction};
use crate::records::GpuMaterial;
use crate::records::constants::MODEL_GLTF;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The lobes' chances at a vertex, for its view direction; all 0 where the material sends nothing
/// on (`Lobes`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Lobes {
    pub specular: f32,
    pub diffuse: f32,
    pub transmission: f32,
    /// The specular lobe is a mirror (GGX's alpha under MIN_ALPHA, or a paper material's
    /// reflection): a delta that only its own sampling finds.
    pub mirror: bool,
}

/// A direction a vertex sends its path on (`BsdfSample`): the throughput's factor f cos θ / pdf,
/// and the reflection lobes' mixture density (0 where a delta lobe or the transmission drew it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BsdfSample {
    pub dir: Vec3,
    pub weight: Vec3,
    pub pdf: f32,
    /// It leaves on the far side of the surface.
    pub through: bool,
}

const NO_SAMPLE: BsdfSample = BsdfSample {
    dir: Vec3::ZERO,
    weight: Vec3::ZERO,
    pdf: 0.0,
    through: false,
};

fn path_alpha(s: &GltfSurface) -> f32 {
    s.roughness * s.roughness
}

fn is_gltf(material: &GpuMaterial) -> bool {
    material.model == MODEL_GLTF
}

/// The lobes' chances, weighed by what each would carry seen at `n_dot_v` (`path_lobes`).
pub(crate) fn path_lobes(material: &GpuMaterial, s: &GltfSurface, n_dot_v: f32) -> Lobes {
    let lobes = if is_gltf(material) {
        let dielectric = max3(dielectric_fresnel(s, n_dot_v));
        let metal = max3(metal_fresnel(s, n_dot_v));
        let under = (1.0 - s.metallic) * (1.0 - dielectric) * max3(s.base);
        Lobes {
            specular: dielectric * (1.0 - s.metallic) + metal * s.metallic,
            diffuse: under * (1.0 - s.transmission),
            transmission: under * s.transmission,
            mirror: path_alpha(s) < MIN_ALPHA,
        }
    } else {
        Lobes {
            specular: material.reflect,
            diffuse: max3(v3(material.color)),
            transmission: material.transmit,
            mirror: true,
        }
    };
    let sum = lobes.specular + lobes.diffuse + lobes.transmission;
    if !(sum > 0.0) {
        return Lobes {
            specular: 0.0,
            diffuse: 0.0,
            transmission: 0.0,
            ..lobes
        };
    }
    Lobes {
        specular: lobes.specular / sum,
        diffuse: lobes.diffuse / sum,
        transmission: lobes.transmission / sum,
        ..lobes
    }
}

/// The density of GGX's visible-normal sampling of the reflection `l`: D(h) G1(v) / (4 n·v).
pub(crate) fn specular_pdf(n: Vec3, v: Vec3, l: Vec3, alpha: f32) -> f32 {
    let (n_dot_v, n_dot_l) = (n.dot(v), n.dot(l));
    if n_dot_v <= 0.0 || n_dot_l <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize();
    ggx_distribution(n.dot(h).max(0.0), alpha) * smith_g1(n_dot_v, alpha) / (4.0 * n_dot_v)
}

/// The density of the reflection lobes' mixture at `l` (`reflection_pdf`).
pub(crate) fn reflection_pdf(s: &GltfSurface, lobes: &Lobes, n: Vec3, v: Vec3, l: Vec3) -> f32 {
    let mut pdf = lobes.diffuse * n.dot(l).max(0.0) / PI;
    if !lobes.mirror && lobes.specular > 0.0 {
        pdf += lobes.specular * specular_pdf(n, v, l, path_alpha(s));
    }
    pdf
}

/// The BRDF of the lobes a light sample can find, all but mirrors (`reflection_brdf`).
pub(crate) fn reflection_brdf(
    material: &GpuMaterial,
    s: &GltfSurface,
    lobes: &Lobes,
    n: Vec3,
    v: Vec3,
    l: Vec3,
) -> Vec3 {
    if !is_gltf(material) {
        return v3(material.color) / PI;
    }
    if !lobes.mirror {
        return gltf_brdf(s, n, v, l);
    }
    let v_dot_h = v.dot((l + v).normalize());
    s.base * ((1.0 - s.transmission) / PI) * (1.0 - max3(dielectric_fresnel(s, v_dot_h))) * (1.0 - s.metallic)
}

/// What a punctual light of irradiance 1 from `l` gives the viewer, as the Whitted integrator
/// lights a surface (`punctual_response`).
pub(crate) fn punctual_response(material: &GpuMaterial, s: &GltfSurface, frame: ShadingFrame, l: Vec3) -> Vec3 {
    let n_dot_l = frame.shading.dot(l);
    if is_gltf(material) {
        return n_dot_l * gltf_brdf(s, frame.shading, frame.view, l);
    }
    let mut highlight = 0.0;
    let r_dot_v = reflect(-l, frame.shading).dot(frame.view);
    if r_dot_v > 0.0 && material.specular > 0.0 {
        highlight = material.specular * r_dot_v.powf(material.shininess);
    }
    v3(material.color) * n_dot_l + Vec3::splat(highlight)
}

/// A reflection drawn from the mixture, weighted f cos θ / pdf (`mixture_sample`).
fn mixture_sample(
    material: &GpuMaterial,
    s: &GltfSurface,
    lobes: &Lobes,
    frame: ShadingFrame,
    dir: Vec3,
) -> BsdfSample {
    let n_dot_l = frame.shading.dot(dir);
    if n_dot_l <= 0.0 || frame.normal.dot(dir) <= 0.0 {
        return NO_SAMPLE;
    }
    let pdf = reflection_pdf(s, lobes, frame.shading, frame.view, dir);
    if !(pdf > 0.0) {
        return NO_SAMPLE;
    }
    let f = reflection_brdf(material, s, lobes, frame.shading, frame.view, dir);
    BsdfSample {
        dir,
        weight: f * n_dot_l / pdf,
        pdf,
        through: false,
    }
}

/// A microfacet normal about `n` drawn through GGX's visible normals.
fn visible_normal(n: Vec3, v: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let (t, b) = tangent_frame(n);
    let local = sample_visible_normal(Vec3::new(v.dot(t), v.dot(b), n.dot(v).max(0.0)), alpha, u.to_array());
    local.x * t + local.y * b + local.z * n
}

/// The next direction of a path at a surface seen along `frame.view`, drawn with `u` (lobe,
/// direction, direction); `entering` whether the path arrives from outside a volume
/// (`sample_bsdf`).
pub(crate) fn sample_bsdf(
    material: &GpuMaterial,
    s: &GltfSurface,
    lobes: &Lobes,
    frame: ShadingFrame,
    entering: bool,
    u: Vec3,
) -> BsdfSample {
    let (n, v) = (frame.shading, frame.view);
    let mirrored = reflect(-v, n);
    let du = Vec2::new(u.y, u.z);
    if u.x < lobes.diffuse {
        return mixture_sample(material, s, lobes, frame, sample_cosine(n, du));
    }
    let gltf = is_gltf(material);
    if u.x < lobes.diffuse + lobes.specular {
        if !lobes.mirror {
            let h = visible_normal(n, v, path_alpha(s), du);
            return mixture_sample(material, s, lobes, frame, (2.0 * v.dot(h) * h - v).normalize());
        }
        if frame.normal.dot(mirrored) <= 0.0 {
            return NO_SAMPLE;
        }
        let reflectance = if gltf {
            let n_dot_v = n.dot(v).max(0.0);
            dielectric_fresnel(s, n_dot_v) * (1.0 - s.metallic) + metal_fresnel(s, n_dot_v) * s.metallic
        } else {
            Vec3::splat(material.reflect)
        };
        return BsdfSample {
            dir: mirrored,
            weight: reflectance / lobes.specular,
            pdf: 0.0,
            through: false,
        };
    }
    if !(lobes.transmission > 0.0) {
        return NO_SAMPLE;
    }
    if !gltf {
        // The paper's glass: Fresnel picks reflection or refraction; past the critical angle all
        // of it reflects.
        let eta = if entering { 1.0 / material.ior } else { material.ior };
        let cos_i = v.dot(n);
        let bent = refracted_direction(-v, n, eta);
        let fresnel = match bent {
            Some(t) => fresnel_schlick(if entering { cos_i } else { -t.dot(n) }, material.ior),
            None => 1.0,
        };
        let weight = Vec3::splat(material.transmit / lobes.transmission);
        return match bent {
            Some(t) if u.y >= fresnel => BsdfSample {
                dir: t,
                weight,
                pdf: 0.0,
                through: true,
            },
            _ => BsdfSample {
                dir: mirrored,
                weight,
                pdf: 0.0,
                through: false,
            },
        };
    }
    // glTF's transmission: the specular lobe's sample carried through the surface, weighted by
    // what the dielectric layer lets pass.
    let alpha = path_alpha(s);
    let n_dot_v = n.dot(v).max(0.0);
    let h = if lobes.mirror {
        n
    } else {
        visible_normal(n, v, alpha, du)
    };
    let v_dot_h = v.dot(h);
    let reflected = (2.0 * v_dot_h * h - v).normalize();
    let share = if lobes.mirror {
        1.0
    } else {
        let n_dot_l = n.dot(reflected);
        if n_dot_l > 0.0 && n_dot_v > 0.0 {
            smith_g2(n_dot_l, n_dot_v, alpha) / smith_g1(n_dot_v, alpha)
        } else {
            0.0
        }
    };
    let passed = (1.0 - s.metallic) * s.transmission * (1.0 - max3(dielectric_fresnel(s, v_dot_h))) * share;
    let weight = s.base * passed / lobes.transmission;
    if material.volume != 0 {
        let eta = if entering { 1.0 / s.ior } else { s.ior };
        return match refracted_direction(-v, h, eta) {
            Some(t) => BsdfSample {
                dir: t,
                weight,
                pdf: 0.0,
                through: true,
            },
            None => BsdfSample {
                dir: reflected,
                weight,
                pdf: 0.0,
                through: false,
            },
        };
    }
    BsdfSample {
        dir: reflected - 2.0 * reflected.dot(n) * n,
        weight,
        pdf: 0.0,
        through: true,
    }
}
