//! The GPU renderer: one full-screen triangle, all tracing in the fragment shader.

pub mod build;
pub mod compute;
pub mod context;
pub mod readback;
pub mod render;
pub mod shader;
pub mod threaded;
pub mod timing;
pub mod upload;

pub use context::GpuContext;
pub use render::GpuRenderer;
