//! What can go wrong on the GPU, typed so that callers word their own messages and hints.

use crate::error::MissingBvh;
use crate::modes::Backend;
use crate::modes::{MemoryMode, Pipeline};
use std::fmt;

/// What can go wrong on the GPU (see the module).
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter, on the backend asked for or on any.
    #[error("no GPU adapter found{}", match .backend {
        Some(backend) => format!(" on the {backend} backend"),
        None => " (install a driver, for example mesa-vulkan-drivers)".to_string(),
    })]
    NoAdapter {
        /// The backend asked for; `None` for any.
        backend: Option<Backend>,
    },
    /// The adapter would not open a device.
    #[error("cannot open a device on adapter {adapter}: {message}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// The driver's words.
        message: String,
    },
    /// wgpu reported a validation or out-of-memory error while `what` ran.
    #[error("{what} failed on the GPU: {message}")]
    Operation {
        /// What ran ("the LBVH build", say).
        what: &'static str,
        /// wgpu's words.
        message: String,
    },
    /// The scene needs more of something than the adapter's limits allow (the driver's
    /// acceleration structures' instances or primitives, say).
    #[error("the scene needs {needed} {what}, where the adapter allows {allowed}")]
    Limit {
        /// What is counted, in the plural.
        what: &'static str,
        /// How many the scene needs.
        needed: u64,
        /// How many the adapter allows.
        allowed: u64,
    },
    /// One of the scene's record arrays does not fit the memory mode on this adapter.
    #[error("scene too big for {memory} memory: {records} {array} records need {needed}, the adapter allows {allowed}")]
    TooBig {
        /// The memory mode asked for.
        memory: MemoryMode,
        /// The record array's name ("triangle", say).
        array: &'static str,
        /// Its records.
        records: usize,
        /// What they need.
        needed: Capacity,
        /// What the adapter allows.
        allowed: Capacity,
    },
    /// A scene rewritten in a renderer has another count of records than the one it was made
    /// with: a renderer's arrays keep their size (a moving scene moves its records, never adds any).
    #[error("rewriting the scene: {records} {array} records, where {uploaded} were uploaded")]
    RecordCountChanged {
        /// The record array's name.
        array: &'static str,
        /// Its records now.
        records: usize,
        /// Its records when the renderer was made.
        uploaded: usize,
    },
    /// A BVH rebuilt on the GPU reaches the shader through storage buffers only.
    #[error("a BVH rebuilt on the GPU is read from storage memory, not {memory} memory")]
    RebuildNeedsStorage {
        /// The memory mode asked for.
        memory: MemoryMode,
    },
    /// A walk that reads a BVH was given a scene without one.
    #[error(transparent)]
    MissingBvh(#[from] MissingBvh),
    /// The image is wider or taller than the adapter's largest texture.
    #[error("image {width}x{height} is larger than the adapter's maximum texture size {max}")]
    ImageTooLarge {
        /// The image's width, in pixels.
        width: u32,
        /// Its height.
        height: u32,
        /// The adapter's largest texture side.
        max: u32,
    },
    /// A frame target of this size is more memory than the adapter allocates at once.
    #[error(
        "image {width}x{height} needs {bytes} bytes per frame target, more than the adapter's largest allocation ({max} bytes, about {max_pixels} pixels)"
    )]
    FrameTooLarge {
        /// The image's width, in pixels.
        width: u32,
        /// Its height.
        height: u32,
        /// The bytes of one frame target of that size.
        bytes: u64,
        /// The adapter's largest buffer, in bytes.
        max: u64,
        /// About the most pixels a frame target of that many bytes holds.
        max_pixels: u64,
    },
    /// The adapter lacks what a mode needs (ray queries, say).
    #[error("adapter {adapter} cannot {what}")]
    Unsupported {
        /// The adapter's name.
        adapter: String,
        /// What it cannot do, after "cannot".
        what: &'static str,
    },
    /// The adapter lacks what `pipeline` needs.
    #[error("adapter {adapter} cannot {what}, which the {pipeline} pipeline needs")]
    PipelineUnsupported {
        /// The adapter's name.
        adapter: String,
        /// The pipeline asked for.
        pipeline: Pipeline,
        /// What the adapter cannot do, after "cannot".
        what: &'static str,
    },
    /// Mapping a read-back buffer failed.
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    /// The device was lost (a driver reset, a GPU removed, a browser's decision): nothing made on
    /// it works again; a new device must be opened.
    #[error("the GPU was lost ({why})")]
    Lost {
        /// wgpu's reason.
        why: String,
    },
    /// `WGPU_BACKEND` names no backend.
    #[error("WGPU_BACKEND={0:?} names no backend wgpu knows (vulkan, gl, metal, dx12, webgpu)")]
    UnknownBackendEnv(String),
}

/// What a record array needs, or an adapter allows, in the unit of its memory mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Capacity {
    /// A buffer binding's bytes.
    Bytes(u64),
    /// A texture's rows, of `texels_per_row` where they are a record array's.
    TextureRows {
        /// The rows.
        rows: u64,
        /// Texels in a row, where the rows are a record array's.
        texels_per_row: Option<u32>,
    },
    /// Indices exact in the f32 texels of texture memory: at most `records` of them, where given.
    ExactIndices {
        /// The most records whose indices an f32 holds exactly, where given.
        records: Option<u64>,
    },
}

impl fmt::Display for Capacity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Capacity::Bytes(bytes) => write!(f, "{bytes} bytes"),
            Capacity::TextureRows {
                rows,
                texels_per_row: Some(width),
            } => write!(f, "{rows} rows of {width} texels"),
            Capacity::TextureRows {
                rows,
                texels_per_row: None,
            } => write!(f, "{rows} rows"),
            Capacity::ExactIndices { records: None } => f.write_str("exact float indices"),
            Capacity::ExactIndices { records: Some(n) } => {
                write!(f, "{n} records, what a texel can index exactly")
            }
        }
    }
}
