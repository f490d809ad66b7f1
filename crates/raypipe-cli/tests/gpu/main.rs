//! The command line's tests that need a GPU or the shared models, through one harness that
//! reports a missing one as ignored (see `common::harness`).

#[path = "../common/mod.rs"]
mod common;

mod bench;
mod bvh;
mod models;

fn main() -> std::process::ExitCode {
    let tests = [bench::tests(), bvh::tests(), models::tests()];
    common::harness::run(tests.into_iter().flatten().collect())
}
