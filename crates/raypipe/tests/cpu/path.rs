//! The path integrator on the CPU reference against numbers derived here: white furnaces (a
//! Lambertian sphere returns the environment's radiance exactly; a GGX sphere, its radiance times
//! the directional albedo integrated here), a Lambertian plane under a point light (the
//! irradiance in closed form), and no ambient term. The GPU matches the CPU in tests/gpu/.

use crate::common::{PLANE_SIZE, centre, plane_scene};
use crate::environment::{pixel, render, sphere_pixels, sphere_scene};
use glam::Vec3;
use raypipe::modes::Integrator;
use raypipe::scene::{Environment, Light, LightKind, Material, Pbr, Scene};
use std::f64::consts::PI;

const RADIANCE: f32 = 0.7;

fn path_traced(mut scene: Scene, max_depth: u32) -> Scene {
    scene.settings.integrator = Integrator::Path;
    scene.settings.max_depth = max_depth;
    scene
}

/// A white Lambertian sphere in a uniform environment reflects all of it: every pixel reads the
/// environment's radiance, whatever the depth (a convex sphere never sees itself, so one bounce
/// holds all its light). The light sample and the BSDF's share it by MIS; a weight dropped or
/// doubled moves the mean by a third or more.
#[test]
fn a_white_lambertian_sphere_in_a_uniform_environment_reads_its_radiance() {
    let size = 24;
    let eye = Vec3::new(0.0, 0.0, 3.0);
    let white = Material {
        color: Vec3::ONE,
        specular: 0.0,
        ..Material::default()
    };
    for depth in [0, 1, 5] {
        let scene = path_traced(
            sphere_scene(white, eye, size, Environment::uniform(Vec3::splat(RADIANCE))),
            depth,
        );
        let pixels = sphere_pixels(&render(&scene, 64), eye, size);
        assert!(pixels.len() > 150, "{} pixels", pixels.len());
        let mean = pixels.iter().sum::<Vec3>() / pixels.len() as f32;
        assert!(
            (mean - Vec3::splat(RADIANCE)).abs().max_element() < 0.005 * RADIANCE,
            "depth {depth}: mean {mean}"
        );
        // Each pixel alone is 64 samples of an estimator that spans 0 to 4 L at depth 0 (the light
        // sample alone): within 35 %.
        for p in &pixels {
            assert!(
                (*p - Vec3::splat(RADIANCE)).abs().max_element() < 0.35 * RADIANCE,
                "depth {depth}: {p}"
            );
        }
    }
}

/// The directional albedo at normal incidence (n = v = +z) of glTF's BRDF (Appendix B, written
/// out: D with α = roughness², Smith's height-correlated visibility, Schlick's Fresnel with
/// F0 = 0.04 for the dielectric and the base colour for the metal) for a grey base colour:
/// ∫ f(l) cos θ dω by the midpoint rule.
fn albedo_head_on(base: f64, metallic: f64, roughness: f64) -> f64 {
    let alpha = roughness * roughness;
    let a2 = alpha * alpha;
    let rings = 4000;
    let mut sum = 0.0;
    for i in 0..rings {
        let theta = (i as f64 + 0.5) / rings as f64 * PI / 2.0;
        let n_dot_l = theta.cos();
        // h halves the angle between l and v = n; f does not depend on the azimuth.
        let n_dot_h = (theta / 2.0).cos();
        let v_dot_h = n_dot_h;
        let d = a2 / (PI * (n_dot_h * n_dot_h * (a2 - 1.0) + 1.0).powi(2));
        let visibility = 0.5 / (n_dot_l * 1.0 + (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt());
        let schlick = |f0: f64| f0 + (1.0 - f0) * (1.0 - v_dot_h).powi(5);
        let dielectric = (1.0 - schlick(0.04)) * base / PI + schlick(0.04) * d * visibility;
        let metal = schlick(base) * d * visibility;
        let f = (1.0 - metallic) * dielectric + metallic * metal;
        let solid_angle = theta.sin() * (PI / 2.0 / rings as f64) * 2.0 * PI;
        sum += f * n_dot_l * solid_angle;
    }
    sum
}

/// The furnace for glTF's BRDF: a sphere of roughness 0.3 to 0.8, dielectric, metal or half
/// and half, seen head-on through a narrow camera, returns the environment's radiance times its
/// directional albedo there.
#[test]
fn a_gltf_sphere_in_a_uniform_environment_reads_its_albedo() {
    let size = 8;
    let eye = Vec3::new(0.0, 0.0, 3.0);
    for (metallic, roughness) in [(0.0, 0.3), (1.0, 0.5), (0.5, 0.8)] {
        let material = Material {
            color: Vec3::splat(0.8),
            pbr: Some(Pbr {
                metallic,
                roughness,
                ..Pbr::default()
            }),
            ..Material::default()
        };
        let mut scene = path_traced(
            sphere_scene(material, eye, size, Environment::uniform(Vec3::splat(RADIANCE))),
            3,
        );
        // Every pixel within 1.2 degrees of head-on.
        scene.camera.fov_degrees = 2.0;
        let frame = render(&scene, 256);
        let mean = (0..size * size)
            .map(|i| pixel(&frame, i % size, i / size))
            .sum::<Vec3>()
            / (size * size) as f32;
        let expected = RADIANCE * albedo_head_on(0.8, metallic as f64, roughness as f64) as f32;
        assert!(
            (mean - Vec3::splat(expected)).abs().max_element() < 0.01 * expected,
            "metallic {metallic}, roughness {roughness}: {mean}, the albedo says {expected}"
        );
    }
}

/// glTF's BRDF with no specular layer: a Lambertian surface, base / π.
fn lambertian(base: f32) -> Material {
    Material {
        color: Vec3::splat(base),
        pbr: Some(Pbr {
            metallic: 0.0,
            roughness: 1.0,
            specular_factor: 0.0,
            ..Pbr::default()
        }),
        ..Material::default()
    }
}

/// A Lambertian plane (glTF's BRDF with no specular layer: base / π) under a point light of I
/// candela at height h straight above the pixel: L = (I / h²) (base / π), with nothing else in the
/// picture: no ambient term, whatever the depth.
#[test]
fn a_lambertian_plane_under_a_point_light_shows_the_closed_form_irradiance() {
    let base = 0.6;
    let lambert = lambertian(base);
    let (candela, height) = (20.0, 2.0);
    let light = Light {
        position: Vec3::new(0.0, 0.0, height),
        color: Vec3::splat(candela),
        kind: LightKind::Point { range: None },
    };
    let mut scene = path_traced(plane_scene(lambert, vec![light]), 4);
    scene.settings.ambient = 0.5;
    let expected = (candela / (height * height)) as f64 * base as f64 / PI;
    let got = centre(&scene);
    assert!(
        (got - Vec3::splat(expected as f32)).abs().max_element() < 1e-5,
        "{got}, the formula says {expected}"
    );
    assert_eq!(PLANE_SIZE % 2, 1, "the centre pixel looks straight down");
}

/// The same plane under an emitting square of radiance Le and half side a, at height h straight
/// above the pixel and facing it: the irradiance is 4 Le (a / r) atan(a / r) with r = √(a² + h²)
/// (four corner rectangles of the textbook form factor), and L = (base / π) E. The square is
/// single-sided, so the camera above sees the plane through its back. Its light comes from the
/// emitter samples and the BSDF's, weighed by MIS; dropping either weight, or the emitter
/// samples, moves the mean by far more than the tolerance.
#[test]
fn a_lambertian_plane_under_an_emitting_square_shows_the_closed_form_irradiance() {
    let base = 0.6;
    let lambert = lambertian(base);
    let (radiance, a, h) = (3.0f32, 0.5f32, 1.0f32);
    let emitter = Material {
        color: Vec3::ZERO,
        emission: Vec3::splat(radiance),
        pbr: Some(Pbr::default()),
        double_sided: false,
        ..Material::default()
    };
    let mut scene = path_traced(plane_scene(lambert, vec![]), 3);
    scene.materials.push(emitter);
    let corners = [(-a, -a), (a, -a), (a, a), (-a, a)].map(|(x, y)| Vec3::new(x, y, h));
    // Facing -z, down to the plane.
    scene
        .triangles
        .extend(crate::common::quad_triangles(corners, 1, false, None));
    let mut packed = raypipe::records::PackedScene::new(&scene).unwrap();
    assert_eq!(packed.path.globals.emitter_count, 2, "both triangles are emitters");
    packed.build_bvh();
    let frame = raypipe::cpu::render_with(
        &packed,
        raypipe::modes::Accel::Threaded,
        raypipe::cpu::Count::Rays,
        4096,
        &|| {},
    )
    .unwrap();
    let r = (a * a + h * h).sqrt() as f64;
    let irradiance = 4.0 * radiance as f64 * (a as f64 / r) * (a as f64 / r).atan();
    let expected = (base as f64 / PI * irradiance) as f32;
    let got = pixel(&frame, PLANE_SIZE / 2, PLANE_SIZE / 2);
    assert!(
        (got - Vec3::splat(expected)).abs().max_element() < 0.02 * expected,
        "{got}, the formula says {expected}"
    );
}
