//! The PLY parser on arbitrary bytes: a mesh, or an error of one short line that does not
//! echo the input; never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::mesh::{MeshFormat, parse};

fuzz_target!(|data: &[u8]| {
    match parse(data, MeshFormat::Ply, &mut Vec::new()) {
        // The parsers validate what they return.
        Ok(mesh) => assert!(mesh.validate().is_ok()),
        Err(e) => short_line(&e.to_string()),
    }
});

/// The promise of every error: one line, short, whatever the input.
fn short_line(message: &str) {
    assert!(!message.contains('\n') && message.len() <= 400, "{message:?}");
}
