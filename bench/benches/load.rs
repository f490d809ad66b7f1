//! Model loading: glTF against PLY of the same triangles, parsed from bytes already in memory (what
//! `raypipe render FILE` does after reading the file), on the largest glTF sample of the shared
//! models and on the Bunny's 69,451 triangles. The PLY and GLB twins are written here from the
//! parsed triangles. Run: `cargo bench -p raypipe-bench --bench load` (needs `../shared/models`).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raypipe::mesh::{self, Mesh, MeshFormat};
use raypipe::scene::gltf::{self, Files};
use std::path::PathBuf;

fn models() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/models")
}

/// One mesh as a binary little-endian PLY.
fn binary_ply(mesh: &Mesh) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    let mut out = header.into_bytes();
    for p in &mesh.positions {
        out.extend(p.to_array().iter().flat_map(|c| c.to_le_bytes()));
    }
    for t in &mesh.triangles {
        out.push(3);
        out.extend(t.iter().flat_map(|&i| (i as i32).to_le_bytes()));
    }
    out
}

/// One mesh as a GLB: one node, one primitive, u32 indices.
fn glb(mesh: &Mesh) -> Vec<u8> {
    let mut bin: Vec<u8> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let positions_length = bin.len();
    bin.extend(mesh.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let bounds = mesh.bounds();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":{:?},"max":{:?}}},
{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteLength":{positions_length}}},{{"buffer":0,"byteOffset":{positions_length},"byteLength":{}}}],
"buffers":[{{"byteLength":{}}}]}}"#,
        mesh.positions.len(),
        bounds.min.to_array(),
        bounds.max.to_array(),
        mesh.triangles.len() * 3,
        bin.len() - positions_length,
        bin.len()
    );
    let mut json = json.into_bytes();
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    for word in [
        u32::from_le_bytes(*b"glTF"),
        2,
        total as u32,
        json.len() as u32,
        u32::from_le_bytes(*b"JSON"),
    ] {
        out.extend(word.to_le_bytes());
    }
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn load(c: &mut Criterion) {
    let models = models();
    if !models.is_dir() {
        eprintln!("{} is missing: nothing to load", models.display());
        return;
    }
    let rigged_bytes = std::fs::read(models.join("gltf/RiggedSimple.gltf")).unwrap();
    let rigged = gltf::parse(&rigged_bytes, Files::None, &mut Vec::new()).unwrap().mesh();
    let bunny_bytes = std::fs::read(models.join("bunny.ply")).unwrap();
    let bunny = mesh::parse(&bunny_bytes, MeshFormat::Ply, &mut Vec::new()).unwrap();
    let cases = [
        (
            "RiggedSimple",
            &rigged,
            Some(("gltf (data URIs, as shipped)", rigged_bytes.clone())),
            None,
        ),
        (
            "Bunny",
            &bunny,
            None,
            Some(("ply (ASCII, as shipped)", bunny_bytes.clone())),
        ),
    ];
    for (name, mesh, shipped_gltf, shipped_ply) in cases {
        let mut group = c.benchmark_group(format!("load_{name}"));
        group.throughput(Throughput::Elements(mesh.triangles.len() as u64));
        let gltf_inputs = shipped_gltf.into_iter().chain([("glb", glb(mesh))]);
        for (label, bytes) in gltf_inputs {
            let parsed = gltf::parse(&bytes, Files::None, &mut Vec::new()).unwrap().mesh();
            assert_eq!(parsed.triangles.len(), mesh.triangles.len(), "{name} {label}");
            group.bench_function(format!("{label}, {} bytes", bytes.len()), |b| {
                b.iter(|| gltf::parse(&bytes, Files::None, &mut Vec::new()).unwrap())
            });
        }
        let ply_inputs = shipped_ply.into_iter().chain([("ply (binary)", binary_ply(mesh))]);
        for (label, bytes) in ply_inputs {
            let parsed = mesh::parse(&bytes, MeshFormat::Ply, &mut Vec::new()).unwrap();
            assert_eq!(parsed.triangles.len(), mesh.triangles.len(), "{name} {label}");
            group.bench_function(format!("{label}, {} bytes", bytes.len()), |b| {
                b.iter(|| mesh::parse(&bytes, MeshFormat::Ply, &mut Vec::new()).unwrap())
            });
        }
        group.finish();
    }
}

criterion_group!(benches, load);
criterion_main!(benches);
