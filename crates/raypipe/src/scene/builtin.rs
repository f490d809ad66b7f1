//! Built-in scenes by name: the classic Whitted scene and the paper's procedural sphere clouds.

use super::{Camera, Checker, Light, Material, Plane, RenderSettings, Scene, Sphere};
use crate::error::InputError;
use crate::rng::SplitMix64;
use crate::scene::ToneMap;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// The names `by_name` understands, for help texts and error messages.
pub const NAMES: &[&str] = &[
    "whitted",
    "sphere-8k",
    "torus-5k",
    "sphere:N",
    "torus:N",
    "random:N[:SEED]",
    "bounce:N[:SEED]",
];

/// Largest primitive count a procedural family accepts: `raypipe bvh` builds trees this large;
/// renders take at most [`crate::scene::MAX_RECORDS`] primitives.
pub(crate) const MAX_COUNT: usize = 1 << 26;

/// Returns `Ok(None)` when `name` is not a built-in (it may be a file), `Err` when it is one with bad
/// parameters.
pub fn by_name(name: &str) -> Result<Option<Scene>, InputError> {
    let fail = |message: String| InputError::new(format!("scene '{name}': {message}"));
    let mut parts = name.split(':');
    let family = parts.next().unwrap_or_default();
    let params: Vec<&str> = parts.collect();
    let count = |index: usize| -> Result<usize, InputError> {
        let text = params
            .get(index)
            .ok_or_else(|| fail(format!("{family} needs a count, as in {family}:1000")))?;
        match text.parse::<usize>() {
            Ok(n) if (1..=MAX_COUNT).contains(&n) => Ok(n),
            _ => Err(fail(format!(
                "count must be an integer in 1..={MAX_COUNT} (renders take up to {})",
                crate::scene::MAX_RECORDS
            ))),
        }
    };
    let expect_params = |n: std::ops::RangeInclusive<usize>| -> Result<(), InputError> {
        if n.contains(&params.len()) {
            Ok(())
        } else {
            Err(fail(format!("wrong number of ':' parameters for {family}")))
        }
    };
    let scene = match family {
        "whitted" => {
            expect_params(0..=0)?;
            whitted()
        }
        "sphere-8k" => {
            expect_params(0..=0)?;
            sphere_shell(8000)
        }
        "torus-5k" => {
            expect_params(0..=0)?;
            torus(5000)
        }
        "sphere" => {
            expect_params(1..=1)?;
            sphere_shell(count(0)?)
        }
        "torus" => {
            expect_params(1..=1)?;
            torus(count(0)?)
        }
        "random" | "bounce" => {
            expect_params(1..=2)?;
            let seed = match params.get(1) {
                Some(text) => text
                    .parse::<u64>()
                    .map_err(|_| fail("seed must be an unsigned integer".into()))?,
                None => 1,
            };
            if family == "random" {
                random(count(0)?, seed)
            } else {
                bounce(count(0)?, seed)
            }
        }
        _ => return Ok(None),
    };
    debug_assert_eq!(scene.validate(), Ok(()));
    Ok(Some(scene))
}

fn diffuse(color: Vec3) -> Material {
    Material {
        color,
        specular: 0.3,
        shininess: 30.0,
        ..Material::default()
    }
}

fn mirror() -> Material {
    Material {
        color: Vec3::splat(0.05),
        specular: 0.8,
        shininess: 120.0,
        reflect: 0.85,
        ..Material::default()
    }
}

fn glass() -> Material {
    Material {
        color: Vec3::ZERO,
        specular: 0.8,
        shininess: 200.0,
        transmit: 0.95,
        ior: 1.5,
        ..Material::default()
    }
}

/// A checkerboard floor at height `y`, using materials `a` and `b`.
fn floor(y: f32, a: u32, b: u32, size: f32) -> Plane {
    Plane {
        point: Vec3::new(0.0, y, 0.0),
        normal: Vec3::Y,
        material: a,
        checker: Some(Checker { material: b, size }),
    }
}

/// The classic: a mirror sphere and a glass sphere over a checkerboard.
pub fn whitted() -> Scene {
    Scene {
        camera: Camera {
            eye: Vec3::new(0.0, 1.2, -6.0),
            target: Vec3::new(0.0, -0.1, 0.0),
            up: Vec3::Y,
            fov_degrees: 40.0,
        },
        settings: RenderSettings {
            background: Vec3::new(0.3, 0.5, 0.8),
            ..RenderSettings::default()
        },
        lights: vec![
            Light::constant(Vec3::new(5.0, 8.0, -6.0), Vec3::splat(0.9)),
            Light::constant(Vec3::new(-6.0, 5.0, -2.0), Vec3::splat(0.35)),
        ],
        materials: vec![
            diffuse(Vec3::new(0.85, 0.15, 0.1)),
            diffuse(Vec3::new(0.9, 0.85, 0.2)),
            mirror(),
            glass(),
            diffuse(Vec3::new(0.2, 0.4, 0.9)),
        ],
        spheres: vec![
            Sphere {
                center: Vec3::new(-0.9, 0.0, 1.0),
                radius: 1.0,
                material: 2,
            },
            Sphere {
                center: Vec3::new(0.8, -0.25, -0.9),
                radius: 0.75,
                material: 3,
            },
            Sphere {
                center: Vec3::new(-2.0, -0.6, -0.4),
                radius: 0.4,
                material: 4,
            },
        ],
        planes: vec![floor(-1.0, 0, 1, 1.0)],
        triangles: Vec::new(),
        mesh_starts: Vec::new(),
        textures: Vec::new(),
        motion: None,
        environment: None,
        tone_map: ToneMap::None,
    }
}

/// The materials of the sphere clouds: colours, a mirror and a glass.
fn cloud_materials() -> Vec<Material> {
    vec![
        diffuse(Vec3::new(0.9, 0.9, 0.9)),
        diffuse(Vec3::new(0.25, 0.25, 0.3)),
        diffuse(Vec3::new(0.9, 0.3, 0.2)),
        diffuse(Vec3::new(0.2, 0.7, 0.3)),
        diffuse(Vec3::new(0.25, 0.4, 0.9)),
        diffuse(Vec3::new(0.9, 0.75, 0.2)),
        mirror(),
        glass(),
    ]
}

/// The first material index of a cloud primitive (0 and 1 are the floor's).
const CLOUD_FIRST: u32 = 2;
const CLOUD_MATERIALS: u32 = 6;

fn cloud_scene(spheres: Vec<Sphere>, floor_y: f32) -> Scene {
    Scene {
        camera: Camera {
            eye: Vec3::new(0.0, 1.0, -4.5),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: 40.0,
        },
        settings: RenderSettings::default(),
        lights: vec![
            Light::constant(Vec3::new(4.0, 6.0, -5.0), Vec3::splat(0.8)),
            Light::constant(Vec3::new(-5.0, 3.0, -2.0), Vec3::splat(0.3)),
        ],
        materials: cloud_materials(),
        spheres,
        planes: vec![floor(floor_y, 0, 1, 0.5)],
        triangles: Vec::new(),
        mesh_starts: Vec::new(),
        textures: Vec::new(),
        motion: None,
        environment: None,
        tone_map: ToneMap::None,
    }
}

/// `n` spheres on the unit sphere's surface (a Fibonacci lattice), as in the paper's "Sphere 8K".
pub(crate) fn sphere_shell(n: usize) -> Scene {
    let golden_angle = PI * (3.0 - 5f32.sqrt());
    // Each sphere covers about its share of the shell's area.
    let radius = 0.9 / (n as f32).sqrt();
    let spheres = (0..n)
        .map(|k| {
            let y = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
            let ring = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden_angle * k as f32;
            Sphere {
                center: Vec3::new(ring * phi.cos(), y, ring * phi.sin()),
                radius,
                material: CLOUD_FIRST + (k as u32 * 7) % CLOUD_MATERIALS,
            }
        })
        .collect();
    cloud_scene(spheres, -1.3)
}

/// `n` spheres on a torus (major radius 1, minor 0.4): the paper's "Torus 5K".
pub fn torus(n: usize) -> Scene {
    let (major, minor) = (1.0f32, 0.4f32);
    let golden = (5f32.sqrt() - 1.0) / 2.0;
    let radius = 0.55 * (4.0 * major * minor / n as f32).sqrt();
    let spheres = (0..n)
        .map(|k| {
            let u = TAU * k as f32 / n as f32;
            let v = TAU * (k as f32 * golden).fract();
            let ring = major + minor * v.cos();
            Sphere {
                center: Vec3::new(ring * u.cos(), minor * v.sin(), ring * u.sin()),
                radius,
                material: CLOUD_FIRST + (k as u32 * 5) % CLOUD_MATERIALS,
            }
        })
        .collect();
    let mut scene = cloud_scene(spheres, -0.8);
    scene.camera.eye = Vec3::new(0.0, 2.6, -3.6);
    scene
}

/// `n` spheres at random in a box, deterministic for `seed`; some mirrors and some glass.
pub fn random(n: usize, seed: u64) -> Scene {
    let mut rng = SplitMix64::new(seed);
    // Radii shrink with the count so that the box stays about equally full.
    let base_radius = 0.45 / (n as f32).cbrt();
    let spheres = (0..n)
        .map(|_| {
            let center = Vec3::new(
                3.0 * rng.next_f32() - 1.5,
                2.0 * rng.next_f32() - 1.0,
                3.0 * rng.next_f32() - 1.5,
            );
            let radius = base_radius * (0.5 + rng.next_f32());
            let material = CLOUD_FIRST + (rng.next_u64() % CLOUD_MATERIALS as u64) as u32;
            Sphere {
                center,
                radius,
                material,
            }
        })
        .collect();
    let mut scene = cloud_scene(spheres, -1.5);
    scene.camera.eye = Vec3::new(0.0, 1.5, -5.5);
    scene
}

/// `random(n, seed)` set in motion: every sphere flies at its own velocity and bounces off the
/// walls of the box.
pub fn bounce(n: usize, seed: u64) -> Scene {
    let mut scene = random(n, seed);
    // Another stream than the positions' (which use `seed`).
    let mut rng = SplitMix64::new(!seed);
    let velocities = (0..n)
        .map(|_| Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5))
        .collect();
    scene.motion = Some(super::Motion::Bounce(super::Bounce {
        velocities,
        lo: Vec3::new(-1.5, -1.0, -1.5),
        hi: Vec3::new(1.5, 1.0, 1.5),
    }));
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_is_valid_and_sized() {
        for (name, spheres) in [
            ("whitted", 3),
            ("sphere-8k", 8000),
            ("torus-5k", 5000),
            ("sphere:10", 10),
            ("torus:7", 7),
            ("random:50", 50),
            ("random:50:9", 50),
            ("bounce:40", 40),
        ] {
            let scene = by_name(name).unwrap().unwrap();
            assert_eq!(scene.validate(), Ok(()), "{name}");
            assert_eq!(scene.spheres.len(), spheres, "{name}");
        }
    }

    #[test]
    fn bouncing_spheres_move_and_stay_in_their_box() {
        let scene = bounce(200, 3);
        let later = scene.at_time(33.3).unwrap();
        assert_ne!(scene.spheres, later.spheres);
        let Some(super::super::Motion::Bounce(motion)) = &scene.motion else {
            panic!("bounce moves its spheres")
        };
        for s in &later.spheres {
            assert!(
                s.center.cmpge(motion.lo - 1e-4).all() && s.center.cmple(motion.hi + 1e-4).all(),
                "{s:?}"
            );
        }
        assert_eq!(scene.at_time(0.0).unwrap().spheres, scene.spheres);
    }

    #[test]
    fn random_is_deterministic_per_seed() {
        assert_eq!(random(100, 3), random(100, 3));
        assert_ne!(random(100, 3), random(100, 4));
        // SplitMix64's published first output for seed 0 pins the generator.
        assert_eq!(SplitMix64::new(0).next_u64(), 0xE220_A839_7B1D_CDAF);
    }

    #[test]
    fn bad_parameters_are_errors_and_other_names_are_not_builtins() {
        assert!(by_name("random").is_err());
        assert!(by_name("random:0").is_err());
        assert!(by_name("random:x").is_err());
        assert!(by_name("random:10:-1").is_err());
        assert!(by_name("whitted:3").is_err());
        assert!(by_name("scenes/whitted.toml").unwrap().is_none());
    }
}
