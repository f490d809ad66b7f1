//! The environment on the CPU reference against what docs/scene-format.md states, written out
//! here: the equirectangular convention and the rotation (background and mirror pixels equal a map
//! whose colour is a known function of direction), the white furnace, and the occlusion texture's
//! share of the environment's light. The GPU matches the CPU in tests/gpu/.

use crate::common::{centre, plane_scene, render_cpu};
use glam::Vec3;
use raypipe::image::Frame;
use raypipe::modes::{Accel, Count};
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Environment, Material, Pbr, RenderSettings, Scene, Sphere, Texture, TextureMap, Wrap};
use std::f32::consts::PI;

/// The colour the test map gives direction `e` (unit, in the environment's own frame): a
/// different linear ramp per channel, so that a swapped, mirrored or turned lookup shows.
fn ramp(e: Vec3) -> Vec3 {
    Vec3::new(0.5 + 0.4 * e.x, 0.5 + 0.4 * e.y, 0.5 + 0.4 * e.z)
}

/// A 512 x 256 map of `ramp`, texel by texel by the stated convention: u from the left edge, v
/// from the top row, direction (sin θ sin φ, cos θ, -sin θ cos φ) with φ = 2π (u - 0.5) and
/// θ = π v, the inverse of u = 0.5 + atan2(x, -z) / 2π, v = acos(y) / π.
fn ramp_environment() -> Environment {
    let (width, height) = (512u32, 256u32);
    let mut texels = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let phi = 2.0 * PI * ((x as f32 + 0.5) / width as f32 - 0.5);
            let theta = PI * (y as f32 + 0.5) / height as f32;
            let e = Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos());
            texels.push(ramp(e).to_array());
        }
    }
    Environment::from_rgb(width, height, &texels).unwrap().0
}

/// A scene of one sphere of `material` at the origin, radius 1, seen from `eye`, lit by
/// `environment` alone (no lights, no ambient term).
pub(crate) fn sphere_scene(material: Material, eye: Vec3, size: u32, environment: Environment) -> Scene {
    let mut scene = Scene {
        camera: Camera {
            eye,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: 60.0,
        },
        settings: RenderSettings {
            width: size,
            height: size,
            max_depth: 2,
            background: Vec3::new(9.0, 9.0, 9.0),
            ambient: 0.0,
            accel: None,
            integrator: Default::default(),
        },
        materials: vec![material],
        spheres: vec![Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
            material: 0,
        }],
        ..Scene::default()
    };
    scene.set_environment(Some(environment));
    scene
}

pub(crate) fn render(scene: &Scene, samples: u32) -> Frame {
    let mut packed = PackedScene::new(scene).unwrap();
    packed.build_bvh();
    if samples == 1 {
        return render_cpu(&packed, Accel::Threaded);
    }
    raypipe::cpu::render_with(&packed, Accel::Threaded, Count::Rays, samples, &|| {}).unwrap()
}

/// The camera ray through pixel (x, y)'s centre, by the convention of docs/scene-format.md.
pub(crate) fn camera_ray(camera: &Camera, size: u32, x: u32, y: u32) -> Vec3 {
    let forward = (camera.target - camera.eye).normalize();
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    let tan = (camera.fov_degrees.to_radians() / 2.0).tan();
    let px = (2.0 * (x as f32 + 0.5) / size as f32 - 1.0) * tan;
    let py = (1.0 - 2.0 * (y as f32 + 0.5) / size as f32) * tan;
    (forward + px * right + py * up).normalize()
}

/// Where the unit sphere at the origin reflects the ray from `eye` along `d`, and how squarely the
/// ray meets it; `None` where it misses.
pub(crate) fn mirrored(eye: Vec3, d: Vec3) -> Option<(Vec3, f32)> {
    let b = eye.dot(d);
    let discriminant = b * b - (eye.length_squared() - 1.0);
    if discriminant < 0.0 {
        return None;
    }
    let n = eye + (-b - discriminant.sqrt()) * d;
    Some((d - 2.0 * d.dot(n) * n, -d.dot(n)))
}

/// The sphere's pixels that meet it at more than a grazing angle, in a `size`-pixel image from
/// `eye` (as `sphere_scene` frames it).
pub(crate) fn sphere_pixels(frame: &Frame, eye: Vec3, size: u32) -> Vec<Vec3> {
    let camera = Camera {
        eye,
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_degrees: 60.0,
    };
    (0..size * size)
        .map(|i| (i % size, i / size))
        .filter(|&(x, y)| mirrored(eye, camera_ray(&camera, size, x, y)).is_some_and(|(_, s)| s > 0.1))
        .map(|(x, y)| pixel(frame, x, y))
        .collect()
}

pub(crate) fn pixel(frame: &Frame, x: u32, y: u32) -> Vec3 {
    let [r, g, b, _] = frame.color[(y * frame.width + x) as usize];
    Vec3::new(r, g, b)
}

#[test]
fn escaping_rays_read_the_environment_by_the_stated_convention_and_rotation() {
    // A mirror (the paper's material: reflects all, no colour of its own) in the ramp, turned by
    // 30 degrees counter-clockwise seen from above and doubled: direction d reads the map at
    // R(-30) d, R(a) turning +z toward +x.
    let size = 48;
    let mirror = Material {
        color: Vec3::ZERO,
        reflect: 1.0,
        ..Material::default()
    };
    let eye = Vec3::new(1.0, 1.5, 3.5);
    let mut environment = ramp_environment();
    environment.rotation_degrees = 30.0;
    environment.intensity = 2.0;
    let scene = sphere_scene(mirror, eye, size, environment);
    let frame = render(&scene, 1);
    let turned_back = |d: Vec3| {
        let (sin, cos) = (-30.0f32).to_radians().sin_cos();
        Vec3::new(cos * d.x + sin * d.z, d.y, -sin * d.x + cos * d.z)
    };
    let (mut background, mut reflected) = (0, 0);
    for y in 0..size {
        for x in 0..size {
            let d = camera_ray(&scene.camera, size, x, y);
            // A mirror pixel's reflected cone spans about 0.15 radians of the map (the sphere's
            // curvature spreads it), over which the filtered map departs from the ramp's value at
            // the centre by up to 0.03 near the poles; the background's spans 0.024.
            let (direction, tolerance) = match mirrored(eye, d) {
                None => {
                    background += 1;
                    (d, 0.01)
                }
                // Grazing hits: the pixel's reflection turns fast across it.
                Some((_, squareness)) if squareness < 0.2 => continue,
                Some((r, _)) => {
                    reflected += 1;
                    (r, 0.03)
                }
            };
            let expected = 2.0 * ramp(turned_back(direction));
            let got = pixel(&frame, x, y);
            assert!(
                (got - expected).abs().max_element() < tolerance,
                "pixel ({x}, {y}): {got} for {expected} (direction {direction})"
            );
        }
    }
    assert!(
        background > 500 && reflected > 300,
        "{background} background, {reflected} mirror pixels"
    );
}

/// The directional albedo of a white GGX metal (Appendix B: D with α = roughness², Smith's
/// height-correlated G2, F = 1) seen at cos θ = `mu`, integrated over microfacet normals h:
/// E = ∫ D(h) G2(v, l) (v·h) / (n·v) dh over the h whose reflection l leaves above the surface.
pub(crate) fn white_metal_albedo(mu: f64, roughness: f64) -> f64 {
    let a2 = roughness.powi(4);
    let lambda = |c: f64| (-1.0 + (1.0 + a2 * (1.0 - c * c) / (c * c)).sqrt()) / 2.0;
    let v = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let (rings, segments) = (400, 800);
    let pi = std::f64::consts::PI;
    let mut sum = 0.0;
    for i in 0..rings {
        let theta = (i as f64 + 0.5) / rings as f64 * pi / 2.0;
        for j in 0..segments {
            let phi = (j as f64 + 0.5) / segments as f64 * 2.0 * pi;
            let h = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()];
            let v_dot_h = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            let l_z = 2.0 * v_dot_h * h[2] - v[2];
            if v_dot_h <= 0.0 || l_z <= 0.0 {
                continue;
            }
            let d = a2 / (pi * (h[2] * h[2] * (a2 - 1.0) + 1.0).powi(2));
            let g2 = 1.0 / (1.0 + lambda(mu) + lambda(l_z));
            let area = theta.sin() * (pi / 2.0 / rings as f64) * (2.0 * pi / segments as f64);
            sum += d * g2 * v_dot_h / mu * area;
        }
    }
    sum
}

/// The furnace: a white metal sphere in an environment of radiance 0.7 everywhere. A mirror
/// (roughness 0) returns exactly that; at roughness 0.5 the pixel facing the camera returns 0.7
/// times the BRDF's albedo there (single scattering loses the rest, as Appendix B's BRDF does).
#[test]
fn a_white_metal_in_a_uniform_environment_reads_its_radiance() {
    let size = 24;
    let metal = |roughness: f32| Material {
        color: Vec3::ONE,
        pbr: Some(Pbr {
            metallic: 1.0,
            roughness,
            ..Pbr::default()
        }),
        ..Material::default()
    };
    let eye = Vec3::new(0.0, 0.0, 3.0);
    let environment = Environment::uniform(Vec3::splat(0.7));

    let mirror = render(&sphere_scene(metal(0.0), eye, size, environment.clone()), 1);
    let pixels = sphere_pixels(&mirror, eye, size);
    assert!(pixels.len() > 150, "{} pixels", pixels.len());
    for p in &pixels {
        assert!((*p - Vec3::splat(0.7)).abs().max_element() < 0.007, "{p}");
    }

    let rough = render(&sphere_scene(metal(0.5), eye, size, environment), 256);
    // The centre pixel sees the sphere within half a degree of head-on.
    let centre = pixel(&rough, size / 2, size / 2);
    let expected = 0.7 * white_metal_albedo(1.0, 0.5) as f32;
    assert!(
        (centre - Vec3::splat(expected)).abs().max_element() < 0.01 * expected,
        "{centre} for {expected}"
    );
    // Over the disc (grazing pixels lose more): within 12 % of 0.7.
    let pixels = sphere_pixels(&rough, eye, size);
    let mean = pixels.iter().sum::<Vec3>() / pixels.len() as f32;
    assert!(
        (mean - Vec3::splat(0.7)).abs().max_element() < 0.12 * 0.7,
        "mean {mean}"
    );
}

/// A glTF surface's diffuse light from the environment, times the occlusion texture: a map of
/// 0.5 at full strength halves it, and at strength 0.5 takes a quarter.
#[test]
fn occlusion_scales_the_environment_light() {
    let occlusion = |strength: Option<f32>| {
        let material = Material {
            color: Vec3::new(0.8, 0.6, 0.4),
            pbr: Some(Pbr {
                metallic: 0.0,
                roughness: 1.0,
                occlusion_texture: strength.map(|_| TextureMap::plain(0)),
                occlusion_strength: strength.unwrap_or(1.0),
                ..Pbr::default()
            }),
            ..Material::default()
        };
        let mut scene = plane_scene(material, Vec::new());
        scene.textures = vec![Texture::from_linear(
            2,
            2,
            &[[0.5, 0.5, 0.5, 1.0]; 4],
            [Wrap::Repeat; 2],
        )];
        scene.set_environment(Some(Environment::uniform(Vec3::splat(0.7))));
        centre(&scene)
    };
    // Facing +z, the surface sees half the sphere of radiance 0.7: E / π = 0.7.
    let open = occlusion(None);
    let expected = 0.7 * Vec3::new(0.8, 0.6, 0.4);
    assert!((open - expected).abs().max_element() < 0.007, "{open} for {expected}");
    let full = occlusion(Some(1.0));
    assert!(
        (full - 0.5 * open).abs().max_element() < 1e-3,
        "{full} for half of {open}"
    );
    let half = occlusion(Some(0.5));
    assert!(
        (half - 0.75 * open).abs().max_element() < 1e-3,
        "{half} for three quarters of {open}"
    );
}
