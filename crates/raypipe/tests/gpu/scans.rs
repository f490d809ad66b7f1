//! The shared scans (`../shared/models`) load with their published counts, and the Bunny, whose
//! scan has no normals, shades smooth unless asked flat.

use crate::common::harness::Test;
use raypipe::image::diff::{Tolerance, compare};
use raypipe::mesh;
use raypipe::modes::Accel;
use raypipe::records::PackedScene;
use raypipe::scene::Scene;
use raypipe::scene::model::{ModelOptions, Normals};
use std::path::Path;

fn the_shared_scans_load_with_their_published_counts(models: &Path) {
    for (name, vertices, faces) in [("bunny.ply", 35_947, 69_451), ("fertility.off", 23_188, 46_388)] {
        let path = models.join(name);
        let mesh = mesh::load(&path).unwrap();
        assert_eq!(mesh.positions.len(), vertices, "{name}");
        assert_eq!(mesh.triangles.len(), faces, "{name}: every face is a triangle");
    }
}

fn the_bunny_shades_smooth_unless_asked_flat(models: &Path) {
    let bunny = models.join("bunny.ply");
    assert!(mesh::load(&bunny).unwrap().normals.is_none(), "the scan has no normals");
    let scene = |normals| {
        let options = ModelOptions {
            normals,
            ..Default::default()
        };
        let mut scene = Scene::load_with(bunny.to_str().unwrap(), &options).unwrap();
        (scene.settings.width, scene.settings.height) = (120, 90);
        scene
    };
    let smooth = scene(None);
    assert!(smooth.triangles.iter().all(|t| t.normals.is_some()));
    let flat = scene(Some(Normals::Flat));
    assert!(flat.triangles.iter().all(|t| t.normals.is_none()));
    let render = |scene: &Scene| {
        let mut packed = PackedScene::new(scene).unwrap();
        packed.build_bvh();
        raypipe::cpu::render(&packed, Accel::Threaded).unwrap()
    };
    let (smooth, flat) = (render(&smooth), render(&flat));
    let stats = compare(&smooth.display(), &flat.display()).unwrap();
    assert!(
        Tolerance::COLOR.check(&stats).is_err(),
        "smooth and flat look alike: {stats:?}"
    );
    // The same surface, hit at the same places: only the shading normals differ.
    assert_eq!(smooth.depth().data, flat.depth().data);
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        models the_shared_scans_load_with_their_published_counts,
        models the_bunny_shades_smooth_unless_asked_flat,
    ]
}
