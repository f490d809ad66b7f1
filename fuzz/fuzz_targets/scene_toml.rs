//! The scene-file parser on arbitrary text: a scene that packs for the tracers, or an error of one
//! short line that does not echo the input; never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::records::PackedScene;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match raypipe::scene::file::parse(text) {
        Ok(scene) => {
            if let Err(e) = PackedScene::new(&scene) {
                short_line(&e.to_string());
            }
        }
        Err(e) => short_line(&e.to_string()),
    }
});

/// The promise of every error: one line, short, whatever the input.
fn short_line(message: &str) {
    assert!(!message.contains('\n') && message.len() <= 400, "{message:?}");
}
