//! Tangents for a normal-mapped primitive whose file gives none: MikkTSpace's, as the glTF
//! specification asks (the `mikktspace` crate), one per triangle corner.

use glam::{Vec2, Vec3, Vec4};

/// An indexed triangle list as MikkTSpace reads it, and the corners' tangents it writes.
struct Corners<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    coordinates: &'a [Vec2],
    triangles: &'a [[u32; 3]],
    tangents: Vec<[Vec4; 3]>,
}

impl Corners<'_> {
    fn vertex(&self, face: usize, corner: usize) -> usize {
        self.triangles[face][corner] as usize
    }
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, corner: usize) -> [f32; 3] {
        self.positions[self.vertex(face, corner)].to_array()
    }

    fn normal(&self, face: usize, corner: usize) -> [f32; 3] {
        self.normals[self.vertex(face, corner)].to_array()
    }

    fn tex_coord(&self, face: usize, corner: usize) -> [f32; 2] {
        self.coordinates[self.vertex(face, corner)].to_array()
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, corner: usize) {
        self.tangents[face][corner] = Vec4::from(tangent);
    }
}

/// MikkTSpace's tangent at every corner of `triangles`, for the coordinates the normal map reads;
/// `None` where a primitive lacks normals or those coordinates (the reader refuses a normal map
/// there first) or MikkTSpace finds nothing to work on. A degenerate corner gets a zero tangent,
/// which the shaders read as "no tangent" and shade without the map.
pub(crate) fn mikktspace_tangents(
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    coordinates: Option<&[Vec2]>,
    triangles: &[[u32; 3]],
) -> Option<Vec<[Vec4; 3]>> {
    let mut corners = Corners {
        positions,
        normals: normals?,
        coordinates: coordinates?,
        triangles,
        tangents: vec![[Vec4::ZERO; 3]; triangles.len()],
    };
    mikktspace::generate_tangents(&mut corners).then_some(corners.tangents)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_mapped_square_gets_tangents_along_u_with_a_right_handed_bitangent() {
        // The unit square in the xy plane, facing +z, u along +x and v along +y.
        let positions = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let normals = [Vec3::Z; 4];
        let coordinates = positions.map(|p| Vec2::new(p.x, p.y));
        let triangles = [[0, 1, 2], [0, 2, 3]];
        let tangents = mikktspace_tangents(&positions, Some(&normals), Some(&coordinates), &triangles).unwrap();
        for corner in tangents.iter().flatten() {
            assert!((corner.truncate() - Vec3::X).length() < 1e-5, "{corner}");
            // bitangent = w cross(n, t) = cross(z, x) = y: along v.
            assert_eq!(corner.w, 1.0);
        }
        // v running the other way (down the image, as glTF's often does) flips the sign.
        let flipped = positions.map(|p| Vec2::new(p.x, 1.0 - p.y));
        let tangents = mikktspace_tangents(&positions, Some(&normals), Some(&flipped), &triangles).unwrap();
        assert!(tangents.iter().flatten().all(|t| t.w == -1.0));
        assert!(mikktspace_tangents(&positions, None, Some(&coordinates), &triangles).is_none());
    }
}
