//! `raypipe`'s command line as a library: the binary (`main.rs`) runs [`cli::run`], and the tests
//! use its modules directly. It owns what the raypipe library must not: flags, progress bars,
//! printing, and image and plot files.
//!
//! The modules depend one way: `cli` dispatches to the subcommands (`render`, `view`, `bench`,
//! `bvh`, `diff`, `info`); they share `scene_args` (a scene's flags and loading), `device` (the
//! GPU or CPU that renders), `report` (messages, output, medians), `io` (image files), `plot` and
//! `args`, none of which imports a subcommand.

pub mod args;
pub mod bench;
pub mod bvh;
pub mod cli;
pub mod device;
pub mod diff;
pub mod info;
pub mod io;
pub mod notices;
pub mod plot;
pub mod render;
pub mod report;
pub mod scene_args;
pub mod view;
