//! The scene `raypipe render MODEL` gets: one model framed by a camera and two lights on a
//! checkered floor just below its lowest point, or a glTF file's own camera and lights, with the
//! studio environment where it brings no light of its own.

use super::{DEFAULT_CREASE_DEGREES, Floor, MeshAs, Normals, Placement, SphereCount, add_mesh, place_gltf};
use crate::bvh::aabb::Aabb;
use crate::error::InputError;
use crate::mesh::Mesh;
use crate::modes::Integrator;
use crate::scene::animation::ClipChoice;
use crate::scene::environment::Environment;
use crate::scene::gltf::GltfScene;
use crate::scene::{
    Camera, Checker, Light, LightKind, Material, Pbr, Plane, RenderSettings, Scene, Similarity, ToneMap,
};
use glam::Vec3;

/// What a caller says of a model file it renders alone: triangles or spheres, how many spheres, a
/// rotation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelOptions {
    /// Triangles or spheres; the model's default where `None`.
    pub as_: Option<MeshAs>,
    /// How many spheres; the default where `None`.
    pub spheres: Option<usize>,
    /// Euler angles in degrees, as [`Placement::rotate`].
    pub rotate: Option<Vec3>,
    /// The shading normals; the default where `None`.
    pub normals: Option<Normals>,
    /// Degrees, as [`Placement::crease_degrees`].
    pub crease: Option<f32>,
    /// For a glTF: the animation that plays, as [`Placement::animation`].
    pub animation: Option<ClipChoice>,
    /// What the framed model stands on (a glTF with a camera of its own gets no floor).
    pub floor: Floor,
}

impl ModelOptions {
    /// Whether every option is its default.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    pub(in crate::scene) fn placement(&self) -> Result<Placement, InputError> {
        let as_ = match (self.as_, self.spheres) {
            (Some(MeshAs::Triangles), Some(_)) => {
                return Err(InputError::new("a sphere count needs the model placed as spheres"));
            }
            (Some(as_), _) => as_,
            (None, Some(_)) => MeshAs::Spheres,
            (None, None) => MeshAs::Triangles,
        };
        Ok(Placement {
            as_,
            spheres: self.spheres.map_or(SphereCount::Vertices, SphereCount::Sampled),
            rotate: self.rotate.unwrap_or(Vec3::ZERO),
            normals: self.normals.unwrap_or_default(),
            crease_degrees: self.crease.unwrap_or(DEFAULT_CREASE_DEGREES),
            animation: self.animation.clone(),
            ..Placement::default()
        })
    }
}

/// The scene for `raypipe render MODEL`: the model normalized (longest side 2, centred), clay on a
/// checkered floor that touches it, two lights, and a camera that frames its bounding sphere;
/// `shown` names the file in messages.
pub fn scene_around(mesh: Mesh, shown: &str, options: &ModelOptions) -> Result<Scene, InputError> {
    let placement = options.placement().map_err(|e| e.in_origin(shown))?;
    let mut scene = Scene {
        settings: RenderSettings::default(),
        materials: framing_materials(),
        ..Scene::default()
    };
    add_mesh(&mut scene, mesh, &placement).map_err(|e| e.in_origin(shown))?;
    let framing = Framing::of(&scene);
    scene.camera = framing.camera();
    scene.lights = framing.lights();
    scene.planes.extend(framing.floor(options.floor));
    scene.validate().map_err(|e| e.in_origin(shown))?;
    Ok(scene)
}

/// The scene for `raypipe render FILE.glb`: the file's triangles, materials and textures in its own
/// units (placed by the options' rotation, if any), its camera and lights. Without a camera it is
/// framed as a model is, on the floor; without lights it gets a model's two.
pub fn gltf_scene(gltf: &GltfScene, shown: &str, options: &ModelOptions) -> Result<Scene, InputError> {
    let placement = Placement {
        normalize: false,
        ..options.placement().map_err(|e| e.in_origin(shown))?
    };
    let mut scene = Scene {
        // A glTF file's materials are physically based: they are traced as light goes.
        settings: RenderSettings {
            integrator: Integrator::Path,
            ..RenderSettings::default()
        },
        materials: framing_materials(),
        ..Scene::default()
    };
    let place = place_gltf(&mut scene, gltf, &placement).map_err(|e| e.in_origin(shown))?;
    let framing = Framing::of(&scene);
    match gltf.camera {
        Some(camera) => {
            scene.camera = Camera {
                eye: place.point(camera.eye),
                target: place.point(camera.target),
                up: place.direction(camera.up),
                ..camera
            }
        }
        None => {
            scene.camera = framing.camera();
            scene.planes.extend(framing.floor(options.floor));
            // The floor belongs to the picture: a glTF surface like the model's, under the same
            // light.
            scene.materials[1] = gltf_floor(FLOOR_LIGHT);
            scene.materials[2] = gltf_floor(FLOOR_DARK);
        }
    }
    scene.lights = gltf.lights.iter().map(|light| place_light(light, &place)).collect();
    if scene.lights.is_empty() {
        // A glTF material answers E with its BRDF, a white diffuse one with E / pi: lights pi
        // times a model's show a glTF model as bright as a model file's clay. The studio gives
        // its metals something to reflect and its shadows some light.
        scene.lights = framing
            .lights()
            .into_iter()
            .map(|light| Light {
                color: light.color * std::f32::consts::PI,
                ..light
            })
            .collect();
        scene.set_environment(Some(Environment::studio()));
    }
    scene.tone_map = ToneMap::Neutral;
    scene.validate().map_err(|e| e.in_origin(shown))?;
    Ok(scene)
}

/// A file's light carried by the placement (a rotation: distances, and so the units, stay).
fn place_light(light: &Light, place: &Similarity) -> Light {
    let kind = match light.kind {
        LightKind::Spot {
            direction,
            inner_cone,
            outer_cone,
            range,
        } => LightKind::Spot {
            direction: place.direction(direction),
            inner_cone,
            outer_cone,
            range,
        },
        LightKind::Directional { direction } => LightKind::Directional {
            direction: place.direction(direction),
        },
        kind => kind,
    };
    Light {
        position: place.point(light.position),
        kind,
        ..*light
    }
}

/// A framed model's materials: clay for the model (material 0), then the floor's two squares.
fn framing_materials() -> Vec<Material> {
    vec![
        Material {
            color: Vec3::new(0.85, 0.6, 0.45),
            specular: 0.25,
            shininess: 40.0,
            ..Material::default()
        },
        Material {
            color: Vec3::splat(0.85),
            ..Material::default()
        },
        Material {
            color: Vec3::splat(0.35),
            ..Material::default()
        },
    ]
}

/// The albedos of a framed glTF's floor checker: a light grey and a darker one, both well inside
/// what paper and paint reflect (a photographer's grey card is 0.18), so that under the framing
/// lights neither clips to white.
pub const FLOOR_LIGHT: f32 = 0.5;
/// The checker's darker squares.
pub const FLOOR_DARK: f32 = 0.25;

/// A framed glTF's floor: a rough, white-lit dielectric of `albedo` (glTF's metallic-roughness,
/// roughness 1).
fn gltf_floor(albedo: f32) -> Material {
    Material {
        color: Vec3::splat(albedo),
        pbr: Some(Pbr {
            metallic: 0.0,
            roughness: 1.0,
            ..Pbr::default()
        }),
        ..Material::default()
    }
}

/// The floor's gap below a framed model, in its bounding sphere's radii.
pub const FLOOR_GAP: f32 = 1e-3;

/// How a lone model is shown: a camera on its bounding sphere, two lights, a checkered floor that
/// touches it (materials 1 and 2 of [`framing_materials`]).
pub(super) struct Framing {
    center: Vec3,
    pub(super) radius: f32,
    bounds: Aabb,
}

impl Framing {
    pub(super) fn of(scene: &Scene) -> Self {
        let bounds = scene_bounds(scene);
        Self {
            center: bounds.centroid(),
            radius: ((bounds.max - bounds.min) * 0.5).length(),
            bounds,
        }
    }

    fn camera(&self) -> Camera {
        let fov: f32 = 35.0;
        // About the distance where the bounding sphere fills the vertical field of view; a bit
        // nearer, since the bounding box's corners are seldom filled.
        let distance = 0.85 * self.radius / (fov.to_radians() * 0.5).sin();
        let view = Vec3::new(0.0, 0.3, 1.0).normalize();
        Camera {
            eye: self.center + view * distance,
            target: self.center,
            up: Vec3::Y,
            fov_degrees: fov,
        }
    }

    fn lights(&self) -> Vec<Light> {
        vec![
            Light::constant(self.center + Vec3::new(3.0, 5.0, 4.0) * self.radius, Vec3::splat(0.8)),
            Light::constant(self.center + Vec3::new(-4.0, 2.0, 1.0) * self.radius, Vec3::splat(0.3)),
        ]
    }

    /// The floor, just below the lowest point: a model that rests on its lowest plane (a quad, a
    /// base) lies apart from it, so the two never fight over a pixel. The gap is small against the
    /// model, and twice what a ray's origin is moved off a surface where the scene lies far from
    /// the origin (`RAY_BIAS` times the largest coordinate), so the floor's shadow rays start
    /// below what rests on it.
    fn floor(&self, floor: Floor) -> Option<Plane> {
        if floor == Floor::None {
            return None;
        }
        let reach = self.center.abs().max_element() + 4.0 * self.radius;
        let gap = (FLOOR_GAP * self.radius).max(2.0 * crate::constants::RAY_BIAS * reach);
        Some(Plane {
            point: Vec3::new(0.0, self.bounds.min.y - gap, 0.0),
            normal: Vec3::Y,
            material: 1,
            checker: Some(Checker {
                material: 2,
                size: self.radius * 0.25,
            }),
        })
    }
}

/// The box around the scene's spheres and triangles.
pub(super) fn scene_bounds(scene: &Scene) -> Aabb {
    let points = scene
        .spheres
        .iter()
        .flat_map(|s| [s.center - Vec3::splat(s.radius), s.center + Vec3::splat(s.radius)])
        .chain(scene.triangles.iter().flat_map(|t| t.vertices));
    Aabb::around_points(points)
}
