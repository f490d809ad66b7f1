//! Adapter and device: which backend, which limits, and turning wgpu's errors into ours.
//!
//! Start-up is async, as a browser needs it: the command line blocks on these futures, a web page
//! awaits them. An adapter can be asked for a surface (WebGL2 has none to offer before its canvas).

use crate::choice::Choice;
use crate::error::one_line;
use crate::gpu::GpuError;
use crate::gpu::device::pipelines::PipelineCache;
use crate::modes::{Accel, Backend, MemoryMode};
use std::future::Future;
use std::pin::Pin;
use std::sync::{Arc, Mutex, Weak};
use std::task::{Context, Poll, Waker};

/// An instance over `backends`, or over `WGPU_BACKEND`'s where it is set.
pub fn instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    wgpu::Instance::new(desc.with_env())
}

/// A `WGPU_BACKEND` that names no backend wgpu knows is an error, not a silent fall back to no
/// adapter (and so to the CPU): wgpu itself only logs it.
fn check_backend_env() -> Result<(), GpuError> {
    // The names `wgpu::Backends::from_comma_list` reads.
    const KNOWN: [&str; 11] = [
        "vulkan", "vk", "dx12", "d3d12", "metal", "mtl", "opengl", "gles", "gl", "webgpu", "noop",
    ];
    match std::env::var("WGPU_BACKEND") {
        Ok(value)
            if !value.trim().is_empty()
                && !value
                    .split(',')
                    .all(|name| KNOWN.contains(&name.trim().to_lowercase().as_str())) =>
        {
            Err(GpuError::UnknownBackendEnv(value))
        }
        _ => Ok(()),
    }
}

/// The backends to try, in order: the chosen one; else `WGPU_BACKEND`'s; else the primary ones
/// (Vulkan, Metal, DX12) and, only where they offer no adapter, GL, whose probing is slow and noisy.
fn backend_order(backend: Option<Backend>) -> Vec<wgpu::Backends> {
    match backend {
        Some(backend) => vec![backend.backends()],
        None if std::env::var_os("WGPU_BACKEND").is_some() => vec![wgpu::Backends::all()],
        None => vec![wgpu::Backends::PRIMARY, wgpu::Backends::GL],
    }
}

/// An adapter and the device opened on it. Cloning shares them: wgpu's handles are reference
/// counted, so a renderer, a rebuild and a readback each hold their own.
#[derive(Clone, Debug)]
pub struct GpuContext {
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device every raypipe resource is made on.
    pub device: wgpu::Device,
    /// Its queue, which renderers and rebuilds submit to.
    pub queue: wgpu::Queue,
    /// The adapter's name, backend, device type and driver.
    pub info: wgpu::AdapterInfo,
    /// Whether passes can be timed with timestamp queries.
    pub timestamps: bool,
    /// Whether work between passes can be timed too (`TIMESTAMP_QUERY_INSIDE_ENCODERS`).
    pub encoder_timestamps: bool,
    /// The smallest and largest subgroup, where shaders may use subgroup operations.
    pub subgroups: Option<(u32, u32)>,
    /// Whether shaders may trace the driver's acceleration structures with ray queries
    /// ([`Accel::RayQuery`]).
    pub ray_queries: bool,
    /// Why the device was lost, once wgpu said so ([`GpuContext::watch_loss`]).
    lost: Arc<Mutex<Loss>>,
    /// The pipelines compiled on the device, for renderers and builders made again alike.
    pub(crate) pipelines: PipelineCache,
}

/// What a context knows of its device's loss, and who waits to hear of it.
#[derive(Debug, Default)]
struct Loss {
    why: Option<String>,
    /// The tasks awaiting [`GpuContext::when_lost`].
    waiting: Vec<Waker>,
}

impl Loss {
    fn why(loss: &Mutex<Loss>) -> Option<String> {
        loss.lock().unwrap_or_else(|e| e.into_inner()).why.clone()
    }
}

impl Drop for Loss {
    /// Gone with the device, never lost: its waiters hear `None`.
    fn drop(&mut self) {
        self.waiting.drain(..).for_each(Waker::wake);
    }
}

/// [`GpuContext::when_lost`]'s future.
pub struct WhenLost(Weak<Mutex<Loss>>);

impl Future for WhenLost {
    type Output = Option<String>;

    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<String>> {
        let Some(loss) = self.0.upgrade() else {
            return Poll::Ready(None);
        };
        let mut loss = loss.lock().unwrap_or_else(|e| e.into_inner());
        match &loss.why {
            Some(why) => Poll::Ready(Some(why.clone())),
            None => {
                if !loss.waiting.iter().any(|waiting| waiting.will_wake(cx.waker())) {
                    loss.waiting.push(cx.waker().clone());
                }
                Poll::Pending
            }
        }
    }
}

impl GpuContext {
    /// The first adapter wgpu offers on the chosen backends, or `None` when there is none.
    pub async fn new(backend: Option<Backend>) -> Result<Option<Self>, GpuError> {
        check_backend_env()?;
        for backends in backend_order(backend) {
            let instance = instance(backends);
            if let Ok(adapter) = instance.request_adapter(&wgpu::RequestAdapterOptions::default()).await {
                return Self::open(adapter).await.map(Some);
            }
        }
        Ok(None)
    }

    /// Like [`GpuContext::new`], but no adapter is an error.
    pub async fn require(backend: Option<Backend>) -> Result<Self, GpuError> {
        Self::new(backend).await?.ok_or(GpuError::NoAdapter { backend })
    }

    /// An adapter of `instance` that can present to `surface` (a window's, or a canvas's).
    pub async fn for_surface(instance: &wgpu::Instance, surface: &wgpu::Surface<'_>) -> Result<Self, GpuError> {
        check_backend_env()?;
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                compatible_surface: Some(surface),
                ..Default::default()
            })
            .await
            .map_err(|_| GpuError::NoAdapter { backend: None })?;
        Self::open(adapter).await
    }

    /// A context on a device the caller opened itself (a program with its own wgpu device and
    /// window). raypipe uses the features the device has (timestamp queries, subgroups) and is
    /// bound by the limits it was opened with: storage memory needs 8 storage buffers a stage, and
    /// large scenes the adapter's buffer and texture limits (`adapter.limits()`).
    pub fn from_device(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let info = adapter.get_info();
        let features = device.features();
        let subgroups = !cfg!(target_arch = "wasm32") && features.contains(wgpu::Features::SUBGROUP);
        Self {
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            encoder_timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS),
            subgroups: subgroups.then_some((info.subgroup_min_size, info.subgroup_max_size)),
            ray_queries: features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY),
            lost: Arc::default(),
            pipelines: PipelineCache::default(),
            adapter,
            device,
            queue,
            info,
        }
    }

    /// Opens a device on `adapter` with every limit it offers (large scenes need its real buffer and
    /// texture limits, ray queries its acceleration structures' limits), timestamp queries and ray
    /// queries where it has them.
    ///
    /// On GL, the devices of one adapter share its context, where wgpu binds the vertex array of
    /// the device opened last: dropping a second device there leaves the first drawing nothing.
    /// Open one device per GL adapter, or keep the later ones alive.
    pub async fn open(adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        if let Some(warning) = driver_warning(&info) {
            log::warn!("{warning}");
        }
        // Subgroup operations speed up the build's sort. Not in a browser: naga would pass the
        // shader on without the `enable subgroups;` that the browser's compiler asks for.
        // Ray queries: no browser offers them yet.
        let wanted = if cfg!(target_arch = "wasm32") {
            wgpu::Features::TIMESTAMP_QUERY
        } else {
            wgpu::Features::TIMESTAMP_QUERY
                | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
                | wgpu::Features::SUBGROUP
                | wgpu::Features::EXPERIMENTAL_RAY_QUERY
        };
        let required_features = adapter.features() & wanted;
        let experimental_features = if required_features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) {
            // SAFETY: wgpu asks callers of its experimental features to accept that they may still
            // have bugs. Ray queries are used only by `Accel::RayQuery`, whose images the tests hold
            // to the BVH walks'.
            unsafe { wgpu::ExperimentalFeatures::enabled() }
        } else {
            wgpu::ExperimentalFeatures::disabled()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("raypipe"),
                required_features,
                required_limits: adapter.limits(),
                experimental_features,
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device {
                adapter: format!("{} ({:?})", info.name, info.backend),
                message: one_line(&e.to_string()),
            })?;
        // Errors are caught by error scopes around each operation; anything else is reported, not a panic.
        device.on_uncaptured_error(Arc::new(|error| {
            log::warn!("GPU error outside an operation: {}", one_line(&error.to_string()));
        }));
        // The device has the features asked for: what a caller's device has, raypipe uses.
        let ctx = Self::from_device(adapter, device, queue);
        ctx.watch_loss();
        Ok(ctx)
    }

    /// Hears of the device's loss (wgpu's device-lost callback, which this replaces): from then
    /// on the operations of everything made on it fail with [`GpuError::Lost`] rather than with
    /// wgpu's words for the broken pieces. [`GpuContext::open`] calls it; a caller of
    /// [`GpuContext::from_device`] with no callback of its own may.
    pub fn watch_loss(&self) {
        let lost = self.lost.clone();
        self.device.set_device_lost_callback(move |reason, message| {
            let why = match one_line(&message) {
                line if line.is_empty() => format!("{reason:?}").to_lowercase(),
                line => line,
            };
            log::warn!("the GPU was lost ({why})");
            let mut loss = lost.lock().unwrap_or_else(|e| e.into_inner());
            loss.why = Some(why);
            loss.waiting.drain(..).for_each(Waker::wake);
        });
    }

    /// Why the device was lost, if it was (and [`GpuContext::watch_loss`] heard of it).
    pub fn lost(&self) -> Option<String> {
        Loss::why(&self.lost)
    }

    /// Resolves with why the device was lost when [`GpuContext::watch_loss`] hears of it, or with
    /// `None` once the device and every clone of this context are gone. For a program that must
    /// act on a loss while it draws nothing (a browser may stop its animation frames then).
    pub fn when_lost(&self) -> WhenLost {
        WhenLost(Arc::downgrade(&self.lost))
    }

    /// `Err(GpuError::Lost)` once the device is lost: checked before work that would make
    /// resources on it.
    pub fn live(&self) -> Result<(), GpuError> {
        match self.lost() {
            Some(why) => Err(GpuError::Lost { why }),
            None => Ok(()),
        }
    }

    /// `error`, or [`GpuError::Lost`] where the device was lost: what failed then is the loss.
    pub fn explain(&self, error: GpuError) -> GpuError {
        self.live().err().unwrap_or(error)
    }

    /// One line naming the adapter, its backend and driver.
    pub fn describe(&self) -> String {
        describe(&self.info)
    }

    /// The limits the device was opened with.
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// The acceleration modes this device can trace with: all but ray queries where it lacks them.
    pub fn accels(&self) -> Vec<Accel> {
        Accel::ALL
            .iter()
            .copied()
            .filter(|a| self.ray_queries || !a.needs_ray_queries())
            .collect()
    }

    /// The memory modes the fragment shader can read on this device: storage buffers only where
    /// the fragment stage may bind them (WebGL2's may not).
    pub fn memory_modes(&self) -> Vec<MemoryMode> {
        let storage = self.limits().max_storage_buffers_per_shader_stage >= 8;
        [MemoryMode::Uniform, MemoryMode::Storage, MemoryMode::Texture]
            .into_iter()
            .filter(|&m| m != MemoryMode::Storage || storage)
            .collect()
    }

    /// The memory mode for scenes of any size: storage buffers where the fragment stage has them,
    /// textures otherwise, and textures on a browser's software fallback adapter (Chromium's
    /// SwiftShader), where the walks run 1.3x to 2x faster from textures than from storage buffers
    /// (docs/BENCHMARKS.md, "The page against three-mesh-bvh").
    pub fn default_memory(&self) -> MemoryMode {
        let browser_fallback =
            self.info.backend == wgpu::Backend::BrowserWebGpu && self.info.device_type == wgpu::DeviceType::Cpu;
        if self.memory_modes().contains(&MemoryMode::Storage) && !browser_fallback {
            MemoryMode::Storage
        } else {
            MemoryMode::Texture
        }
    }

    /// The BVH walk for a page that names none: the stack walk on a software adapter (Chromium's
    /// SwiftShader under WebGPU or WebGL2, llvmpipe), where it is the fastest (on SwiftShader 1.3x
    /// to 1.8x the threaded walk's speed on the Bunny, level with it on llvmpipe:
    /// docs/BENCHMARKS.md, "The page against three-mesh-bvh"); the threaded walk elsewhere, as
    /// `raypipe` defaults to.
    pub fn default_accel(&self) -> Accel {
        if self.info.device_type == wgpu::DeviceType::Cpu {
            Accel::Stack
        } else {
            Accel::Threaded
        }
    }

    /// Runs `f` inside validation and out-of-memory error scopes; a wgpu error becomes an `Err`.
    pub async fn checked<T>(&self, what: &'static str, f: impl FnOnce() -> Result<T, GpuError>) -> Result<T, GpuError> {
        let scopes = self.error_scopes(what);
        let result = f();
        let popped = scopes.pop().await;
        if popped.is_err() {
            // A pipeline compiled in the scopes may be the one that failed.
            self.pipelines.clear();
        }
        popped?;
        result
    }

    /// Pipelines the device keeps compiled (render and compute), for the next renderer or builder
    /// made from the same shader and layouts.
    pub fn cached_pipelines(&self) -> usize {
        self.pipelines.len()
    }

    /// Opens validation and out-of-memory error scopes around what is recorded until
    /// [`ErrorScopes::pop`]: [`GpuContext::checked`] for work whose wait must borrow nothing.
    pub fn error_scopes(&self, what: &'static str) -> ErrorScopes {
        ErrorScopes {
            what,
            lost: self.lost.clone(),
            memory: self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory),
            validation: self.device.push_error_scope(wgpu::ErrorFilter::Validation),
        }
    }
}

/// Error scopes opened by [`GpuContext::error_scopes`].
pub struct ErrorScopes {
    what: &'static str,
    lost: Arc<Mutex<Loss>>,
    memory: wgpu::ErrorScopeGuard,
    validation: wgpu::ErrorScopeGuard,
}

impl ErrorScopes {
    /// Closes the scopes now; the future says whether wgpu reported an error in them.
    pub fn pop(self) -> impl Future<Output = Result<(), GpuError>> + 'static {
        let (what, lost) = (self.what, self.lost);
        let validation = self.validation.pop();
        let memory = self.memory.pop();
        async move {
            let error = validation.await.or(memory.await);
            match (error, Loss::why(&lost)) {
                (None, _) => Ok(()),
                (Some(_), Some(why)) => Err(GpuError::Lost { why }),
                (Some(error), None) => Err(GpuError::Operation {
                    what,
                    message: one_line(&error.to_string()),
                }),
            }
        }
    }
}

/// The oldest Mesa whose llvmpipe (lavapipe, llvmpipe GL) was seen to run the tracer correctly.
const MESA_TESTED_GOOD: (u32, u32) = (25, 0);

/// Mesa 22.3.6's llvmpipe ends the fragment shader's ray loop early with rays still on the stack
/// (reflections and refractions go missing on scenes with small glass spheres); 25.0.7 is correct.
/// Versions in between were not tested.
pub(crate) fn driver_warning(info: &wgpu::AdapterInfo) -> Option<String> {
    if !info.name.contains("llvmpipe") {
        return None;
    }
    let text = format!("{} {}", info.driver, info.driver_info);
    let version = text.split("Mesa ").nth(1)?;
    let mut numbers = version
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|n| n.parse::<u32>().ok());
    let found = (numbers.next()?, numbers.next().unwrap_or(0));
    (found < MESA_TESTED_GOOD).then(|| {
        format!(
            "Mesa {}.{} llvmpipe is older than the oldest Mesa seen to trace correctly ({}.{}); Mesa 22.3 drops reflected and refracted rays (on Debian 12, install Mesa from bookworm-backports)",
            found.0, found.1, MESA_TESTED_GOOD.0, MESA_TESTED_GOOD.1
        )
    })
}

/// An adapter in one line: its name, backend, device type and driver.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    let driver = [info.driver.as_str(), info.driver_info.as_str()]
        .iter()
        .filter(|s| !s.is_empty())
        .copied()
        .collect::<Vec<_>>()
        .join(" ");
    // A browser's WebGPU may keep the adapter's name and driver to itself.
    let name = if info.name.is_empty() {
        "unnamed adapter"
    } else {
        &info.name
    };
    let driver = if driver.is_empty() {
        "not named".to_string()
    } else {
        driver
    };
    format!("{name} ({:?}, {:?}, driver: {driver})", info.backend, info.device_type)
}

/// A buffer mapping as a future: resolved by wgpu's callback, which a native device fires during
/// `poll` and a browser fires on its own.
pub(crate) fn map_future(
    slice: wgpu::BufferSlice<'_>,
    mode: wgpu::MapMode,
) -> impl Future<Output = Result<(), wgpu::BufferAsyncError>> + use<> {
    let shared = Arc::new(Mutex::new(MapState::default()));
    let callback = Arc::clone(&shared);
    slice.map_async(mode, move |result| {
        let mut state = callback.lock().unwrap_or_else(|e| e.into_inner());
        state.result = Some(result);
        if let Some(waker) = state.waker.take() {
            waker.wake();
        }
    });
    MapFuture { shared }
}

/// Waits for a buffer mapping made by [`map_future`], after the copies it reads were submitted. A
/// native device fires the callback in a blocking `poll`; a browser's WebGPU fires it on its own;
/// WebGL2 (wgpu's GL backend) fires it only in `poll`, which cannot block in a browser: there the
/// wait polls once per task of the browser's event loop, where the GPU's progress shows.
pub(crate) async fn wait_mapped(
    device: &wgpu::Device,
    mapped: impl Future<Output = Result<(), wgpu::BufferAsyncError>>,
) -> Result<(), GpuError> {
    let failed = |e: &dyn std::fmt::Display| GpuError::Readback(e.to_string());
    #[cfg(not(target_arch = "wasm32"))]
    {
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| failed(&e))?;
        mapped.await.map_err(|e| failed(&e))
    }
    #[cfg(target_arch = "wasm32")]
    {
        let mut mapped = std::pin::pin!(mapped);
        loop {
            device.poll(wgpu::PollType::Poll).map_err(|e| failed(&e))?;
            if let Poll::Ready(result) = mapped.as_mut().poll(&mut Context::from_waker(Waker::noop())) {
                return result.map_err(|e| failed(&e));
            }
            next_task().await;
        }
    }
}

/// Resolves in a later task of the browser's event loop (`setTimeout(0)`).
#[cfg(target_arch = "wasm32")]
async fn next_task() {
    use wasm_bindgen::JsCast;
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        let set_timeout = js_sys::Reflect::get(&js_sys::global(), &"setTimeout".into())
            .ok()
            .and_then(|f| f.dyn_into::<js_sys::Function>().ok());
        match set_timeout {
            Some(set_timeout) => {
                let _ = set_timeout.call2(&wasm_bindgen::JsValue::NULL, &resolve, &0.into());
            }
            None => {
                let _ = resolve.call0(&wasm_bindgen::JsValue::NULL);
            }
        }
    });
    let _ = wasm_bindgen_futures::JsFuture::from(promise).await;
}

#[derive(Default)]
struct MapState {
    result: Option<Result<(), wgpu::BufferAsyncError>>,
    waker: Option<Waker>,
}

struct MapFuture {
    shared: Arc<Mutex<MapState>>,
}

impl Future for MapFuture {
    type Output = Result<(), wgpu::BufferAsyncError>;

    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        let mut state = self.shared.lock().unwrap_or_else(|e| e.into_inner());
        match state.result.take() {
            Some(result) => Poll::Ready(result),
            None => {
                state.waker = Some(cx.waker().clone());
                Poll::Pending
            }
        }
    }
}
