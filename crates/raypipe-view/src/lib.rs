//! raypipe's live viewer: the paper's system in a window. Every frame is traced in the fragment
//! shader and shown by the display pass; moving scenes rebuild their BVH on the GPU every frame;
//! the camera, the acceleration and memory modes, the bounce depth and the view change live, from
//! keys and from a small egui panel. While nothing moves, each frame adds a jittered sample per
//! pixel, up to a cap, and the display shows their mean.
//!
//! The viewer reads no files and writes none: its host (the `raypipe view` command) loads dropped
//! files and saves screenshots. The tracer, the camera and the modes build for wasm32 too, where
//! the web page (crates/raypipe-web) uses them with controls of its own; the window is native only.

#[cfg(not(target_arch = "wasm32"))]
mod app;
mod camera;
#[cfg(not(target_arch = "wasm32"))]
mod panel;
pub mod player;
pub mod tracer;

pub use camera::CameraControl;
pub use player::{Clock, FlyKeys, FrameReport, Player, Screen, Timings, TracerRequest, overlay_pass, surface_config};
pub use tracer::{TraceError, Tracer, next_texture, present_format};

use raypipe::gpu::{GpuContext, GpuError};
use raypipe::image::Frame;
use raypipe::image::tonemap::DisplayTransform;
use raypipe::modes::Aov;
use raypipe::modes::Backend;
use raypipe::modes::{Accel, Builder, Integrator, MemoryMode, Pipeline};
use raypipe::scene::{Environment, Scene};
use std::path::{Path, PathBuf};

/// What the viewer traces with; every field can change while it runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Modes {
    /// The stage that traces: the fragment shader of a full-screen triangle, or a compute kernel.
    pub pipeline: Pipeline,
    pub accel: Accel,
    /// How a still scene's BVH is built (a moving scene's is the LBVH, rebuilt every frame).
    pub builder: Builder,
    pub memory: MemoryMode,
    /// Bounces after the primary ray.
    pub depth: u32,
    /// How light is carried: Whitted's or the path tracer.
    pub integrator: Integrator,
    pub view: Aov,
    /// Whether moving scenes stand still (at the time they reached).
    pub paused: bool,
    /// Whether presentation waits for the display's refresh.
    pub vsync: bool,
    /// The colour view's exposure and tone map (screenshots take them too).
    pub display: DisplayTransform,
}

/// A key that changes a mode, as the window and the page both bind them: B, G, M, V, [ and ], I,
/// Space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeKey {
    /// B: the next acceleration mode.
    Accel,
    /// G: the next pipeline.
    Pipeline,
    /// M: the next memory mode.
    Memory,
    /// V: the next view.
    View,
    /// [: one bounce less.
    FewerBounces,
    /// ]: one bounce more.
    MoreBounces,
    /// I: the other integrator.
    Integrator,
    /// Space: pause or resume the motion.
    Pause,
}

impl ModeKey {
    /// The key by its name, which is the same in winit's `KeyCode` and a browser's
    /// `KeyboardEvent.code`.
    pub fn from_code(code: &str) -> Option<Self> {
        Some(match code {
            "KeyB" => Self::Accel,
            "KeyG" => Self::Pipeline,
            "KeyM" => Self::Memory,
            "KeyV" => Self::View,
            "BracketLeft" => Self::FewerBounces,
            "BracketRight" => Self::MoreBounces,
            "KeyI" => Self::Integrator,
            "Space" => Self::Pause,
            _ => return None,
        })
    }
}

/// The variant after `value` in `T::ALL`, round to the first.
pub fn next<T: raypipe::Choice>(value: T) -> T {
    next_of(value, T::ALL)
}

/// The value after `value` among `offered`, round to the first; the first where `value` is not
/// among them.
pub fn next_of<T: Copy + PartialEq>(value: T, offered: &[T]) -> T {
    match offered.iter().position(|&v| v == value) {
        Some(i) => offered[(i + 1) % offered.len()],
        None => offered[0],
    }
}

impl Modes {
    /// The modes `key` asks for, on a device that traces with the acceleration modes `accels`
    /// ([`GpuContext::accels`]: ray queries where it has them).
    pub fn after(mut self, key: ModeKey, accels: &[Accel]) -> Modes {
        match key {
            ModeKey::Accel => self.accel = next_of(self.accel, accels),
            ModeKey::Pipeline => self.pipeline = next(self.pipeline),
            ModeKey::Memory => self.memory = next(self.memory),
            ModeKey::View => self.view = next(self.view),
            ModeKey::FewerBounces => self.depth = self.depth.saturating_sub(1),
            ModeKey::MoreBounces => self.depth = (self.depth + 1).min(raypipe::scene::MAX_DEPTH_LIMIT),
            ModeKey::Integrator => self.integrator = next(self.integrator),
            ModeKey::Pause => self.paused = !self.paused,
        }
        self
    }

    /// Whether going from `current` to these modes needs a new tracer (another shader or scene
    /// records); the other views share one, but the cost view needs the shader's cost variant.
    pub fn needs_new_tracer(&self, current: &Modes) -> bool {
        (
            self.pipeline,
            self.accel,
            self.builder,
            self.memory,
            self.depth,
            self.integrator,
        ) != (
            current.pipeline,
            current.accel,
            current.builder,
            current.memory,
            current.depth,
            current.integrator,
        ) || (self.view == Aov::Cost) != (current.view == Aov::Cost)
    }

    /// Whether the device can trace with these modes at all.
    pub fn check(&self, ctx: &GpuContext) -> Result<(), ModesError> {
        if !ctx.memory_modes().contains(&self.memory) {
            return Err(ModesError::NoMemory {
                adapter: ctx.describe(),
                memory: self.memory,
            });
        }
        if !ctx.accels().contains(&self.accel) {
            return Err(ModesError::NoRayQueries {
                adapter: ctx.describe(),
            });
        }
        Ok(())
    }
}

/// Why modes cannot serve a scene on a device.
#[derive(Debug, thiserror::Error)]
pub enum ModesError {
    #[error("{adapter} has no {memory} memory for fragment shaders")]
    NoMemory { adapter: String, memory: MemoryMode },
    #[error("{adapter} has no ray queries (--accel rayquery needs Vulkan, DX12 or Metal ray queries)")]
    NoRayQueries { adapter: String },
    #[error(
        "the {0} builder builds a still scene's tree once; this scene moves, and its tree is rebuilt every frame by the LBVH"
    )]
    BuilderCannotFollowMotion(Builder),
}

/// A run that draws a fixed number of frames and exits: for tests and demos.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    /// Frames to draw before exiting.
    pub frames: u32,
    /// Where the last frame is saved, as `P` saves it.
    pub screenshot: Option<PathBuf>,
    /// Degrees the camera turns about its target each frame.
    pub orbit_degrees: f32,
    /// Files opened after the first frame, as if dropped on the window.
    pub drops: Vec<PathBuf>,
}

pub struct ViewerOptions {
    /// The scene's name, for the title and messages.
    pub name: String,
    /// The scene, at its starting image size (the window's inner size) and camera.
    pub scene: Scene,
    pub modes: Modes,
    /// Whether `modes`' tone map was asked for: if not, a file dropped later is shown with its
    /// scene's own (a glTF's Khronos PBR Neutral, say).
    pub tone_map_chosen: bool,
    /// Whether `modes`' integrator was asked for: if not, a file dropped later is traced with its
    /// scene's own (path for a glTF file).
    pub integrator_chosen: bool,
    /// Samples per pixel a still frame gathers, one per frame, before the viewer stops tracing
    /// (progressive anti-aliasing; 1 shows `render`'s unjittered image).
    pub samples: u32,
    /// Where a moving scene's motion starts, in seconds.
    pub time: f32,
    pub backend: Option<Backend>,
    pub script: Option<Script>,
}

/// What the viewer asks of the program that runs it.
pub trait Host {
    /// Loads a dropped file as a scene.
    fn load(&self, path: &Path) -> Result<Scene, HostError>;
    /// Loads a dropped `.hdr` or `.exr` as an environment for the current scene.
    fn load_environment(&self, path: &Path) -> Result<Environment, HostError>;
    /// Saves a frame (the linear frame, as read back) to `path`, as `raypipe render` writes files:
    /// `view`, with colour through `transform`.
    fn save(&self, frame: &Frame, view: Aov, transform: &DisplayTransform, path: &Path) -> Result<(), HostError>;
    /// Where `P` saves its next screenshot of `view`.
    fn screenshot_path(&self, view: Aov) -> PathBuf;
}

/// A file the host could not load or save: the file, and the host's one line on why, in its own
/// words (a command line names its flags).
#[derive(Debug, thiserror::Error)]
#[error("{reason}")]
pub struct HostError {
    pub path: PathBuf,
    pub reason: String,
}

/// Why `P` (or a script's last frame) saved no screenshot.
#[derive(Debug, thiserror::Error)]
pub enum ScreenshotError {
    #[error("no frame yet")]
    NoFrame,
    #[error(transparent)]
    Read(#[from] GpuError),
    #[error(transparent)]
    Save(#[from] HostError),
}

#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error("no display to open a window on (neither DISPLAY nor WAYLAND_DISPLAY is set)")]
    NoDisplay,
    #[error("cannot open a window: {0}")]
    Window(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The scene could not be traced with the modes asked for.
    #[error(transparent)]
    Trace(#[from] TraceError),
    #[error(transparent)]
    Screenshot(#[from] ScreenshotError),
}

/// What a run drew, and how fast.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Summary {
    pub frames: u32,
    /// Median GPU time of the trace pass, where the adapter has timestamp queries.
    pub trace_ms: Option<f64>,
    /// Median wall-clock time from one frame to the next: trace, display pass, panel and present.
    pub frame_ms: f64,
}

/// Opens the window and runs until it is closed, or until the script's frames are drawn.
#[cfg(not(target_arch = "wasm32"))]
pub fn run(options: ViewerOptions, host: Box<dyn Host>) -> Result<Summary, ViewError> {
    let wayland = std::env::var_os("WAYLAND_DISPLAY").is_some();
    if std::env::var_os("DISPLAY").is_none() && !wayland {
        return Err(ViewError::NoDisplay);
    }
    app::run(options, host)
}
