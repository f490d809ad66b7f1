//! The GPU side: a context (adapter and device, for a surface or none), the renderer that traces
//! into its targets in the fragment shader, the display pass that shows them, the per-frame LBVH
//! rebuild in compute passes (with skinning and morphing before it), and readback for the callers that need pixels.

pub mod build;
pub mod compute;
pub mod context;
pub mod deform;
pub mod display;
mod error;
pub mod rayquery;
pub mod readback;
pub mod rebuild;
pub mod region;
pub mod renderer;
pub mod shader;
pub mod threaded;
pub mod timing;
pub mod upload;
pub mod wide;

pub use context::GpuContext;
pub use display::{Display, Shown};
pub use error::{Capacity, GpuError};
pub use rebuild::{CpuRebuild, CpuStep, SceneRebuild};
pub use renderer::{Renderer, RendererOptions, TimedFrame};
pub use shader::RecordKind;
