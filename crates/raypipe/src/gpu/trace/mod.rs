//! The tracer: the renderer (targets, pipelines, encoding a frame), the composition of its
//! shader, the scene's upload, the region of pixels it traces, and the display pass.

pub mod display;
pub mod region;
pub mod renderer;
#[cfg(feature = "internals")]
pub mod shader;
#[cfg(not(feature = "internals"))]
pub(crate) mod shader;
#[cfg(feature = "internals")]
pub mod upload;
#[cfg(not(feature = "internals"))]
pub(crate) mod upload;

pub use display::{Display, Shown};
pub use renderer::{Renderer, RendererOptions, TimedFrame};
pub use shader::RecordKind;
