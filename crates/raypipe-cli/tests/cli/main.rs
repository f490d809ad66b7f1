//! The command line's tests that need no GPU (every render here is `--device cpu`): files written
//! whole, `diff` exiting by its threshold (`commands`), the integrator and samples a render takes
//! (`integrator`), and hostile input and failing outputs
//! ending in one short line and exit code 2, never a panic (`hostile`). One binary, so that the
//! tests link once.

#[path = "../common/mod.rs"]
mod common;

mod commands;
mod hostile;
mod integrator;
