//! The device: adapter and device (`context`), errors, reading buffers and textures back, GPU
//! timestamps, and what compute passes share.

pub(crate) mod compute;
pub mod context;
mod error;
pub(crate) mod pipelines;
#[cfg(feature = "internals")]
pub mod readback;
#[cfg(not(feature = "internals"))]
pub(crate) mod readback;
pub(crate) mod timing;

pub use context::GpuContext;
pub use error::{Capacity, GpuError};
