//! raypipe in a web page: the viewer compiled to `wasm32-unknown-unknown`, tracing on a canvas
//! through WebGPU (storage memory, moving scenes rebuilt in compute passes; texture memory on the
//! browser's software fallback adapter, where it is faster) or WebGL2 (texture memory, since its
//! fragment shaders have no storage buffers; moving scenes rebuilt on the CPU in wasm). Where the
//! URL names no walk, a software adapter gets the stack walk, its fastest, and others the threaded.
//! `scripts/build-web.sh` builds the page; `web/` holds its HTML and script.
//!
//! The tracer, the camera and the modes are the native viewer's (`raypipe-view`); this crate is
//! the page's host for them, as `raypipe view` is the window's: the URL's settings, the controls'
//! calls, the animation frames and the status the page shows.

pub mod params;
pub mod status;

#[cfg(target_arch = "wasm32")]
mod console;
#[cfg(target_arch = "wasm32")]
mod page;

#[cfg(target_arch = "wasm32")]
pub use page::{Viewer, controls, start};
