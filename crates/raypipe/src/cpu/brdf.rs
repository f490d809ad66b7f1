//! glTF's metallic-roughness BRDF (the specification's Appendix B) and the sampling of its
//! reflections: the twin of `shaders/brdf.wgsl`.

use glam::Vec3;
use std::f32::consts::PI;

/// The smallest GGX alpha direct light is evaluated with: a point light's highlight on a mirror
/// is then a tiny spot rather than 0/0.
pub(crate) const MIN_ALPHA: f32 = 1e-3;

/// What a glTF surface is made of at a hit, its maps applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GltfSurface {
    pub base: Vec3,
    pub metallic: f32,
    pub roughness: f32,
    pub transmission: f32,
    pub ior: f32,
    /// KHR_materials_specular: the factor and colour of the dielectric layer.
    pub specular_factor: f32,
    pub specular_color: Vec3,
}

fn pow5(x: f32) -> f32 {
    let x2 = x * x;
    x2 * x2 * x
}

pub(crate) fn max3(v: Vec3) -> f32 {
    v.x.max(v.y.max(v.z))
}

/// Trowbridge-Reitz (GGX) normal distribution D.
pub(crate) fn ggx_distribution(n_dot_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let f = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    a2 / (PI * f * f)
}

/// Smith's height-correlated visibility V = G2 / (4 |n·l| |n·v|).
pub(crate) fn smith_visibility(n_dot_l: f32, n_dot_v: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt();
    let gl = n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt();
    let sum = gv + gl;
    if sum > 0.0 { 0.5 / sum } else { 0.0 }
}

/// Smith's masking G1 of one direction.
pub(crate) fn smith_g1(n_dot_x: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    2.0 * n_dot_x / (n_dot_x + (a2 + (1.0 - a2) * n_dot_x * n_dot_x).sqrt())
}

/// Smith's height-correlated masking-shadowing G2.
pub(crate) fn smith_g2(n_dot_l: f32, n_dot_v: f32, alpha: f32) -> f32 {
    4.0 * n_dot_l * n_dot_v * smith_visibility(n_dot_l, n_dot_v, alpha)
}

/// The dielectric layer's Fresnel reflectance at `v_dot_h` (Schlick), KHR_materials_specular's
/// factor and colour applied: F0 = min(((ior - 1) / (ior + 1))² specular colour, 1) and F90 = 1,
/// both times the factor.
pub(crate) fn dielectric_fresnel(s: &GltfSurface, v_dot_h: f32) -> Vec3 {
    let r = (s.ior - 1.0) / (s.ior + 1.0);
    let f0 = (r * r * s.specular_color).min(Vec3::ONE);
    s.specular_factor * (f0 + (Vec3::ONE - f0) * pow5(1.0 - v_dot_h.abs()))
}

/// The metal's Fresnel reflectance (Schlick, F0 the base colour).
pub(crate) fn metal_fresnel(s: &GltfSurface, v_dot_h: f32) -> Vec3 {
    s.base + (Vec3::ONE - s.base) * pow5(1.0 - v_dot_h.abs())
}

/// The glTF BRDF for light arriving from `l` and leaving to `v`, about the shading normal `n`
/// (all unit, `l` and `v` on `n`'s side): mix(dielectric, metal, metallic) with
/// dielectric = (1 - max F) (1 - transmission) base / π + F D V and metal = F_metal D V.
pub(crate) fn gltf_brdf(s: &GltfSurface, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
    let h = (l + v).normalize();
    let n_dot_l = n.dot(l).max(0.0);
    let n_dot_v = n.dot(v).max(0.0);
    let n_dot_h = n.dot(h).max(0.0);
    let v_dot_h = v.dot(h);
    let alpha = (s.roughness * s.roughness).max(MIN_ALPHA);
    let specular = ggx_distribution(n_dot_h, alpha) * smith_visibility(n_dot_l, n_dot_v, alpha);
    let fresnel = dielectric_fresnel(s, v_dot_h);
    let diffuse = s.base * ((1.0 - s.transmission) / PI);
    let dielectric = diffuse * (1.0 - max3(fresnel)) + fresnel * specular;
    let metal = metal_fresnel(s, v_dot_h) * specular;
    dielectric * (1.0 - s.metallic) + metal * s.metallic
}

/// A unit `n`'s tangent frame (Duff et al. 2017): two unit vectors that make, with `n`, a
/// right-handed orthonormal basis.
pub(crate) fn tangent_frame(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A microfacet normal drawn from GGX's distribution of normals visible from `v` (Heitz 2018),
/// in the frame where the surface normal is +z; `u` uniform in [0, 1)².
pub(crate) fn sample_visible_normal(v: Vec3, alpha: f32, u: [f32; 2]) -> Vec3 {
    let vh = Vec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let len_sq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len_sq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len_sq.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// Where a glTF surface sends its reflected ray, and what the ray carries back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SpecularSample {
    /// Unit, on `n`'s side unless `weight` is zero.
    pub dir: Vec3,
    /// The reflected radiance's factor: F at a mirror; F G2 / G1(v), the visible-normal
    /// estimator, for a rough surface.
    pub weight: Vec3,
    /// The dielectric layer's Fresnel reflectance at the sampled normal: what transmission loses.
    pub dielectric_fresnel: Vec3,
    /// G2 / G1(v) for a rough surface (1 at a mirror; 0 where the drawn ray would leave below the
    /// surface): the estimator's share, which transmitted rays drawn the same way take too.
    pub share: f32,
}

/// The reflected ray of a glTF surface seen from `v` about the shading normal `n`: the mirror
/// direction at roughness 0, else one drawn through GGX's visible normals with `u`.
pub(crate) fn sample_specular(s: &GltfSurface, n: Vec3, v: Vec3, u: [f32; 2]) -> SpecularSample {
    let alpha = s.roughness * s.roughness;
    let n_dot_v = n.dot(v).max(0.0);
    let h = if alpha == 0.0 {
        n
    } else {
        let (t, b) = tangent_frame(n);
        let local = sample_visible_normal(Vec3::new(v.dot(t), v.dot(b), n_dot_v), alpha, u);
        local.x * t + local.y * b + local.z * n
    };
    let v_dot_h = v.dot(h);
    let dir = (2.0 * v_dot_h * h - v).normalize();
    let n_dot_l = n.dot(dir);
    let fresnel = dielectric_fresnel(s, v_dot_h);
    let mixed = fresnel * (1.0 - s.metallic) + metal_fresnel(s, v_dot_h) * s.metallic;
    let share = if alpha == 0.0 {
        1.0
    } else if n_dot_l > 0.0 && n_dot_v > 0.0 {
        smith_g2(n_dot_l, n_dot_v, alpha) / smith_g1(n_dot_v, alpha)
    } else {
        0.0
    };
    SpecularSample {
        dir,
        weight: mixed * share,
        dielectric_fresnel: fresnel,
        share,
    }
}
