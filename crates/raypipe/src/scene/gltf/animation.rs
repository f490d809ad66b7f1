//! What moves in a glTF file, read into a [`Rig`]: the nodes' rest transforms and hierarchy,
//! skins, the animations' channels and samplers, and each vertex's joints and weights and morph
//! targets. Every reference, count and number is checked here, so that posing cannot fail.

use super::data::read_floats;
use crate::error::{GltfPart, InputError};
use crate::scene::animation::{
    Channel, Clip, Influences, Interpolation, MAX_INFLUENCES, MAX_JOINTS, MorphTarget, Node, Path, Rig, Sampler, Skin,
    Transform,
};
use glam::{Mat4, Quat, Vec3};
use gltf::json;
use gltf::json::accessor::Type;
use gltf::json::validation::Checked;

/// How far a vertex's weights may sum from one before they are normalized with a notice.
const WEIGHT_SUM_SLACK: f32 = 2e-3;

/// The nodes (every one, with its parent), skins and animations of a validated document.
/// `parents` comes from the hierarchy walk, which refused cycles and shared children.
pub(crate) fn read_rig(
    root: &json::Root,
    buffers: &[Vec<u8>],
    parents: &[Option<usize>],
    notices: &mut Vec<String>,
) -> Result<Rig, InputError> {
    let nodes = root
        .nodes
        .iter()
        .enumerate()
        .map(|(n, node)| {
            let rest = rest_transform(node);
            Node {
                parent: parents[n],
                rest,
                weights: node.weights.clone(),
            }
        })
        .collect::<Vec<_>>();
    for (n, node) in nodes.iter().enumerate() {
        if let Some(weights) = &node.weights
            && !weights.iter().all(|w| w.is_finite())
        {
            return Err(InputError::in_gltf(GltfPart::Node(n), "weights must be finite"));
        }
    }
    let order = parents_first(parents);
    let skins = root
        .skins
        .iter()
        .enumerate()
        .map(|(s, skin)| read_skin(root, buffers, skin).map_err(|e| e.within(GltfPart::Skin(s))))
        .collect::<Result<Vec<_>, _>>()?;
    let clips = root
        .animations
        .iter()
        .enumerate()
        .map(|(a, animation)| {
            read_clip(root, buffers, animation, &nodes, notices).map_err(|e| e.within(GltfPart::Animation(a)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Rig {
        nodes,
        order,
        skins,
        clips,
        instances: Vec::new(),
    })
}

/// A node's own transform as the file writes it: its matrix, or its translation, rotation and
/// scale (each defaulting to the identity's). Unchecked: see [`Transform::check`].
pub(crate) fn rest_transform(node: &json::Node) -> Transform {
    match node.matrix {
        Some(m) => Transform::Matrix(Mat4::from_cols_array(&m)),
        None => Transform::Decomposed {
            translation: node.translation.map_or(Vec3::ZERO, Vec3::from),
            rotation: node.rotation.map_or(Quat::IDENTITY, |r| Quat::from_array(r.0)),
            scale: node.scale.map_or(Vec3::ONE, Vec3::from),
        },
    }
}

/// Every node, each after its parent.
fn parents_first(parents: &[Option<usize>]) -> Vec<usize> {
    let mut children = vec![Vec::new(); parents.len()];
    for (n, parent) in parents.iter().enumerate() {
        if let Some(p) = parent {
            children[*p].push(n);
        }
    }
    let mut order = Vec::with_capacity(parents.len());
    let mut stack: Vec<usize> = (0..parents.len()).filter(|&n| parents[n].is_none()).rev().collect();
    while let Some(n) = stack.pop() {
        order.push(n);
        stack.extend(children[n].iter().rev());
    }
    order
}

fn read_skin(root: &json::Root, buffers: &[Vec<u8>], skin: &json::Skin) -> Result<Skin, InputError> {
    let joints: Vec<usize> = skin.joints.iter().map(|j| j.value()).collect();
    if joints.is_empty() {
        return Err(InputError::new("no joints"));
    }
    if joints.len() > MAX_JOINTS {
        return Err(InputError::new(format!(
            "{} joints, more than the {MAX_JOINTS} a skin may have",
            joints.len()
        )));
    }
    let inverse_binds = match &skin.inverse_bind_matrices {
        None => vec![Mat4::IDENTITY; joints.len()],
        Some(accessor) => {
            let floats = read_floats(root, buffers, accessor.value(), &[Type::Mat4])?;
            let fail = |message: String| Err(InputError::in_gltf(GltfPart::Accessor(accessor.value()), message));
            if floats.len() / 16 < joints.len() {
                return fail(format!(
                    "{} inverse bind matrices for {} joints",
                    floats.len() / 16,
                    joints.len()
                ));
            }
            if !floats.iter().all(|f| f.is_finite()) {
                return fail("inverse bind matrices must be finite".into());
            }
            floats
                .chunks_exact(16)
                .take(joints.len())
                .map(Mat4::from_cols_slice)
                .collect()
        }
    };
    Ok(Skin { joints, inverse_binds })
}

fn read_clip(
    root: &json::Root,
    buffers: &[Vec<u8>],
    animation: &json::Animation,
    nodes: &[Node],
    notices: &mut Vec<String>,
) -> Result<Clip, InputError> {
    let mut channels = Vec::new();
    for (c, channel) in animation.channels.iter().enumerate() {
        let channel =
            read_channel(root, buffers, animation, channel, nodes).map_err(|e| e.within(GltfPart::Channel(c)))?;
        channels.push(channel);
    }
    if channels.is_empty() {
        notices.push(format!(
            "animation {}: no channels, so nothing moves",
            animation.name.as_deref().unwrap_or("(unnamed)")
        ));
    }
    Ok(Clip {
        name: animation.name.clone(),
        channels,
    })
}

fn read_channel(
    root: &json::Root,
    buffers: &[Vec<u8>],
    animation: &json::Animation,
    channel: &json::animation::Channel,
    nodes: &[Node],
) -> Result<Channel, InputError> {
    let fail = |message: String| Err(InputError::new(message));
    let node = channel.target.node.value();
    let path = match channel.target.path {
        Checked::Valid(json::animation::Property::Translation) => Path::Translation,
        Checked::Valid(json::animation::Property::Rotation) => Path::Rotation,
        Checked::Valid(json::animation::Property::Scale) => Path::Scale,
        Checked::Valid(json::animation::Property::MorphTargetWeights) => Path::Weights,
        Checked::Invalid => return fail("unknown target path".into()),
    };
    if path != Path::Weights && matches!(nodes[node].rest, Transform::Matrix(_)) {
        return fail(format!(
            "animates node {node}, whose transform is a matrix (only translation, rotation and scale may be animated)"
        ));
    }
    let Some(sampler) = animation.samplers.get(channel.sampler.value()) else {
        return fail(format!("sampler {} does not exist", channel.sampler.value()));
    };
    let width = match path {
        Path::Translation | Path::Scale => 3,
        Path::Rotation => 4,
        Path::Weights => match morph_target_count(root, node) {
            Some(count) => count,
            None => {
                return fail(format!(
                    "animates the weights of node {node}, which has no morph targets"
                ));
            }
        },
    };
    let sampler = read_sampler(root, buffers, sampler, path, width)?;
    Ok(Channel { node, path, sampler })
}

/// The morph targets of the mesh on `node` (every primitive of a mesh has as many).
fn morph_target_count(root: &json::Root, node: usize) -> Option<usize> {
    let mesh = &root.meshes[root.nodes[node].mesh?.value()];
    let count = mesh.primitives.first()?.targets.as_ref().map_or(0, |t| t.len());
    (count > 0).then_some(count)
}

fn read_sampler(
    root: &json::Root,
    buffers: &[Vec<u8>],
    sampler: &json::animation::Sampler,
    path: Path,
    width: usize,
) -> Result<Sampler, InputError> {
    let interpolation = match sampler.interpolation {
        Checked::Valid(json::animation::Interpolation::Step) => Interpolation::Step,
        Checked::Valid(json::animation::Interpolation::Linear) => Interpolation::Linear,
        Checked::Valid(json::animation::Interpolation::CubicSpline) => Interpolation::CubicSpline,
        Checked::Invalid => return Err(InputError::new("unknown interpolation")),
    };
    let times = read_floats(root, buffers, sampler.input.value(), &[Type::Scalar])?;
    let output_type = match path {
        Path::Translation | Path::Scale => Type::Vec3,
        Path::Rotation => Type::Vec4,
        Path::Weights => Type::Scalar,
    };
    let values = read_floats(root, buffers, sampler.output.value(), &[output_type])?;
    let read = Sampler {
        times,
        values,
        width,
        interpolation,
    };
    read.validate().map_err(|e| {
        InputError::new(format!(
            "sampler of input accessor {} and output accessor {}: {e}",
            sampler.input.value(),
            sampler.output.value()
        ))
    })?;
    Ok(read)
}

/// A primitive's joints and weights (JOINTS_n and WEIGHTS_n, n = 0 and 1), for `vertex_count`
/// vertices: joint indices below the most a skin may have (the skin that uses the mesh checks its
/// own count), weights normalized where they do not sum to one.
pub(crate) fn read_influences(
    root: &json::Root,
    buffers: &[Vec<u8>],
    sets: &[(usize, usize)],
    vertex_count: usize,
    notices: &mut Vec<String>,
) -> Result<Vec<Influences>, InputError> {
    let mut influences = vec![Influences::default(); vertex_count];
    for (set, &(joints_accessor, weights_accessor)) in sets.iter().enumerate().take(MAX_INFLUENCES / 4) {
        let joints = read_floats(root, buffers, joints_accessor, &[Type::Vec4])?;
        let weights = read_floats(root, buffers, weights_accessor, &[Type::Vec4])?;
        for (accessor, values) in [(joints_accessor, &joints), (weights_accessor, &weights)] {
            if values.len() != vertex_count * 4 {
                return Err(InputError::in_gltf(
                    GltfPart::Accessor(accessor),
                    format!("{} elements where POSITION has {vertex_count}", values.len() / 4),
                ));
            }
        }
        for v in 0..vertex_count {
            for c in 0..4 {
                let (joint, weight) = (joints[v * 4 + c], weights[v * 4 + c]);
                if !(weight.is_finite() && weight >= 0.0) {
                    return Err(InputError::in_gltf(
                        GltfPart::Accessor(weights_accessor),
                        format!("weight {c} of vertex {v} must be finite and not negative"),
                    ));
                }
                if !(joint >= 0.0 && (joint as usize) < MAX_JOINTS && joint.fract() == 0.0) {
                    return Err(InputError::in_gltf(
                        GltfPart::Accessor(joints_accessor),
                        format!("vertex {v} names joint {joint}, and a skin has at most {MAX_JOINTS}"),
                    ));
                }
                let slot = set * 4 + c;
                influences[v].joints[slot] = joint as u16;
                influences[v].weights[slot] = weight;
            }
        }
    }
    let mut normalized = 0;
    for (v, influence) in influences.iter_mut().enumerate() {
        let sum: f32 = influence.weights.iter().sum();
        if sum <= 0.0 {
            return Err(InputError::new(format!("vertex {v}: its joint weights are all zero")));
        }
        if (sum - 1.0).abs() > WEIGHT_SUM_SLACK {
            normalized += 1;
        }
        for w in &mut influence.weights {
            *w /= sum;
        }
    }
    if normalized > 0 {
        notices.push(format!(
            "{normalized} vertices have joint weights that do not sum to one: normalized"
        ));
    }
    Ok(influences)
}

/// A primitive's morph targets: position and normal offsets, as many as its vertices.
pub(crate) fn read_targets(
    root: &json::Root,
    buffers: &[Vec<u8>],
    primitive: &json::mesh::Primitive,
    vertex_count: usize,
) -> Result<Vec<MorphTarget>, InputError> {
    let Some(targets) = &primitive.targets else {
        return Ok(Vec::new());
    };
    let offsets = |accessor: Option<&json::Index<json::Accessor>>, t: usize, what: &str| {
        accessor
            .map(|index| {
                let within = |e: InputError| e.within(GltfPart::MorphTarget(t));
                let floats = read_floats(root, buffers, index.value(), &[Type::Vec3]).map_err(within)?;
                let fail =
                    |message: String| Err(within(InputError::in_gltf(GltfPart::Accessor(index.value()), message)));
                if floats.len() != vertex_count * 3 {
                    return fail(format!(
                        "{} {what} offsets where POSITION has {vertex_count}",
                        floats.len() / 3
                    ));
                }
                if !floats.iter().all(|f| f.is_finite()) {
                    return fail(format!("{what} offsets must be finite"));
                }
                Ok(floats.chunks_exact(3).map(Vec3::from_slice).collect())
            })
            .transpose()
    };
    targets
        .iter()
        .enumerate()
        .map(|(t, target)| {
            Ok(MorphTarget {
                positions: offsets(target.positions.as_ref(), t, "position")?,
                normals: offsets(target.normals.as_ref(), t, "normal")?,
            })
        })
        .collect()
}
