//! Closed meshes seen from inside, for the watertightness tests: every primary ray must hit, so a
//! pixel that misses is a ray that slipped between two triangles sharing an edge.

use glam::{Quat, Vec3};
use raypipe::image::{DEPTH_MISS, Frame};
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Material, Scene, Triangle};
use std::collections::HashMap;

/// Vertices and faces, vertices shared by index: neighbouring faces meet on bit-identical edges.
pub struct IndexedMesh {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
}

/// An icosahedron subdivided `levels` times onto the unit sphere: 20 * 4^levels faces.
pub fn icosphere(levels: u32) -> IndexedMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut vertices: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|v| Vec3::from_array(v).normalize())
    .to_vec();
    let mut faces = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut midpoints = HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                vertices.push(((vertices[a as usize] + vertices[b as usize]) * 0.5).normalize());
                vertices.len() as u32 - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut vertices);
                let bc = midpoint(b, c, &mut vertices);
                let ca = midpoint(c, a, &mut vertices);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    IndexedMesh { vertices, faces }
}

/// The cube [-1, 1]^3 with each face cut into `n` x `n` squares of two triangles: 12 n^2 faces,
/// whose edges lie along the axes before rotation.
pub fn tessellated_cube(n: u32) -> IndexedMesh {
    let mut index = HashMap::new();
    let mut vertices = Vec::new();
    let mut vertex = |grid: [u32; 3]| {
        *index.entry(grid).or_insert_with(|| {
            vertices.push(Vec3::from_array(grid.map(|g| 2.0 * g as f32 / n as f32 - 1.0)));
            vertices.len() as u32 - 1
        })
    };
    let mut faces = Vec::new();
    for axis in 0..3 {
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let corner = |di: u32, dj: u32| {
                        let mut grid = [0; 3];
                        grid[axis] = side;
                        grid[(axis + 1) % 3] = i + di;
                        grid[(axis + 2) % 3] = j + dj;
                        grid
                    };
                    let [a, b, c, d] = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)].map(&mut vertex);
                    faces.extend([[a, b, c], [a, c, d]]);
                }
            }
        }
    }
    IndexedMesh { vertices, faces }
}

/// `mesh` scaled by `scale`, rotated and moved to `center`, with the camera at its centre looking
/// along `look`: no lights, no bounces, so every pixel is one primary ray that must hit.
pub fn seen_from_inside(
    mesh: &IndexedMesh,
    scale: f32,
    rotation: Quat,
    center: Vec3,
    look: Vec3,
    size: u32,
) -> PackedScene {
    let placed: Vec<Vec3> = mesh.vertices.iter().map(|&v| rotation * (v * scale) + center).collect();
    let mut scene = Scene {
        camera: Camera {
            eye: center,
            target: center + look,
            up: Vec3::Y,
            fov_degrees: 100.0,
        },
        ..Scene::default()
    };
    scene.lights.clear();
    scene.planes.clear();
    scene.spheres.clear();
    scene.materials = vec![Material::default()];
    scene.triangles = mesh
        .faces
        .iter()
        .map(|f| Triangle {
            vertices: f.map(|i| placed[i as usize]),
            normals: None,
            uvs: None,
            material: 0,
            ..Default::default()
        })
        .collect();
    scene.settings.width = size;
    scene.settings.height = size;
    scene.settings.max_depth = 0;
    let mut packed = PackedScene::new(&scene).unwrap();
    packed.build_bvh();
    packed
}

/// The closed-mesh cases: both meshes, rotated, at distances from the origin from hundreds to tens
/// of thousands of units, each looking along a direction that is not an axis.
pub fn cases(size: u32) -> Vec<(String, PackedScene)> {
    let sphere = icosphere(4);
    let cube = tessellated_cube(20);
    let rotation = Quat::from_euler(glam::EulerRot::YXZ, 0.7, 0.4, 0.2);
    [
        (
            "icosphere",
            &sphere,
            3.0,
            Vec3::new(310.0, -120.0, 270.0),
            Vec3::new(0.3, 0.2, 1.0),
        ),
        (
            "icosphere",
            &sphere,
            40.0,
            Vec3::new(-21_000.0, 9_000.0, 13_000.0),
            Vec3::new(-1.0, 0.4, 0.1),
        ),
        (
            "cube",
            &cube,
            5.0,
            Vec3::new(700.0, 450.0, -380.0),
            Vec3::new(0.5, -0.3, 0.8),
        ),
        (
            "cube",
            &cube,
            60.0,
            Vec3::new(17_000.0, -26_000.0, 4_000.0),
            Vec3::new(-0.2, 0.9, -0.4),
        ),
    ]
    .into_iter()
    .map(|(name, mesh, scale, center, look)| {
        let scene = seen_from_inside(mesh, scale, rotation, center, look, size);
        (format!("{name} x{scale} at {center}"), scene)
    })
    .collect()
}

/// Pixels whose primary ray hit nothing.
pub fn misses(frame: &Frame) -> usize {
    frame.surface.iter().filter(|s| s[3] == DEPTH_MISS).count()
}
