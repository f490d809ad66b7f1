//! What raypipe's test binaries share.
//!
//! One test harness for the tests that need a GPU, the shared models, a display or the glTF
//! validator (libtest-mimic): the GPU is opened once per binary and shared by every test (wgpu's
//! error scopes are per thread; on GL, whose context one thread holds at a time and others wait
//! for only a second, the GPU tests take turns while the others run beside them), and a test whose
//! GPU, models, display or validator is missing is reported as *ignored*, with the reason, in the
//! summary a newcomer sees. `RAYPIPE_REQUIRE_GPU=1`, `RAYPIPE_REQUIRE_MODELS=1`,
//! `RAYPIPE_REQUIRE_DISPLAY=1` (window tests: Xvfb) and `RAYPIPE_REQUIRE_VALIDATOR=1` turn a
//! missing one into a failure; `RAYPIPE_ONLY_GPU_TESTS=1` runs the tests that need a GPU alone, and
//! `RAYPIPE_TEST_TIMES=1` prints each test's time.
//!
//! And [`models`]: test models written by independent writers in every format the loaders read.

pub mod models;

use libtest_mimic::{Arguments, Completion, Failed, Trial};
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
    GpuWindowModels(fn(&GpuContext, &Path)),
    /// The Khronos glTF-Validator (Node.js and web/'s npm package `gltf-validator`); the body gets
    /// the repository's root, where `web/validate-gltf.mjs` runs it.
    Validator(fn(&Path)),
}

/// What a body needs besides itself.
#[derive(Clone, Copy, Default)]
struct Needs {
    gpu: bool,
    models: bool,
    display: bool,
    validator: bool,
}

impl Body {
    fn needs(&self) -> Needs {
        let (gpu, models, display, validator) = match self {
            Body::Plain(_) => (false, false, false, false),
            Body::Gpu(_) => (true, false, false, false),
            Body::Models(_) => (false, true, false, false),
            Body::GpuModels(_) => (true, true, false, false),
            Body::GpuWindow(_) => (true, false, true, false),
            Body::GpuWindowModels(_) => (true, true, true, false),
            Body::Validator(_) => (false, false, false, true),
        };
        Needs {
            gpu,
            models,
            display,
            validator,
        }
    }
}

pub struct Test {
    pub name: &'static str,
    pub body: Body,
}

/// `tests![plain a, gpu b, models c, gpu_models d, gpu_window e, gpu_window_models f,
/// validator g]`: tests named after their functions.
#[macro_export]
macro_rules! tests {
    ($($kind:ident $f:path),* $(,)?) => {
        vec![$($crate::Test {
            name: stringify!($f),
            body: $crate::tests!(@body $kind $f),
        }),*]
    };
    (@body plain $f:path) => { $crate::Body::Plain($f) };
    (@body gpu $f:path) => { $crate::Body::Gpu($f) };
    (@body models $f:path) => { $crate::Body::Models($f) };
    (@body gpu_models $f:path) => { $crate::Body::GpuModels($f) };
    (@body gpu_window $f:path) => { $crate::Body::GpuWindow($f) };
    (@body gpu_window_models $f:path) => { $crate::Body::GpuWindowModels($f) };
    (@body validator $f:path) => { $crate::Body::Validator($f) };
}

fn required(variable: &str) -> bool {
    std::env::var(variable).as_deref() == Ok("1")
}

/// The repository's root.
pub fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Where the shared models are (`../shared/models`, beside the repository), if there.
pub fn models_dir() -> Option<PathBuf> {
    let dir = repository().join("../shared/models");
    dir.join("bunny.ply").is_file().then_some(dir)
}

/// `dir`, fresh and empty: what an earlier run left there is removed first, so that no old output
/// can satisfy a new run. (A test binary passes its `CARGO_TARGET_TMPDIR` folder.)
pub fn fresh_dir(dir: PathBuf) -> PathBuf {
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}

/// Whether `tool` is a file in a folder on PATH.
fn on_path(tool: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|path| std::env::split_paths(&path).any(|dir| dir.join(tool).is_file()))
}

/// Whether `xvfb-run`, imagemagick's `import`, `xdotool` and `python3` (which sends a window its
/// close request) are on PATH.
fn virtual_display() -> bool {
    ["xvfb-run", "import", "xdotool", "python3"].into_iter().all(on_path)
}

/// Whether Node.js runs and web/'s `gltf-validator` package is installed (`npm ci --prefix web`).
fn validator() -> bool {
    repository().join("web/node_modules/gltf-validator").is_dir()
        && std::process::Command::new("node").arg("--version").output().is_ok()
}

/// What the tests need that is missing, each with its line for the summary and the variable that
/// makes it a failure.
const MISSING: [(&str, &str, &str); 4] = [
    (
        "no GPU adapter found",
        "RAYPIPE_REQUIRE_GPU",
        "install mesa-vulkan-drivers",
    ),
    (
        "../shared/models/ not found",
        "RAYPIPE_REQUIRE_MODELS",
        "the shared models",
    ),
    (
        "xvfb-run, imagemagick's import, xdotool or python3 not found",
        "RAYPIPE_REQUIRE_DISPLAY",
        "scripts/install-deps.sh installs them",
    ),
    (
        "Node.js or web/node_modules/gltf-validator not found",
        "RAYPIPE_REQUIRE_VALIDATOR",
        "npm ci --prefix web",
    ),
];

struct Resources {
    gpu: Option<GpuContext>,
    models: Option<PathBuf>,
    display: bool,
    validator: bool,
}

impl Resources {
    /// Per need (GPU, models, display, validator): whether it is missing.
    fn missing(&self, needs: Needs) -> [bool; 4] {
        [
            needs.gpu && self.gpu.is_none(),
            needs.models && self.models.is_none(),
            needs.display && !self.display,
            needs.validator && !self.validator,
        ]
    }
}

/// Runs `tests` as libtest would, with the GPU and the models opened once. Under
/// `RAYPIPE_ONLY_GPU_TESTS=1` only the tests that need a GPU run: how a second backend repeats
/// what depends on the backend and nothing else.
pub fn run(mut tests: Vec<Test>) -> ExitCode {
    let args = Arguments::from_args();
    if required("RAYPIPE_ONLY_GPU_TESTS") {
        let before = tests.len();
        tests.retain(|t| t.body.needs().gpu);
        eprintln!(
            "RAYPIPE_ONLY_GPU_TESTS=1: the {} tests that need no GPU are left out",
            before - tests.len()
        );
    }
    let any = |need: fn(Needs) -> bool| tests.iter().any(|t| need(t.body.needs()));
    let gpu = if any(|n| n.gpu) {
        pollster::block_on(GpuContext::new(None)).unwrap_or_else(|e| panic!("opening the GPU failed: {e}"))
    } else {
        None
    };
    if let Some(ctx) = &gpu {
        eprintln!("GPU tests on {}", ctx.describe());
    }
    let resources = Arc::new(Resources {
        gpu,
        models: models_dir(),
        display: any(|n| n.display) && virtual_display(),
        validator: any(|n| n.validator) && validator(),
    });
    let all = Needs {
        gpu: any(|n| n.gpu),
        models: any(|n| n.models),
        display: any(|n| n.display),
        validator: any(|n| n.validator),
    };
    for (missing, (what, variable, how)) in resources.missing(all).into_iter().zip(MISSING) {
        if missing {
            let outcome = if required(variable) {
                format!(", and fail because {variable}=1")
            } else {
                format!(" ({how}; {variable}=1 makes this a failure)")
            };
            eprintln!("{what}: the tests that need it are ignored{outcome}");
        }
    }
    let trials = tests.into_iter().map(|test| trial(test, &resources)).collect();
    libtest_mimic::run(&args, trials).exit_code()
}

/// Under `RAYPIPE_TEST_TIMES=1`, each test's wall time on stderr when it ends, passed or not: where
/// a suite's time goes (on a software adapter, mostly into compiling pipelines the first time).
struct Clock(&'static str, std::time::Instant);

impl Drop for Clock {
    fn drop(&mut self) {
        eprintln!("{:8.2} s {}", self.1.elapsed().as_secs_f64(), self.0);
    }
}

/// A trial that runs `test`'s body, or, where something it needs is missing, is ignored with the
/// reason (a failure where the reason's variable requires it).
fn trial(test: Test, resources: &Arc<Resources>) -> Trial {
    let needs = test.body.needs();
    let resources = Arc::clone(resources);
    Trial::ignorable_test(test.name, move || {
        let missing = resources.missing(needs);
        if let Some((_, (what, variable, _))) = missing.iter().zip(MISSING).find(|(m, _)| **m) {
            if required(variable) {
                return Err(Failed::from(format!("{what}, and {variable}=1")));
            }
            return Ok(Completion::ignored_with(what));
        }
        let gpu = || resources.gpu.as_ref().expect("checked above");
        let models = || resources.models.as_deref().expect("checked above");
        let _turn = (needs.gpu && gpu().info.backend == wgpu::Backend::Gl)
            .then(|| ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner()));
        let _clock = required("RAYPIPE_TEST_TIMES").then(|| Clock(test.name, std::time::Instant::now()));
        match test.body {
            Body::Plain(f) => f(),
            Body::Gpu(f) | Body::GpuWindow(f) => f(gpu()),
            Body::Models(f) => f(models()),
            Body::GpuModels(f) | Body::GpuWindowModels(f) => f(gpu(), models()),
            Body::Validator(f) => f(&repository()),
        }
        Ok(Completion::Completed)
    })
}
