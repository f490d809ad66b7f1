//! The scene-file parser on arbitrary text: a valid scene or a one-line error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match raypipe::scene::file::parse(text) {
        Ok(scene) => assert!(scene.validate().is_ok()),
        Err(e) => assert!(!e.contains('\n')),
    }
});
