//! One test harness for the tests that need a GPU or the shared models (libtest-mimic): the GPU is
//! opened once per binary and shared by every test (wgpu's error scopes are per thread; on GL,
//! whose context one thread holds at a time and others wait for only a second, the GPU tests take
//! turns while the others run beside them), and a test
//! whose GPU or models are missing is reported as *ignored*, with the reason, in the summary a
//! newcomer sees. `RAYPIPE_REQUIRE_GPU=1` and `RAYPIPE_REQUIRE_MODELS=1` turn a missing one into a
//! failure.

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
}

fn required(variable: &str) -> bool {
    std::env::var(variable).as_deref() == Ok("1")
}

/// Where the shared models are (`../shared/models`, beside the repository), if there.
pub fn models_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/models");
    dir.join("bunny.ply").is_file().then_some(dir)
}

struct Resources {
    gpu: Option<GpuContext>,
    models: Option<PathBuf>,
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
    let resources = Arc::new(Resources { gpu, models });
    let trials = tests.into_iter().map(|test| trial(test, &resources)).collect();
    libtest_mimic::run(&args, trials).exit_code()
}

fn trial(test: Test, resources: &Arc<Resources>) -> Trial {
    let (wants_gpu, wants_models) = match test.body {
        Body::Plain(_) => (false, false),
        Body::Gpu(_) => (true, false),
        Body::Models(_) => (false, true),
        Body::GpuModels(_) => (true, true),
    };
    let missing_gpu = wants_gpu && resources.gpu.is_none();
    let missing_models = wants_models && resources.models.is_none();
    let must_fail =
        (missing_gpu && required("RAYPIPE_REQUIRE_GPU")) || (missing_models && required("RAYPIPE_REQUIRE_MODELS"));
    let ignored = (missing_gpu || missing_models) && !must_fail;
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
            (_, None, _) => return Err(Failed::from("no GPU adapter found")),
            (_, _, None) => return Err(Failed::from("../shared/models/ not found")),
        }
        Ok(())
    })
    .with_ignored_flag(ignored)
}
