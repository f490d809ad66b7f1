//! raypipe: Whitted ray tracing in the fragment shader of the ordinary graphics pipeline.
//!
//! Data flows scene → packed records → (GPU upload → full-screen triangle → fragment shader) or
//! (CPU reference tracer, function by function the shader's twin) → frame → image files.

pub mod bvh;
pub mod cli;
pub mod cpu;
pub mod gpu;
pub mod image;
pub mod mesh;
pub mod render;
pub mod scene;
