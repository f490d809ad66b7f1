//! Triangle meshes from model files (PLY, OBJ, OFF), and what scenes make of them: triangles, or
//! spheres placed on the surface as in the paper's Figure 1.
//!
//! Every loader returns a [`Mesh`] whose faces are already triangulated (polygons as fans) and whose
//! indices are checked; [`Mesh::validate`] then checks what every format shares. Errors are one line,
//! `FILE:LINE: what` where the format has lines, `FILE: element N: what` where it does not.

mod obj;
mod off;
mod ply;

use crate::bvh::aabb::Aabb;
use crate::error::InputError;
use crate::rng::SplitMix64;
use glam::Vec3;
use std::path::Path;

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// The vertices.
    pub positions: Vec<Vec3>,
    /// One per position, when the file has vertex normals (not necessarily unit length).
    pub normals: Option<Vec<Vec3>>,
    /// Counter-clockwise seen from outside, as the file gives them.
    pub triangles: Vec<[u32; 3]>,
}

/// A parse or validation error of a model: the line where the format has lines, and what. The file
/// is named by [`load`], or by whoever parsed the bytes.
pub(crate) type MeshError = InputError;

/// The model formats, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Stanford PLY (ASCII or binary).
    Ply,
    /// Wavefront OBJ.
    Obj,
    /// Object File Format.
    Off,
}

impl MeshFormat {
    const BY_EXTENSION: [(&str, MeshFormat); 3] = [("ply", Self::Ply), ("obj", Self::Obj), ("off", Self::Off)];

    /// The format a path's extension names, if it names one.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Self::BY_EXTENSION
            .iter()
            .find(|(known, _)| *known == ext)
            .map(|&(_, format)| format)
    }

    /// Refuses a file whose first bytes (`head`; the whole file where `whole`) cannot begin a file
    /// of this format, before the rest of it is read. What the head does not settle is left to
    /// the parser.
    pub fn check_head(self, head: &[u8], whole: bool) -> Result<(), MeshError> {
        match self {
            Self::Ply => ply::check_head(head, whole),
            Self::Off => off::check_head(head, whole),
            Self::Obj => match head.iter().position(|&b| b == 0) {
                Some(at) => Err(MeshError::new(format!("not a text file: a NUL byte at byte {at}"))),
                None => Ok(()),
            },
        }
    }

    /// The extensions read, for messages: ".ply, .obj, .off".
    pub fn extension_list() -> String {
        Self::BY_EXTENSION.map(|(ext, _)| format!(".{ext}")).join(", ")
    }
}

/// Whether `path` names a model file by its extension.
pub(crate) fn is_model_path(path: &Path) -> bool {
    MeshFormat::from_path(path).is_some()
}

/// Reads, parses and validates a model file. Every error names the path; what the file holds that
/// is ignored (OBJ materials) is logged as a notice.
pub fn load(path: &Path) -> Result<Mesh, InputError> {
    let shown = path.display().to_string();
    let format = MeshFormat::from_path(path).ok_or_else(|| {
        InputError::new(format!(
            "unknown model format (expected a file ending in {})",
            MeshFormat::extension_list()
        ))
        .in_origin(&shown)
    })?;
    let bytes =
        crate::input::read_regular_after_head(path, "model file", crate::input::MAX_MODEL_BYTES, |head, whole| {
            format.check_head(head, whole)
        })?;
    let mut notices = Vec::new();
    let mesh = parse(&bytes, format, &mut notices).map_err(|e| e.in_origin(&shown))?;
    for notice in notices {
        log::info!("{shown}: {notice}");
    }
    Ok(mesh)
}

/// Parses and validates a model in `format`. Things the file holds that are ignored (OBJ materials)
/// are reported in `notices`.
pub fn parse(bytes: &[u8], format: MeshFormat, notices: &mut Vec<String>) -> Result<Mesh, MeshError> {
    let mesh = match format {
        MeshFormat::Ply => ply::parse(bytes)?,
        MeshFormat::Obj => obj::parse(bytes, notices)?,
        MeshFormat::Off => off::parse(bytes)?,
    };
    mesh.validate()?;
    Ok(mesh)
}

/// Appends polygon `face` (already checked against the vertex count) as a fan of triangles.
fn push_fan(triangles: &mut Vec<[u32; 3]>, face: &[u32]) {
    for k in 1..face.len().saturating_sub(1) {
        triangles.push([face[0], face[k], face[k + 1]]);
    }
}

/// Checks a polygon's indices, for the parsers: at least three, each below `vertex_count`.
/// The one rule of every format for a face that cannot be a polygon.
fn too_few_corners(corners: usize) -> String {
    format!("a face needs at least 3 vertices (got {corners})")
}

fn check_face(face: &[i64], vertex_count: usize) -> Result<Vec<u32>, String> {
    if face.len() < 3 {
        return Err(too_few_corners(face.len()));
    }
    face.iter()
        .map(|&index| {
            if index < 0 || index as u64 >= vertex_count as u64 {
                Err(format!("vertex index {index} out of range ({vertex_count} vertices)"))
            } else {
                Ok(index as u32)
            }
        })
        .collect()
}

/// The rotation by Euler angles in degrees: about x, then y, then z.
pub(crate) fn euler_rotation(degrees: Vec3) -> glam::Quat {
    glam::Quat::from_euler(
        glam::EulerRot::ZYX,
        degrees.z.to_radians(),
        degrees.y.to_radians(),
        degrees.x.to_radians(),
    )
}

impl Mesh {
    /// What every format shares: something to render, finite numbers, indices in range.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.triangles.is_empty() {
            return Err(MeshError::new("empty mesh: no faces"));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::new(format!(
                "vertex {i}: coordinates must be finite (got {})",
                self.positions[i]
            )));
        }
        if let Some(normals) = &self.normals {
            assert_eq!(
                normals.len(),
                self.positions.len(),
                "the parsers give one normal per vertex"
            );
            if let Some(i) = normals.iter().position(|n| !n.is_finite()) {
                return Err(MeshError::new(format!("vertex {i}: normal must be finite")));
            }
        }
        let n = self.positions.len();
        for (t, triangle) in self.triangles.iter().enumerate() {
            if let Some(&index) = triangle.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::new(format!(
                    "triangle {t}: vertex index {index} out of range ({n} vertices)"
                )));
            }
        }
        Ok(())
    }

    /// The box around the mesh's vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::around_points(self.positions.iter().copied())
    }

    /// Centres the bounding box at the origin and scales its longest side to 2.
    pub fn normalize(&mut self) {
        let bounds = self.bounds();
        let center = bounds.centroid();
        let longest = (bounds.max - bounds.min).max_element();
        let scale = if longest > 0.0 { 2.0 / longest } else { 1.0 };
        for p in &mut self.positions {
            *p = (*p - center) * scale;
        }
    }

    /// Rotates about the origin by Euler angles in degrees: about x, then y, then z.
    pub fn rotate(&mut self, degrees: Vec3) {
        let r = euler_rotation(degrees);
        for p in &mut self.positions {
            *p = r * *p;
        }
        for n in self.normals.iter_mut().flatten() {
            *n = r * *n;
        }
    }

    /// p' = p * scale + translate; `scale` is positive, so normals keep their direction.
    pub fn transform(&mut self, scale: f32, translate: Vec3) {
        for p in &mut self.positions {
            *p = *p * scale + translate;
        }
    }

    /// A triangle's three corners.
    pub fn corners(&self, triangle: [u32; 3]) -> [Vec3; 3] {
        triangle.map(|i| self.positions[i as usize])
    }

    /// Each triangle's corner normals from the faces around each corner: the unit face normals of
    /// the faces that share the corner's position (by value, so that files that repeat vertices
    /// smooth too), weighted by the angle each makes at that corner (Thürmer and Wüthrich 1998).
    /// Only faces within `crease_degrees` of the corner's own face join in, so sharper edges stay
    /// sharp. A corner with nothing to blend (a degenerate face) gets its face's normal.
    pub fn smooth_normals(&self, crease_degrees: f32) -> Vec<[Vec3; 3]> {
        let face_normals: Vec<Vec3> = self
            .triangles
            .iter()
            .map(|&t| {
                let [a, b, c] = self.corners(t);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        let corner_angle = |t: [u32; 3], k: usize| {
            let corners = self.corners(t);
            let (p, q, r) = (corners[k], corners[(k + 1) % 3], corners[(k + 2) % 3]);
            (q - p).normalize_or_zero().angle_between((r - p).normalize_or_zero())
        };
        // Faces around each position, with their angle there.
        let mut around: std::collections::HashMap<[u32; 3], Vec<(u32, f32)>> = Default::default();
        for (f, &t) in self.triangles.iter().enumerate() {
            for (k, &i) in t.iter().enumerate() {
                let key = self.positions[i as usize].to_array().map(f32::to_bits);
                let angle = corner_angle(t, k);
                if angle.is_finite() {
                    around.entry(key).or_default().push((f as u32, angle));
                }
            }
        }
        let min_cos = crease_degrees.to_radians().cos();
        self.triangles
            .iter()
            .enumerate()
            .map(|(f, &t)| {
                let own = face_normals[f];
                t.map(|i| {
                    let key = self.positions[i as usize].to_array().map(f32::to_bits);
                    let blended: Vec3 = around
                        .get(&key)
                        .into_iter()
                        .flatten()
                        .map(|&(g, angle)| (face_normals[g as usize], angle))
                        .filter(|(n, _)| n.dot(own) >= min_cos)
                        .map(|(n, angle)| n * angle)
                        .sum();
                    let normal = blended.normalize_or_zero();
                    if normal == Vec3::ZERO { own } else { normal }
                })
            })
            .collect()
    }

    /// A triangle's area.
    pub fn triangle_area(&self, triangle: [u32; 3]) -> f32 {
        let [a, b, c] = self.corners(triangle);
        0.5 * (b - a).cross(c - a).length()
    }

    /// The mesh's surface area, summed in f64.
    pub fn area(&self) -> f64 {
        self.triangles.iter().map(|&t| self.triangle_area(t) as f64).sum()
    }

    /// `count` points on the surface, uniform by area, the same for the same `seed` everywhere: a
    /// triangle is picked with probability proportional to its area, then a point uniform in it.
    pub fn sample_surface(&self, count: usize, seed: u64) -> Vec<Vec3> {
        let mut cumulative = Vec::with_capacity(self.triangles.len());
        let mut total = 0.0f64;
        for &t in &self.triangles {
            total += self.triangle_area(t) as f64;
            cumulative.push(total);
        }
        let mut rng = SplitMix64::new(seed);
        let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        (0..count)
            .map(|_| {
                let target = unit() * total;
                let k = cumulative
                    .partition_point(|&c| c <= target)
                    .min(self.triangles.len() - 1);
                let [a, b, c] = self.corners(self.triangles[k]);
                // Folding the unit square onto the triangle keeps the density uniform.
                let (mut u, mut v) = (unit() as f32, unit() as f32);
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                a + u * (b - a) + v * (c - a)
            })
            .collect()
    }

    /// The default sphere radius for `count` spheres on this surface: each sphere's disc covers twice
    /// its share of the area, so that randomly placed spheres leave few holes (about e^-2 of it).
    pub fn default_sphere_radius(&self, count: usize) -> f32 {
        (2.0 * self.area() / (std::f64::consts::PI * count.max(1) as f64)).sqrt() as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        Mesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(2.0, 4.0, 0.0),
                Vec3::new(0.0, 4.0, 0.0),
            ],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn fans_triangulate_polygons() {
        let mut triangles = Vec::new();
        push_fan(&mut triangles, &[4, 5, 6, 7, 8]);
        assert_eq!(triangles, vec![[4, 5, 6], [4, 6, 7], [4, 7, 8]]);
    }

    #[test]
    fn normalize_centres_and_scales_the_longest_side_to_two() {
        let mut mesh = square();
        mesh.normalize();
        let bounds = mesh.bounds();
        assert_eq!(bounds.min, Vec3::new(-0.5, -1.0, 0.0));
        assert_eq!(bounds.max, Vec3::new(0.5, 1.0, 0.0));
        mesh.transform(2.0, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(
            mesh.bounds(),
            Aabb::new(Vec3::new(0.0, -2.0, 0.0), Vec3::new(2.0, 2.0, 0.0))
        );
    }

    #[test]
    fn rotation_turns_x_then_y_then_z() {
        let mut mesh = Mesh {
            positions: vec![Vec3::X, Vec3::Y],
            normals: Some(vec![Vec3::Z, Vec3::Z]),
            triangles: vec![],
        };
        // x by 90 sends y to z; then z by 90 sends x to y.
        mesh.rotate(Vec3::new(90.0, 0.0, 90.0));
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-6;
        assert!(close(mesh.positions[0], Vec3::Y), "{}", mesh.positions[0]);
        assert!(close(mesh.positions[1], Vec3::Z), "{}", mesh.positions[1]);
        // The normal turns alike: z to -y about x, then -y to x about z.
        assert!(close(mesh.normals.as_ref().unwrap()[0], Vec3::X), "{:?}", mesh.normals);
    }

    #[test]
    fn samples_are_on_the_surface_uniform_and_deterministic() {
        let mesh = square();
        let points = mesh.sample_surface(20_000, 7);
        assert_eq!(points, mesh.sample_surface(20_000, 7));
        assert_ne!(points, mesh.sample_surface(20_000, 8));
        for p in &points {
            assert!(
                p.x >= 0.0 && p.x <= 2.0 && p.y >= 0.0 && p.y <= 4.0 && p.z == 0.0,
                "{p}"
            );
        }
        // Uniform by area: each half of the rectangle (split across the diagonal's triangles) and
        // each quadrant gets its share within a few standard deviations.
        let lower = points.iter().filter(|p| p.y < 2.0).count() as f64 / points.len() as f64;
        let left = points.iter().filter(|p| p.x < 1.0).count() as f64 / points.len() as f64;
        assert!((lower - 0.5).abs() < 0.015, "{lower}");
        assert!((left - 0.5).abs() < 0.015, "{left}");
        assert!((mesh.area() - 8.0).abs() < 1e-6);
    }

    #[test]
    fn validation_names_the_element() {
        let mut mesh = square();
        mesh.positions[2].y = f32::NAN;
        assert!(
            mesh.validate()
                .unwrap_err()
                .message
                .starts_with("vertex 2: coordinates must be finite")
        );
        let mut mesh = square();
        mesh.triangles[1][2] = 9;
        assert_eq!(
            mesh.validate().unwrap_err().message,
            "triangle 1: vertex index 9 out of range (4 vertices)"
        );
        let empty = Mesh {
            triangles: vec![],
            ..square()
        };
        assert_eq!(empty.validate().unwrap_err().message, "empty mesh: no faces");
    }

    #[test]
    fn formats_follow_the_extension_in_any_case() {
        assert_eq!(MeshFormat::from_path(Path::new("a/b.PLY")), Some(MeshFormat::Ply));
        assert_eq!(MeshFormat::from_path(Path::new("b.off")), Some(MeshFormat::Off));
        assert_eq!(MeshFormat::from_path(Path::new("b.obj")), Some(MeshFormat::Obj));
        assert_eq!(MeshFormat::from_path(Path::new("b.stl")), None);
        let err = load(Path::new("model.stl")).unwrap_err().to_string();
        assert!(err.starts_with("model.stl: unknown model format"), "{err}");
    }
}
