//! The shared scans (`../shared/models`) load with their published counts.

use crate::common::harness::Test;
use raypipe::mesh;
use std::path::Path;

fn the_shared_scans_load_with_their_published_counts(models: &Path) {
    for (name, vertices, faces) in [("bunny.ply", 35_947, 69_451), ("fertility.off", 23_188, 46_388)] {
        let path = models.join(name);
        let mesh = mesh::load(&path).unwrap();
        assert_eq!(mesh.positions.len(), vertices, "{name}");
        assert_eq!(mesh.triangles.len(), faces, "{name}: every face is a triangle");
    }
}

pub fn tests() -> Vec<Test> {
    crate::tests![models the_shared_scans_load_with_their_published_counts]
}
