//! Model files: every format gives the same mesh, scene files place meshes as they say, and no
//! mutation of a file makes a parser panic. (The shared scans load in the `gpu` harness; the command
//! line's messages for broken files are the CLI's tests.)

use crate::common::models::{self, TestModel, every_format};
use crate::common::test_dir;
use glam::Vec3;
use proptest::prelude::*;
use raypipe::bvh::aabb::Aabb;
use raypipe::mesh::{self, Mesh, MeshFormat};
use std::path::{Path, PathBuf};

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The mesh as a list of triangles by their corners: what must not depend on the format (OBJ loaders
/// may renumber vertices).
fn corner_triangles(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    mesh.triangles.iter().map(|&t| mesh.corners(t)).collect()
}

fn corner_normals(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    let normals = mesh.normals.as_ref().expect("the test models have normals");
    mesh.triangles.iter().map(|t| t.map(|i| normals[i as usize])).collect()
}

#[test]
fn every_format_gives_the_same_triangles() {
    let model = models::torus(12, 6);
    let dir = test_dir("meshes-formats");
    let expected: Vec<[Vec3; 3]> = model
        .quads
        .iter()
        .flat_map(|q| {
            let p = |i: u32| Vec3::from_array(model.positions[i as usize]);
            [[p(q[0]), p(q[1]), p(q[2])], [p(q[0]), p(q[2]), p(q[3])]]
        })
        .collect();
    for (name, bytes) in every_format(&model) {
        let mesh = mesh::load(&write(&dir, name, &bytes)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(corner_triangles(&mesh), expected, "{name}");
        let normals = corner_normals(&mesh);
        for (triangle, corners) in normals.iter().zip(&expected) {
            for (n, p) in triangle.iter().zip(corners) {
                // The torus normal points from the tube's centre line to the point.
                let center = Vec3::new(p.x, 0.0, p.z).normalize();
                assert!((*p - center).normalize().dot(*n) > 0.999, "{name}: normal {n} at {p}");
            }
        }
    }
}

/// A file's bytes (what a web page is given) make the scene its path makes, in every format; a
/// TOML scene too; errors name the file and its line.
#[test]
fn a_file_given_as_bytes_makes_the_scene_its_path_makes() {
    let model = models::torus(12, 6);
    let dir = test_dir("meshes-bytes");
    for (name, bytes) in every_format(&model) {
        let path = write(&dir, name, &bytes);
        let from_path = raypipe::scene::Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let from_bytes = raypipe::scene::Scene::from_bytes(name, &bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(from_bytes, from_path, "{name}");
    }
    let toml = std::fs::read("../../scenes/whitted.toml").unwrap();
    assert_eq!(
        raypipe::scene::Scene::from_bytes("whitted.toml", &toml).unwrap(),
        raypipe::scene::Scene::load("../../scenes/whitted.toml").unwrap()
    );
    let broken = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n";
    let error = raypipe::scene::Scene::from_bytes("broken.obj", broken)
        .unwrap_err()
        .to_string();
    assert_eq!(error, "broken.obj:4: face vertex index out of bounds");
    let error = raypipe::scene::Scene::from_bytes("notes.txt", b"hello")
        .unwrap_err()
        .to_string();
    assert!(error.starts_with("notes.txt: unknown file type"), "{error}");
    let error = raypipe::scene::Scene::from_bytes("bad.toml", b"[camera]\neye = 3\n")
        .unwrap_err()
        .to_string();
    assert!(error.starts_with("bad.toml:2:"), "{error}");
    let error = raypipe::scene::Scene::from_bytes("latin.toml", b"\xff\xfe")
        .unwrap_err()
        .to_string();
    assert_eq!(error, "latin.toml: cannot read scene file: it is not UTF-8 text");
}

/// A scene file places its meshes relative to itself: normalize, scale, translate.
#[test]
fn scene_meshes_are_placed_as_the_file_says() {
    let dir = test_dir("meshes-placement");
    write(&dir, "torus.ply", &models::binary_ply(&models::torus(8, 4), false));
    let scene = write(
        &dir,
        "placed.toml",
        b"[material.clay]\ncolor = [0.8, 0.5, 0.4]\n\n[[mesh]]\nfile = \"torus.ply\"\nscale = 0.5\ntranslate = [3, 0, 0]\nmaterial = \"clay\"\n\n[[mesh]]\nfile = \"torus.ply\"\nas = \"spheres\"\nspheres = 300\nnormalize = false\n",
    );
    let scene = raypipe::scene::Scene::load(scene.to_str().unwrap()).unwrap();
    assert_eq!(scene.triangles.len(), 64);
    assert_eq!(scene.spheres.len(), 300);
    let Aabb { min: lo, max: hi } = Aabb::around_points(scene.triangles.iter().flat_map(|t| t.vertices));
    // Normalized, the torus spans x in [-1, 1]; scaled by 0.5 and moved by 3: [2.5, 3.5].
    assert!((lo.x - 2.5).abs() < 1e-5 && (hi.x - 3.5).abs() < 1e-5, "{lo} {hi}");
    assert!(scene.triangles.iter().all(|t| t.normals.is_some() && t.material == 0));
    // Not normalized, the spheres sit on the mesh as written.
    let written = mesh::load(&dir.join("torus.ply")).unwrap();
    for s in &scene.spheres {
        let on_a_triangle = written
            .triangles
            .iter()
            .any(|&t| on_triangle(s.center, written.corners(t)));
        assert!(on_a_triangle, "sphere at {} is off the surface", s.center);
    }
}

/// Smooth normals computed from a torus's faces are its analytic normals, to within the facets'
/// spread (24 x 12 quads: faces 15 and 30 degrees apart).
#[test]
fn smooth_normals_follow_the_surface() {
    let model = models::torus(24, 12);
    let mesh = mesh::parse(&models::flat_off(&model), MeshFormat::Off, &mut Vec::new()).unwrap();
    assert!(mesh.normals.is_none());
    let smooth = mesh.smooth_normals(60.0);
    for (t, corners) in mesh.triangles.iter().zip(&smooth) {
        for (&i, n) in t.iter().zip(corners) {
            let exact = Vec3::from_array(model.normals[i as usize]);
            assert!(n.dot(exact) > 0.995, "vertex {i}: {n} against {exact}");
            assert!((n.length() - 1.0).abs() < 1e-5);
        }
    }
}

/// A cube's edges are 90 degrees: a 60-degree crease keeps every face flat, a 180-degree one
/// blends a corner's three faces equally (the angle weights make it independent of how the faces
/// are cut into triangles).
#[test]
fn the_crease_angle_keeps_sharp_edges_sharp() {
    let positions: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) * 2.0 - 1.0)
        .collect();
    // Two triangles per face, counter-clockwise from outside.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let cube = Mesh {
        positions,
        normals: None,
        triangles,
    };
    for (t, corners) in cube.triangles.iter().zip(cube.smooth_normals(60.0)) {
        let [a, b, c] = cube.corners(*t);
        let face = (b - a).cross(c - a).normalize();
        assert!(
            corners.iter().all(|n| n.dot(face) > 1.0 - 1e-6),
            "{corners:?} against {face}"
        );
    }
    for (t, corners) in cube.triangles.iter().zip(cube.smooth_normals(180.0)) {
        for (&i, n) in t.iter().zip(corners) {
            let diagonal = cube.positions[i as usize].normalize();
            assert!(n.dot(diagonal) > 1.0 - 1e-5, "corner {i}: {n} against {diagonal}");
        }
    }
}

/// `normals` in a `[[mesh]]`: by default the file's where it has them and smooth ones where not;
/// "flat" none; a name that is not a mode is one line naming the mesh.
#[test]
fn scene_meshes_get_the_normals_they_ask_for() {
    let dir = test_dir("meshes-normals");
    let model = models::torus(8, 4);
    write(&dir, "with.ply", &models::binary_ply(&model, true));
    write(&dir, "without.off", &models::flat_off(&model));
    let load = |table: &str| {
        let path = write(&dir, "scene.toml", format!("[[mesh]]\n{table}\n").as_bytes());
        raypipe::scene::Scene::load(path.to_str().unwrap())
    };
    let normals =
        |table: &str| -> Vec<Option<[Vec3; 3]>> { load(table).unwrap().triangles.iter().map(|t| t.normals).collect() };
    let from_file = normals("file = \"with.ply\"");
    let smooth = normals("file = \"without.off\"");
    assert!(from_file.iter().chain(&smooth).all(Option::is_some));
    assert_ne!(from_file, smooth, "the file's normals are not the computed ones");
    assert_eq!(smooth, normals("file = \"with.ply\"\nnormals = \"smooth\""));
    assert!(
        normals("file = \"with.ply\"\nnormals = \"flat\"")
            .iter()
            .all(Option::is_none)
    );
    let creased = normals("file = \"without.off\"\ncrease = 10");
    assert_ne!(creased, smooth, "a 10-degree crease keeps the 4-sided torus's edges");
    let error = load("file = \"with.ply\"\nnormals = \"shiny\"")
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(":1: mesh 0: normals must be one of auto, flat, smooth (got \"shiny\")"),
        "{error}"
    );
    let error = load("file = \"with.ply\"\ncrease = 200").unwrap_err().to_string();
    assert!(
        error.contains("crease must be an angle from 0 to 180 degrees"),
        "{error}"
    );
}

fn on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> bool {
    let n = (b - a).cross(c - a);
    let in_plane = (p - a).dot(n).abs() <= 1e-5 * n.length();
    // Barycentric coordinates from areas, each within [0, 1] up to rounding.
    let weights = [(b - p).cross(c - p), (c - p).cross(a - p), (a - p).cross(b - p)].map(|w| w.dot(n) / n.dot(n));
    in_plane && weights.iter().all(|&w| (-1e-4..=1.0 + 1e-4).contains(&w))
}

/// Mutations of a valid file: flipped bytes, cut ranges, inserted bytes, truncation.
#[derive(Clone, Debug)]
enum Mutation {
    Flip(usize, u8),
    Cut(usize, usize),
    Insert(usize, Vec<u8>),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, bits)| Mutation::Flip(at, bits)),
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Cut(at, len)),
        (
            any::<usize>(),
            prop::collection::vec(
                prop_oneof![any::<u8>(), Just(b' '), Just(b'\n'), Just(b'9'), Just(b'-')],
                1..12
            )
        )
            .prop_map(|(at, bytes)| Mutation::Insert(at, bytes)),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn mutate(mut bytes: Vec<u8>, mutations: &[Mutation]) -> Vec<u8> {
    for m in mutations {
        let len = bytes.len().max(1);
        match m {
            Mutation::Flip(at, bits) => {
                if let Some(b) = bytes.get_mut(at % len) {
                    *b ^= bits;
                }
            }
            Mutation::Cut(at, n) => {
                let start = (at % len).min(bytes.len());
                let end = (start + n).min(bytes.len());
                bytes.drain(start..end);
            }
            Mutation::Insert(at, new) => {
                let at = (at % len).min(bytes.len());
                bytes.splice(at..at, new.iter().copied());
            }
            Mutation::Truncate(at) => bytes.truncate(at % len),
        }
    }
    bytes
}

fn small_files() -> Vec<(MeshFormat, Vec<u8>)> {
    let model: TestModel = models::torus(4, 3);
    every_format(&model)
        .into_iter()
        .map(|(name, bytes)| (MeshFormat::from_path(Path::new(name)).unwrap(), bytes))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// A mutated file parses to a valid mesh or fails with one line; it never panics.
    #[test]
    fn mutated_files_never_panic(which in 0usize..5, mutations in prop::collection::vec(mutation(), 1..4)) {
        let (format, bytes) = small_files().swap_remove(which);
        let bytes = mutate(bytes, &mutations);
        match mesh::parse(&bytes, format, &mut Vec::new()) {
            Ok(mesh) => prop_assert!(mesh.validate().is_ok()),
            Err(e) => {
                let message = e.to_string();
                prop_assert!(!message.contains('\n') && !message.trim().is_empty(), "{message:?}");
            }
        }
    }
}

/// A gigabyte of zeros (a sparse file: no disk) named as a model is refused by its first bytes,
/// each format with its own reason.
#[test]
fn a_sparse_gigabyte_is_refused_by_its_header() {
    let dir = crate::common::test_dir("sparse-models");
    for (name, expected) in [
        ("zeros.ply", "zeros.ply:1: expected 'ply': not a PLY file"),
        ("zeros.off", "zeros.off:1: expected the keyword OFF"),
        ("zeros.obj", "zeros.obj: not a text file: a NUL byte at byte 0"),
        ("zeros.glb", "zeros.glb: not a glTF file"),
    ] {
        let path = dir.join(name);
        std::fs::File::create(&path).unwrap().set_len(1 << 30).unwrap();
        let error = raypipe::scene::Scene::load(path.to_str().unwrap())
            .unwrap_err()
            .to_string();
        std::fs::remove_file(&path).unwrap();
        assert!(error.starts_with(&format!("{}/{expected}", dir.display())), "{error}");
        assert!(error.len() < 300, "{error}");
    }
    // A header that never ends within the first bytes read.
    let path = dir.join("endless.ply");
    let mut header = b"ply\nformat ascii 1.0\n".to_vec();
    header.resize(200_000, b'\n');
    std::fs::write(&path, &header).unwrap();
    let error = raypipe::scene::Scene::load(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(error.starts_with(&format!("{}/endless.ply", dir.display())), "{error}");
    assert!(error.contains("no end_header in the first 65536 bytes"), "{error}");
}
