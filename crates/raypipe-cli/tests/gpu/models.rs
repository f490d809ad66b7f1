//! The shared scans through the command line.

use crate::common::harness::Test;
use crate::common::models::test_dir;
use crate::common::raypipe;
use std::path::Path;

fn the_bunny_renders_as_20k_spheres(models: &Path) {
    let bunny = models.join("bunny.ply");
    let out = test_dir("cli-bunny").join("bunny-spheres.png");
    let output = raypipe(&[
        "render",
        bunny.to_str().unwrap(),
        "--spheres",
        "20000",
        "--width",
        "96",
        "--height",
        "72",
        "--stats",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(stdout.contains("20000 spheres, 0 triangles"), "{stdout}");
    // The bunny fills a good part of the frame: clay pixels (red well above blue) are common.
    let image = image::open(&out).unwrap().to_rgb8();
    let clay = image.pixels().filter(|p| p[0] as i32 > p[2] as i32 + 40).count();
    assert!(clay > image.len() / 3 / 20, "{clay} clay pixels of {}", image.len() / 3);
}

pub fn tests() -> Vec<Test> {
    crate::tests![models the_bunny_renders_as_20k_spheres]
}
