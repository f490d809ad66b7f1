//! Meshes in scenes: a model placed (normalized, scaled, moved) and added as triangles or as spheres
//! on its surface; and the scene `raypipe render MODEL` gets, which frames one model.

use super::animation::{Animated, ClipChoice, CornerNormals, PlacedInstance};
use super::gltf::GltfScene;
use super::{Motion, Scene, Similarity, Sphere, Triangle};
use crate::bvh::aabb::Aabb;
use crate::error::InputError;
use crate::mesh::{self, Mesh};
use glam::Vec3;
use std::sync::Arc;

mod framing;

pub use framing::{FLOOR_GAP, ModelOptions, gltf_scene, scene_around};

/// What a mesh becomes in a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeshAs {
    /// Its triangles, as primitives of the BVH.
    #[default]
    Triangles,
    /// Spheres placed on its surface, as in the paper's figures.
    Spheres,
}

crate::choice::impl_choice!(
    MeshAs,
    [
        (Triangles, "triangles", "its triangles, as primitives of the BVH"),
        (
            Spheres,
            "spheres",
            "spheres placed on its surface, as in the paper's figures"
        ),
    ]
);

/// Where a mesh's triangles get the normals they shade with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Normals {
    /// The file's vertex normals where it has them, else smooth.
    #[default]
    Auto,
    /// The face's own normal: faceted.
    Flat,
    /// Angle-weighted vertex normals computed from the faces, with the crease angle.
    Smooth,
}

crate::choice::impl_choice!(
    Normals,
    [
        (Auto, "auto", "the file's vertex normals where it has them, else smooth"),
        (Flat, "flat", "each face's own normal: faceted"),
        (
            Smooth,
            "smooth",
            "angle-weighted vertex normals from the faces; edges sharper than the crease angle stay sharp"
        ),
    ]
);

/// What a framed model stands on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Floor {
    /// A checkered floor just below its lowest point.
    #[default]
    Checker,
    /// Nothing: the model floats in the background.
    None,
}

crate::choice::impl_choice!(
    Floor,
    [
        (
            Checker,
            "checker",
            "a checkered floor just below the model's lowest point"
        ),
        (None, "none", "no floor: the model floats in the background"),
    ]
);

/// The crease angle's default: edges between faces further apart than this stay sharp.
pub(crate) const DEFAULT_CREASE_DEGREES: f32 = 60.0;

/// How many spheres a mesh becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphereCount {
    /// This many, by area-weighted sampling of the surface.
    Sampled(usize),
    /// One on every vertex.
    Vertices,
}

/// Where and how a mesh enters a scene (the `[[mesh]]` table of a scene file).
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// Triangles, or spheres on the surface or at the vertices.
    pub as_: MeshAs,
    /// How many spheres, where the mesh becomes spheres.
    pub spheres: SphereCount,
    /// Sphere radius; by default [`Mesh::default_sphere_radius`] of the placed mesh.
    pub radius: Option<f32>,
    /// Euler angles in degrees (about x, then y, then z), applied first, about the model's origin.
    pub rotate: Vec3,
    /// Centre the bounding box at the origin, longest side 2, before `scale` and `translate`.
    pub normalize: bool,
    /// Uniform scale, after the rotation and normalization.
    pub scale: f32,
    /// Added last.
    pub translate: Vec3,
    /// Seed of the surface sampling.
    pub seed: u64,
    /// Index into the scene's materials.
    pub material: u32,
    /// The triangles' shading normals.
    pub normals: Normals,
    /// For smooth normals: faces further apart than this many degrees do not blend.
    pub crease_degrees: f32,
    /// For a glTF with animations: the clip that plays (the first by default).
    pub animation: Option<ClipChoice>,
    /// For a glTF with animations: the clip's time at the scene's time 0, in seconds.
    pub time: f32,
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            as_: MeshAs::Triangles,
            spheres: SphereCount::Vertices,
            radius: None,
            rotate: Vec3::ZERO,
            normalize: true,
            scale: 1.0,
            translate: Vec3::ZERO,
            seed: 0,
            material: 0,
            normals: Normals::Auto,
            crease_degrees: DEFAULT_CREASE_DEGREES,
            animation: None,
            time: 0.0,
        }
    }
}

impl Placement {
    /// Why the placement cannot be used, if it cannot: its numbers finite, its scale positive.
    pub fn validate(&self) -> Result<(), InputError> {
        let fail = |message: String| Err(InputError::new(message));
        if !(self.scale > 0.0 && self.scale.is_finite()) {
            return fail(format!("scale must be positive and finite (got {})", self.scale));
        }
        if !self.translate.is_finite() {
            return fail("translate must be finite".into());
        }
        if !self.rotate.is_finite() {
            return fail("rotate must be finite".into());
        }
        if !self.time.is_finite() {
            return fail("time must be finite".into());
        }
        match self.spheres {
            SphereCount::Sampled(0) => return fail("spheres must be at least 1".into()),
            SphereCount::Sampled(n) if n > crate::scene::MAX_RECORDS => {
                return fail(format!(
                    "spheres must be at most {} (got {n})",
                    crate::scene::MAX_RECORDS
                ));
            }
            _ => {}
        }
        if let Some(radius) = self.radius
            && !(radius > 0.0 && radius.is_finite())
        {
            return fail(format!("radius must be positive and finite (got {radius})"));
        }
        if !(0.0..=180.0).contains(&self.crease_degrees) {
            return fail(format!(
                "crease must be an angle from 0 to 180 degrees (got {})",
                self.crease_degrees
            ));
        }
        if self.as_ == MeshAs::Spheres
            && (self.normals != Normals::Auto || self.crease_degrees != DEFAULT_CREASE_DEGREES)
        {
            return fail("normals and crease apply to a mesh placed as triangles".into());
        }
        Ok(())
    }
}

/// Places `mesh` and adds it to `scene`: its triangles, or spheres on its surface.
pub fn add_mesh(scene: &mut Scene, mut mesh: Mesh, placement: &Placement) -> Result<(), InputError> {
    placement.validate()?;
    if placement.rotate != Vec3::ZERO {
        mesh.rotate(placement.rotate);
    }
    if placement.normalize {
        mesh.normalize();
    }
    mesh.transform(placement.scale, placement.translate);
    if placement.as_ == MeshAs::Triangles && mesh.triangles.iter().all(|&t| mesh.triangle_area(t) == 0.0) {
        log::warn!("every triangle of the mesh has zero area: rays pass through it");
    }
    let material = placement.material;
    match placement.as_ {
        MeshAs::Triangles => {
            // Each triangle's corner normals, or none to shade flat.
            let corner_normals: Option<Vec<[Vec3; 3]>> = match (placement.normals, &mesh.normals) {
                (Normals::Flat, _) => None,
                (Normals::Auto, Some(file)) => {
                    Some(mesh.triangles.iter().map(|t| t.map(|i| file[i as usize])).collect())
                }
                (Normals::Smooth, _) | (Normals::Auto, None) => Some(mesh.smooth_normals(placement.crease_degrees)),
            };
            scene.triangles.reserve(mesh.triangles.len());
            scene.mesh_starts.push(scene.triangles.len() as u32);
            for (f, &t) in mesh.triangles.iter().enumerate() {
                scene.triangles.push(Triangle {
                    vertices: mesh.corners(t),
                    normals: corner_normals.as_ref().map(|n| n[f]),
                    material,
                    ..Triangle::default()
                });
            }
        }
        MeshAs::Spheres => {
            let centers = match placement.spheres {
                SphereCount::Sampled(count) => mesh.sample_surface(count, placement.seed),
                SphereCount::Vertices => mesh.positions.clone(),
            };
            let radius = placement
                .radius
                .unwrap_or_else(|| mesh.default_sphere_radius(centers.len()));
            if !(radius > 0.0 && radius.is_finite()) {
                return Err(InputError::new(
                    "the mesh has no area to size spheres by: give a radius",
                ));
            }
            scene.spheres.extend(centers.into_iter().map(|center| Sphere {
                center,
                radius,
                material,
            }));
        }
    }
    Ok(())
}

/// Adds a glTF to `scene`, placed after the file's own node transforms: its triangles with its
/// materials and textures, or spheres on its surface. Returns the placement's transform, which the
/// file's camera and lights take too. A file with animations is posed at the placement's time of
/// its clip, and its moving triangles join the scene's motion (spheres stand still).
pub(crate) fn place_gltf(scene: &mut Scene, gltf: &GltfScene, placement: &Placement) -> Result<Similarity, InputError> {
    let clip = match &gltf.rig {
        Some(rig) => rig.clip(placement.animation.as_ref())?,
        None if placement.animation.is_some() => {
            return Err(InputError::new("an animation is chosen, and the file has none"));
        }
        None => None,
    };
    let posed;
    let gltf = match clip {
        Some(clip) if (clip, placement.time) != (0, 0.0) => {
            posed = gltf.posed(Some(clip), placement.time);
            &posed
        }
        _ => gltf,
    };
    let place = gltf_similarity(gltf, placement);
    match placement.as_ {
        MeshAs::Triangles => {
            let starts = add_gltf_triangles(scene, gltf, placement, &place)?;
            if let Some(animated) = clip.and_then(|clip| animated_part(gltf, clip, placement.time, &place, &starts)) {
                drop_moving_tangents(scene, &animated);
                let animated = Arc::new(animated);
                match &mut scene.motion {
                    None => scene.motion = Some(Motion::Animations(vec![animated])),
                    Some(Motion::Animations(list)) => list.push(animated),
                    Some(Motion::Bounce(_)) => {
                        return Err(InputError::new("a scene of bouncing spheres takes no animated file"));
                    }
                }
            }
        }
        MeshAs::Spheres => {
            if clip.is_some() {
                log::info!("the animation is not played: spheres stand where the pose puts them");
            }
            add_mesh(scene, gltf.mesh(), placement)?
        }
    }
    Ok(place)
}

/// Leaves the tangents out of the triangles that move: a moving mesh's tangents would stay as the
/// rest pose has them, so its normal maps are not applied (a notice says so).
fn drop_moving_tangents(scene: &mut Scene, animated: &Animated) {
    let mut dropped = false;
    for placed in &animated.placed {
        let triangles = &mut scene.triangles[placed.first_triangle..][..placed.triangles.len()];
        for triangle in triangles.iter_mut().filter(|t| t.tangents.is_some()) {
            triangle.tangents = None;
            dropped = true;
        }
    }
    if dropped {
        log::info!("normal maps on moving meshes are not applied yet: they shade with their vertex normals");
    }
}

/// The placement's transform of a glTF: its rotation, then (with `normalize`) the box centred at
/// the origin with its longest side 2, then its scale and translation.
fn gltf_similarity(gltf: &GltfScene, placement: &Placement) -> Similarity {
    let rotation = mesh::euler_rotation(placement.rotate);
    let (mut scale, mut translation) = (1.0, Vec3::ZERO);
    if placement.normalize {
        let bounds = Aabb::around_points(
            gltf.primitives
                .iter()
                .flat_map(|p| p.positions.iter().map(|&q| rotation * q)),
        );
        let longest = (bounds.max - bounds.min).max_element();
        scale = if longest > 0.0 { 2.0 / longest } else { 1.0 };
        translation = -bounds.centroid() * scale;
    }
    Similarity {
        rotation,
        scale: scale * placement.scale,
        translation: translation * placement.scale + placement.translate,
    }
}

/// Adds a glTF's triangles, placed, to `scene`, with its materials and textures after the scene's
/// own. The file's vertex normals are used where `normals` is Auto and it has them; other
/// triangles get smooth (or, for Flat, no) normals as model files do. Returns, per primitive,
/// where its triangles start in `scene` and where its normals come from.
fn add_gltf_triangles(
    scene: &mut Scene,
    gltf: &GltfScene,
    placement: &Placement,
    place: &Similarity,
) -> Result<Vec<(usize, CornerNormals)>, InputError> {
    if scene.triangles.len() + gltf.triangle_count() > super::MAX_RECORDS {
        return Err(InputError::new(format!(
            "more than the {} triangles a render takes",
            super::MAX_RECORDS
        )));
    }
    let material_base = scene.materials.len() as u32;
    let texture_base = scene.textures.len() as u32;
    scene
        .materials
        .extend(gltf.materials.iter().map(|m| m.with_textures_from(texture_base)));
    scene.textures.extend(gltf.textures.iter().cloned());
    let mut starts = Vec::with_capacity(gltf.primitives.len());
    for primitive in &gltf.primitives {
        let normals_from = match (placement.normals, &primitive.normals) {
            (Normals::Flat, _) => CornerNormals::Flat,
            (Normals::Auto, Some(_)) => CornerNormals::File,
            (Normals::Smooth, _) | (Normals::Auto, None) => CornerNormals::Smooth(placement.crease_degrees),
        };
        starts.push((scene.triangles.len(), normals_from));
        scene.mesh_starts.push(scene.triangles.len() as u32);
        let positions: Vec<Vec3> = primitive.positions.iter().map(|&p| place.point(p)).collect();
        let corner_normals =
            normals_from.corners(&primitive.triangles, &positions, primitive.normals.as_deref(), place);
        for (f, t) in primitive.triangles.iter().enumerate() {
            scene.triangles.push(Triangle {
                vertices: t.map(|i| positions[i as usize]),
                normals: corner_normals.as_ref().map(|n| n[f]),
                uvs: primitive.uvs.as_ref().map(|uvs| t.map(|i| uvs[i as usize])),
                material: material_base + primitive.material,
                uvs1: primitive.uvs1.as_ref().map(|uvs| t.map(|i| uvs[i as usize])),
                colors: primitive.colors.as_ref().map(|colors| t.map(|i| colors[i as usize])),
                // The placement turns tangents as it turns normals (its scale is uniform).
                tangents: primitive
                    .tangents
                    .as_ref()
                    .map(|tangents| tangents[f].map(|t| (place.rotation * t.truncate()).extend(t.w))),
            });
        }
    }
    Ok(starts)
}

/// The moving part of a glTF (posed at `offset` of `clip`), placed as [`add_gltf_triangles`]
/// placed it (`starts` is what it returned), or `None` where the clip moves none of it.
fn animated_part(
    gltf: &GltfScene,
    clip: usize,
    offset: f32,
    place: &Similarity,
    starts: &[(usize, CornerNormals)],
) -> Option<Animated> {
    let rig = gltf.rig.as_ref()?;
    let moving = rig.moving_instances(clip);
    let placed: Vec<PlacedInstance> = (0..gltf.primitives.len())
        .filter(|&i| moving[i])
        .map(|i| PlacedInstance {
            instance: i,
            first_triangle: starts[i].0,
            triangles: gltf.primitives[i].triangles.clone(),
            normals: starts[i].1,
        })
        .collect();
    (!placed.is_empty()).then(|| Animated {
        rig: rig.clone(),
        clip,
        offset,
        place: *place,
        placed,
    })
}

#[cfg(test)]
mod tests {
    use super::framing::{Framing, scene_bounds};
    use super::*;

    fn tetrahedron() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X * 4.0, Vec3::Y * 4.0, Vec3::Z * 4.0],
            normals: None,
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn triangles_are_placed_after_normalizing() {
        let mut scene = Scene::default();
        let placement = Placement {
            scale: 0.5,
            translate: Vec3::new(10.0, 0.0, 0.0),
            ..Placement::default()
        };
        add_mesh(&mut scene, tetrahedron(), &placement).unwrap();
        assert_eq!(scene.triangles.len(), 4);
        let bounds = scene_bounds(&scene);
        assert_eq!(bounds.min, Vec3::new(9.5, -0.5, -0.5));
        assert_eq!(bounds.max, Vec3::new(10.5, 0.5, 0.5));
    }

    #[test]
    fn spheres_sample_the_surface_or_sit_on_vertices() {
        let mut scene = Scene::default();
        let sampled = Placement {
            as_: MeshAs::Spheres,
            spheres: SphereCount::Sampled(500),
            ..Placement::default()
        };
        add_mesh(&mut scene, tetrahedron(), &sampled).unwrap();
        assert_eq!(scene.spheres.len(), 500);
        let radius = scene.spheres[0].radius;
        assert!(radius > 0.0 && scene.spheres.iter().all(|s| s.radius == radius));

        let mut scene = Scene::default();
        let on_vertices = Placement {
            as_: MeshAs::Spheres,
            radius: Some(0.1),
            ..Placement::default()
        };
        add_mesh(&mut scene, tetrahedron(), &on_vertices).unwrap();
        assert_eq!(scene.spheres.len(), 4);
        assert_eq!(scene.spheres[0].radius, 0.1);
    }

    /// The floor lies just below the model's lowest point, a gap small against the model; with
    /// `Floor::None` there is none.
    #[test]
    fn a_framed_model_stands_just_above_its_floor() {
        let scene = scene_around(tetrahedron(), "t.off", &ModelOptions::default()).unwrap();
        let lowest = scene_bounds(&scene).min.y;
        let radius = Framing::of(&scene).radius;
        let [floor] = scene.planes[..] else {
            panic!("one floor: {:?}", scene.planes)
        };
        let gap = lowest - floor.point.y;
        assert!(
            gap > 0.0 && gap <= 2.0 * FLOOR_GAP * radius,
            "gap {gap}, radius {radius}"
        );
        let floating = ModelOptions {
            floor: Floor::None,
            ..ModelOptions::default()
        };
        assert!(
            scene_around(tetrahedron(), "t.off", &floating)
                .unwrap()
                .planes
                .is_empty()
        );
    }

    #[test]
    fn bad_placements_are_refused() {
        let zero = Placement {
            as_: MeshAs::Spheres,
            spheres: SphereCount::Sampled(0),
            ..Placement::default()
        };
        assert_eq!(zero.validate().unwrap_err().message, "spheres must be at least 1");
        let negative = Placement {
            scale: -1.0,
            ..Placement::default()
        };
        assert!(
            negative
                .validate()
                .unwrap_err()
                .message
                .starts_with("scale must be positive")
        );
    }
}
