//! raypipe: Whitted ray tracing in the fragment shader of the ordinary graphics pipeline.
//!
//! On a wgpu device of the program's own (`examples/offscreen.rs` opens one and writes the PNG):
//!
//! ```no_run
//! use raypipe::bvh::morton::MortonBits;
//! use raypipe::gpu::{GpuContext, Renderer, RendererOptions};
//! use raypipe::records::PackedScene;
//! use raypipe::scene::Scene;
//! # async fn run(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue)
//! #     -> Result<(), Box<dyn std::error::Error>> {
//! let ctx = GpuContext::from_device(adapter, device, queue);
//! let mut scene = Scene::load("whitted")?;
//! (scene.settings.width, scene.settings.height) = (320, 240);
//! let mut packed = PackedScene::new(&scene)?;
//! packed.build_bvh();
//! let mut renderer = Renderer::new(&ctx, &packed, RendererOptions::default()).await?;
//! let frame = renderer.read_frame().await?.frame;
//! // 320 x 240 RGB bytes, sRGB-encoded: what `raypipe render whitted --width 320 --height 240`
//! // writes as its PNG.
//! let rgb = frame.display().to_bytes();
//! # Ok(())
//! # }
//! ```
//!
//! Data flows scene → GPU records (the packed scene, which builds its BVH over the packed
//! primitives) → (GPU upload → full-screen triangle → fragment shader) or (CPU reference tracer,
//! function by function the shader's twin) → frame. Modules use lower layers only, in this order:
//! `choice`, `constants` (the numbers both tracers agree on), `parallel` and `rng` at the bottom;
//! `modes`; `error`; `input`; `bvh`; `mesh`; `scene` (a model, with no GPU codes); `records` (the
//! one encoding of a scene for the GPU); `image` (frames and their comparison); and the two
//! tracers, `cpu` and `gpu`, which use all of these and not each other. No files of one folder
//! use each other in a circle. The crate's test `tests/cpu/layers.rs` holds both.
//!
//! The API is what this page's modules show. The `internals` feature, which only the project's
//! own tests and benchmarks turn on (through `raypipe-test-support`), also makes public what they
//! check beneath it: the CPU twin's walks, hit tests and per-pixel tracer, the shaders' sources and
//! their records' layouts (`records::layouts`), the shader's composition and upload, the skinning
//! pass, the threaded layout's kernel and the per-frame rebuild (`gpu::SceneRebuild`).
//!
//! The library prints nothing and reads no flags: notices go through the `log` crate, errors are
//! typed ([`error`], [`gpu::GpuError`]), and it builds for `wasm32-unknown-unknown`.
//!
//! A program with a wgpu device of its own traces through [`gpu::GpuContext::from_device`]: load
//! or build a [`scene::Scene`], pack it ([`records::PackedScene`], with its BVH), make a
//! [`gpu::Renderer`], and read the frame back or record it into the program's encoder;
//! `examples/offscreen.rs` does so on one page (`cargo run --release --example offscreen --
//! out.png`). A moving scene goes to [`gpu::MovingScene`] instead, which poses it at each time,
//! rebuilds (or refits) its tree on the GPU or the CPU as the memory mode allows, and records that
//! work before the trace; the CPU reference poses with its CPU half, [`records::PosedScene`].

// Every public item says what it is.
#![deny(missing_docs)]

pub mod bvh;
pub mod choice;
pub mod constants;
pub mod cpu;
pub mod error;
pub mod gpu;
pub mod image;
pub mod input;
pub mod mesh;
pub mod modes;
mod parallel;
pub mod records;
pub mod rng;
pub mod scene;

pub use choice::Choice;
pub use error::{Element, InputError};
pub use modes::{Accel, MemoryMode, Pipeline};
