//! Past the adapter's limits a render is one line that names the scene and says what would work,
//! found before anything big is allocated.

use crate::common::harness::Test;
use crate::common::{assert_clean_error, raypipe};
use raypipe::gpu::GpuContext;

fn render(args: &[&str]) -> std::process::Output {
    let out = crate::common::test_dir("limits").join("out.png");
    let out = out.to_str().unwrap().to_string();
    raypipe(&[&["render"], args, &["--device", "gpu", "-q", "-o", &out]].concat())
}

/// The refusals every adapter makes: an image wider than its largest texture, a scene too big for
/// uniform memory. (A frame target past the largest buffer, which few adapters reach below their
/// texture size, is refused under lowered limits in a unit test of the renderer's size
/// check; its message is checked in report.rs.)
fn limits_are_one_line_that_names_the_scene_and_a_way_out(ctx: &GpuContext) {
    let side = ctx.limits().max_texture_dimension_2d;
    let too_wide = (side + 1).to_string();
    assert_clean_error(
        &render(&["whitted", "--width", &too_wide, "--height", "8"]),
        &["whitted: "],
    );
    assert_clean_error(
        &render(&["random:100000", "--memory", "uniform", "--width", "8", "--height", "8"]),
        &[
            "random:100000: scene too big for --memory uniform",
            "use --memory storage",
        ],
    );
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![gpu limits_are_one_line_that_names_the_scene_and_a_way_out]
}
