//! The viewer on a canvas: WebGPU where the browser has it, else WebGL2; every frame traced in the
//! fragment shader (or the compute kernel, on WebGPU) and shown by the display pass, from the
//! browser's animation frames. The page's HTML controls call [`Viewer`]'s methods; what runs is
//! published each frame as `window.raypipeStatus`.
//!
//! Building a tracer is async in a browser (shader compilation and error scopes resolve on the
//! browser's event loop), so a switch of mode or scene is started here and lands a few frames later;
//! until then the previous tracer keeps drawing, and a failed switch leaves it in place with its
//! message shown.

use crate::params::{Setting, StartParams, WebBackend};
use raypipe::Choice;
use raypipe::gpu::GpuContext;
use raypipe::scene::environment::is_environment_file;
use raypipe::scene::model::{Floor, ModelOptions};
use raypipe::scene::{Environment, Scene};
use raypipe_view::{FlyKeys, ModeKey, Modes, Player, Screen, Timings, TracerRequest};
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;
use web_time::Instant;

/// The page's handle on the viewer: the controls' calls land here.
#[wasm_bindgen]
pub struct Viewer {
    page: Rc<RefCell<Page>>,
}

struct Page {
    backend: WebBackend,
    screen: Screen,
    /// The scene, modes, camera, tracer and clock. Its frame rate is the wall clock's between
    /// presented frames: the browser paces them by the GPU's progress. Timestamp queries are not
    /// read here ([`Timings::Skip`]).
    player: Player,
    /// A tracer is being built.
    busy: bool,
    /// The request made while one was being built: built next.
    waiting: Option<(TracerRequest, Option<OpenedFile>)>,
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
}

/// Starts the viewer on `canvas` with the settings of `query` (the URL's `?...`). Where the page
/// cannot start (no WebGPU and no WebGL2, a scene that does not load), `window.raypipeStatus.error`
/// says why and the promise rejects with the same line.
#[wasm_bindgen]
pub async fn start(canvas: web_sys::HtmlCanvasElement, query: String) -> Result<Viewer, JsError> {
    crate::console::install();
    let search =
        web_sys::UrlSearchParams::new_with_str(&query).map_err(|_| JsError::new("cannot read the URL's query"))?;
    let pairs = query_pairs(&search);
    let (params, errors) = StartParams::from_pairs(pairs.iter().map(|(k, v)| (k.as_str(), v.as_str())));
    match open(canvas, params, errors).await {
        Ok(page) => {
            let page = Rc::new(RefCell::new(page));
            page.borrow().publish();
            animate(page.clone());
            Ok(Viewer { page })
        }
        Err(why) => {
            publish_failure(&why);
            Err(JsError::new(&why))
        }
    }
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

async fn open(canvas: web_sys::HtmlCanvasElement, params: StartParams, errors: Vec<String>) -> Result<Page, String> {
    let mut scene = builtin_scene(&params.scene).map_err(|why| format!("{}: {why}", params.scene))?;
    canvas.set_width(params.width);
    canvas.set_height(params.height);
    let style = canvas.style();
    let _ = style.set_property("width", &format!("{}px", params.width));
    let _ = style.set_property("height", &format!("{}px", params.height));
    let (backend, ctx, surface) = connect(&canvas, params.backend).await?;
    let max_side = ctx.limits().max_texture_dimension_2d;
    if params.width > max_side || params.height > max_side {
        return Err(format!(
            "{}x{} is larger than {} draws ({max_side} pixels a side at most)",
            params.width,
            params.height,
            ctx.describe()
        ));
    }
    let adapter = ctx.describe();
    let screen = Screen::new(ctx, surface, (params.width, params.height), true)
        .ok_or_else(|| format!("{adapter} cannot present to the canvas"))?;
    let ctx = &screen.ctx;
    (scene.settings.width, scene.settings.height) = (params.width, params.height);
    let modes = Modes {
        pipeline: params.pipeline,
        accel: params.accel.unwrap_or(ctx.default_accel()),
        builder: params.builder,
        memory: params.memory.unwrap_or(ctx.default_memory()),
        depth: params.depth.unwrap_or(scene.settings.max_depth),
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
    player.start_at(params.time);
    player.clock.speed = params.speed;
    Ok(Page {
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
    })
}

/// A file's name and bytes, as the page was given them.
type OpenedFile = (String, Rc<Vec<u8>>);

/// The animation-frame callback, which asks for the next frame with itself.
type FrameCallback = Rc<RefCell<Option<Closure<dyn FnMut()>>>>;

/// Draws a frame at every animation frame of the browser, for as long as the page lives.
fn animate(page: Rc<RefCell<Page>>) {
    let callback: FrameCallback = Rc::new(RefCell::new(None));
    let again = callback.clone();
    *callback.borrow_mut() = Some(Closure::new(move || {
        Page::frame(&page);
        if let Some(next) = again.borrow().as_ref() {
            request_animation_frame(next);
        }
    }));
    if let Some(first) = callback.borrow().as_ref() {
        request_animation_frame(first);
    }
}

fn request_animation_frame(callback: &Closure<dyn FnMut()>) {
    if let Some(window) = web_sys::window() {
        let _ = window.request_animation_frame(callback.as_ref().unchecked_ref());
    }
}

impl Page {
    fn frame(page: &Rc<RefCell<Page>>) {
        let mut this = page.borrow_mut();
        let this = &mut *this;
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

    /// `window.raypipeStatus`: what runs, for the page's readout and for tests.
    fn publish(&self) {
        let status = js_sys::Object::new();
        let set = |key: &str, value: JsValue| {
            let _ = js_sys::Reflect::set(&status, &key.into(), &value);
        };
        let optional = |value: Option<f64>| value.map_or(JsValue::NULL, JsValue::from);
        let player = &self.player;
        let modes = &player.modes;
        set("frames", player.frames.into());
        set("backend", self.backend.name().into());
        set("adapter", self.screen.ctx.describe().into());
        set("scene", player.name.clone().into());
        set("error", player.message.clone().map_or(JsValue::NULL, JsValue::from));
        set("busy", self.busy.into());
        set("width", self.screen.config.width.into());
        set("height", self.screen.config.height.into());
        set("primitives", (player.primitives() as u32).into());
        set("pipeline", modes.pipeline.name().into());
        set("accel", modes.accel.name().into());
        set("builder", modes.builder.name().into());
        set("memory", modes.memory.name().into());
        set("memories", memory_names(&self.screen.ctx).into());
        set("depth", modes.depth.into());
        set("aov", modes.view.name().into());
        set("exposure", modes.display.exposure.into());
        set("tonemap", modes.display.tone_map.name().into());
        set("paused", modes.paused.into());
        set("floor", (self.floor != Floor::None).into());
        set(
            "environment",
            self.environment
                .as_ref()
                .map_or(JsValue::NULL, |(name, _)| name.as_str().into()),
        );
        set("moving", player.scene.motion.is_some().into());
        set("time", player.clock.time.into());
        set("duration", optional(player.duration().map(f64::from)));
        set("speed", player.clock.speed.into());
        set("samples", player.gathered().into());
        set("spp", player.spp.into());
        set("fps", player.rate.fps.into());
        set("frameMs", player.rate.frame_ms.into());
        set("buildMs", optional(player.build_ms));
        set("firstFrameMs", optional(self.first_frame_ms));
        if let Some(window) = web_sys::window() {
            let _ = js_sys::Reflect::set(&window, &"raypipeStatus".into(), &status);
        }
    }

    /// Builds the tracer `request` asks for and swaps it in when it is ready (unless a later
    /// request came first); on failure the current one stays and the message shows.
    /// `source` is the file a new scene was read from: the page keeps it once the scene is in.
    fn build(page: &Rc<RefCell<Page>>, request: TracerRequest, source: Option<OpenedFile>) {
        let ctx = {
            let mut this = page.borrow_mut();
            if this.busy {
                // One build at a time: WebGPU's error scopes, which a build pushes and pops across
                // awaits, must not interleave. The latest request waits for the running one.
                this.waiting = Some((request, source));
                return;
            }
            this.busy = true;
            // The last request's message no longer applies.
            this.player.message = None;
            this.publish();
            this.screen.ctx.clone()
        };
        let page = page.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let built = request.build(&ctx).await;
            let waiting = {
                let mut this = page.borrow_mut();
                this.busy = false;
                if this.player.is_current(&request) {
                    let new_scene = request.new_scene.is_some();
                    this.player.install(request, built);
                    if new_scene && this.player.message.is_none() {
                        this.opened = source;
                    }
                    this.publish();
                }
                this.waiting.take()
            };
            if let Some((request, source)) = waiting {
                Page::build(&page, request, source);
            }
        });
    }

    /// A new scene: its size is the canvas's; it replaces the current one once its tracer is built.
    fn open_scene(page: &Rc<RefCell<Page>>, name: String, loaded: Result<Scene, String>, source: Option<OpenedFile>) {
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
                Page::build(page, request, source);
            }
            Err(why) => {
                let mut this = page.borrow_mut();
                this.player.say(why);
                this.publish();
            }
        }
    }
}

fn memory_names(ctx: &GpuContext) -> js_sys::Array {
    ctx.memory_modes().iter().map(|m| JsValue::from(m.name())).collect()
}

fn publish_failure(why: &str) {
    let status = js_sys::Object::new();
    let set = |key: &str, value: JsValue| {
        let _ = js_sys::Reflect::set(&status, &key.into(), &value);
    };
    set("frames", 0.into());
    set("backend", JsValue::NULL);
    set("adapter", JsValue::NULL);
    set("scene", JsValue::NULL);
    set("error", why.into());
    if let Some(window) = web_sys::window() {
        let _ = js_sys::Reflect::set(&window, &"raypipeStatus".into(), &status);
    }
}

#[wasm_bindgen]
impl Viewer {
    /// Changes one setting by the URL's names (`accel`, `builder`, `memory`, `pipeline`, `depth`,
    /// `aov`, `exposure`, `tonemap`, `paused`, `spp`, `scene`); a bad value or a mode that cannot serve the scene shows its
    /// message and changes nothing.
    pub fn set(&self, key: &str, value: &str) {
        let setting = match Setting::parse(key, value) {
            Ok(setting) => setting,
            Err(why) => return self.fail(why),
        };
        let mut asked = self.page.borrow().player.modes;
        match setting {
            Setting::Scene(name) => {
                let loaded = builtin_scene(&name).map_err(|why| format!("{name}: {why}"));
                return Page::open_scene(&self.page, name, loaded, None);
            }
            Setting::Floor(floor) => {
                // A model file shows the new floor at once: it is opened again from its bytes.
                let opened = {
                    let mut this = self.page.borrow_mut();
                    this.floor = floor;
                    this.publish();
                    this.opened.clone()
                };
                if let Some((name, bytes)) = opened {
                    self.open_bytes(name, bytes);
                }
                return;
            }
            Setting::Accel(accel) => asked.accel = accel,
            Setting::Builder(builder) => asked.builder = builder,
            Setting::Memory(memory) => asked.memory = memory,
            Setting::Pipeline(pipeline) => asked.pipeline = pipeline,
            Setting::Depth(depth) => asked.depth = depth,
            Setting::View(view) => asked.view = view,
            Setting::Paused(paused) => asked.paused = paused,
            Setting::Exposure(ev) => asked.display.exposure = ev,
            Setting::ToneMap(tone_map) => asked.display.tone_map = tone_map,
            Setting::Spp(spp) => {
                self.page.borrow_mut().player.set_spp(spp);
                return;
            }
            Setting::Time(time) => {
                let mut this = self.page.borrow_mut();
                this.player.seek(time);
                return;
            }
            Setting::Speed(speed) => {
                self.page.borrow_mut().player.clock.speed = speed;
                return;
            }
            Setting::Model(_)
            | Setting::Environment(_)
            | Setting::Width(_)
            | Setting::Height(_)
            | Setting::Backend(_) => {
                return self.fail(format!(
                    "{key} is set in the page's address only (reload with ?{key}={value})"
                ));
            }
        }
        self.set_modes(asked);
    }

    fn set_modes(&self, asked: Modes) {
        let request = self.page.borrow_mut().player.set_modes(asked);
        match request {
            Some(request) => Page::build(&self.page, request, None),
            None => {
                let mut this = self.page.borrow_mut();
                this.player.message = None;
                this.publish();
            }
        }
    }

    fn fail(&self, why: String) {
        let mut this = self.page.borrow_mut();
        this.player.say(why);
        this.publish();
    }

    /// Shows a failure of the page's script (a model URL that could not be fetched): the message
    /// line, and the current scene stays.
    pub fn report(&self, why: String) {
        self.fail(why);
    }

    /// Opens a file the page was given (the file input, a drop, or the `model` or `environment`
    /// URL): a TOML scene, a PLY, OBJ or OFF model, a glTF, or an environment, parsed here. A
    /// broken one shows its error and the current scene stays.
    pub fn open_file(&self, name: String, bytes: Vec<u8>) {
        self.open_bytes(name, Rc::new(bytes));
    }

    /// A file's bytes parsed as its name says, a model file on the page's floor; an environment
    /// lights the current scene and those opened after it.
    fn open_bytes(&self, name: String, bytes: Rc<Vec<u8>>) {
        if is_environment_file(&name) {
            return match Environment::decode(&name, &bytes) {
                Ok(environment) => {
                    let request = {
                        let mut this = self.page.borrow_mut();
                        this.environment = Some((name, environment.clone()));
                        this.player.relight(Some(environment))
                    };
                    Page::build(&self.page, request, None);
                }
                Err(why) => self.fail(why.in_origin(&name).to_string()),
            };
        }
        let mut options = ModelOptions::default();
        if raypipe::scene::is_model_file(std::path::Path::new(&name)) {
            options.floor = self.page.borrow().floor;
        }
        let loaded = Scene::from_bytes_with(&name, &bytes, &options).map_err(|e| e.to_string());
        Page::open_scene(&self.page, name.clone(), loaded, Some((name, bytes)));
    }

    /// A drag of the pointer by (`dx`, `dy`) CSS pixels: orbit with the primary button, pan with
    /// the others.
    pub fn drag(&self, dx: f32, dy: f32, pan: bool) {
        let mut this = self.page.borrow_mut();
        if pan {
            let height = this.screen.config.height as f32;
            this.player.camera.pan(dx, dy, height);
        } else {
            this.player.camera.orbit(dx, dy);
        }
    }

    /// Wheel steps towards the target (negative: away).
    pub fn dolly(&self, steps: f32) {
        self.page.borrow_mut().player.camera.dolly(steps);
    }

    /// A key by its `KeyboardEvent.code`: the viewer's keys (R, B, G, M, V, [ ], Space, and
    /// W A S D Q E held to fly). Returns whether the viewer used it.
    pub fn key(&self, code: &str, pressed: bool) -> bool {
        if self.page.borrow_mut().fly.set(code, pressed) {
            return true;
        }
        if !pressed {
            return false;
        }
        if code == "KeyR" {
            self.page.borrow_mut().player.camera.reset();
            return true;
        }
        let Some(key) = ModeKey::from_code(code) else {
            return false;
        };
        let page = self.page.borrow();
        let asked = page.player.modes.after(key, &page.screen.ctx.accels());
        drop(page);
        self.set_modes(asked);
        true
    }
}
