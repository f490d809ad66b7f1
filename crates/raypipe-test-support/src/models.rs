//! Models for tests, made here: a torus with vertex normals, written by independent writers in every
//! format the loaders read (ASCII and binary PLY of either byte order, OFF, OBJ).

use std::f32::consts::TAU;
use std::fmt::Write;

/// An indexed mesh as the writers see it: quads, so that loaders must triangulate.
pub struct TestModel {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub quads: Vec<[u32; 4]>,
}

/// A torus around the y axis (major radius 1, minor 0.35), `rings` x `sides` quads, counter-clockwise
/// seen from outside.
pub fn torus(rings: u32, sides: u32) -> TestModel {
    let (major, minor) = (1.0f32, 0.35f32);
    let mut model = TestModel {
        positions: Vec::new(),
        normals: Vec::new(),
        quads: Vec::new(),
    };
    for i in 0..rings {
        let u = TAU * i as f32 / rings as f32;
        for j in 0..sides {
            let v = TAU * j as f32 / sides as f32;
            let normal = [v.cos() * u.cos(), v.sin(), v.cos() * u.sin()];
            let ring = major + minor * v.cos();
            model.positions.push([ring * u.cos(), minor * v.sin(), ring * u.sin()]);
            model.normals.push(normal);
        }
    }
    let index = |i: u32, j: u32| (i % rings) * sides + (j % sides);
    for i in 0..rings {
        for j in 0..sides {
            model
                .quads
                .push([index(i, j), index(i, j + 1), index(i + 1, j + 1), index(i + 1, j)]);
        }
    }
    model
}

pub fn ascii_ply(model: &TestModel) -> Vec<u8> {
    let mut text = String::new();
    writeln!(text, "ply\nformat ascii 1.0\ncomment written by the raypipe tests").unwrap();
    writeln!(text, "element vertex {}", model.positions.len()).unwrap();
    // Normals first and an extra property: loaders must go by names, not positions.
    for name in ["nx", "ny", "nz", "x", "y", "z", "confidence"] {
        writeln!(text, "property float {name}").unwrap();
    }
    writeln!(text, "element face {}", model.quads.len()).unwrap();
    writeln!(text, "property list uchar int vertex_indices\nend_header").unwrap();
    for (p, n) in model.positions.iter().zip(&model.normals) {
        writeln!(text, "{} {} {} {} {} {} 0.5", n[0], n[1], n[2], p[0], p[1], p[2]).unwrap();
    }
    for q in &model.quads {
        writeln!(text, "4 {} {} {} {}", q[0], q[1], q[2], q[3]).unwrap();
    }
    text.into_bytes()
}

pub fn binary_ply(model: &TestModel, little_endian: bool) -> Vec<u8> {
    let order = if little_endian {
        "binary_little_endian"
    } else {
        "binary_big_endian"
    };
    let mut bytes = format!(
        "ply\nformat {order} 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         property float nx\nproperty float ny\nproperty float nz\nelement face {}\n\
         property list uchar uint vertex_indices\nend_header\n",
        model.positions.len(),
        model.quads.len()
    )
    .into_bytes();
    let f64_bytes = |v: f64| {
        if little_endian {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    let f32_bytes = |v: f32| {
        if little_endian {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    let u32_bytes = |v: u32| {
        if little_endian {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    for (p, n) in model.positions.iter().zip(&model.normals) {
        for &c in p {
            bytes.extend(f64_bytes(c as f64));
        }
        for &c in n {
            bytes.extend(f32_bytes(c));
        }
    }
    for q in &model.quads {
        bytes.push(4);
        for &i in q {
            bytes.extend(u32_bytes(i));
        }
    }
    bytes
}

/// NOFF: the vertex normals follow the coordinates.
pub fn off(model: &TestModel) -> Vec<u8> {
    let mut text = String::from("NOFF\n# vertices faces edges\n");
    writeln!(text, "{} {} 0", model.positions.len(), model.quads.len()).unwrap();
    for (p, n) in model.positions.iter().zip(&model.normals) {
        writeln!(text, "{} {} {} {} {} {}", p[0], p[1], p[2], n[0], n[1], n[2]).unwrap();
    }
    for q in &model.quads {
        writeln!(text, "4 {} {} {} {}", q[0], q[1], q[2], q[3]).unwrap();
    }
    text.into_bytes()
}

/// Plain OFF, without normals: its triangles shade flat.
pub fn flat_off(model: &TestModel) -> Vec<u8> {
    let mut text = format!("OFF\n{} {} 0\n", model.positions.len(), model.quads.len());
    for p in &model.positions {
        writeln!(text, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for q in &model.quads {
        writeln!(text, "4 {} {} {} {}", q[0], q[1], q[2], q[3]).unwrap();
    }
    text.into_bytes()
}

/// A scene of spheres and triangles mixed: a smooth glass torus, a flat mirror torus, a torus of
/// clay spheres and a checkered floor. `rings` x `sides` quads per torus, `spheres` spheres; its
/// files are written to `dir`.
pub fn mixed_scene(dir: &std::path::Path, rings: u32, sides: u32, spheres: usize) -> raypipe::scene::Scene {
    let model = torus(rings, sides);
    std::fs::write(dir.join("smooth.ply"), binary_ply(&model, true)).unwrap();
    std::fs::write(dir.join("flat.off"), flat_off(&model)).unwrap();
    let text = format!(
        "[camera]\neye = [0, 2.2, -4.5]\ntarget = [0, 0, 0.3]\nfov = 45\n\
         [[light]]\nposition = [3, 5, -4]\n[[light]]\nposition = [-4, 3, -1]\ncolor = [0.3, 0.3, 0.3]\n\
         [material.clay]\ncolor = [0.85, 0.55, 0.4]\nspecular = 0.3\n\
         [material.glass]\ncolor = [0.1, 0.1, 0.1]\ntransmit = 0.9\nreflect = 0.05\nior = 1.5\nspecular = 0.5\n\
         [material.mirror]\ncolor = [0.2, 0.2, 0.2]\nreflect = 0.8\n\
         [material.light_tile]\n[material.dark_tile]\ncolor = [0.3, 0.3, 0.3]\n\
         [[plane]]\npoint = [0, -0.6, 0]\nnormal = [0, 1, 0]\nmaterial = \"light_tile\"\nchecker_material = \"dark_tile\"\nchecker_size = 0.5\n\
         [[mesh]]\nfile = \"smooth.ply\"\nscale = 0.8\ntranslate = [-1.1, 0, 0]\nmaterial = \"glass\"\n\
         [[mesh]]\nfile = \"flat.off\"\nnormals = \"flat\"\nscale = 0.8\ntranslate = [1.1, 0, 0]\nmaterial = \"mirror\"\n\
         [[mesh]]\nfile = \"smooth.ply\"\nas = \"spheres\"\nspheres = {spheres}\nscale = 0.7\ntranslate = [0, 0, 1.6]\nmaterial = \"clay\"\n"
    );
    let path = dir.join("mixed.toml");
    std::fs::write(&path, text).unwrap();
    raypipe::scene::Scene::load(path.to_str().unwrap()).unwrap()
}

/// Two objects (the first half of the quads and the rest), with a material library to ignore.
pub fn obj(model: &TestModel) -> Vec<u8> {
    let mut text = String::from("mtllib missing.mtl\n");
    for p in &model.positions {
        writeln!(text, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for n in &model.normals {
        writeln!(text, "vn {} {} {}", n[0], n[1], n[2]).unwrap();
    }
    let half = model.quads.len() / 2;
    for (k, q) in model.quads.iter().enumerate() {
        if k == 0 || k == half {
            writeln!(text, "o part{k}\nusemtl clay").unwrap();
        }
        let corner = |i: u32| format!("{0}//{0}", i + 1);
        writeln!(
            text,
            "f {} {} {} {}",
            corner(q[0]),
            corner(q[1]),
            corner(q[2]),
            corner(q[3])
        )
        .unwrap();
    }
    text.into_bytes()
}

/// Every format of `model`, as (file name, bytes).
pub fn every_format(model: &TestModel) -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("model-ascii.ply", ascii_ply(model)),
        ("model-little.ply", binary_ply(model, true)),
        ("model-big.ply", binary_ply(model, false)),
        ("model.off", off(model)),
        ("model.obj", obj(model)),
    ]
}
