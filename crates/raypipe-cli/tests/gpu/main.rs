//! The command line's tests that need a GPU or the shared models, through one harness that
//! reports a missing one as ignored (see `common::harness`).

#[path = "../common/mod.rs"]
mod common;

// The binary's own image reader, to read back what it wrote.
use raypipe_cli::io;

mod bench;
mod bvh;
mod limits;
mod models;
mod progress;
mod view;

fn main() -> std::process::ExitCode {
    let tests = [
        bench::tests(),
        bvh::tests(),
        limits::tests(),
        models::tests(),
        progress::tests(),
        view::tests(),
    ];
    common::harness::run(tests.into_iter().flatten().collect())
}
