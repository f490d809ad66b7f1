//! Shared inputs of the benchmarks: the boxes of `random:N` scenes.

use raypipe::bvh::aabb::Aabb;
use raypipe::records::PackedScene;

/// The sphere boxes of the built-in `random:N` scene (seed 1).
pub fn random_boxes(n: usize) -> (PackedScene, Vec<Aabb>) {
    let scene = raypipe::scene::builtin::random(n, 1);
    let packed = PackedScene::new(&scene).expect("built-in scenes are valid");
    let boxes = packed.primitive_boxes();
    (packed, boxes)
}
