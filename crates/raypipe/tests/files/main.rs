//! The tests of files read through the harness: glTF documents written here with known answers
//! (`gltf`), hostile ones (`gltf_hostile`) and their animation (`animation`), the shared animated
//! samples, and the Khronos validator's verdict on every file the tests write. None needs a GPU.

#[path = "../common/mod.rs"]
mod common;

mod animation;
mod gltf;
mod gltf_hostile;

fn main() -> std::process::ExitCode {
    common::harness::run(
        [gltf::tests(), gltf_hostile::tests(), animation::tests()]
            .into_iter()
            .flatten()
            .collect(),
    )
}
