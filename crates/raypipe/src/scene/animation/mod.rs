//! Animated geometry, independent of the file it came from: a node hierarchy whose translations,
//! rotations, scales and morph weights follow keyframe clips, and mesh primitives posed by it:
//! morphed (rest positions plus weighted target offsets), then skinned (each vertex by up to eight
//! joints' matrices) or carried by their node. [`super::gltf`] reads these from a glTF file; a
//! scene in motion holds them as [`Animated`] and poses its triangles at any time.
//!
//! Evaluation follows the glTF 2.0 specification: times before a sampler's first key take its
//! first value and after its last its last; LINEAR rotations are spherical; CUBICSPLINE is the
//! cubic Hermite spline of the keys' tangents; rotations are normalized after interpolation.

use super::Similarity;
use crate::error::InputError;
use crate::mesh::Mesh;
use glam::{Mat3, Mat4, Quat, Vec3};
use std::sync::Arc;

mod keys;

pub use keys::{Channel, Clip, Interpolation, Path, Sampler};

/// Most joints a skin may have. Characters use tens to a few hundred; the bound keeps a hostile
/// file from making every vertex's skinning read an unbounded table.
pub(crate) const MAX_JOINTS: usize = 4096;
/// Joint influences a vertex may have: JOINTS_0 and JOINTS_1, four each.
pub(crate) const MAX_INFLUENCES: usize = 8;

/// A node's own transform: a matrix (which no channel may animate), or translation, rotation and
/// scale, composed T * R * S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transform {
    /// A whole matrix (not animated).
    Matrix(Mat4),
    /// Translation, rotation and scale, composed T * R * S.
    Decomposed {
        /// Applied last.
        translation: Vec3,
        /// A unit quaternion.
        rotation: Quat,
        /// Per axis, applied first.
        scale: Vec3,
    },
}

impl Transform {
    /// Finite numbers and a rotation of about unit length (it is normalized when composed); the
    /// error says what is off.
    pub fn check(&self) -> Result<(), InputError> {
        match *self {
            Transform::Matrix(m) if !m.is_finite() => Err(InputError::new("matrix must be finite")),
            Transform::Matrix(_) => Ok(()),
            Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                if !(translation.is_finite() && rotation.is_finite() && scale.is_finite()) {
                    return Err(InputError::new("translation, rotation and scale must be finite"));
                }
                let length = rotation.length();
                if !(length > 0.5 && length < 2.0) {
                    return Err(InputError::new(format!(
                        "rotation must be a unit quaternion (length {length})"
                    )));
                }
                Ok(())
            }
        }
    }

    /// The matrix, or T * R * S with the rotation normalized.
    pub fn matrix(&self) -> Mat4 {
        match *self {
            Transform::Matrix(m) => m,
            Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => Mat4::from_scale_rotation_translation(scale, rotation.normalize(), translation),
        }
    }
}

/// A node of the hierarchy: its parent, rest transform and morph weights.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// The parent node; `None` for a root.
    pub parent: Option<usize>,
    /// Its transform where no channel moves it.
    pub rest: Transform,
    /// Morph weights the node gives its mesh, where it overrides the mesh's.
    pub weights: Option<Vec<f32>>,
}

/// A skin: its joints (nodes) and their inverse bind matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// The joints' nodes.
    pub joints: Vec<usize>,
    /// Per joint: from the mesh's space to the joint's, at bind time.
    pub inverse_binds: Vec<Mat4>,
}

/// Offsets a morph target adds to its primitive's vertices, scaled by its weight.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    /// Offsets added to the positions, where the target moves them.
    pub positions: Option<Vec<Vec3>>,
    /// Offsets added to the normals, where the target moves them.
    pub normals: Option<Vec<Vec3>>,
}

/// Up to eight joints (indices into the skin's list) and their weights, summing to one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Influences {
    /// The joints.
    pub joints: [u16; MAX_INFLUENCES],
    /// Their weights.
    pub weights: [f32; MAX_INFLUENCES],
}

/// A mesh primitive as the file stores it, in its mesh's space, with what deforms it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RestPrimitive {
    /// The vertices.
    pub positions: Vec<Vec3>,
    /// The vertex normals, where the file has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per vertex, for a skinned mesh; empty otherwise.
    pub influences: Vec<Influences>,
    /// The morph targets.
    pub targets: Vec<MorphTarget>,
    /// The mesh's morph weights, one per target.
    pub weights: Vec<f32>,
}

/// A primitive placed by a node: the node carries it, or its skin's joints do.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// The node that places it.
    pub node: usize,
    /// Its skin, where the joints carry it.
    pub skin: Option<usize>,
    /// The primitive, shared by every instance of it.
    pub rest: Arc<RestPrimitive>,
    /// Where the primitive stands under its node: one of the node's EXT_mesh_gpu_instancing
    /// transforms, or the identity.
    pub offset: Mat4,
}

/// Everything that moves in a file: its nodes, skins and clips, and its primitives, one
/// [`Instance`] per placed primitive in the order the file's scene lists them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rig {
    /// The nodes, as the file lists them.
    pub nodes: Vec<Node>,
    /// Every node, parents before children.
    pub order: Vec<usize>,
    /// The skins.
    pub skins: Vec<Skin>,
    /// The animations.
    pub clips: Vec<Clip>,
    /// The placed primitives.
    pub instances: Vec<Instance>,
}

/// A clip by its place in the file or its name (`--animation`, a scene file's `animation`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ClipChoice {
    /// The clip at this place in the file.
    Index(usize),
    /// The clip of this name.
    Name(String),
}

impl ClipChoice {
    /// A number is an index; anything else a name.
    pub fn parse(text: &str) -> Self {
        match text.parse() {
            Ok(index) => ClipChoice::Index(index),
            Err(_) => ClipChoice::Name(text.to_string()),
        }
    }
}

/// The nodes at one time: world matrices and morph weights.
pub struct Pose {
    /// Per node, from its space to the file's world.
    pub world: Vec<Mat4>,
    /// Per node, the weights its channels set (empty where none does).
    pub weights: Vec<Vec<f32>>,
}

impl Rig {
    /// The clip `choice` names (the first where it names none), or `None` where the file has no
    /// animation; the error lists what it has.
    pub fn clip(&self, choice: Option<&ClipChoice>) -> Result<Option<usize>, InputError> {
        let names = || {
            let listed: Vec<String> = self
                .clips
                .iter()
                .enumerate()
                .map(|(i, c)| format!("{i} ({})", c.name.as_deref().unwrap_or("unnamed")))
                .collect();
            if listed.is_empty() {
                "none".to_string()
            } else {
                listed.join(", ")
            }
        };
        match choice {
            None => Ok((!self.clips.is_empty()).then_some(0)),
            Some(ClipChoice::Index(i)) if *i < self.clips.len() => Ok(Some(*i)),
            Some(ClipChoice::Name(name)) => match self.clips.iter().position(|c| c.name.as_deref() == Some(name)) {
                Some(i) => Ok(Some(i)),
                None => Err(InputError::new(format!(
                    "no animation named {name:?}; the file has: {}",
                    names()
                ))),
            },
            Some(ClipChoice::Index(i)) => Err(InputError::new(format!("no animation {i}; the file has: {}", names()))),
        }
    }

    /// The nodes at time `t` of `clip` (`None`: at rest).
    pub fn pose(&self, clip: Option<usize>, t: f32) -> Pose {
        let mut locals: Vec<Transform> = self.nodes.iter().map(|n| n.rest).collect();
        let mut weights = vec![Vec::new(); self.nodes.len()];
        let mut buffer = [0.0f32; 4];
        for channel in clip.map_or(&[][..], |c| &self.clips[c].channels) {
            if channel.path == Path::Weights {
                let mut values = vec![0.0; channel.sampler.width];
                channel.sampler.sample(t, false, &mut values);
                weights[channel.node] = values;
                continue;
            }
            // Reading refuses channels on a node whose transform is a matrix.
            let Transform::Decomposed {
                translation,
                rotation,
                scale,
            } = &mut locals[channel.node]
            else {
                continue;
            };
            match channel.path {
                Path::Translation => {
                    channel.sampler.sample(t, false, &mut buffer[..3]);
                    *translation = Vec3::from_slice(&buffer);
                }
                Path::Rotation => {
                    channel.sampler.sample(t, true, &mut buffer);
                    *rotation = Quat::from_slice(&buffer);
                }
                Path::Scale => {
                    channel.sampler.sample(t, false, &mut buffer[..3]);
                    *scale = Vec3::from_slice(&buffer);
                }
                Path::Weights => unreachable!("handled above"),
            }
        }
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        for &n in &self.order {
            let local = locals[n].matrix();
            world[n] = match self.nodes[n].parent {
                Some(parent) => world[parent] * local,
                None => local,
            };
        }
        Pose { world, weights }
    }

    /// Which instances `clip` moves: those whose node, a joint of their skin, or an ancestor of
    /// either is animated.
    pub fn moving_instances(&self, clip: usize) -> Vec<bool> {
        let mut moving = vec![false; self.nodes.len()];
        let mut morphing = vec![false; self.nodes.len()];
        for channel in &self.clips[clip].channels {
            match channel.path {
                Path::Weights => morphing[channel.node] = true,
                _ => moving[channel.node] = true,
            }
        }
        for &n in &self.order {
            if let Some(parent) = self.nodes[n].parent {
                moving[n] |= moving[parent];
            }
        }
        self.instances
            .iter()
            .map(|instance| {
                morphing[instance.node]
                    || match instance.skin {
                        Some(skin) => self.skins[skin].joints.iter().any(|&j| moving[j]),
                        None => moving[instance.node],
                    }
            })
            .collect()
    }

    /// The morph weights that `pose` gives `instance`: its node's animated ones, else the node's
    /// own, else its mesh's.
    fn morph_weights<'a>(&'a self, instance: &'a Instance, pose: &'a Pose) -> &'a [f32] {
        let animated = &pose.weights[instance.node];
        if !animated.is_empty() {
            animated
        } else {
            self.nodes[instance.node]
                .weights
                .as_deref()
                .unwrap_or(&instance.rest.weights)
        }
    }

    /// Per joint of `skin`, the matrix from the mesh's space at bind time to the world at `pose`.
    fn joint_matrices(&self, skin: &Skin, pose: &Pose) -> Vec<Mat4> {
        skin.joints
            .iter()
            .zip(&skin.inverse_binds)
            .map(|(&joint, inverse_bind)| pose.world[joint] * *inverse_bind)
            .collect()
    }

    /// An instance's vertices (and normals, where it has them) in world space at `pose`: morphed,
    /// then skinned or carried by their node.
    pub fn deform(&self, instance: &Instance, pose: &Pose) -> (Vec<Vec3>, Option<Vec<Vec3>>) {
        let rest = &*instance.rest;
        let weights = self.morph_weights(instance, pose);
        let mut positions = rest.positions.clone();
        let mut normals = rest.normals.clone();
        for (target, &w) in rest.targets.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            if let Some(offsets) = &target.positions {
                for (p, d) in positions.iter_mut().zip(offsets) {
                    *p += *d * w;
                }
            }
            if let (Some(normals), Some(offsets)) = (&mut normals, &target.normals) {
                for (n, d) in normals.iter_mut().zip(offsets) {
                    *n += *d * w;
                }
            }
        }
        match instance.skin {
            Some(skin) => {
                let joints = self.joint_matrices(&self.skins[skin], pose);
                for (v, influences) in rest.influences.iter().enumerate() {
                    let mut matrix = Mat4::ZERO;
                    for (&joint, &weight) in influences.joints.iter().zip(&influences.weights) {
                        if weight != 0.0 {
                            matrix += joints[joint as usize] * weight;
                        }
                    }
                    positions[v] = matrix.transform_point3(positions[v]);
                    if let Some(normals) = &mut normals {
                        normals[v] = normal_matrix(&matrix) * normals[v];
                    }
                }
            }
            None => {
                let world = pose.world[instance.node] * instance.offset;
                let to_world = normal_matrix(&world);
                for p in &mut positions {
                    *p = world.transform_point3(*p);
                }
                for n in normals.iter_mut().flatten() {
                    *n = to_world * *n;
                }
            }
        }
        for n in normals.iter_mut().flatten() {
            *n = n.normalize_or_zero();
        }
        (positions, normals)
    }
}

/// The matrix that carries normals through `m`: the inverse transpose of its linear part (the
/// identity where it collapses space).
fn normal_matrix(m: &Mat4) -> Mat3 {
    let linear = Mat3::from_mat4(*m);
    if linear.determinant() == 0.0 {
        Mat3::IDENTITY
    } else {
        linear.inverse().transpose()
    }
}

/// Where a moving primitive's shading normals come from, frame after frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CornerNormals {
    /// The file's, deformed with the vertices.
    File,
    /// Smooth normals of the deformed surface, blended across edges sharper than no crease of
    /// this many degrees.
    Smooth(f32),
    /// None: flat shading.
    Flat,
}

impl CornerNormals {
    /// The shading normals at each of `triangles`' corners: the file's `normals` (per vertex,
    /// before placing) turned by `place`, smooth ones of the placed `positions`, or none.
    pub fn corners(
        self,
        triangles: &[[u32; 3]],
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        place: &Similarity,
    ) -> Option<Vec<[Vec3; 3]>> {
        match (self, normals) {
            (CornerNormals::File, Some(normals)) => Some(
                triangles
                    .iter()
                    .map(|t| t.map(|i| place.direction(normals[i as usize])))
                    .collect(),
            ),
            (CornerNormals::Smooth(crease), _) => {
                let mesh = Mesh {
                    positions: positions.to_vec(),
                    normals: None,
                    triangles: triangles.to_vec(),
                };
                Some(mesh.smooth_normals(crease))
            }
            // A placement gives File only to primitives with normals of their own.
            (CornerNormals::File, None) | (CornerNormals::Flat, _) => None,
        }
    }
}

/// An instance whose triangles a scene holds, from `first_triangle` on, in the order of
/// `triangles`.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedInstance {
    /// Which of the rig's instances.
    pub instance: usize,
    /// The scene's triangle its triangles start at.
    pub first_triangle: usize,
    /// Vertex indices, winding as placed.
    pub triangles: Vec<[u32; 3]>,
    /// Where the triangles' normals come from as it moves.
    pub normals: CornerNormals,
}

/// One clip of a rig playing in a scene: the instances it moves, placed as the scene placed the
/// file.
#[derive(Clone, Debug, PartialEq)]
pub struct Animated {
    /// What moves.
    pub rig: Arc<Rig>,
    /// Which of its clips plays.
    pub clip: usize,
    /// Added to the scene's time: where in the clip the scene's time 0 falls.
    pub offset: f32,
    /// How the scene placed the file (framing, a scene file's transform).
    pub place: Similarity,
    /// The instances the scene holds.
    pub placed: Vec<PlacedInstance>,
}

/// What moves one placed instance at a time, for a deformation that runs elsewhere (the GPU's
/// skinning pass): the matrices that carry its morphed vertices into the scene, placement
/// included (one per joint of its skin, or its node's one), and its morph weights (one per
/// target).
#[derive(Clone, Debug, PartialEq)]
pub struct InstancePose {
    /// Joint matrices, or the node's one.
    pub matrices: Vec<Mat4>,
    /// Morph weights.
    pub weights: Vec<f32>,
}

/// New corners (and corner normals, where the triangles have them) for a run of a scene's
/// triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct MovedTriangles {
    /// The first triangle of the run.
    pub first: usize,
    /// Each triangle's corners.
    pub vertices: Vec<[Vec3; 3]>,
    /// Each triangle's corner normals.
    pub normals: Option<Vec<[Vec3; 3]>>,
}

impl Animated {
    /// Seconds the clip plays.
    pub fn duration(&self) -> f32 {
        self.rig.clips[self.clip].duration()
    }

    /// Each placed instance's matrices and morph weights at scene time `t`: what
    /// [`Animated::moved`] applies, for a deformation that runs elsewhere. A skinned vertex is the
    /// weighted sum of its joints' matrices applied to it; the placement, a similarity, commutes
    /// with that sum (the weights sum to one) and is folded into every matrix.
    pub fn instance_poses(&self, t: f32) -> Vec<InstancePose> {
        let pose = self.rig.pose(Some(self.clip), t + self.offset);
        let place = self.place.matrix();
        self.placed
            .iter()
            .map(|placed| {
                let instance = &self.rig.instances[placed.instance];
                let matrices = match instance.skin {
                    Some(skin) => self.rig.joint_matrices(&self.rig.skins[skin], &pose),
                    None => vec![pose.world[instance.node] * instance.offset],
                };
                let mut weights = self.rig.morph_weights(instance, &pose).to_vec();
                weights.resize(instance.rest.targets.len(), 0.0);
                InstancePose {
                    matrices: matrices.into_iter().map(|m| place * m).collect(),
                    weights,
                }
            })
            .collect()
    }

    /// The moving triangles at scene time `t`.
    pub fn moved(&self, t: f32) -> Vec<MovedTriangles> {
        let pose = self.rig.pose(Some(self.clip), t + self.offset);
        self.placed
            .iter()
            .map(|placed| {
                let (positions, normals) = self.rig.deform(&self.rig.instances[placed.instance], &pose);
                let positions: Vec<Vec3> = positions.into_iter().map(|p| self.place.point(p)).collect();
                let vertices = placed
                    .triangles
                    .iter()
                    .map(|t| t.map(|i| positions[i as usize]))
                    .collect();
                let normals = placed
                    .normals
                    .corners(&placed.triangles, &positions, normals.as_deref(), &self.place);
                MovedTriangles {
                    first: placed.first_triangle,
                    vertices,
                    normals,
                }
            })
            .collect()
    }
}
