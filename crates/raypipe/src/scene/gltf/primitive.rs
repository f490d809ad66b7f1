//! A mesh's primitives read in the mesh's own space, once however many nodes use the mesh: their
//! attributes (positions, normals, texture coordinates, colours, tangents, joints and weights,
//! morph targets) checked against their accessors, and their triangles assembled from the mode.

use super::SceneReader;
use super::data::{read_floats, read_indices};
use super::tangents::mikktspace_tangents;
use crate::error::{GltfPart, InputError};
use crate::scene::animation::RestPrimitive;
use glam::{Vec2, Vec3, Vec4};
use gltf::json::accessor::Type;
use gltf::mesh::Mode;
use std::rc::Rc;
use std::sync::Arc;

/// A mesh primitive in its mesh's own space, read once however many nodes use the mesh.
pub(super) struct LocalPrimitive {
    /// Positions, normals, and what deforms them.
    pub(super) rest: Arc<RestPrimitive>,
    pub(super) uvs: Option<Vec<Vec2>>,
    pub(super) uvs1: Option<Vec<Vec2>>,
    pub(super) colors: Option<Vec<Vec4>>,
    /// Per triangle corner, in the mesh's space.
    pub(super) tangents: Option<Vec<[Vec4; 3]>>,
    pub(super) triangles: Vec<[u32; 3]>,
    pub(super) material: u32,
    /// The highest joint index its vertices name, where it has JOINTS_0.
    pub(super) max_joint: Option<u16>,
}

impl SceneReader<'_> {
    pub(super) fn mesh(&mut self, mesh: &gltf::Mesh) -> Result<Rc<Vec<LocalPrimitive>>, InputError> {
        if let Some(local) = self.meshes.get(&mesh.index()) {
            return Ok(local.clone());
        }
        let mut local = Vec::new();
        for primitive in mesh.primitives() {
            let weights = mesh.weights().unwrap_or(&[]);
            if let Some(read) = self.primitive(&primitive, mesh.index(), weights).map_err(|e| {
                e.within(GltfPart::Primitive(primitive.index()))
                    .within(GltfPart::Mesh(mesh.index()))
            })? {
                local.push(read);
            }
        }
        let local = Rc::new(local);
        self.meshes.insert(mesh.index(), local.clone());
        Ok(local)
    }

    fn primitive(
        &mut self,
        primitive: &gltf::Primitive,
        mesh: usize,
        mesh_weights: &[f32],
    ) -> Result<Option<LocalPrimitive>, InputError> {
        let mode = primitive.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.skipped_modes += 1;
            return Ok(None);
        }
        let attribute = |semantic: gltf::Semantic| primitive.get(&semantic).map(|a| a.index());
        let position = attribute(gltf::Semantic::Positions).ok_or_else(|| InputError::new("no POSITION attribute"))?;
        let positions: Vec<Vec3> = self
            .vectors::<3>(position, Type::Vec3, None, "position")?
            .into_iter()
            .map(Vec3::from)
            .collect();
        let vertex_count = Some(positions.len());
        let normals = attribute(gltf::Semantic::Normals)
            .map(|index| self.vectors::<3>(index, Type::Vec3, vertex_count, "normal"))
            .transpose()?
            .map(|normals| normals.into_iter().map(Vec3::from).collect());
        let coordinates = |set: u32| -> Result<Option<Vec<Vec2>>, InputError> {
            Ok(attribute(gltf::Semantic::TexCoords(set))
                .map(|index| self.vectors::<2>(index, Type::Vec2, vertex_count, "texture coordinate"))
                .transpose()?
                .map(|uvs| uvs.into_iter().map(Vec2::from).collect()))
        };
        let uvs = coordinates(0)?;
        let uvs1 = coordinates(1)?;
        let colors = attribute(gltf::Semantic::Colors(0))
            .map(|index| self.colors(index, positions.len()))
            .transpose()?;
        let file_tangents = attribute(gltf::Semantic::Tangents)
            .map(|index| self.vectors::<4>(index, Type::Vec4, vertex_count, "tangent"))
            .transpose()?;
        let vertex_count = positions.len();
        let indices = match primitive.indices() {
            Some(accessor) => read_indices(self.root, self.buffers, accessor.index(), vertex_count)?,
            None => (0..vertex_count as u32).collect(),
        };
        let triangles = assemble(mode, &indices);
        let material = self.materials.index_of(primitive.material().index());
        let sets = [uvs.is_some(), uvs1.is_some()];
        let needs_tangents = self.materials.check_attributes(material, sets, normals.is_some())?;
        let tangents = match &file_tangents {
            _ if !needs_tangents => None,
            Some(tangents) => Some(
                triangles
                    .iter()
                    .map(|t| t.map(|i| Vec4::from(tangents[i as usize])))
                    .collect(),
            ),
            None => {
                let set = self.materials.normal_map_set(material);
                let coordinates = if set == 1 { &uvs1 } else { &uvs };
                mikktspace_tangents(&positions, normals.as_deref(), coordinates.as_deref(), &triangles)
            }
        };
        let json = &self.root.meshes[mesh].primitives[primitive.index()];
        let targets = super::animation::read_targets(self.root, self.buffers, json, vertex_count)?;
        if !mesh_weights.is_empty() && mesh_weights.len() != targets.len() {
            return Err(InputError::new(format!(
                "{} mesh weights for {} morph targets",
                mesh_weights.len(),
                targets.len()
            )));
        }
        if !mesh_weights.iter().all(|w| w.is_finite()) {
            return Err(InputError::new("mesh weights must be finite"));
        }
        let mut weights = mesh_weights.to_vec();
        weights.resize(targets.len(), 0.0);
        let sets: Vec<(usize, usize)> = (0..2)
            .map_while(|n| {
                Some((
                    attribute(gltf::Semantic::Joints(n))?,
                    attribute(gltf::Semantic::Weights(n))?,
                ))
            })
            .collect();
        let influences = if sets.is_empty() {
            Vec::new()
        } else {
            super::animation::read_influences(self.root, self.buffers, &sets, vertex_count, self.notices)?
        };
        let max_joint = influences.iter().flat_map(|i| i.joints).max();
        Ok(Some(LocalPrimitive {
            rest: Arc::new(RestPrimitive {
                positions,
                normals,
                influences,
                targets,
                weights,
            }),
            uvs,
            uvs1,
            colors,
            tangents,
            triangles,
            material,
            max_joint,
        }))
    }

    /// COLOR_0: VEC3 or VEC4 of floats or normalized unsigned bytes or shorts, as linear RGBA.
    fn colors(&self, index: usize, vertex_count: usize) -> Result<Vec<Vec4>, InputError> {
        let (_, _, type_) = super::data::lookup(self.root, index)?;
        let colors: Vec<Vec4> = if type_ == Type::Vec3 {
            let rgb = self.vectors::<3>(index, Type::Vec3, Some(vertex_count), "colour")?;
            rgb.into_iter().map(|c| Vec3::from(c).extend(1.0)).collect()
        } else {
            let rgba = self.vectors::<4>(index, Type::Vec4, Some(vertex_count), "colour")?;
            rgba.into_iter().map(Vec4::from).collect()
        };
        Ok(colors)
    }

    /// A vertex attribute's elements of `N` floats, every one finite, and as many as POSITION's
    /// (`vertex_count`) where that is given; `what` names an element in messages.
    fn vectors<const N: usize>(
        &self,
        index: usize,
        type_: Type,
        vertex_count: Option<usize>,
        what: &str,
    ) -> Result<Vec<[f32; N]>, InputError> {
        let floats = read_floats(self.root, self.buffers, index, &[type_])?;
        let elements: Vec<[f32; N]> = floats
            .chunks_exact(N)
            .map(|c| c.try_into().expect("chunks of N"))
            .collect();
        if let Some(count) = vertex_count
            && elements.len() != count
        {
            return Err(InputError::in_gltf(
                GltfPart::Accessor(index),
                format!("{} elements where POSITION has {count}", elements.len()),
            ));
        }
        if let Some(k) = elements.iter().position(|e| !e.iter().all(|c| c.is_finite())) {
            return Err(InputError::in_gltf(
                GltfPart::Accessor(index),
                format!("{what} {k} is not finite"),
            ));
        }
        Ok(elements)
    }
}

/// A primitive's triangles from its indices: lists as they are, strips and fans unrolled (every
/// other strip triangle turned so that all keep the first one's winding).
pub(super) fn assemble(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .map(|i| {
                let [a, b, c] = [indices[i], indices[i + 1], indices[i + 2]];
                if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (1..indices.len().saturating_sub(1))
            .map(|i| [indices[0], indices[i], indices[i + 1]])
            .collect(),
        _ => indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_the_winding() {
        assert_eq!(
            assemble(Mode::TriangleStrip, &[0, 1, 2, 3, 4]),
            vec![[0, 1, 2], [2, 1, 3], [2, 3, 4]]
        );
        assert_eq!(assemble(Mode::TriangleFan, &[0, 1, 2, 3]), vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(assemble(Mode::Triangles, &[0, 1, 2, 3]), vec![[0, 1, 2]]);
        assert!(assemble(Mode::TriangleStrip, &[0, 1]).is_empty());
    }
}
