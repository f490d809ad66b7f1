//! The OFF parser on arbitrary bytes: a valid mesh or a one-line error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::mesh::{MeshFormat, parse};

fuzz_target!(|data: &[u8]| {
    match parse(data, MeshFormat::Off, &mut Vec::new()) {
        Ok(mesh) => assert!(mesh.validate().is_ok()),
        Err(e) => assert!(!e.to_string().contains('\n')),
    }
});
