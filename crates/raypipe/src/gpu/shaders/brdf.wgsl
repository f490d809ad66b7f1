// glTF's metallic-roughness BRDF (the specification's Appendix B) and the sampling of its
// reflections. Mirrored by src/cpu/brdf.rs.

const PI: f32 = 3.14159265358979;
// The smallest GGX alpha direct light is evaluated with: a point light's highlight on a mirror is
// then a tiny spot rather than 0/0.
const MIN_ALPHA: f32 = 1e-3;

// What a glTF surface is made of at a hit, its maps applied.
struct GltfSurface {
    base: vec3<f32>,
    metallic: f32,
    roughness: f32,
    transmission: f32,
    ior: f32,
    // KHR_materials_specular: the factor and colour of the dielectric layer.
    specular_factor: f32,
    specular_color: vec3<f32>,
}

fn pow5(x: f32) -> f32 {
    let x2 = x * x;
    return x2 * x2 * x;
}

fn max3(v: vec3<f32>) -> f32 {
    return max(v.x, max(v.y, v.z));
}

// Trowbridge-Reitz (GGX) normal distribution D.
fn ggx_distribution(n_dot_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let f = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * f * f);
}

// Smith's height-correlated visibility V = G2 / (4 |n.l| |n.v|).
fn smith_visibility(n_dot_l: f32, n_dot_v: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    let gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    let sum = gv + gl;
    return select(0.0, 0.5 / sum, sum > 0.0);
}

// Smith's masking G1 of one direction.
fn smith_g1(n_dot_x: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    return 2.0 * n_dot_x / (n_dot_x + sqrt(a2 + (1.0 - a2) * n_dot_x * n_dot_x));
}

// Smith's height-correlated masking-shadowing G2.
fn smith_g2(n_dot_l: f32, n_dot_v: f32, alpha: f32) -> f32 {
    return 4.0 * n_dot_l * n_dot_v * smith_visibility(n_dot_l, n_dot_v, alpha);
}

// The dielectric layer's Fresnel reflectance (Schlick) with KHR_materials_specular's factor and
// colour: F0 = min(((ior - 1) / (ior + 1))^2 specular colour, 1) and F90 = 1, times the factor.
fn dielectric_fresnel(s: GltfSurface, v_dot_h: f32) -> vec3<f32> {
    let r = (s.ior - 1.0) / (s.ior + 1.0);
    let f0 = min(r * r * s.specular_color, vec3<f32>(1.0));
    return s.specular_factor * (f0 + (vec3<f32>(1.0) - f0) * pow5(1.0 - abs(v_dot_h)));
}

// The metal's Fresnel reflectance (Schlick, F0 the base colour).
fn metal_fresnel(s: GltfSurface, v_dot_h: f32) -> vec3<f32> {
    return s.base + (vec3<f32>(1.0) - s.base) * pow5(1.0 - abs(v_dot_h));
}

// The BRDF for light from l leaving to v about the shading normal n: mix(dielectric, metal,
// metallic), dielectric = (1 - max F) (1 - transmission) base / pi + F D V, metal = F_metal D V.
fn gltf_brdf(s: GltfSurface, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    let h = normalize(l + v);
    let n_dot_l = max(dot(n, l), 0.0);
    let n_dot_v = max(dot(n, v), 0.0);
    let n_dot_h = max(dot(n, h), 0.0);
    let v_dot_h = dot(v, h);
    let alpha = max(s.roughness * s.roughness, MIN_ALPHA);
    let specular = ggx_distribution(n_dot_h, alpha) * smith_visibility(n_dot_l, n_dot_v, alpha);
    let fresnel = dielectric_fresnel(s, v_dot_h);
    let diffuse = s.base * ((1.0 - s.transmission) / PI);
    let dielectric = diffuse * (1.0 - max3(fresnel)) + fresnel * specular;
    let metal = metal_fresnel(s, v_dot_h) * specular;
    return dielectric * (1.0 - s.metallic) + metal * s.metallic;
}

struct TangentFrame {
    t: vec3<f32>,
    b: vec3<f32>,
}

// A unit n's tangent frame (Duff et al. 2017).
fn tangent_frame(n: vec3<f32>) -> TangentFrame {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return TangentFrame(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

// A microfacet normal drawn from GGX's distribution of normals visible from v (Heitz 2018), in the
// frame where the surface normal is +z; u uniform in [0, 1)^2.
fn sample_visible_normal(v: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let len_sq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if (len_sq > 0.0) {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(len_sq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    return normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
}

// Where a glTF surface sends its reflected ray and what the ray carries back: F at a mirror,
// F G2 / G1(v) (the visible-normal estimator) for a rough surface; the dielectric Fresnel term
// at the sampled normal (what transmission loses) and the estimator's share G2 / G1(v).
struct SpecularSample {
    dir: vec3<f32>,
    weight: vec3<f32>,
    dielectric_fresnel: vec3<f32>,
    share: f32,
}

// The reflected ray seen from v about the shading normal n: the mirror direction at roughness 0,
// else one drawn through GGX's visible normals with u.
fn sample_specular(s: GltfSurface, n: vec3<f32>, v: vec3<f32>, u: vec2<f32>) -> SpecularSample {
    let alpha = s.roughness * s.roughness;
    let n_dot_v = max(dot(n, v), 0.0);
    var h = n;
    if (alpha != 0.0) {
        let frame = tangent_frame(n);
        let local = sample_visible_normal(vec3<f32>(dot(v, frame.t), dot(v, frame.b), n_dot_v), alpha, u);
        h = local.x * frame.t + local.y * frame.b + local.z * n;
    }
    let v_dot_h = dot(v, h);
    let dir = normalize(2.0 * v_dot_h * h - v);
    let n_dot_l = dot(n, dir);
    let fresnel = dielectric_fresnel(s, v_dot_h);
    let mixed = fresnel * (1.0 - s.metallic) + metal_fresnel(s, v_dot_h) * s.metallic;
    var share = 1.0;
    if (alpha != 0.0) {
        share = 0.0;
        if (n_dot_l > 0.0 && n_dot_v > 0.0) {
            share = smith_g2(n_dot_l, n_dot_v, alpha) / smith_g1(n_dot_v, alpha);
        }
    }
    return SpecularSample(dir, mixed * share, fresnel, share);
}
