//! The glTF reader on arbitrary bytes (JSON or GLB, external files refused): a scene whose indices
//! are in range and whose numbers are finite, or an error of one short line; never a panic, and
//! never an allocation the bytes do not pay for.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::scene::gltf::{Files, parse};

fuzz_target!(|data: &[u8]| {
    match parse(data, Files::None, &mut Vec::new()) {
        Ok(scene) => {
            for primitive in &scene.primitives {
                let n = primitive.positions.len();
                assert!(primitive.triangles.iter().flatten().all(|&i| (i as usize) < n));
                assert!(primitive.positions.iter().all(|p| p.is_finite()));
                assert!((primitive.material as usize) < scene.materials.len());
            }
            for texture in &scene.textures {
                assert!(texture.validate().is_ok());
            }
        }
        Err(e) => short_line(&e.to_string()),
    }
});

/// The promise of every error: one line, short, whatever the input.
fn short_line(message: &str) {
    assert!(!message.contains('\n') && message.len() <= 400, "{message:?}");
}
