//! The device: adapter and device (`context`), errors, reading buffers and textures back, GPU
//! timestamps, and what compute passes share.

pub mod compute;
pub mod context;
mod error;
pub mod readback;
pub mod timing;

pub use context::GpuContext;
pub use error::{Capacity, GpuError};
