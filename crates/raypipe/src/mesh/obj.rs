//! Wavefront OBJ through `tobj`: positions, vertex normals where every face corner has one, faces
//! triangulated, every object and group merged into one mesh. Materials are ignored with a notice.
//!
//! tobj reports what went wrong but not where; [`locate`] finds the line it stopped at.

use super::{Mesh, MeshError};
use glam::Vec3;
use std::io::Cursor;

pub fn parse(bytes: &[u8], notices: &mut Vec<String>) -> Result<Mesh, MeshError> {
    let text = std::str::from_utf8(bytes).map_err(|e| MeshError::new(format!("not a text file: {e}")))?;
    check_statements(text)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        // One index for position and normal, so normals come out one per vertex.
        single_index: true,
        ..Default::default()
    };
    let wants_materials = std::cell::Cell::new(false);
    let (models, _) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |_| {
        wants_materials.set(true);
        Ok(Default::default())
    })
    .map_err(|e| match locate(text, &e) {
        Some(line) => MeshError::at(line, e.to_string()),
        None => MeshError::new(e.to_string()),
    })?;
    if wants_materials.get() || text.lines().any(|l| l.trim_start().starts_with("usemtl")) {
        notices.push("materials ignored: the scene's material applies to the whole mesh".into());
    }

    let mut mesh = Mesh::default();
    let with_normals = models
        .iter()
        .all(|m| m.mesh.normals.len() == m.mesh.positions.len() && !m.mesh.positions.is_empty());
    let mut normals = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        if with_normals {
            normals.extend(m.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])));
        }
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    if with_normals && !mesh.positions.is_empty() {
        mesh.normals = Some(normals);
    }
    Ok(mesh)
}

/// What tobj lets through and a later check could not place, because tobj renumbers vertices and
/// drops faces: non-finite coordinates (tobj takes `nan` and `inf` as numbers), and faces of fewer
/// than three corners (which OFF and PLY refuse too).
fn check_statements(text: &str) -> Result<(), MeshError> {
    let (mut vertex, mut face) = (0, 0);
    for (i, line) in text.lines().enumerate() {
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => {
                if tokens.take(3).any(|t| t.parse::<f32>().is_ok_and(|v| !v.is_finite())) {
                    return Err(MeshError::at(
                        i + 1,
                        format!("vertex {vertex}: coordinates must be finite"),
                    ));
                }
                vertex += 1;
            }
            Some("f") => {
                let corners = tokens.count();
                if corners < 3 {
                    return Err(MeshError::at(
                        i + 1,
                        format!("face {face}: {}", super::too_few_corners(corners)),
                    ));
                }
                face += 1;
            }
            _ => {}
        }
    }
    Ok(())
}

/// The line tobj's error is about: the first line of the statement kind it names that does not
/// parse, or for an index out of range, the first face that refers past the vertices read so far.
fn locate(text: &str, error: &tobj::LoadError) -> Option<usize> {
    use tobj::LoadError as E;
    let keyword = match error {
        E::PositionParseError => "v",
        E::NormalParseError => "vn",
        E::TexcoordParseError => "vt",
        E::FaceParseError | E::InvalidPolygon => "f",
        E::FaceVertexOutOfBounds | E::FaceNormalOutOfBounds | E::FaceTexCoordOutOfBounds => {
            return locate_index_out_of_range(text);
        }
        _ => return None,
    };
    text.lines().enumerate().find_map(|(i, line)| {
        let mut tokens = line.split_whitespace();
        if tokens.next() != Some(keyword) {
            return None;
        }
        let arguments: Vec<&str> = tokens.collect();
        let bad = match keyword {
            "f" => {
                arguments.len() < 3
                    || arguments
                        .iter()
                        .any(|corner| corner.split('/').any(|k| !k.is_empty() && k.parse::<i64>().is_err()))
            }
            "vt" => arguments.is_empty() || arguments.iter().any(|a| a.parse::<f32>().is_err()),
            _ => arguments.len() < 3 || arguments.iter().any(|a| a.parse::<f32>().is_err()),
        };
        bad.then_some(i + 1)
    })
}

fn locate_index_out_of_range(text: &str) -> Option<usize> {
    let mut counts = [0i64; 3]; // positions, texture coordinates, normals read so far
    for (i, line) in text.lines().enumerate() {
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("f") => {
                let bad = tokens.any(|corner| {
                    corner.split('/').zip(counts).any(|(k, count)| {
                        k.parse::<i64>()
                            .is_ok_and(|k| k == 0 || k > count || (k < 0 && -k > count))
                    })
                });
                if bad {
                    return Some(i + 1);
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::parse;
    use glam::Vec3;

    const TWO_OBJECTS: &str = "mtllib scene.mtl\no first\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl red\nf 1 2 3 4\no second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n";

    #[test]
    fn objects_merge_polygons_triangulate_and_materials_give_a_notice() {
        let mut notices = Vec::new();
        let mesh = parse(TWO_OBJECTS.as_bytes(), &mut notices).unwrap();
        assert_eq!(mesh.triangles.len(), 3);
        assert_eq!(mesh.positions.len(), 7);
        let last = mesh.triangles[2].map(|i| mesh.positions[i as usize]);
        assert_eq!(last, [Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)]);
        assert_eq!(notices.len(), 1, "{notices:?}");
    }

    #[test]
    fn normals_come_per_vertex() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
        let mesh = parse(text.as_bytes(), &mut Vec::new()).unwrap();
        assert_eq!(mesh.normals, Some(vec![Vec3::Z; 3]));
    }

    #[test]
    fn errors_name_the_line() {
        let err = |text: &str| parse(text.as_bytes(), &mut Vec::new()).unwrap_err().to_string();
        assert!(err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").starts_with("4: "));
        assert!(err("v 0 0 0\nv 1 x 0\n").starts_with("2: "));
        assert_eq!(
            err("v 0 0 0\n\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"),
            "3: vertex 1: coordinates must be finite"
        );
    }

    /// The rule OFF and PLY apply: tobj alone would drop the face without a word.
    #[test]
    fn a_face_of_two_corners_is_refused() {
        let err = parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n", &mut Vec::new()).unwrap_err();
        assert_eq!(err.to_string(), "5: face 1: a face needs at least 3 vertices (got 2)");
    }
}
