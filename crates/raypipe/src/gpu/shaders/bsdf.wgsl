// A material's scattering as the path integrator draws it: the lobes of a glTF surface (GGX
// specular drawn through its visible normals, Lambertian diffuse drawn by the cosine, and the
// transmission of KHR_materials_transmission through thin walls and volumes) and of the paper's
// materials (Lambert, a mirror, glass), picked by their Fresnel-weighted weights. Mirrored by
// src/cpu/bsdf.rs.

// The lobes' chances at a vertex, for its view direction; all 0 where the material sends nothing
// on.
struct Lobes {
    specular: f32,
    diffuse: f32,
    transmission: f32,
    // The specular lobe is a mirror (GGX's alpha under MIN_ALPHA, or a paper material's
    // reflection): a delta that only its own sampling finds.
    mirror: bool,
}

// A direction a vertex sends its path on: the throughput's factor f cos θ / pdf, and the pdf of
// the reflection lobes' mixture in solid angle (0 where a delta lobe or the transmission drew it:
// no light sample finds those directions, so their light needs no weighting). `through`: it
// leaves on the far side of the surface.
struct BsdfSample {
    dir: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    through: bool,
}

fn no_bsdf_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
}

// The GGX alpha of a glTF surface as the path integrator reads it.
fn path_alpha(s: GltfSurface) -> f32 {
    return s.roughness * s.roughness;
}

fn path_lobes(material: Material, s: GltfSurface, n_dot_v: f32) -> Lobes {
    var lobes: Lobes;
    if (HAS_GLTF_MATERIALS && material.model == MODEL_GLTF) {
        let dielectric = max3(dielectric_fresnel(s, n_dot_v));
        let metal = max3(metal_fresnel(s, n_dot_v));
        let under = (1.0 - s.metallic) * (1.0 - dielectric) * max3(s.base);
        lobes = Lobes(dielectric * (1.0 - s.metallic) + metal * s.metallic, under * (1.0 - s.transmission), under * s.transmission,
            path_alpha(s) < MIN_ALPHA);
    } else {
        lobes = Lobes(material.reflect, max3(material.color), material.transmit, true);
    }
    let sum = lobes.specular + lobes.diffuse + lobes.transmission;
    if (!(sum > 0.0)) {
        return Lobes(0.0, 0.0, 0.0, lobes.mirror);
    }
    return Lobes(lobes.specular / sum, lobes.diffuse / sum, lobes.transmission / sum, lobes.mirror);
}

// The density of GGX's visible-normal sampling of the reflection l (Heitz 2018): D(h) G1(v) /
// (4 n.v).
fn specular_pdf(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, alpha: f32) -> f32 {
    let n_dot_v = dot(n, v);
    let n_dot_l = dot(n, l);
    if (n_dot_v <= 0.0 || n_dot_l <= 0.0) {
        return 0.0;
    }
    let h = normalize(v + l);
    return ggx_distribution(max(dot(n, h), 0.0), alpha) * smith_g1(n_dot_v, alpha) / (4.0 * n_dot_v);
}

// The density of the reflection lobes' mixture at l: what a light sample weighs itself against.
fn reflection_pdf(material: Material, s: GltfSurface, lobes: Lobes, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> f32 {
    var pdf = lobes.diffuse * max(dot(n, l), 0.0) / PI;
    if (!lobes.mirror && lobes.specular > 0.0) {
        pdf += lobes.specular * specular_pdf(n, v, l, path_alpha(s));
    }
    return pdf;
}

// The BRDF of the lobes a light sample can find (all but mirrors): glTF's (gltf_brdf, its
// specular term left out where it is a mirror), or the paper's Lambert, colour / π.
fn reflection_brdf(material: Material, s: GltfSurface, lobes: Lobes, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    if (!(HAS_GLTF_MATERIALS && material.model == MODEL_GLTF)) {
        return material.color / PI;
    }
    if (!lobes.mirror) {
        return gltf_brdf(s, n, v, l);
    }
    let v_dot_h = dot(v, normalize(l + v));
    return s.base * ((1.0 - s.transmission) / PI) * (1.0 - max3(dielectric_fresnel(s, v_dot_h))) * (1.0 - s.metallic);
}

// What a punctual light of irradiance 1 from l gives the viewer: as the Whitted integrator lights a
// surface, Lambert and Phong for the paper's materials, glTF's BRDF (its highlight on a mirror a
// tiny spot) for glTF's.
fn punctual_response(material: Material, s: GltfSurface, frame: ShadingFrame, l: vec3<f32>) -> vec3<f32> {
    let n_dot_l = dot(frame.shading, l);
    if (HAS_GLTF_MATERIALS && material.model == MODEL_GLTF) {
        return n_dot_l * gltf_brdf(s, frame.shading, frame.view, l);
    }
    var highlight = 0.0;
    let r_dot_v = dot(reflect(-l, frame.shading), frame.view);
    if (r_dot_v > 0.0 && material.specular > 0.0) {
        highlight = material.specular * pow(r_dot_v, material.shininess);
    }
    return material.color * n_dot_l + vec3<f32>(highlight);
}

// A reflection drawn from the mixture (diffuse or rough specular), weighted f cos θ / pdf; none
// where it would leave below the geometric surface.
fn mixture_sample(material: Material, s: GltfSurface, lobes: Lobes, frame: ShadingFrame, dir: vec3<f32>) -> BsdfSample {
    let n_dot_l = dot(frame.shading, dir);
    if (n_dot_l <= 0.0 || dot(frame.normal, dir) <= 0.0) {
        return no_bsdf_sample();
    }
    let pdf = reflection_pdf(material, s, lobes, frame.shading, frame.view, dir);
    if (!(pdf > 0.0)) {
        return no_bsdf_sample();
    }
    let f = reflection_brdf(material, s, lobes, frame.shading, frame.view, dir);
    return BsdfSample(dir, f * n_dot_l / pdf, pdf, false);
}

// A microfacet normal about n drawn through GGX's visible normals.
fn visible_normal(n: vec3<f32>, v: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let basis = tangent_frame(n);
    let local = sample_visible_normal(vec3<f32>(dot(v, basis.t), dot(v, basis.b), max(dot(n, v), 0.0)), alpha, u);
    return local.x * basis.t + local.y * basis.b + local.z * n;
}

// The next direction of a path at a surface seen along frame.view, drawn with u (lobe, direction,
// direction); `entering` whether the path arrives from outside a volume.
fn sample_bsdf(material: Material, s: GltfSurface, lobes: Lobes, frame: ShadingFrame, entering: bool, u: vec3<f32>) -> BsdfSample {
    let n = frame.shading;
    let v = frame.view;
    let mirrored = reflect(-v, n);
    if (u.x < lobes.diffuse) {
        return mixture_sample(material, s, lobes, frame, sample_cosine(n, u.yz));
    }
    let gltf = HAS_GLTF_MATERIALS && material.model == MODEL_GLTF;
    if (u.x < lobes.diffuse + lobes.specular) {
        if (!lobes.mirror) {
            let h = visible_normal(n, v, path_alpha(s), u.yz);
            return mixture_sample(material, s, lobes, frame, normalize(2.0 * dot(v, h) * h - v));
        }
        if (dot(frame.normal, mirrored) <= 0.0) {
            return no_bsdf_sample();
        }
        var reflectance = vec3<f32>(material.reflect);
        if (gltf) {
            let n_dot_v = max(dot(n, v), 0.0);
            reflectance = dielectric_fresnel(s, n_dot_v) * (1.0 - s.metallic) + metal_fresnel(s, n_dot_v) * s.metallic;
        }
        return BsdfSample(mirrored, reflectance / lobes.specular, 0.0, false);
    }
    if (!(lobes.transmission > 0.0)) {
        return no_bsdf_sample();
    }
    if (!gltf) {
        // The paper's glass: Fresnel picks reflection or refraction; past the critical angle all
        // of it reflects.
        let eta = select(material.ior, 1.0 / material.ior, entering);
        let cos_i = dot(v, n);
        let bent = refracted_direction(-v, n, eta);
        var fresnel = 1.0;
        if (bent.w > 0.0) {
            fresnel = fresnel_schlick(select(-dot(bent.xyz, n), cos_i, entering), material.ior);
        }
        let weight = vec3<f32>(material.transmit / lobes.transmission);
        if (u.y < fresnel) {
            return BsdfSample(mirrored, weight, 0.0, false);
        }
        return BsdfSample(bent.xyz, weight, 0.0, true);
    }
    // glTF's transmission: the specular lobe's sample carried through the surface, weighted by
    // what the dielectric layer lets pass (the Whitted integrator's `gltf_branches` does the same).
    let alpha = path_alpha(s);
    var h = n;
    var share = 1.0;
    let n_dot_v = max(dot(n, v), 0.0);
    if (!lobes.mirror) {
        h = visible_normal(n, v, alpha, u.yz);
    }
    let v_dot_h = dot(v, h);
    let reflected = normalize(2.0 * v_dot_h * h - v);
    if (!lobes.mirror) {
        let n_dot_l = dot(n, reflected);
        share = select(0.0, smith_g2(n_dot_l, n_dot_v, alpha) / smith_g1(n_dot_v, alpha), n_dot_l > 0.0 && n_dot_v > 0.0);
    }
    let passed = (1.0 - s.metallic) * s.transmission * (1.0 - max3(dielectric_fresnel(s, v_dot_h))) * share;
    let weight = s.base * passed / lobes.transmission;
    if (HAS_VOLUMES && material.volume != 0u) {
        let eta = select(s.ior, 1.0 / s.ior, entering);
        let bent = refracted_direction(-v, h, eta);
        if (bent.w > 0.0) {
            return BsdfSample(bent.xyz, weight, 0.0, true);
        }
        return BsdfSample(reflected, weight, 0.0, false);
    }
    return BsdfSample(reflected - 2.0 * dot(reflected, n) * n, weight, 0.0, true);
}
