//! glTF materials and lights on the CPU reference against formulas written out here, not taken
//! from the library: the Appendix B BRDF for a dielectric, a metal and a mix; inverse-square
//! falloff and the range window; the spot cone's smooth edge; directional light and its parallel
//! shadow rays; a texture transform's texel. The GPU matches the CPU in tests/gpu/.

use crate::common::{centre, plane_scene, quad_triangles};
use glam::{Quat, Vec2, Vec3};
use raypipe::modes::Accel;
use raypipe::records::PackedScene;
use raypipe::scene::{Light, LightKind, Material, Pbr, Scene, Texture, TextureMap, TextureTransform, Triangle, Wrap};
use std::f64::consts::PI;

fn gltf_material(base: Vec3, metallic: f32, roughness: f32) -> Material {
    Material {
        color: base,
        pbr: Some(Pbr {
            metallic,
            roughness,
            ..Pbr::default()
        }),
        ..Material::default()
    }
}

fn point(position: Vec3, candela: f32, range: Option<f32>) -> Light {
    Light {
        position,
        color: Vec3::splat(candela),
        kind: LightKind::Point { range },
    }
}

/// The glTF BRDF (the specification's Appendix B) for n = v = +z, written out in f64:
/// f = (1 - metallic) [(1 - F) c / pi + F D V] + metallic [F_metal D V].
fn brdf_formula(base: [f64; 3], metallic: f64, roughness: f64, l: [f64; 3]) -> [f64; 3] {
    brdf_with_specular(base, metallic, roughness, 1.0, [1.0; 3], l)
}

/// `brdf_formula` with KHR_materials_specular's strength and colour: the dielectric's Fresnel
/// term is F = strength (F0 + (1 - F0) (1 - v.h)^5) with F0 = min(0.04 colour, 1), and its diffuse
/// part keeps 1 - max(F).
fn brdf_with_specular(
    base: [f64; 3],
    metallic: f64,
    roughness: f64,
    strength: f64,
    colour: [f64; 3],
    l: [f64; 3],
) -> [f64; 3] {
    let norm = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
    let l = l.map(|c| c / norm);
    let (n_dot_l, n_dot_v) = (l[2], 1.0);
    // h = (l + v) / |l + v|
    let h = [l[0], l[1], l[2] + 1.0];
    let h_norm = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let (n_dot_h, v_dot_h) = (h[2] / h_norm, h[2] / h_norm);
    let alpha: f64 = roughness * roughness;
    let a2 = alpha * alpha;
    let d = a2 / (PI * (n_dot_h * n_dot_h * (a2 - 1.0) + 1.0).powi(2));
    let vis = 0.5
        / (n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt()
            + n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt());
    let schlick = |f0: f64| f0 + (1.0 - f0) * (1.0 - v_dot_h).powi(5);
    // F0 = ((1.5 - 1) / (1.5 + 1))^2 = 0.04, tinted.
    let fresnel = colour.map(|c| strength * schlick((0.04 * c).min(1.0)));
    let max_fresnel = fresnel.iter().copied().fold(0.0, f64::max);
    std::array::from_fn(|i| {
        let dielectric = (1.0 - max_fresnel) * base[i] / PI + fresnel[i] * d * vis;
        let metal = schlick(base[i]) * d * vis;
        (1.0 - metallic) * dielectric + metallic * metal
    })
}

fn assert_close(got: Vec3, expected: [f64; 3], what: &str) {
    for c in 0..3 {
        let e = expected[c] as f32;
        assert!(
            (got[c] - e).abs() <= 1e-4 * e.abs().max(0.1),
            "{what}: channel {c} is {}, the formula says {e}",
            got[c]
        );
    }
}

#[test]
fn a_lit_plane_shows_the_gltf_brdf_for_dielectrics_metals_and_mixes() {
    let light_at = Vec3::new(1.5, 0.5, 2.0);
    let candela = 12.0;
    let d2 = light_at.length_squared() as f64;
    let cos = (light_at.z / light_at.length()) as f64;
    let base = [0.8, 0.4, 0.2];
    for (metallic, roughness) in [(0.0, 0.5), (1.0, 0.3), (0.5, 0.7), (0.0, 1.0)] {
        let material = gltf_material(
            Vec3::from_array(base.map(|c| c as f32)),
            metallic as f32,
            roughness as f32,
        );
        let got = centre(&plane_scene(material, vec![point(light_at, candela, None)]));
        let f = brdf_formula(base, metallic, roughness, light_at.to_array().map(|c| c as f64));
        let expected = f.map(|f| candela as f64 / d2 * cos * f);
        assert_close(got, expected, &format!("metallic {metallic}, roughness {roughness}"));
    }
}

#[test]
fn the_specular_maps_scale_the_dielectric_layer() {
    // KHR_materials_specular's strength factor 0.8 times its texture's alpha 0.5, and its colour
    // factor (4, 2, 1) times its texture's (0.5, 1, 0.25): strength 0.4, colour (2, 2, 0.25).
    let light_at = Vec3::new(1.5, 0.5, 2.0);
    let candela = 12.0;
    let base = [0.8, 0.4, 0.2];
    let mut material = gltf_material(Vec3::from_array(base.map(|c| c as f32)), 0.0, 0.5);
    let pbr = material.pbr.as_mut().unwrap();
    pbr.specular_factor = 0.8;
    pbr.specular_color = Vec3::new(4.0, 2.0, 1.0);
    pbr.specular_texture = Some(TextureMap::plain(0));
    pbr.specular_color_texture = Some(TextureMap::plain(1));
    let mut scene = plane_scene(material, vec![point(light_at, candela, None)]);
    scene.textures = vec![
        Texture::from_linear(1, 1, &[[1.0, 1.0, 1.0, 0.5]], [Wrap::Repeat; 2]),
        Texture::from_linear(1, 1, &[[0.5, 1.0, 0.25, 1.0]], [Wrap::Repeat; 2]),
    ];
    let irradiance = candela as f64 / light_at.length_squared() as f64 * (light_at.z / light_at.length()) as f64;
    let l = light_at.to_array().map(|c| c as f64);
    let f = brdf_with_specular(base, 0.0, 0.5, 0.4, [2.0, 2.0, 0.25], l);
    assert_close(centre(&scene), f.map(|f| irradiance * f), "both maps");
    // Without the maps the layer is the factors' alone.
    let pbr = scene.materials[0].pbr.as_mut().unwrap();
    (pbr.specular_texture, pbr.specular_color_texture) = (None, None);
    let f = brdf_with_specular(base, 0.0, 0.5, 0.8, [4.0, 2.0, 1.0], l);
    assert_close(centre(&scene), f.map(|f| irradiance * f), "the factors");
}

#[test]
fn point_lights_fall_off_with_the_inverse_square_and_end_at_their_range() {
    let white = gltf_material(Vec3::ONE, 0.0, 1.0);
    let at = |d: f32, range| centre(&plane_scene(white, vec![point(Vec3::new(0.0, 0.0, d), 10.0, range)]));
    let (one, two, four) = (at(1.0, None), at(2.0, None), at(4.0, None));
    assert!(
        (one.x / two.x - 4.0).abs() < 1e-4 && (one.x / four.x - 16.0).abs() < 1e-3,
        "{one} {two} {four}"
    );
    // Straight above, h = n = v = l, alpha = 1: f = (1 - 0.04) / pi + 0.04 D V with
    // D = alpha² / (pi alpha⁴) = 1 / pi and V = 0.5 / (1 + 1).
    let f = 0.96 / PI + 0.04 / PI * 0.25;
    assert_close(one, [10.0 * f; 3], "1 m");
    // The window: clamp(1 - (d / range)^4, 0, 1) / d².
    let window = 1.0 - (2.0f64 / 3.0).powi(4);
    assert_close(at(2.0, Some(3.0)), [10.0 / 4.0 * window * f; 3], "range 3 at 2 m");
    assert_eq!(at(2.0, Some(1.9)), Vec3::ZERO, "beyond its range a light gives nothing");
}

#[test]
fn a_spot_is_full_inside_its_inner_cone_dark_beyond_its_outer_and_smooth_between() {
    let white = gltf_material(Vec3::ONE, 0.0, 1.0);
    let (inner, outer) = (0.2f32, 0.5f32);
    let lit_at = |angle: f32| {
        // The spot straight above the hit, its axis turned `angle` off the way down to it.
        let direction = Quat::from_rotation_x(angle) * Vec3::NEG_Z;
        let spot = Light {
            position: Vec3::new(0.0, 0.0, 2.0),
            color: Vec3::splat(8.0),
            kind: LightKind::Spot {
                direction,
                inner_cone: inner,
                outer_cone: outer,
                range: None,
            },
        };
        centre(&plane_scene(white, vec![spot])).x as f64
    };
    let full = lit_at(0.0);
    assert!(
        (lit_at(inner * 0.9) - full).abs() < 1e-6 * full,
        "inside the inner cone"
    );
    assert_eq!(lit_at(outer * 1.02), 0.0, "beyond the outer cone");
    for angle in [0.25f32, 0.35, 0.45] {
        let (c, ci, co) = (angle.cos() as f64, inner.cos() as f64, outer.cos() as f64);
        let step = ((c - co) / (ci - co)).clamp(0.0, 1.0);
        let expected = full * step * step;
        assert!(
            (lit_at(angle) - expected).abs() < 2e-4 * full,
            "at {angle} rad: {} where the cone says {expected}",
            lit_at(angle)
        );
    }
}

#[test]
fn directional_light_is_parallel_and_its_shadows_reach_to_infinity() {
    let white = gltf_material(Vec3::ONE, 0.0, 1.0);
    let travel = Vec3::new(-0.6, 0.0, -0.8);
    let sun = Light {
        position: Vec3::ZERO,
        color: Vec3::splat(3.0),
        kind: LightKind::Directional { direction: travel },
    };
    let mut scene = plane_scene(white, vec![sun]);
    let f = brdf_formula([1.0; 3], 0.0, 1.0, [0.6, 0.0, 0.8]);
    assert_close(centre(&scene), f.map(|f| 3.0 * 0.8 * f), "lux times cosine times BRDF");
    // A small triangle far up the beam, beyond where any point light would stand, still shades
    // the hit.
    let far = -travel * 1e4;
    scene.triangles.push(Triangle {
        vertices: [
            far + Vec3::new(-5.0, -5.0, 0.0),
            far + Vec3::new(5.0, -5.0, 0.0),
            far + Vec3::new(0.0, 5.0, 0.0),
        ],
        normals: None,
        uvs: None,
        material: 0,
        ..Default::default()
    });
    assert_eq!(centre(&scene), Vec3::ZERO);
}

#[test]
fn emission_and_the_texture_transform_pick_the_texel_the_extension_says() {
    // A 2x2 emissive texture (red, green / blue, white); no lights, so a pixel is its emission.
    let texels = [
        [1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
        [1.0, 1.0, 1.0, 1.0],
    ];
    let texture = Texture::from_linear(2, 2, &texels, [Wrap::Repeat; 2]);
    let emissive = |transform| {
        let mut material = gltf_material(Vec3::ZERO, 0.0, 1.0);
        material.emission = Vec3::ONE;
        material.pbr.as_mut().unwrap().emissive_texture = Some(TextureMap {
            transform,
            ..TextureMap::plain(0)
        });
        let mut scene = plane_scene(material, Vec::new());
        scene.textures = vec![texture.clone()];
        centre(&scene)
    };
    // The hit's coordinates are (0, 0); u' = cos r sx u + sin r sy v + ox, v' = -sin r sx u + cos r sy v + oy.
    // Offset to texel (1, 0)'s centre: green.
    let offset = TextureTransform {
        offset: Vec2::new(0.75, 0.25),
        ..TextureTransform::default()
    };
    assert_close(emissive(offset), [0.0, 1.0, 0.0], "offset");
    // The surface's (0, 0) carried to (0.25, 0.75) by offset alone, whatever the rotation and scale
    // do to it: blue.
    let turned = TextureTransform {
        offset: Vec2::new(0.25, 0.75),
        rotation: 1.0,
        scale: Vec2::new(3.0, 2.0),
    };
    assert_close(emissive(turned), [0.0, 0.0, 1.0], "offset with rotation and scale");
    // The rows: (1, 0) turned a quarter counter-clockwise as the image is seen (v down) is (0, -1).
    let quarter = TextureTransform {
        rotation: std::f32::consts::FRAC_PI_2,
        ..TextureTransform::default()
    };
    let [u, v] = quarter.rows();
    assert!(u[0].abs() < 1e-7 && (v[0] + 1.0).abs() < 1e-7, "{u:?} {v:?}");
    // Seen in the image: the hit's coordinates moved to (0.25, 0) and turned a quarter land at
    // (0, -0.25), which repeats to (0, 0.75): halfway between texels (1, 1) and (0, 1), blue and
    // white. Turned the other way they would land on the first row, red and green.
    let turned_at = |transform| {
        let mut material = gltf_material(Vec3::ZERO, 0.0, 1.0);
        material.emission = Vec3::ONE;
        material.pbr.as_mut().unwrap().emissive_texture = Some(TextureMap {
            transform,
            ..TextureMap::plain(0)
        });
        let mut scene = plane_scene(material, Vec::new());
        scene.textures = vec![texture.clone()];
        for t in &mut scene.triangles {
            t.uvs = t.uvs.map(|uvs| uvs.map(|uv| uv + Vec2::new(0.25, 0.0)));
        }
        centre(&scene)
    };
    assert_close(turned_at(quarter), [0.5, 0.5, 1.0], "a quarter turn");
}

#[test]
fn an_unlit_surface_shows_its_base_colour_whatever_the_light() {
    // KHR_materials_unlit: base colour times its map, here a 1x1 texture of (0.5, 1, 0.25); the
    // point light, the emission and the metal's reflection leave it as it is.
    let texture = Texture::from_linear(1, 1, &[[0.5, 1.0, 0.25, 1.0]], [Wrap::Repeat; 2]);
    let mut material = gltf_material(Vec3::new(0.8, 0.6, 0.4), 1.0, 0.0);
    material.texture = Some(TextureMap::plain(0));
    material.emission = Vec3::ONE;
    material.pbr.as_mut().unwrap().unlit = true;
    let mut scene = plane_scene(material, vec![point(Vec3::new(0.0, 0.0, 2.0), 50.0, None)]);
    scene.textures = vec![texture];
    scene.settings.max_depth = 3;
    assert_close(centre(&scene), [0.4, 0.6, 0.1], "unlit");
    // Lit, the same material shows the light and its emission.
    scene.materials[0].pbr.as_mut().unwrap().unlit = false;
    assert!(centre(&scene).x > 1.0, "the lit material");
}

/// `plane_scene` with `corners` on every corner of its two triangles.
fn with_corners(mut scene: Scene, set: impl Fn(&mut Triangle)) -> Scene {
    scene.triangles.iter_mut().for_each(set);
    scene
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    // Unlit, so the pixel is the base colour itself.
    let mut material = gltf_material(Vec3::splat(0.8), 0.0, 1.0);
    material.pbr.as_mut().unwrap().unlit = true;
    let plain = plane_scene(material, Vec::new());
    assert_close(centre(&plain), [0.8, 0.8, 0.8], "without colours");
    let coloured = with_corners(plain, |t| t.colors = Some([glam::Vec4::new(0.5, 0.25, 1.0, 1.0); 3]));
    assert_close(centre(&coloured), [0.4, 0.2, 0.8], "COLOR_0");
}

#[test]
fn a_map_on_the_second_coordinate_set_reads_it() {
    // A 2x1 texture, red then green; set 0 looks at red's centre, set 1 at green's.
    let texture = Texture::from_linear(2, 1, &[[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]], [Wrap::Clamp; 2]);
    let unlit_on = |set: u32| {
        let mut material = gltf_material(Vec3::ONE, 0.0, 1.0);
        material.pbr.as_mut().unwrap().unlit = true;
        material.texture = Some(TextureMap {
            tex_coord: set,
            ..TextureMap::plain(0)
        });
        let mut scene = with_corners(plane_scene(material, Vec::new()), |t| {
            t.uvs = Some([Vec2::new(0.25, 0.5); 3]);
            t.uvs1 = Some([Vec2::new(0.75, 0.5); 3]);
        });
        scene.textures = vec![texture.clone()];
        centre(&scene)
    };
    assert_close(unlit_on(0), [1.0, 0.0, 0.0], "set 0");
    assert_close(unlit_on(1), [0.0, 1.0, 0.0], "set 1");
}

#[test]
fn a_normal_map_tilts_the_normal_along_its_tangent_frame() {
    // A Lambert surface (no specular layer) under parallel light coming down from +y at 45 degrees:
    // the pixel is E (n . l) c / pi. Its normal map tilts n toward the bitangent (texel green above
    // one half): with the tangent along +x and w = 1 the bitangent is cross(z, x) = +y, toward
    // the light; with w = -1, away from it.
    let light_dir = Vec3::new(0.0, -1.0, -1.0).normalize();
    let sun = Light {
        position: Vec3::ZERO,
        color: Vec3::splat(3.0),
        kind: LightKind::Directional { direction: light_dir },
    };
    // The normal (0, 0.6, 0.8) encoded as (n + 1) / 2, as a normal map holds it.
    let texel = [0.5, 0.8, 0.9, 1.0];
    let render = |w: Option<f32>, scale: f32| {
        let mut material = gltf_material(Vec3::ONE, 0.0, 1.0);
        let pbr = material.pbr.as_mut().unwrap();
        pbr.specular_factor = 0.0;
        pbr.normal_scale = scale;
        pbr.normal_texture = w.map(|_| TextureMap::plain(0));
        let mut scene = with_corners(plane_scene(material, vec![sun]), |t| {
            t.normals = Some([Vec3::Z; 3]);
            t.tangents = w.map(|w| [glam::Vec4::new(1.0, 0.0, 0.0, w); 3]);
        });
        scene.textures = vec![Texture::from_linear(1, 1, &[texel], [Wrap::Repeat; 2])];
        centre(&scene).x as f64
    };
    // The texel as the texture holds it (half floats), decoded: 2 x - 1.
    let decode = |x: f64| 2.0 * half_float(x) - 1.0;
    let lambert = |n: [f64; 3]| {
        let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let l = [0.0, 1.0 / 2f64.sqrt(), 1.0 / 2f64.sqrt()];
        3.0 * (n[1] * l[1] + n[2] * l[2]) / length / PI
    };
    let (y, z) = (decode(0.8), decode(0.9));
    let close = |got: f64, expected: f64, what: &str| {
        assert!(
            (got - expected).abs() <= 1e-5 * expected,
            "{what}: {got}, the formula says {expected}"
        );
    };
    close(render(None, 1.0), lambert([0.0, 0.0, 1.0]), "no map");
    close(render(Some(1.0), 1.0), lambert([0.0, y, z]), "toward the light");
    close(
        render(Some(-1.0), 1.0),
        lambert([0.0, -y, z]),
        "away from the light (w = -1)",
    );
    close(
        render(Some(1.0), 0.5),
        lambert([0.0, 0.5 * y, z]),
        "normalTexture.scale 0.5",
    );
}

/// `x` rounded to the nearest half float, as textures hold texels.
fn half_float(x: f64) -> f64 {
    // Half floats in [0.5, 1) are multiples of 2^-11.
    assert!((0.5..1.0).contains(&x));
    (x * 2048.0).round() / 2048.0
}

#[test]
fn a_volume_refracts_at_its_surfaces_and_absorbs_by_beer_lambert() {
    use raypipe::cpu::intersect::Ray;
    use raypipe::cpu::trace::Tracer;
    use raypipe::scene::Volume;
    // A slab of glass (z in [0, 1]: a quad on top facing +z, one below facing -z, single-sided)
    // over two unlit floor quads at z = -1, red for x < 5.75 and green beyond. A ray from
    // (0, 0, 5) at 45 degrees enters the top at x = 4, refracts to sin t = sin 45 / 1.5, crosses
    // the slab in 1 / cos t and leaves its bottom at x = 4 + tan t, parallel to itself again, to
    // meet the floor at x = 5 + tan t = 5.53: red, dimmed by exp(-absorption * 1 / cos t). Through a
    // thin wall it would go straight on to x = 6: green.
    let quad = |x0: f32, x1: f32, z: f32, up: bool, material: u32| {
        let corners = [(x0, -50.0), (x1, -50.0), (x1, 50.0), (x0, 50.0)].map(|(x, y)| Vec3::new(x, y, z));
        quad_triangles(corners, material, up, None)
    };
    let unlit = |color: Vec3| {
        let mut material = gltf_material(color, 0.0, 1.0);
        material.pbr.as_mut().unwrap().unlit = true;
        material
    };
    let trace = |volume: Option<Volume>| {
        let mut glass = gltf_material(Vec3::ONE, 0.0, 0.0);
        glass.transmit = 1.0;
        glass.double_sided = false;
        let pbr = glass.pbr.as_mut().unwrap();
        // No specular layer: all of the light is transmitted, none reflected.
        pbr.specular_factor = 0.0;
        pbr.volume = volume;
        let mut triangles = Vec::new();
        for part in [
            quad(-50.0, 50.0, 1.0, true, 0),
            quad(-50.0, 50.0, 0.0, false, 0),
            quad(-50.0, 5.75, -1.0, true, 1),
            quad(5.75, 50.0, -1.0, true, 2),
        ] {
            triangles.extend(part);
        }
        // The plane scene's camera and settings, with the slab and floors, and bounces.
        let mut scene = plane_scene(glass, Vec::new());
        scene.settings.max_depth = 5;
        scene.materials.extend([unlit(Vec3::X), unlit(Vec3::Y)]);
        scene.triangles = triangles;
        let mut packed = PackedScene::new(&scene).unwrap();
        packed.build_bvh();
        let dir = Vec3::new(1.0, 0.0, -1.0).normalize();
        let trace = |accel| {
            Tracer::new(&packed, accel)
                .unwrap()
                .trace_pixel(Ray::new(Vec3::new(0.0, 0.0, 5.0), dir))
        };
        let color = trace(Accel::Threaded).color;
        assert_eq!(color, trace(Accel::Brute).color);
        color
    };
    let sin_t = std::f64::consts::FRAC_1_SQRT_2 / 1.5;
    let path = 1.0 / (1.0 - sin_t * sin_t).sqrt();
    let volume = Volume {
        attenuation_color: Vec3::splat(0.5),
        attenuation_distance: 2.0,
    };
    let absorption = -(0.5f64.ln()) / 2.0;
    let expected = (-absorption * path).exp();
    let through = trace(Some(volume));
    // The refracted ray starts RAY_BIAS times the hit's reach (about 5) below the top, so its path
    // inside is 5e-4 / cos t shorter than the slab's: 2e-4 of the light, within 1e-3.
    assert!(
        (through.x as f64 - expected).abs() <= 1e-3 * expected && through.y == 0.0 && through.z == 0.0,
        "through the volume: {through}, the formula says {expected}"
    );
    assert_close(trace(None), [0.0, 1.0, 0.0], "through two thin walls");
}
