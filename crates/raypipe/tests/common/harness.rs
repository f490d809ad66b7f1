//! One test harness for the tests that need a GPU or the shared models (libtest-mimic): the GPU is
//! opened once per binary and shared by every test (wgpu's error scopes are per thread; on GL,
//! whose context one thread holds at a time and others wait for only a second, the GPU tests take
//! turns while the others run beside them), and a test
//! whose GPU or models are missing is reported as *ignored*, with the reason, in the summary a
//! newcomer sees. `RAYPIPE_REQUIRE_GPU=1`, `RAYPIPE_REQUIRE_MODELS=1` and `RAYPIPE_REQUIRE_DISPLAY=1`
//! (window tests: Xvfb) turn a missing one into a failure.

use libtest_mimic::{Arguments, Failed, Trial};
use raypipe::gpu::GpuContext;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Mutex};

/// Held by each GPU test where the backend cannot serve two threads at once.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// A test's body, by what it needs.
pub enum Body {
    Plain(fn()),
    Gpu(fn(&GpuContext)),
    /// The shared models folder.
    Models(fn(&Path)),
    GpuModels(fn(&GpuContext, &Path)),
    /// A GPU and a virtual X display to open windows on (`xvfb-run`, with imagemagick's `import` to
    /// capture it, `xdotool` to type and drag, `python3` to ask a window to close).
    GpuWindow(fn(&GpuContext)),
}

pub struct Test {
    pub name: &'static str,
    pub body: Body,
}

/// `tests![plain a, gpu b, models c, gpu_models d]`: tests named after their functions.
#[macro_export]
macro_rules! tests {
    ($($kind:ident $f:path),* $(,)?) => {
        vec![$($crate::common::harness::Test {
            name: stringify!($f),
            body: $crate::tests!(@body $kind $f),
        }),*]
    };
    (@body plain $f:path) => { $crate::common::harness::Body::Plain($f) };
    (@body gpu $f:path) => { $crate::common::harness::Body::Gpu($f) };
    (@body models $f:path) => { $crate::common::harness::Body::Models($f) };
    (@body gpu_models $f:path) => { $crate::common::harness::Body::GpuModels($f) };
    (@body gpu_window $f:path) => { $crate::common::harness::Body::GpuWindow($f) };
}

fn required(variable: &str) -> bool {
    std::env::var(variable).as_deref() == Ok("1")
}

/// Where the shared models are (`../shared/models`, beside the repository), if there.
pub fn models_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/models");
    dir.join("bunny.ply").is_file().then_some(dir)
}

/// Whether `xvfb-run`, imagemagick's `import`, `xdotool` and `python3` (which sends a window its
/// close request) are on PATH.
fn virtual_display() -> bool {
    ["xvfb-run", "import", "xdotool", "python3"].iter().all(|tool| {
        std::env::var_os("PATH").is_some_and(|path| std::env::split_paths(&path).any(|dir| dir.join(tool).is_file()))
    })
}

struct Resources {
    gpu: Option<GpuContext>,
    models: Option<PathBuf>,
    display: bool,
}

/// Runs `tests` as libtest would, with the GPU and the models opened once.
pub fn run(tests: Vec<Test>) -> ExitCode {
    let args = Arguments::from_args();
    let needs_gpu = tests
        .iter()
        .any(|t| matches!(t.body, Body::Gpu(_) | Body::GpuModels(_)));
    let gpu = if needs_gpu {
        pollster::block_on(GpuContext::new(None)).unwrap_or_else(|e| panic!("opening the GPU failed: {e}"))
    } else {
        None
    };
    match &gpu {
        Some(ctx) => eprintln!("GPU tests on {}", ctx.describe()),
        None if needs_gpu => eprintln!(
            "no GPU adapter found: the GPU tests are ignored{}",
            if required("RAYPIPE_REQUIRE_GPU") {
                ", and fail because RAYPIPE_REQUIRE_GPU=1"
            } else {
                " (install mesa-vulkan-drivers; RAYPIPE_REQUIRE_GPU=1 makes this a failure)"
            }
        ),
        None => {}
    }
    let models = models_dir();
    let needs_models = tests
        .iter()
        .any(|t| matches!(t.body, Body::Models(_) | Body::GpuModels(_)));
    if needs_models && models.is_none() {
        eprintln!(
            "../shared/models/ not found: the model tests are ignored{}",
            if required("RAYPIPE_REQUIRE_MODELS") {
                ", and fail because RAYPIPE_REQUIRE_MODELS=1"
            } else {
                " (RAYPIPE_REQUIRE_MODELS=1 makes this a failure)"
            }
        );
    }
    let display = virtual_display();
    let needs_display = tests.iter().any(|t| matches!(t.body, Body::GpuWindow(_)));
    if needs_display && !display {
        eprintln!(
            "xvfb-run, imagemagick's import, xdotool or python3 not found: the window tests are ignored{}",
            if required("RAYPIPE_REQUIRE_DISPLAY") {
                ", and fail because RAYPIPE_REQUIRE_DISPLAY=1"
            } else {
                " (scripts/install-deps.sh installs them; RAYPIPE_REQUIRE_DISPLAY=1 makes this a failure)"
            }
        );
    }
    let resources = Arc::new(Resources { gpu, models, display });
    let trials = tests.into_iter().map(|test| trial(test, &resources)).collect();
    libtest_mimic::run(&args, trials).exit_code()
}

fn trial(test: Test, resources: &Arc<Resources>) -> Trial {
    let (wants_gpu, wants_models, wants_display) = match test.body {
        Body::Plain(_) => (false, false, false),
        Body::Gpu(_) => (true, false, false),
        Body::Models(_) => (false, true, false),
        Body::GpuModels(_) => (true, true, false),
        Body::GpuWindow(_) => (true, false, true),
    };
    let missing_gpu = wants_gpu && resources.gpu.is_none();
    let missing_models = wants_models && resources.models.is_none();
    let missing_display = wants_display && !resources.display;
    let must_fail = (missing_gpu && required("RAYPIPE_REQUIRE_GPU"))
        || (missing_models && required("RAYPIPE_REQUIRE_MODELS"))
        || (missing_display && required("RAYPIPE_REQUIRE_DISPLAY"));
    let ignored = (missing_gpu || missing_models || missing_display) && !must_fail;
    let resources = Arc::clone(resources);
    Trial::test(test.name, move || {
        let (gpu, models) = (resources.gpu.as_ref(), resources.models.as_deref());
        let _turn = (wants_gpu && gpu.is_some_and(|g| g.info.backend == wgpu::Backend::Gl))
            .then(|| ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner()));
        match (test.body, gpu, models) {
            (Body::Plain(f), _, _) => f(),
            (Body::Gpu(f), Some(gpu), _) => f(gpu),
            (Body::Models(f), _, Some(models)) => f(models),
            (Body::GpuModels(f), Some(gpu), Some(models)) => f(gpu, models),
            (Body::GpuWindow(f), Some(gpu), _) if resources.display => f(gpu),
            (Body::GpuWindow(_), Some(_), _) => {
                return Err(Failed::from("xvfb-run, import, xdotool or python3 not found"));
            }
            (_, None, _) => return Err(Failed::from("no GPU adapter found")),
            (_, _, None) => return Err(Failed::from("../shared/models/ not found")),
        }
        Ok(())
    })
    .with_ignored_flag(ignored)
}
