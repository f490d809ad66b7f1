//! The GPU side, in three layers and the moving scene over them: the device (context, errors,
//! read-back, timing, compute helpers), the GPU builders (the per-frame LBVH, its threaded layout
//! and wide collapse, skinning and morphing, the driver's ray-query structures), and the tracer
//! (the renderer that traces into its targets in the fragment shader or a compute kernel, its
//! shader's composition, the scene's upload, the traced region, the display pass); `rebuild` drives
//! the builders before each frame, and `moving` owns a moving scene: its poses, its tree's rebuild on
//! the GPU or the CPU, and its renderer. `preamble` is the WGSL every pipeline starts from.

pub mod builders;
pub mod device;
pub mod moving;
#[cfg(feature = "internals")]
pub mod preamble;
#[cfg(not(feature = "internals"))]
pub(crate) mod preamble;
#[cfg(feature = "internals")]
pub mod rebuild;
#[cfg(not(feature = "internals"))]
pub(crate) mod rebuild;
pub mod trace;

pub use device::{Capacity, GpuContext, GpuError};
pub use moving::{MotionError, MovingScene, PoseCost, TreeUpdate};
#[cfg(feature = "internals")]
pub use rebuild::SceneRebuild;
pub use trace::{Display, RecordKind, Renderer, RendererOptions, Shown, TimedFrame};
