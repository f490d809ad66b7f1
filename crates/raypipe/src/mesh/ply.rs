//! PLY, ASCII and binary (either byte order), through `ply-rs-bw`.
//!
//! Vertex properties may come in any order and with any scalar type; `x`, `y`, `z` are required, and
//! `nx`, `ny`, `nz` are read as vertex normals when all three are there. Faces are the list
//! `vertex_indices` (or `vertex_index`) of any integer type. Other properties and elements are read
//! past and ignored. Polygons are triangulated as fans.

use super::{Mesh, MeshError, check_face, push_fan};
use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Encoding, Property, PropertyAccess, PropertyAccessResult, PropertyType};
use std::io::Cursor;

/// The magic line and, where the head is not the whole file, the header's end within it.
pub(crate) fn check_head(head: &[u8], whole: bool) -> Result<(), MeshError> {
    if !(head.starts_with(b"ply\n") || head.starts_with(b"ply\r\n")) {
        return Err(MeshError::at(1, "expected 'ply': not a PLY file"));
    }
    if !whole && !head.windows(10).any(|w| w == b"end_header") {
        return Err(MeshError::new(format!(
            "no end_header in the first {} bytes: not a PLY header",
            head.len()
        )));
    }
    Ok(())
}

#[derive(Default)]
struct PlyVertex {
    values: [f64; 6],
}

/// Where each vertex property lands in `PlyVertex::values`.
const VERTEX_PROPERTIES: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];

fn scalar(property: &Property) -> Option<f64> {
    Some(match *property {
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        _ => return None,
    })
}

fn integer_list(property: Property) -> Option<Vec<i64>> {
    fn widen<T: Copy + Into<i64>>(values: Vec<T>) -> Vec<i64> {
        values.into_iter().map(Into::into).collect()
    }
    Some(match property {
        Property::ListChar(v) => widen(v),
        Property::ListUChar(v) => widen(v),
        Property::ListShort(v) => widen(v),
        Property::ListUShort(v) => widen(v),
        Property::ListInt(v) => widen(v),
        Property::ListUInt(v) => widen(v),
        _ => return None,
    })
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(slot) = VERTEX_PROPERTIES.iter().position(|&p| p == name) else {
            return PropertyAccessResult::Ignored;
        };
        match scalar(&property) {
            Some(value) => {
                self.values[slot] = value;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

#[derive(Default)]
struct PlyFace {
    indices: Vec<i64>,
}

/// The face property names in use: the specification's and a common variant.
const FACE_PROPERTIES: [&str; 2] = ["vertex_indices", "vertex_index"];

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if !FACE_PROPERTIES.contains(&name) {
            return PropertyAccessResult::Ignored;
        }
        match integer_list(property) {
            Some(indices) => {
                self.indices = indices;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

/// An element nobody reads: parsed past.
struct Ignored;

impl PropertyAccess for Ignored {
    fn new() -> Self {
        Ignored
    }
}

/// The parser's error as ours: its line where the text has lines (the header, ASCII payloads).
fn parse_error(error: ply_rs_bw::parser::ParseError, has_lines: bool) -> MeshError {
    // The parser quotes the whole offending line after "String:"; the message keeps its words.
    let raw = crate::error::one_line(&error.to_string());
    let text: Vec<String> = raw
        .split(" Error: ")
        .map(|part| match part.find(" String: ") {
            Some(at) => part[..at].trim_end_matches('.').to_string(),
            None => part.to_string(),
        })
        .collect();
    let text = text.join(": ");
    let message = match error.line() {
        Some(line) => text
            .strip_prefix(&format!("Line {line}: "))
            .unwrap_or(&text)
            .to_string(),
        None => text,
    };
    match error.line() {
        Some(line) if has_lines => MeshError::at(line, message),
        _ => MeshError::new(message),
    }
}

pub fn parse(bytes: &[u8]) -> Result<Mesh, MeshError> {
    let mut reader = Reader::new(Cursor::new(bytes));
    let vertex_parser = Parser::<PlyVertex>::new();
    let face_parser = Parser::<PlyFace>::new();
    let skip_parser = Parser::<Ignored>::new();
    let header = vertex_parser
        .read_header(&mut reader)
        .map_err(|e| parse_error(e, true))?;
    let ascii = header.encoding == Encoding::Ascii;

    let vertex_def = header
        .elements
        .get("vertex")
        .ok_or_else(|| MeshError::new("the header declares no 'vertex' element"))?;
    for axis in ["x", "y", "z"] {
        if !vertex_def.properties.contains_key(axis) {
            return Err(MeshError::new(format!("element 'vertex' has no property '{axis}'")));
        }
    }
    let has_normals = ["nx", "ny", "nz"]
        .iter()
        .all(|n| vertex_def.properties.contains_key(*n));
    let face_def = header
        .elements
        .get("face")
        .ok_or_else(|| MeshError::new("the header declares no 'face' element"))?;
    let face_property = FACE_PROPERTIES
        .iter()
        .find_map(|name| face_def.properties.get(*name))
        .ok_or_else(|| MeshError::new("element 'face' has no list property 'vertex_indices'"))?;
    if !matches!(face_property.data_type, PropertyType::List(..)) {
        return Err(MeshError::new(format!(
            "element 'face': property '{}' must be a list",
            face_property.name
        )));
    }

    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut face_first_line = 0;
    for element in header.elements.values() {
        // The reader's line is the next one to read: the element's first, in an ASCII file.
        let first_line = reader.line();
        let result = match element.name.as_str() {
            "vertex" => vertex_parser
                .read_payload_for_element(&mut reader, element, &header)
                .map(|v| vertices = v),
            "face" => {
                face_first_line = first_line;
                face_parser
                    .read_payload_for_element(&mut reader, element, &header)
                    .map(|f| faces = f)
            }
            _ => skip_parser
                .read_payload_for_element(&mut reader, element, &header)
                .map(drop),
        };
        result.map_err(|e| parse_error(e, ascii))?;
    }
    let position = reader.into_inner().position() as usize;
    let left = &bytes[position.min(bytes.len())..];
    // An ASCII file may end in blank lines; anything else after the last element means the counts lie.
    let blank = ascii && left.iter().all(u8::is_ascii_whitespace);
    if !(left.is_empty() || blank) {
        return Err(MeshError::new(format!(
            "{} bytes after the last element the header declares: the counts in the header are wrong",
            left.len()
        )));
    }

    let to_vec3 = |v: &[f64]| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
    let mut mesh = Mesh {
        positions: vertices.iter().map(|v| to_vec3(&v.values[0..3])).collect(),
        normals: has_normals.then(|| vertices.iter().map(|v| to_vec3(&v.values[3..6])).collect()),
        triangles: Vec::with_capacity(faces.len()),
    };
    for (f, face) in faces.iter().enumerate() {
        let indices = check_face(&face.indices, vertices.len()).map_err(|e| {
            let message = format!("face {f}: {e}");
            if ascii {
                MeshError::at(face_first_line + f, message)
            } else {
                MeshError::new(message)
            }
        })?;
        push_fan(&mut mesh.triangles, &indices);
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::parse;
    use glam::Vec3;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment test\nelement vertex 4\nproperty float y\nproperty uchar red\nproperty double x\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 255 0 0\n0 255 1 0\n1 255 1 0\n1 255 0 0\n4 0 1 2 3\n";

    fn binary(little: bool) -> Vec<u8> {
        let format = if little {
            "binary_little_endian"
        } else {
            "binary_big_endian"
        };
        let mut bytes = format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
        )
        .into_bytes();
        let corners = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for value in corners.iter().flatten() {
            bytes.extend(if little {
                value.to_le_bytes()
            } else {
                value.to_be_bytes()
            });
        }
        bytes.push(4);
        for index in 0u32..4 {
            bytes.extend(if little {
                index.to_le_bytes()
            } else {
                index.to_be_bytes()
            });
        }
        bytes
    }

    #[test]
    fn ascii_with_properties_in_any_order() {
        let mesh = parse(ASCII.as_bytes()).unwrap();
        assert_eq!(
            mesh.positions,
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]
        );
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.normals, None);
    }

    #[test]
    fn binary_in_both_byte_orders() {
        let little = parse(&binary(true)).unwrap();
        let big = parse(&binary(false)).unwrap();
        assert_eq!(little, big);
        assert_eq!(little.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(little.triangles.len(), 2);
    }

    #[test]
    fn errors_are_one_line_and_name_where() {
        let err = |bytes: &[u8]| parse(bytes).unwrap_err().to_string();
        let truncated = binary(true);
        let message = err(&truncated[..truncated.len() - 3]);
        assert!(message.contains("face"), "{message}");
        assert!(!message.contains('\n'));
        let out_of_range = ASCII.replace("4 0 1 2 3", "4 0 1 2 9");
        assert_eq!(
            err(out_of_range.as_bytes()),
            "16: face 0: vertex index 9 out of range (4 vertices)"
        );
        let bad_number = ASCII.replace("0 255 1 0", "0 255 x 0");
        assert!(
            err(bad_number.as_bytes()).starts_with("13: "),
            "{}",
            err(bad_number.as_bytes())
        );
        let lying = ASCII.replace("element vertex 4", "element vertex 5");
        let message = err(lying.as_bytes());
        assert!(message.contains("face"), "{message}");
        let extra = ASCII.replace("element vertex 4", "element vertex 3");
        assert!(err(extra.as_bytes()).contains("counts in the header are wrong"));
        assert!(err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n").contains("'y'"));
    }
}
