//! OFF (Object File Format), read by hand: the format is a keyword, three counts and two tables.
//!
//! Accepted: `OFF`, `COFF` and `NOFF` / `CNOFF` (vertex normals after the coordinates; colours are
//! ignored), counts on the keyword's line or the next, `#` comments and blank lines anywhere.
//! Polygons are triangulated as fans. The counts must match the tables exactly.

use super::{Mesh, MeshError, check_face, push_fan};
use glam::Vec3;

/// The file's records: non-blank lines with comments stripped, each with its 1-based line number.
fn records(text: &str) -> impl Iterator<Item = (usize, Vec<&str>)> {
    text.lines().enumerate().filter_map(|(i, line)| {
        let content = line.split('#').next().unwrap_or_default();
        let tokens: Vec<&str> = content.split_whitespace().collect();
        (!tokens.is_empty()).then_some((i + 1, tokens))
    })
}

fn number<T: std::str::FromStr>(line: usize, token: &str, what: &str) -> Result<T, MeshError> {
    token.parse().map_err(|_| {
        MeshError::at(
            line,
            format!("{what}: cannot read '{}' as a number", crate::error::quoted(token)),
        )
    })
}

/// Whether the keyword says the vertices carry normals; an error where it is no OFF keyword.
fn keyword_has_normals(line: usize, keyword: &str) -> Result<bool, MeshError> {
    match keyword {
        "OFF" | "COFF" => Ok(false),
        "NOFF" | "CNOFF" => Ok(true),
        _ => Err(MeshError::at(
            line,
            format!(
                "expected the keyword OFF, COFF, NOFF or CNOFF (got '{}')",
                crate::error::quoted(keyword)
            ),
        )),
    }
}

/// The keyword, from the file's first bytes: its first record must be one.
pub(crate) fn check_head(head: &[u8], whole: bool) -> Result<(), MeshError> {
    let text = match std::str::from_utf8(head) {
        Ok(text) => text,
        // The head may end inside a character; what comes before it must be text.
        Err(e) if !whole && e.error_len().is_none() => std::str::from_utf8(&head[..e.valid_up_to()]).unwrap_or(""),
        Err(e) => return Err(MeshError::new(format!("not a text file: {e}"))),
    };
    match records(text).next() {
        Some((line, header)) => keyword_has_normals(line, header[0]).map(|_| ()),
        None if whole => Ok(()),
        None => Err(MeshError::new(format!(
            "no OFF keyword in the first {} bytes",
            head.len()
        ))),
    }
}

pub fn parse(bytes: &[u8]) -> Result<Mesh, MeshError> {
    let text = std::str::from_utf8(bytes).map_err(|e| MeshError::new(format!("not a text file: {e}")))?;
    let mut records = records(text);
    let (line, header) = records
        .next()
        .ok_or_else(|| MeshError::new("empty file: no OFF header"))?;
    let has_normals = keyword_has_normals(line, header[0])?;
    // The counts follow on the keyword's line or on the next record.
    let (count_line, counts) = if header.len() > 1 {
        (line, header[1..].to_vec())
    } else {
        records
            .next()
            .ok_or_else(|| MeshError::at(line, "the file ends before the vertex and face counts"))?
    };
    if counts.len() < 2 {
        return Err(MeshError::at(count_line, "expected the counts: vertices faces [edges]"));
    }
    let vertex_count: usize = number(count_line, counts[0], "vertex count")?;
    let face_count: usize = number(count_line, counts[1], "face count")?;
    // Each record takes at least two bytes: counts beyond that lie, and must not size allocations.
    if vertex_count.saturating_add(face_count) > bytes.len() / 2 {
        return Err(MeshError::at(
            count_line,
            format!(
                "the header declares {vertex_count} vertices and {face_count} faces, more than a file of {} bytes can hold",
                bytes.len()
            ),
        ));
    }

    let mut mesh = Mesh {
        positions: Vec::with_capacity(vertex_count),
        normals: has_normals.then(|| Vec::with_capacity(vertex_count)),
        triangles: Vec::with_capacity(face_count),
    };
    // The next record of a table the header sized: `index` of `count` `what`.
    let mut last_line = count_line;
    let mut next = |index: usize, count: usize, what: &str| {
        let record = records.next().ok_or_else(|| {
            MeshError::at(
                last_line,
                format!("the header declares {count} {what}, the file ends after {index}"),
            )
        })?;
        last_line = record.0;
        Ok::<_, MeshError>(record)
    };
    for v in 0..vertex_count {
        let (line, tokens) = next(v, vertex_count, "vertices")?;
        let needed = if has_normals { 6 } else { 3 };
        if tokens.len() < needed {
            return Err(MeshError::at(
                line,
                format!("vertex {v}: expected {needed} numbers, found {}", tokens.len()),
            ));
        }
        let what = format!("vertex {v}");
        let value = |k: usize| number::<f32>(line, tokens[k], &what);
        mesh.positions.push(Vec3::new(value(0)?, value(1)?, value(2)?));
        if let Some(normals) = &mut mesh.normals {
            normals.push(Vec3::new(value(3)?, value(4)?, value(5)?));
        }
    }
    let mut face = Vec::new();
    for f in 0..face_count {
        let (line, tokens) = next(f, face_count, "faces")?;
        let what = format!("face {f}");
        let corners: usize = number(line, tokens[0], &what)?;
        if corners >= tokens.len() {
            return Err(MeshError::at(
                line,
                format!("{what}: declares {corners} vertices, lists {}", tokens.len() - 1),
            ));
        }
        face.clear();
        for token in &tokens[1..=corners] {
            face.push(number::<i64>(line, token, &what)?);
        }
        // Anything after the indices is a colour, which is ignored.
        let indices = check_face(&face, vertex_count).map_err(|e| MeshError::at(line, format!("{what}: {e}")))?;
        push_fan(&mut mesh.triangles, &indices);
    }
    if let Some((line, _)) = records.next() {
        return Err(MeshError::at(
            line,
            format!("data after the {vertex_count} vertices and {face_count} faces the header declares"),
        ));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::parse;
    use glam::Vec3;

    const QUAD: &str = "OFF\n# a comment\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn reads_polygons_as_fans_with_or_without_comment_lines() {
        let mesh = parse(QUAD.as_bytes()).unwrap();
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let same = parse(b"OFF 4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n\n4 0 1 2 3 255 0 0\n").unwrap();
        assert_eq!(same, mesh);
    }

    #[test]
    fn noff_reads_normals() {
        let mesh = parse(b"NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n").unwrap();
        assert_eq!(mesh.normals, Some(vec![Vec3::Z; 3]));
    }

    #[test]
    fn errors_name_the_line_and_element() {
        let err = |text: &str| parse(text.as_bytes()).unwrap_err().to_string();
        assert_eq!(
            err("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 7\n"),
            "7: face 0: vertex index 7 out of range (4 vertices)"
        );
        assert_eq!(
            err("OFF\n5 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"),
            "7: the header declares 1 faces, the file ends after 0"
        );
        assert_eq!(
            err("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"),
            "7: the header declares 2 faces, the file ends after 1"
        );
        assert_eq!(
            err("OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"),
            "4: vertex 1: cannot read 'x' as a number"
        );
        assert!(err("PLY\n").starts_with("1: expected the keyword OFF"));
        assert!(err("OFF\n99999999 1 0\n").contains("more than a file of"));
        assert!(err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n").starts_with("7: data after"));
    }
}
