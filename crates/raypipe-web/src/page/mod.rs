//! The viewer on a canvas: WebGPU where the browser has it, else WebGL2; every frame traced in the
//! fragment shader (or the compute kernel, on WebGPU) and shown by the display pass, from the
//! browser's animation frames. The page's HTML controls call [`Viewer`]'s methods; what runs is
//! published as a [`Status`] where it says something new.
//!
//! Building a tracer is async in a browser (shader compilation and error scopes resolve on the
//! browser's event loop), so a switch of mode or scene is started here and lands a few frames later;
//! until then the previous tracer keeps drawing, and a failed switch leaves it in place with its
//! message shown.

use crate::params::{StartParams, WebBackend};
use crate::status::{Status, StatusCamera, Value};
use raypipe::Choice;
use raypipe::gpu::GpuContext;
use raypipe::scene::model::Floor;
use raypipe::scene::{Environment, Scene};
use raypipe_view::{FlyKeys, Modes, Player, Screen, Timings, TracerRequest};
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;
use web_time::Instant;

mod loss;
mod viewer;

/// A viewer's handle: the page's controls, or the npm package's `Viewer`, call its methods.
#[wasm_bindgen]
pub struct Viewer {
    page: Rc<RefCell<Page>>,
}

struct Page {
    canvas: web_sys::HtmlCanvasElement,
    backend: WebBackend,
    screen: Screen,
    /// The scene, modes, camera, tracer and clock. Its frame rate is the wall clock's between
    /// presented frames: the browser paces them by the GPU's progress. Timestamp queries are not
    /// read here ([`Timings::Skip`]).
    player: Player,
    /// A tracer is being built.
    busy: bool,
    /// The request made while one was being built (or while the GPU is lost): built next.
    waiting: Option<Pending>,
    fly: FlyKeys,
    started: Instant,
    first_frame_ms: Option<f64>,
    /// What a model file opened here stands on.
    floor: Floor,
    /// The file the scene was opened from, kept to open it again when the floor changes.
    opened: Option<OpenedFile>,
    /// The environment opened here (`?environment=`, a dropped .hdr or .exr): it lights every
    /// scene opened after it, in place of the scene's own.
    environment: Option<(String, Environment)>,
    gpu: GpuState,
    /// Counts the devices this viewer has opened: a tracer built on an earlier one is not shown.
    generation: u32,
    /// The last status published, as JavaScript reads it and as it was made, when, and who hears
    /// of the next ([`Viewer::on_status`]).
    status: JsValue,
    shown: Option<Status>,
    published_at: Instant,
    listener: Option<js_sys::Function>,
    /// The animation-frame callback and the frame it asked for, dropped by [`Viewer::dispose`].
    frames: FrameCallback,
    frame_request: Option<i32>,
    /// The canvas's context-loss listeners (WebGL2), removed by [`Viewer::dispose`].
    canvas_listeners: Vec<(&'static str, EventListener)>,
    disposed: bool,
}

/// Whether the viewer's device can draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GpuState {
    Live,
    /// Lost (a WebGL2 context lost, a WebGPU device lost): nothing is drawn or built until a new
    /// device is open.
    Lost,
    /// A new device is open and the tracer is being built on it; frames wait for it.
    Restoring,
}

/// A tracer request waiting to be built, with the file it came from and the promise it settles.
struct Pending {
    request: TracerRequest,
    source: Option<OpenedFile>,
    settle: Option<Settle>,
}

/// A `load` promise's two ends: resolved when the scene it opened is shown, rejected with the
/// one-line message otherwise.
struct Settle {
    resolve: js_sys::Function,
    reject: js_sys::Function,
}

impl Settle {
    fn new() -> (js_sys::Promise, Settle) {
        let mut ends = None;
        let promise = js_sys::Promise::new(&mut |resolve, reject| ends = Some(Settle { resolve, reject }));
        (promise, ends.expect("a Promise runs its executor at once"))
    }

    fn done(self, result: Result<(), String>) {
        let _ = match result {
            Ok(()) => self.resolve.call0(&JsValue::NULL),
            Err(why) => self.reject.call1(&JsValue::NULL, &js_sys::Error::new(&why)),
        };
    }
}

fn settle(settle: Option<Settle>, result: Result<(), String>) {
    if let Some(settle) = settle {
        settle.done(result);
    }
}

/// Starts a viewer on `canvas` with the settings of `query` (the URL's `?...`, or the package's
/// options as a query). A bad setting is shown and skipped, unless `strict`, where it rejects.
/// Where the viewer cannot start (no WebGPU and no WebGL2, a scene that does not load), the promise
/// rejects with the one-line reason.
#[wasm_bindgen]
pub async fn start(canvas: web_sys::HtmlCanvasElement, query: String, strict: bool) -> Result<Viewer, JsError> {
    crate::console::install();
    let search =
        web_sys::UrlSearchParams::new_with_str(&query).map_err(|_| JsError::new("cannot read the settings' query"))?;
    let pairs = query_pairs(&search);
    let (params, errors) = StartParams::from_pairs(pairs.iter().map(|(k, v)| (k.as_str(), v.as_str())));
    if strict && !errors.is_empty() {
        return Err(JsError::new(&errors.join("; ")));
    }
    let page = open(canvas, params, errors).await.map_err(|why| JsError::new(&why))?;
    let page = Rc::new(RefCell::new(page));
    Page::watch_canvas(&page);
    Page::watch_device(&page);
    page.borrow_mut().publish();
    animate(&page);
    Ok(Viewer { page })
}

/// What the page's controls offer, from Rust: `{ choices: { accel: [names], builder, memory,
/// pipeline, aov }, accept: ".ply,...", maxDepth, maxSpp }`. The page's script fills its controls
/// from it.
#[wasm_bindgen]
pub fn controls() -> JsValue {
    let object = js_sys::Object::new();
    let set = |target: &js_sys::Object, key: &str, value: JsValue| {
        js_sys::Reflect::set(target, &key.into(), &value).expect("setting a property of a plain object");
    };
    let choices = js_sys::Object::new();
    for (key, names) in crate::params::control_choices() {
        let list: js_sys::Array = names.into_iter().map(JsValue::from).collect();
        set(&choices, key, list.into());
    }
    set(&object, "choices", choices.into());
    set(&object, "accept", crate::params::file_accept().into());
    set(&object, "maxDepth", raypipe::scene::MAX_DEPTH_LIMIT.into());
    set(&object, "maxSpp", crate::params::MAX_SPP.into());
    object.into()
}

fn query_pairs(search: &web_sys::UrlSearchParams) -> Vec<(String, String)> {
    let mut pairs = Vec::new();
    let entries = js_sys::try_iter(&search.entries()).ok().flatten();
    for entry in entries.into_iter().flatten().flatten() {
        let entry: js_sys::Array = entry.unchecked_into();
        pairs.push((
            entry.get(0).as_string().unwrap_or_default(),
            entry.get(1).as_string().unwrap_or_default(),
        ));
    }
    pairs
}

/// A scene by its built-in name; the page has no files but those it is given.
fn builtin_scene(name: &str) -> Result<Scene, String> {
    match raypipe::scene::builtin::by_name(name) {
        Ok(Some(scene)) => Ok(scene),
        Ok(None) => Err(format!(
            "unknown scene '{name}': the page has the built-ins ({}); open a file for anything else",
            raypipe::scene::builtin::NAMES.join(", ")
        )),
        Err(error) => Err(error.to_string()),
    }
}

/// The adapter and the canvas's surface: WebGPU first (a WebGPU adapter is asked for before the
/// canvas gets a context, since a canvas keeps the first kind it gives), else WebGL2.
async fn connect(
    canvas: &web_sys::HtmlCanvasElement,
    wanted: Option<WebBackend>,
) -> Result<(WebBackend, GpuContext, wgpu::Surface<'static>), String> {
    let mut tried = Vec::new();
    if wanted != Some(WebBackend::WebGl2) {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::BROWSER_WEBGPU;
        if wgpu::util::is_browser_webgpu_supported().await {
            let instance = wgpu::Instance::new(desc);
            match instance.request_adapter(&wgpu::RequestAdapterOptions::default()).await {
                Ok(adapter) => {
                    let surface = instance
                        .create_surface(wgpu::SurfaceTarget::Canvas(canvas.clone()))
                        .map_err(|e| format!("WebGPU cannot draw to the canvas: {e}"))?;
                    let ctx = GpuContext::open(adapter).await.map_err(|e| e.to_string())?;
                    return Ok((WebBackend::WebGpu, ctx, surface));
                }
                Err(error) => tried.push(format!("WebGPU offers no adapter ({error})")),
            }
        } else {
            tried.push("this browser has no WebGPU".to_string());
        }
    }
    if wanted != Some(WebBackend::WebGpu) {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::GL;
        let instance = wgpu::Instance::new(desc);
        match instance.create_surface(wgpu::SurfaceTarget::Canvas(canvas.clone())) {
            Ok(surface) => match GpuContext::for_surface(&instance, &surface).await {
                Ok(ctx) => return Ok((WebBackend::WebGl2, ctx, surface)),
                Err(error) => tried.push(format!("WebGL2: {error}")),
            },
            Err(error) => tried.push(format!("this browser has no WebGL2 ({error})")),
        }
    }
    Err(format!("raypipe cannot trace here: {}", tried.join("; ")))
}

/// The adapter, its device and the canvas's surface, ready to present at `size`. Where the device
/// is lost later, WebGPU says so through the context (`GpuContext::lost`); a WebGL2 context's loss
/// is an event of the canvas ([`Page::watch_canvas`]).
async fn screen_on(
    canvas: &web_sys::HtmlCanvasElement,
    wanted: Option<WebBackend>,
    size: (u32, u32),
) -> Result<(WebBackend, Screen), String> {
    let (backend, ctx, surface) = connect(canvas, wanted).await?;
    let max_side = ctx.limits().max_texture_dimension_2d;
    if size.0 > max_side || size.1 > max_side {
        return Err(format!(
            "{}x{} is larger than {} draws ({max_side} pixels a side at most)",
            size.0,
            size.1,
            ctx.describe()
        ));
    }
    let adapter = ctx.describe();
    let screen =
        Screen::new(ctx, surface, size, true).ok_or_else(|| format!("{adapter} cannot present to the canvas"))?;
    Ok((backend, screen))
}

async fn open(canvas: web_sys::HtmlCanvasElement, params: StartParams, errors: Vec<String>) -> Result<Page, String> {
    let mut scene = builtin_scene(&params.scene).map_err(|why| format!("{}: {why}", params.scene))?;
    canvas.set_width(params.width);
    canvas.set_height(params.height);
    let style = canvas.style();
    let _ = style.set_property("width", &format!("{}px", params.width));
    let _ = style.set_property("height", &format!("{}px", params.height));
    let (backend, screen) = screen_on(&canvas, params.backend, (params.width, params.height)).await?;
    let ctx = &screen.ctx;
    (scene.settings.width, scene.settings.height) = (params.width, params.height);
    let modes = Modes {
        pipeline: params.pipeline,
        accel: params.accel.unwrap_or(ctx.default_accel()),
        builder: params.builder,
        memory: params.memory.unwrap_or(ctx.default_memory()),
        depth: params.depth.unwrap_or(scene.settings.max_depth),
        integrator: params.integrator.unwrap_or(scene.settings.integrator),
        view: params.view,
        paused: params.paused,
        vsync: true,
        display: params.display,
    };
    let mut player = Player::new(ctx, params.scene.clone(), scene, modes, screen.size(), params.spp)
        .await
        .map_err(|why| format!("{}: {why}", params.scene))?;
    player.message = (!errors.is_empty()).then(|| errors.join("; "));
    player.tone_map_chosen = params.tone_map_chosen;
    player.integrator_chosen = params.integrator.is_some();
    player.start_at(params.time);
    player.clock.speed = params.speed;
    Ok(Page {
        canvas,
        backend,
        screen,
        player,
        busy: false,
        waiting: None,
        fly: FlyKeys::default(),
        started: Instant::now(),
        first_frame_ms: None,
        floor: params.floor,
        opened: None,
        environment: None,
        gpu: GpuState::Live,
        generation: 0,
        status: JsValue::NULL,
        shown: None,
        published_at: Instant::now(),
        listener: None,
        frames: Rc::new(RefCell::new(None)),
        frame_request: None,
        canvas_listeners: Vec::new(),
        disposed: false,
    })
}

/// A file's name and bytes, as the page was given them.
type OpenedFile = (String, Rc<Vec<u8>>);

/// A listener of DOM events, kept to be removed.
type EventListener = Closure<dyn FnMut(web_sys::Event)>;

/// The animation-frame callback, which asks for the next frame with itself.
type FrameCallback = Rc<RefCell<Option<Closure<dyn FnMut()>>>>;

/// Draws a frame at every animation frame of the browser, until the viewer is disposed.
fn animate(page: &Rc<RefCell<Page>>) {
    let frames = page.borrow().frames.clone();
    let weak = Rc::downgrade(page);
    *frames.borrow_mut() = Some(Closure::new(move || {
        let Some(page) = weak.upgrade() else { return };
        Page::frame(&page);
        Page::request_frame(&page);
    }));
    Page::request_frame(page);
}

impl Page {
    fn request_frame(page: &Rc<RefCell<Page>>) {
        let mut this = page.borrow_mut();
        if this.disposed {
            return;
        }
        let frames = this.frames.clone();
        let callback = frames.borrow();
        if let (Some(window), Some(callback)) = (web_sys::window(), callback.as_ref()) {
            this.frame_request = window.request_animation_frame(callback.as_ref().unchecked_ref()).ok();
        }
    }

    fn frame(page: &Rc<RefCell<Page>>) {
        let lost = {
            let this = page.borrow();
            (this.gpu == GpuState::Live).then(|| this.screen.ctx.lost()).flatten()
        };
        if let Some(why) = lost {
            // Heard of by the frame before the watch's task ran.
            Page::device_lost(page, why);
            return;
        }
        if page.borrow().webgl_context_lost() {
            // Lost since the last frame, its event not yet dispatched: no GL call until it is back.
            Page::lose(page, "the GPU was lost (the WebGL2 context was lost)".into());
            return;
        }
        let mut this = page.borrow_mut();
        let this = &mut *this;
        if this.gpu != GpuState::Live || this.disposed {
            return;
        }
        let report = this
            .player
            .frame(&this.screen, this.fly.direction(), Timings::Skip, |_, _, _| Vec::new());
        if !report.presented {
            return;
        }
        if this.first_frame_ms.is_none() {
            this.first_frame_ms = Some(this.started.elapsed().as_secs_f64() * 1e3);
        }
        this.publish();
    }

    /// What runs now.
    fn status(&self) -> Status {
        let player = &self.player;
        let modes = &player.modes;
        Status {
            frames: player.frames,
            backend: self.backend.name(),
            adapter: self.screen.ctx.describe(),
            scene: player.name.clone(),
            error: player.message.clone(),
            lost: self.gpu != GpuState::Live,
            busy: self.busy,
            width: self.screen.config.width,
            height: self.screen.config.height,
            primitives: player.primitives() as u32,
            pipeline: modes.pipeline.name(),
            accel: modes.accel.name(),
            builder: modes.builder.name(),
            memory: modes.memory.name(),
            memories: self.screen.ctx.memory_modes().iter().map(|m| m.name()).collect(),
            depth: modes.depth,
            integrator: modes.integrator.name(),
            aov: modes.view.name(),
            exposure: modes.display.exposure,
            tonemap: modes.display.tone_map.name(),
            paused: modes.paused,
            floor: self.floor != Floor::None,
            environment: self.environment.as_ref().map(|(name, _)| name.clone()),
            moving: player.scene.motion.is_some(),
            time: player.clock.time,
            duration: player.duration(),
            speed: player.clock.speed,
            samples: player.gathered(),
            spp: player.spp,
            fps: player.rate.fps,
            frame_ms: player.rate.frame_ms,
            build_ms: player.build_ms,
            first_frame_ms: self.first_frame_ms,
            camera: StatusCamera::of(&player.camera.camera),
        }
    }

    /// Publishes the status where it says something new ([`Status::publishes_over`]): as the
    /// object [`Viewer::status`] returns, and to the listener.
    fn publish(&mut self) {
        let status = self.status();
        let since_ms = self.published_at.elapsed().as_secs_f64() * 1e3;
        if !status.publishes_over(self.shown.as_ref(), since_ms) {
            return;
        }
        self.status = to_js(&status);
        self.shown = Some(status);
        self.published_at = Instant::now();
        if let Some(listener) = self.listener.clone() {
            let status = self.status.clone();
            wasm_bindgen_futures::spawn_local(async move {
                let _ = listener.call1(&JsValue::NULL, &status);
            });
        }
    }

    /// Builds the tracer `pending` asks for and swaps it in when it is ready (unless a later
    /// request came first); on failure the current one stays and the message shows.
    /// Its source is the file a new scene was read from: the page keeps it once the scene is in.
    fn build(page: &Rc<RefCell<Page>>, pending: Pending) {
        let (ctx, generation) = {
            let mut this = page.borrow_mut();
            if this.disposed {
                return settle(pending.settle, Err("the viewer was disposed".into()));
            }
            if this.busy || this.gpu != GpuState::Live {
                // One build at a time: WebGPU's error scopes, which a build pushes and pops across
                // awaits, must not interleave; and none on a lost device. The latest request waits.
                if let Some(earlier) = this.waiting.replace(pending) {
                    settle(earlier.settle, Err(superseded(&earlier.request)));
                }
                return;
            }
            this.busy = true;
            // The last request's message no longer applies.
            this.player.message = None;
            this.publish();
            (this.screen.ctx.clone(), this.generation)
        };
        let page = page.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let built = pending.request.build(&ctx).await;
            let waiting = {
                let mut this = page.borrow_mut();
                this.busy = false;
                let Pending {
                    request,
                    source,
                    settle: ends,
                } = pending;
                if this.disposed {
                    settle(ends, Err("the viewer was disposed".into()));
                    return;
                }
                if this.generation != generation || this.gpu != GpuState::Live {
                    // Built on a device since lost: built again on the next, unless a later
                    // request replaces it.
                    let again = Pending {
                        request,
                        source,
                        settle: ends,
                    };
                    if this.waiting.is_none() {
                        this.waiting = Some(again);
                    } else {
                        settle(again.settle, Err(superseded(&again.request)));
                    }
                } else if this.player.is_current(&request) {
                    let new_scene = request.new_scene.is_some();
                    this.player.install(request, built);
                    // Resized while it was built: at the canvas's size now.
                    let size = this.screen.size();
                    if this.player.size() != size
                        && let Err(why) = this.player.resize(size.0, size.1)
                    {
                        this.player.say(why.to_string());
                    }
                    if new_scene && this.player.message.is_none() {
                        this.opened = source;
                    }
                    settle(ends, this.player.message.clone().map_or(Ok(()), Err));
                    this.publish();
                } else {
                    settle(ends, Err(superseded(&request)));
                }
                if this.gpu == GpuState::Live {
                    this.waiting.take()
                } else {
                    None
                }
            };
            if let Some(pending) = waiting {
                Page::build(&page, pending);
            }
        });
    }

    /// A new scene: its size is the canvas's; it replaces the current one once its tracer is built.
    fn open_scene(
        page: &Rc<RefCell<Page>>,
        name: String,
        loaded: Result<Scene, String>,
        source: Option<OpenedFile>,
        ends: Option<Settle>,
    ) {
        match loaded {
            Ok(mut scene) => {
                let request = {
                    let mut this = page.borrow_mut();
                    (scene.settings.width, scene.settings.height) = this.screen.size();
                    if let Some((_, environment)) = &this.environment {
                        scene.set_environment(Some(environment.clone()));
                    }
                    this.player.open(name, scene)
                };
                Page::build(
                    page,
                    Pending {
                        request,
                        source,
                        settle: ends,
                    },
                );
            }
            Err(why) => {
                let mut this = page.borrow_mut();
                this.player.say(why.clone());
                this.publish();
                settle(ends, Err(why));
            }
        }
    }
}

/// Why a request was dropped unbuilt or unshown.
fn superseded(request: &TracerRequest) -> String {
    match &request.new_scene {
        Some((name, _)) => format!("{name}: replaced by a later request before it was shown"),
        None => "replaced by a later request before it was shown".into(),
    }
}

/// A status as the object JavaScript reads, field by field of its schema.
fn to_js(status: &Status) -> JsValue {
    record(status.fields().into_iter().map(|field| (field.name, field.value)))
}

/// Named values as a plain object.
fn record<'a>(values: impl IntoIterator<Item = (&'static str, Value<'a>)>) -> JsValue {
    let object = js_sys::Object::new();
    for (name, value) in values {
        let _ = js_sys::Reflect::set(&object, &name.into(), &js_value(value));
    }
    object.into()
}

pub(super) fn js_value(value: Value) -> JsValue {
    match value {
        Value::Number(n) => JsValue::from(n),
        Value::Text(text) => JsValue::from(text),
        Value::Flag(flag) => JsValue::from(flag),
        Value::Texts(texts) => texts
            .iter()
            .map(|t| JsValue::from(*t))
            .collect::<js_sys::Array>()
            .into(),
        Value::Numbers(numbers) => numbers.into_iter().map(JsValue::from).collect::<js_sys::Array>().into(),
        Value::Record(values) => record(values),
        Value::Null => JsValue::NULL,
    }
}
