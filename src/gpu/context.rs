//! Adapter and device: which backend, which limits, and turning wgpu's errors into ours.

use anyhow::{Context, anyhow};
use clap::ValueEnum;

/// A backend the user can ask for; without one, `WGPU_BACKEND` or wgpu's default order decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl Backend {
    fn backends(self) -> wgpu::Backends {
        match self {
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
            Backend::Metal => wgpu::Backends::METAL,
            Backend::Dx12 => wgpu::Backends::DX12,
        }
    }
}

/// An instance over `backends`, or over `WGPU_BACKEND`'s where it is set.
pub fn instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    wgpu::Instance::new(desc.with_env())
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

pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Whether render passes can be timed with timestamp queries.
    pub timestamps: bool,
}

impl GpuContext {
    /// The first adapter wgpu offers on the chosen backends, or `None` when there is none.
    pub fn new(backend: Option<Backend>) -> anyhow::Result<Option<Self>> {
        let found = backend_order(backend).into_iter().find_map(|backends| {
            pollster::block_on(instance(backends).request_adapter(&wgpu::RequestAdapterOptions::default())).ok()
        });
        let Some(adapter) = found else {
            return Ok(None);
        };
        let info = adapter.get_info();
        if let Some(warning) = driver_warning(&info) {
            eprintln!("warning: {warning}");
        }
        let required_features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("raypipe"),
            required_features,
            // Everything the adapter offers: large scenes need its real buffer and texture limits.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .with_context(|| format!("cannot open a device on adapter {} ({:?})", info.name, info.backend))?;
        // Errors are caught by error scopes around each operation; anything else is reported, not a panic.
        device.on_uncaptured_error(std::sync::Arc::new(|error| {
            eprintln!(
                "warning: GPU error outside an operation: {}",
                one_line(&error.to_string())
            );
        }));
        Ok(Some(Self {
            timestamps: required_features.contains(wgpu::Features::TIMESTAMP_QUERY),
            adapter,
            device,
            queue,
            info,
        }))
    }

    /// Like [`GpuContext::new`], but no adapter is an error.
    pub fn require(backend: Option<Backend>) -> anyhow::Result<Self> {
        Self::new(backend)?.ok_or_else(|| match backend {
            Some(b) => anyhow!("no GPU adapter found on the {b:?} backend"),
            None => {
                anyhow!("no GPU adapter found (install a driver, for example mesa-vulkan-drivers)")
            }
        })
    }

    /// One line naming the adapter, its backend and driver.
    pub fn describe(&self) -> String {
        describe(&self.info)
    }

    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// Runs `f` inside validation and out-of-memory error scopes; a wgpu error becomes an `Err`.
    pub fn checked<T>(&self, what: &str, f: impl FnOnce() -> anyhow::Result<T>) -> anyhow::Result<T> {
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = f();
        let validation = pollster::block_on(validation.pop());
        let memory = pollster::block_on(memory.pop());
        if let Some(error) = validation.or(memory) {
            return Err(anyhow!("{what} failed on the GPU: {}", one_line(&error.to_string())));
        }
        result
    }
}

/// The oldest Mesa whose llvmpipe (lavapipe, llvmpipe GL) was seen to run the tracer correctly.
const MESA_TESTED_GOOD: (u32, u32) = (25, 0);

/// Mesa 22.3.6's llvmpipe ends the fragment shader's ray loop early with rays still on the stack
/// (reflections and refractions go missing on scenes with small glass spheres); 25.0.7 is correct.
/// Versions in between were not tested.
pub fn driver_warning(info: &wgpu::AdapterInfo) -> Option<String> {
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

pub fn describe(info: &wgpu::AdapterInfo) -> String {
    let driver = [info.driver.as_str(), info.driver_info.as_str()]
        .iter()
        .filter(|s| !s.is_empty())
        .copied()
        .collect::<Vec<_>>()
        .join(" ");
    format!(
        "{} ({:?}, {:?}, driver: {})",
        info.name, info.backend, info.device_type, driver
    )
}

/// wgpu's messages span lines; ours are one.
pub fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}
