//! Hostile glTF files: documents and bytes that must end in one line naming the element, files
//! outside the document's folder refused, a huge texture refused before it is decoded, and
//! optional extensions the reader lacks ignored with a notice.

use crate::common::gltf_file::{Packing, glb, textured_quad};
use crate::common::harness::Test;
use crate::common::test_dir;
use crate::gltf::hierarchy;
use raypipe::error::{Element, GltfPart};
use raypipe::scene::Scene;
use raypipe::scene::gltf::{Files, parse};
use serde_json::{Value, json};

/// The file of `hierarchy` with `edit` applied to its JSON, parsed; its error.
fn refused(edit: impl FnOnce(&mut Value)) -> String {
    let b = hierarchy(json!({}));
    let mut document: Value = serde_json::from_slice(&b.gltf()).unwrap();
    edit(&mut document);
    let bytes = serde_json::to_vec(&document).unwrap();
    refused_bytes(&bytes)
}

fn refused_bytes(bytes: &[u8]) -> String {
    match parse(bytes, Files::None, &mut Vec::new()) {
        Ok(_) => panic!("accepted"),
        Err(e) => {
            let message = e.to_string();
            assert!(!message.contains('\n'), "{message}");
            message
        }
    }
}

/// A change to a document's JSON.
type Edit = Box<dyn FnOnce(&mut Value)>;

fn hostile_documents_end_in_one_line_naming_the_element() {
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "accessor past its view",
            Box::new(|d| d["accessors"][0]["byteOffset"] = json!(40)),
            "accessor 0: 3 elements of 12 bytes",
        ),
        (
            "a count that lies",
            Box::new(|d| d["accessors"][0]["count"] = json!(300)),
            "accessor 0: 300 elements of 12 bytes",
        ),
        (
            "count 2^31",
            Box::new(|d| d["accessors"][0]["count"] = json!(1u64 << 31)),
            "accessor 0: count 2147483648 is more than",
        ),
        (
            "a view past its buffer",
            Box::new(|d| d["bufferViews"][0]["byteLength"] = json!(1000)),
            "reach past buffer 0",
        ),
        (
            "terabytes of buffer",
            Box::new(|d| d["buffers"][0]["byteLength"] = json!(1u64 << 42)),
            "buffer 0: byteLength 4398046511104 is more than",
        ),
        (
            "a buffer shorter than it says",
            Box::new(|d| d["buffers"][0]["byteLength"] = json!(1000)),
            "buffer 0: 44 bytes, less than its byteLength 1000",
        ),
        (
            "an index out of range",
            Box::new(|d| d["accessors"][0]["count"] = json!(2)),
            "accessor 1: index 2 is 2, out of range (2 vertices)",
        ),
        (
            "a mesh index out of range",
            Box::new(|d| d["nodes"][0]["mesh"] = json!(7)),
            "nodes[0].mesh: Index out of bounds",
        ),
        (
            "a perspective camera without its object",
            Box::new(|d| {
                d["cameras"] =
                    json!([{ "type": "perspective", "orthographic": { "xmag": 1, "ymag": 1, "zfar": 2, "znear": 1 } }]);
                d["nodes"][1]["camera"] = json!(0);
            }),
            "camera 0: of type perspective, without its perspective object",
        ),
        // gltf-json's own validation would panic on this one (the fuzz target found it).
        (
            "a POSITION accessor out of range",
            Box::new(|d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9)),
            "mesh 0 primitive 0: POSITION accessor 9 does not exist (2 accessors)",
        ),
        (
            "a cycle",
            Box::new(|d| d["nodes"][0]["children"] = json!([1])),
            "node 0: its parents form a cycle",
        ),
        (
            "two parents",
            Box::new(|d| {
                d["nodes"].as_array_mut().unwrap().push(json!({ "children": [0] }));
            }),
            "node 0: a child of nodes 1 and 2",
        ),
        (
            "a loop onto itself",
            Box::new(|d| d["nodes"][0]["children"] = json!([0])),
            "node 0: a child of nodes 0 and 1",
        ),
        (
            "a huge matrix number",
            Box::new(|d| d["nodes"][1]["matrix"] = json!([1e39, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])),
            "node 1",
        ),
        (
            "a zero quaternion",
            Box::new(|d| d["nodes"][1]["rotation"] = json!([0, 0, 0, 0])),
            "node 1: rotation must be a unit quaternion",
        ),
        (
            "a required extension",
            Box::new(|d| d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"])),
            "extension KHR_draco_mesh_compression is required",
        ),
        (
            "an absolute URI",
            Box::new(|d| d["buffers"][0]["uri"] = json!("/etc/passwd")),
            "is absolute",
        ),
        (
            "a URI out of the folder",
            Box::new(|d| d["buffers"][0]["uri"] = json!("../x.bin")),
            "leaves the glTF's folder",
        ),
        (
            "a root listed twice",
            Box::new(|d| d["scenes"][0]["nodes"] = json!([1, 1])),
            "scene 0: node 1 is listed twice",
        ),
        (
            "a child as a root",
            Box::new(|d| d["scenes"][0]["nodes"] = json!([0])),
            "scene 0: node 0 is a child of node 1, not a root",
        ),
        (
            "positions of the wrong type",
            Box::new(|d| d["accessors"][0]["type"] = json!("VEC2")),
            "accessor 0: type Vec2 where [Vec3] is expected",
        ),
    ];
    for (what, edit, expected) in cases {
        let message = refused(edit);
        assert!(message.contains(expected), "{what}: {message}");
    }
}

fn hostile_bytes_end_in_one_line() {
    let b = hierarchy(json!({}));
    let document = b.gltf();
    let json_only: Value = serde_json::from_slice(&document).unwrap();
    let container = glb(&serde_json::to_vec(&json_only).unwrap(), &b.bin);
    // Truncated anywhere, the file is refused, never read past its end.
    for cut in [1, 11, 12, 19, 20, container.len() / 2, container.len() - 1] {
        refused_bytes(&container[..cut]);
    }
    for cut in [0, 1, document.len() / 2, document.len() - 1] {
        refused_bytes(&document[..cut]);
    }
    // A total length shorter than the header (gltf's own reader would subtract past zero), and
    // longer than the file.
    for length in [0u32, 11, container.len() as u32 + 1] {
        let mut short = container.clone();
        short[8..12].copy_from_slice(&length.to_le_bytes());
        let message = refused_bytes(&short);
        assert!(
            message.starts_with(&format!("GLB header: total length {length}")),
            "{message}"
        );
    }
    // A chunk whose length says more than the file holds.
    let mut lying = container.clone();
    lying[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    refused_bytes(&lying);
    let message = refused_bytes(b"\xff\xfe{\"asset\":{}}");
    assert!(message.starts_with("not glTF JSON"), "{message}");
}

fn external_files_are_read_from_the_folder_only() {
    let dir = test_dir("gltf-external");
    let b = hierarchy(json!({}));
    let path = b.write(&dir, "model", Packing::ExternalFiles);
    assert!(Scene::load(path.to_str().unwrap()).is_ok());
    let mut document: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    #[cfg(unix)]
    {
        // A link out of the folder, and a FIFO inside it.
        let outside = test_dir("gltf-outside").join("secret.bin");
        std::fs::write(&outside, &b.bin).unwrap();
        std::os::unix::fs::symlink(&outside, dir.join("link.bin")).unwrap();
        for (uri, expected) in [
            ("link.bin", "lies outside the glTF's folder"),
            ("missing.bin", "no such file"),
        ] {
            document["buffers"][0]["uri"] = json!(uri);
            let text = serde_json::to_vec(&document).unwrap();
            let err = parse(&text, Files::Folder(&dir), &mut Vec::new())
                .unwrap_err()
                .to_string();
            assert!(err.contains(expected), "{uri}: {err}");
        }
        let fifo = dir.join("pipe.bin");
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );
        document["buffers"][0]["uri"] = json!("pipe.bin");
        let text = serde_json::to_vec(&document).unwrap();
        let err = parse(&text, Files::Folder(&dir), &mut Vec::new())
            .unwrap_err()
            .to_string();
        assert!(err.contains("not a regular file"), "{err}");
    }
}

fn a_huge_texture_is_refused_before_it_is_decoded() {
    let b = textured_quad(1.0, [10497, 10497]);
    let mut document: Value = serde_json::from_slice(&b.gltf()).unwrap();
    // A PNG header claiming 65536 x 65536 pixels, without its pixels.
    let mut header = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\x01\0\0\0\x01\0\0\x08\x06\0\0\0".to_vec();
    let crc = crc32(&header[12..29]);
    header.extend_from_slice(&crc.to_be_bytes());
    use base64::Engine;
    let uri = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&header)
    );
    document["images"][0]["uri"] = json!(uri);
    let message = refused_bytes(&serde_json::to_vec(&document).unwrap());
    assert_eq!(
        message,
        "material 0: image 0: 65536x65536 pixels: each side must be in 1..=16384"
    );
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &byte in bytes {
        crc ^= byte as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

fn unsupported_optional_extensions_are_ignored_with_a_notice() {
    let b = hierarchy(json!({}));
    let mut document: Value = serde_json::from_slice(&b.gltf()).unwrap();
    document["extensionsUsed"] = json!(["EXT_future_thing"]);
    let mut notices = Vec::new();
    parse(&serde_json::to_vec(&document).unwrap(), Files::None, &mut notices).unwrap();
    assert_eq!(notices, vec!["extension EXT_future_thing is ignored"]);
}

/// An image with neither a uri nor a buffer view is refused (gltf's own accessor would panic); an
/// image in a buffer view without its mimeType is known by its first bytes.
fn images_without_a_source_or_a_type() {
    let b = textured_quad(1.0, [10497, 10497]);
    let mut document: Value = serde_json::from_slice(&b.gltf()).unwrap();
    document["images"][0] = json!({});
    let message = refused_bytes(&serde_json::to_vec(&document).unwrap());
    assert_eq!(message, "material 0: image 0: neither a bufferView nor a uri");

    let dir = test_dir("gltf-image-type");
    let path = b.write(&dir, "untyped", Packing::Glb);
    let bytes = std::fs::read(&path).unwrap();
    let json_length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut document: Value = serde_json::from_slice(&bytes[20..20 + json_length]).unwrap();
    document["images"][0].as_object_mut().unwrap().remove("mimeType");
    let bin_start = 20 + json_length + 8;
    let untyped = glb(&serde_json::to_vec(&document).unwrap(), &bytes[bin_start..]);
    let file = parse(&untyped, Files::None, &mut Vec::new()).unwrap();
    assert_eq!(file.textures.len(), 1);
}

/// The reader's errors carry where they lie as data, from the outermost part in, so that a viewer
/// may point at it: a primitive's index accessor, a node's instancing attribute, a buffer.
fn errors_carry_their_gltf_element() {
    let element = |edit: Edit| {
        let b = hierarchy(json!({}));
        let mut document: Value = serde_json::from_slice(&b.gltf()).unwrap();
        edit(&mut document);
        parse(&serde_json::to_vec(&document).unwrap(), Files::None, &mut Vec::new())
            .unwrap_err()
            .element
    };
    use GltfPart::*;
    assert_eq!(
        element(Box::new(|d| d["accessors"][0]["count"] = json!(2))),
        Some(Element::Gltf(vec![Mesh(0), Primitive(0), Accessor(1)]))
    );
    assert_eq!(
        element(Box::new(|d| d["buffers"][0]["byteLength"] = json!(1000))),
        Some(Element::Gltf(vec![Buffer(0)]))
    );
    assert_eq!(
        element(Box::new(|d| {
            d["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
            d["nodes"][0]["extensions"] = json!({"EXT_mesh_gpu_instancing": {"attributes": {"SCALE": 9}}});
        })),
        Some(Element::Gltf(vec![
            Node(0),
            Named("EXT_mesh_gpu_instancing".into()),
            Named("SCALE".into())
        ]))
    );
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        plain hostile_documents_end_in_one_line_naming_the_element,
        plain hostile_bytes_end_in_one_line,
        plain external_files_are_read_from_the_folder_only,
        plain a_huge_texture_is_refused_before_it_is_decoded,
        plain unsupported_optional_extensions_are_ignored_with_a_notice,
        plain images_without_a_source_or_a_type,
        plain errors_carry_their_gltf_element,
    ]
}
