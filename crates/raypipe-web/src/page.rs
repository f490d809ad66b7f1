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
use raypipe::gpu::{Display, GpuContext};
use raypipe::scene::Scene;
use raypipe_view::{CameraControl, ModeKey, Modes, Tracer, next_texture, present_format};
use std::cell::RefCell;
use std::collections::HashSet;
use std::rc::Rc;
use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;
use web_time::Instant;

/// Fly speed: the distance to the target per second.
const FLY_PER_SECOND: f32 = 0.8;

/// The page's handle on the viewer: the controls' calls land here.
#[wasm_bindgen]
pub struct Viewer {
    page: Rc<RefCell<Page>>,
}

struct Page {
    backend: WebBackend,
    ctx: GpuContext,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    display: Display,
    tracer: Tracer,
    name: String,
    scene: Scene,
    modes: Modes,
    camera: CameraControl,
    /// Samples per pixel a still frame gathers.
    spp: u32,
    motion_frame: u32,
    /// Frames presented.
    frames: u32,
    /// The one-line message shown on the page, if any.
    error: Option<String>,
    /// Counts tracer requests: a tracer that lands after a later request is dropped.
    requested: u32,
    /// A tracer is being built.
    busy: bool,
    held: HashSet<String>,
    started: Instant,
    first_frame_ms: Option<f64>,
    last_frame: Instant,
    last_presented: Instant,
    fps: f64,
    /// Wall-clock milliseconds between animation frames (smoothed): the browser paces them by the
    /// GPU's progress. Timestamp queries are not read here, since their read would hold the
    /// renderer across the browser's event loop.
    frame_ms: f64,
    build_ms: Option<f64>,
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

/// What the page's controls offer, from Rust: `{ choices: { accel: [names], memory, pipeline,
/// aov }, accept: ".ply,...", maxDepth, maxSpp }`. The page's script fills its controls from it.
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
    let caps = surface.get_capabilities(&ctx.adapter);
    let format = present_format(&caps).ok_or_else(|| format!("{} cannot present to the canvas", ctx.describe()))?;
    let config = wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        width: params.width,
        height: params.height,
        present_mode: wgpu::PresentMode::Fifo,
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes[0],
        view_formats: vec![],
        color_space: Default::default(),
    };
    surface.configure(&ctx.device, &config);
    (scene.settings.width, scene.settings.height) = (params.width, params.height);
    let modes = Modes {
        pipeline: params.pipeline,
        accel: params.accel,
        memory: params.memory.unwrap_or(ctx.default_memory()),
        depth: params.depth.unwrap_or(scene.settings.max_depth),
        view: params.view,
        paused: params.paused,
        vsync: true,
    };
    modes.check(&ctx).map_err(|why| format!("{}: {why}", params.scene))?;
    let camera = CameraControl::new(scene.camera);
    let tracer = Tracer::new(&ctx, &scene, &modes, (config.width, config.height), &camera.camera)
        .await
        .map_err(|why| format!("{}: {why}", params.scene))?;
    let now = Instant::now();
    Ok(Page {
        backend,
        display: Display::new(&ctx, format),
        build_ms: tracer.cpu_build_ms,
        ctx,
        surface,
        config,
        tracer,
        name: params.scene,
        scene,
        modes,
        camera,
        spp: params.spp,
        motion_frame: 0,
        frames: 0,
        error: (!errors.is_empty()).then(|| errors.join("; ")),
        requested: 0,
        busy: false,
        held: HashSet::new(),
        started: now,
        first_frame_ms: None,
        last_frame: now,
        last_presented: now,
        fps: 0.0,
        frame_ms: 0.0,
    })
}

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
        let now = Instant::now();
        let seconds = (now - this.last_frame).as_secs_f64();
        this.last_frame = now;
        this.fly(seconds as f32);
        let moving = this.scene.motion.is_some() && !this.modes.paused;
        if moving && this.frames > 0 {
            this.motion_frame += 1;
        }
        let camera = this.camera.camera;
        this.tracer.renderer.set_camera(&camera);
        if this.scene.motion.is_some() && this.tracer.motion_frame != Some(this.motion_frame) {
            let this = &mut *this;
            match this.tracer.advance(&this.scene, this.motion_frame, this.modes.accel) {
                Ok(Some(ms)) => this.build_ms = Some(ms),
                Ok(None) => {}
                Err(why) => this.error = Some(why),
            }
        }
        let trace = this.tracer.renderer.samples() < this.spp;
        let Some(texture) = next_texture(&this.surface, &this.ctx.device, &this.config) else {
            return;
        };
        let view = texture.texture.create_view(&Default::default());
        let ctx = this.ctx.clone();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        if trace {
            let accel = this.modes.accel;
            this.tracer.encode(&mut encoder, accel);
        }
        this.tracer
            .show(&this.display, &mut encoder, &view, this.modes.view, &camera);
        ctx.queue.submit([encoder.finish()]);
        ctx.queue.present(texture);
        this.frames += 1;
        if this.first_frame_ms.is_none() {
            this.first_frame_ms = Some((now - this.started).as_secs_f64() * 1e3);
        }
        // Between presented frames: a callback that found no texture to draw into presented none.
        let presented = (now - this.last_presented).as_secs_f64().max(1e-6);
        this.last_presented = now;
        if this.frames > 1 {
            this.fps = if this.fps == 0.0 {
                1.0 / presented
            } else {
                0.9 * this.fps + 0.1 / presented
            };
            this.frame_ms = 1e3 / this.fps;
        }
        this.publish();
    }

    /// Moves the camera by the held fly keys, for a frame `seconds` long.
    fn fly(&mut self, seconds: f32) {
        let held = |k: &str| self.held.contains(k) as i32 as f32;
        let step = FLY_PER_SECOND * seconds.min(0.25);
        let forward = held("KeyW") - held("KeyS");
        let right = held("KeyD") - held("KeyA");
        let up = held("KeyE") - held("KeyQ");
        if (forward, right, up) != (0.0, 0.0, 0.0) {
            self.camera.fly(forward * step, right * step, up * step);
        }
    }

    /// `window.raypipeStatus`: what runs, for the page's readout and for tests.
    fn publish(&self) {
        let status = js_sys::Object::new();
        let set = |key: &str, value: JsValue| {
            let _ = js_sys::Reflect::set(&status, &key.into(), &value);
        };
        let optional = |value: Option<f64>| value.map_or(JsValue::NULL, JsValue::from);
        set("frames", self.frames.into());
        set("backend", self.backend.name().into());
        set("adapter", self.ctx.describe().into());
        set("scene", self.name.clone().into());
        set("error", self.error.clone().map_or(JsValue::NULL, JsValue::from));
        set("busy", self.busy.into());
        set("width", self.config.width.into());
        set("height", self.config.height.into());
        set("primitives", (self.tracer.primitives as u32).into());
        set("pipeline", self.modes.pipeline.name().into());
        set("accel", self.modes.accel.name().into());
        set("memory", self.modes.memory.name().into());
        set("memories", memory_names(&self.ctx).into());
        set("depth", self.modes.depth.into());
        set("aov", self.modes.view.name().into());
        set("paused", self.modes.paused.into());
        set("moving", self.scene.motion.is_some().into());
        set("motionFrame", self.motion_frame.into());
        set("samples", self.tracer.renderer.targets().samples().into());
        set("spp", self.spp.into());
        set("fps", self.fps.into());
        set("frameMs", self.frame_ms.into());
        set("buildMs", optional(self.build_ms));
        set("firstFrameMs", optional(self.first_frame_ms));
        if let Some(window) = web_sys::window() {
            let _ = js_sys::Reflect::set(&window, &"raypipeStatus".into(), &status);
        }
    }

    /// Builds a tracer for `modes` (and `scene`, where one is given) and swaps it in when it is
    /// ready; on failure the current one stays and the message shows.
    fn retrace(page: &Rc<RefCell<Page>>, modes: Modes, new_scene: Option<(String, Scene)>) {
        let (ctx, name, traced, size, camera, request) = {
            let mut this = page.borrow_mut();
            if let Err(why) = modes.check(&this.ctx) {
                this.error = Some(why);
                return;
            }
            this.requested += 1;
            this.busy = true;
            // The last request's message no longer applies.
            this.error = None;
            this.publish();
            // The tracer is built after this borrow ends: it gets a scene of its own.
            let (name, traced) = match new_scene {
                Some((name, scene)) => (Some(name), scene),
                None => (None, this.scene.clone()),
            };
            let camera = if name.is_some() {
                traced.camera
            } else {
                this.camera.camera
            };
            let size = (this.config.width, this.config.height);
            (this.ctx.clone(), name, traced, size, camera, this.requested)
        };
        let page = page.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let result = Tracer::new(&ctx, &traced, &modes, size, &camera).await;
            let mut this = page.borrow_mut();
            if this.requested != request {
                return;
            }
            this.busy = false;
            match result {
                Ok(tracer) => {
                    this.build_ms = tracer.cpu_build_ms;
                    this.tracer = tracer;
                    this.modes = modes;
                    this.error = None;
                    if let Some(name) = name {
                        this.camera = CameraControl::new(traced.camera);
                        this.scene = traced;
                        this.name = name;
                        this.motion_frame = 0;
                    }
                }
                Err(why) => {
                    let name = name.unwrap_or_else(|| this.name.clone());
                    log::warn!("{name}: {why}");
                    this.error = Some(format!("{name}: {why}"));
                }
            }
            this.publish();
        });
    }

    /// A new scene: its size is the canvas's; it replaces the current one once its tracer is built.
    fn open_scene(page: &Rc<RefCell<Page>>, name: String, loaded: Result<Scene, String>) {
        let modes = page.borrow().modes;
        match loaded {
            Ok(mut scene) => {
                let this = page.borrow();
                (scene.settings.width, scene.settings.height) = (this.config.width, this.config.height);
                drop(this);
                Page::retrace(page, modes, Some((name, scene)));
            }
            Err(why) => {
                log::warn!("{why}");
                let mut this = page.borrow_mut();
                this.error = Some(why);
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
    /// Changes one setting by the URL's names (`accel`, `memory`, `pipeline`, `depth`, `aov`,
    /// `paused`, `spp`, `scene`); a bad value or a mode that cannot serve the scene shows its
    /// message and changes nothing.
    pub fn set(&self, key: &str, value: &str) {
        let setting = match Setting::parse(key, value) {
            Ok(setting) => setting,
            Err(why) => return self.fail(why),
        };
        let mut asked = self.page.borrow().modes;
        match setting {
            Setting::Scene(name) => {
                let loaded = builtin_scene(&name).map_err(|why| format!("{name}: {why}"));
                return Page::open_scene(&self.page, name, loaded);
            }
            Setting::Accel(accel) => asked.accel = accel,
            Setting::Memory(memory) => asked.memory = memory,
            Setting::Pipeline(pipeline) => asked.pipeline = pipeline,
            Setting::Depth(depth) => asked.depth = depth,
            Setting::View(view) => asked.view = view,
            Setting::Paused(paused) => asked.paused = paused,
            Setting::Spp(spp) => {
                let mut this = self.page.borrow_mut();
                this.spp = spp;
                this.tracer.renderer.restart();
                return;
            }
            Setting::Model(_) | Setting::Width(_) | Setting::Height(_) | Setting::Backend(_) => {
                return self.fail(format!(
                    "{key} is set in the page's address only (reload with ?{key}={value})"
                ));
            }
        }
        self.set_modes(asked);
    }

    fn set_modes(&self, asked: Modes) {
        let current = self.page.borrow().modes;
        if asked.needs_new_tracer(&current) {
            return Page::retrace(&self.page, asked, None);
        }
        let mut this = self.page.borrow_mut();
        this.modes = asked;
        this.error = None;
        this.publish();
    }

    fn fail(&self, why: String) {
        log::warn!("{why}");
        let mut this = self.page.borrow_mut();
        this.error = Some(why);
        this.publish();
    }

    /// Shows a failure of the page's script (a model URL that could not be fetched): the message
    /// line, and the current scene stays.
    pub fn report(&self, why: String) {
        self.fail(why);
    }

    /// Opens a file the page was given (the file input, a drop, or the `model` URL): a TOML scene,
    /// a PLY, OBJ or OFF model, or a glTF, parsed here. A broken one shows its error and the
    /// current scene stays.
    pub fn open_file(&self, name: String, bytes: Vec<u8>) {
        let loaded = Scene::from_bytes(&name, &bytes).map_err(|e| e.to_string());
        Page::open_scene(&self.page, name, loaded);
    }

    /// A drag of the pointer by (`dx`, `dy`) CSS pixels: orbit with the primary button, pan with
    /// the others.
    pub fn drag(&self, dx: f32, dy: f32, pan: bool) {
        let mut this = self.page.borrow_mut();
        if pan {
            let height = this.config.height as f32;
            this.camera.pan(dx, dy, height);
        } else {
            this.camera.orbit(dx, dy);
        }
    }

    /// Wheel steps towards the target (negative: away).
    pub fn dolly(&self, steps: f32) {
        self.page.borrow_mut().camera.dolly(steps);
    }

    /// A key by its `KeyboardEvent.code`: the viewer's keys (R, B, G, M, V, [ ], Space, and
    /// W A S D Q E held to fly). Returns whether the viewer used it.
    pub fn key(&self, code: &str, pressed: bool) -> bool {
        const FLY: [&str; 6] = ["KeyW", "KeyA", "KeyS", "KeyD", "KeyQ", "KeyE"];
        if FLY.contains(&code) {
            let mut this = self.page.borrow_mut();
            if pressed {
                this.held.insert(code.to_string());
            } else {
                this.held.remove(code);
            }
            return true;
        }
        if !pressed {
            return false;
        }
        if code == "KeyR" {
            self.page.borrow_mut().camera.reset();
            return true;
        }
        let Some(key) = ModeKey::from_code(code) else {
            return false;
        };
        let asked = self.page.borrow().modes.after(key);
        self.set_modes(asked);
        true
    }
}
