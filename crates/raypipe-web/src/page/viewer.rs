//! The viewer's JavaScript API (`Viewer`'s methods, which the page's controls and the npm package
//! call): settings, files, the camera's drags and keys, screenshots, status and disposal.

use super::{GpuState, Page, Pending, Settle, Viewer, builtin_scene, js_value, settle};
use crate::params::{MAX_SIDE, Setting};
use crate::status::StatusCamera;
use raypipe::scene::environment::is_environment_file;
use raypipe::scene::model::ModelOptions;
use raypipe::scene::{Environment, Scene};
use raypipe_view::{ModeKey, Modes};
use std::rc::Rc;
use wasm_bindgen::prelude::*;

#[wasm_bindgen]
impl Viewer {
    /// Changes one setting by the URL's names (`accel`, `builder`, `memory`, `pipeline`, `depth`,
    /// `aov`, `exposure`, `tonemap`, `paused`, `spp`, `scene`, `floor`, `time`, `speed`); a bad value
    /// or a mode that cannot serve the scene shows its message and changes nothing. Returns the
    /// message, or `undefined` where the setting was taken (a tracer it needs lands a few frames
    /// later).
    pub fn set(&self, key: &str, value: &str) -> Option<String> {
        let setting = match Setting::parse(key, value) {
            Ok(setting) => setting,
            Err(why) => return self.fail(why),
        };
        let mut asked = self.page.borrow().player.modes;
        match setting {
            Setting::Scene(name) => {
                let loaded = builtin_scene(&name).map_err(|why| format!("{name}: {why}"));
                let failed = loaded.as_ref().err().cloned();
                Page::open_scene(&self.page, name, loaded, None, None);
                return failed;
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
                    self.open_bytes(name, bytes, None);
                }
                return None;
            }
            Setting::Accel(accel) => asked.accel = accel,
            Setting::Builder(builder) => asked.builder = builder,
            Setting::Memory(memory) => asked.memory = memory,
            Setting::Pipeline(pipeline) => asked.pipeline = pipeline,
            Setting::Depth(depth) => asked.depth = depth,
            Setting::Integrator(integrator) => asked.integrator = integrator,
            Setting::View(view) => asked.view = view,
            Setting::Paused(paused) => asked.paused = paused,
            Setting::Exposure(ev) => asked.display.exposure = ev,
            Setting::ToneMap(tone_map) => asked.display.tone_map = tone_map,
            Setting::Spp(spp) => {
                self.page.borrow_mut().player.set_spp(spp);
                return None;
            }
            Setting::Time(time) => {
                self.page.borrow_mut().player.seek(time);
                return None;
            }
            Setting::Speed(speed) => {
                self.page.borrow_mut().player.clock.speed = speed;
                return None;
            }
            Setting::Model(_)
            | Setting::Environment(_)
            | Setting::Width(_)
            | Setting::Height(_)
            | Setting::Backend(_) => {
                return self.fail(format!(
                    "{key} is set when the viewer starts only (the page's address: ?{key}={value})"
                ));
            }
        }
        self.set_modes(asked)
    }

    fn set_modes(&self, asked: Modes) -> Option<String> {
        let request = self.page.borrow_mut().player.set_modes(asked);
        match request {
            Some(request) => Page::build(
                &self.page,
                Pending {
                    request,
                    source: None,
                    settle: None,
                },
            ),
            None => {
                let mut this = self.page.borrow_mut();
                this.player.message = None;
                this.publish();
            }
        }
        None
    }

    fn fail(&self, why: String) -> Option<String> {
        let mut this = self.page.borrow_mut();
        this.player.say(why.clone());
        this.publish();
        Some(why)
    }

    /// Draws at `width` x `height` pixels from the next frame on: the canvas's drawing buffer,
    /// the surface and the tracer's targets (the `<raypipe-viewer>` element follows its size on
    /// the page so). A size the adapter cannot trace is refused with its message, returned, and
    /// the previous size stays; the samples start again.
    pub fn resize(&self, width: u32, height: u32) -> Option<String> {
        let mut this = self.page.borrow_mut();
        if this.disposed || (width, height) == this.screen.size() {
            return None;
        }
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            drop(this);
            return self.fail(format!("size {width}x{height}: each side 1 to {MAX_SIDE} pixels"));
        }
        if this.gpu == GpuState::Live
            && let Err(why) = this.player.resize(width, height)
        {
            drop(this);
            return self.fail(format!("size {width}x{height}: {why}"));
        }
        // On a lost device the size waits in the surface's configuration: the tracer of the
        // restored device is built at it.
        this.canvas.set_width(width);
        this.canvas.set_height(height);
        this.screen.resize(width, height);
        this.publish();
        None
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
        self.open_bytes(name, Rc::new(bytes), None);
    }

    /// [`Viewer::open_file`] as a promise: it resolves once the file's scene (or environment) is
    /// shown, and rejects with the one-line message where it is not (a broken file, a scene the
    /// modes cannot trace, a later request that replaced it).
    pub fn load(&self, name: String, bytes: Vec<u8>) -> js_sys::Promise {
        let (promise, ends) = Settle::new();
        self.open_bytes(name, Rc::new(bytes), Some(ends));
        promise
    }

    /// A file's bytes parsed as its name says, a model file on the page's floor; an environment
    /// lights the current scene and those opened after it.
    fn open_bytes(&self, name: String, bytes: Rc<Vec<u8>>, ends: Option<Settle>) {
        if is_environment_file(&name) {
            return match Environment::decode(&name, &bytes) {
                Ok(environment) => {
                    let request = {
                        let mut this = self.page.borrow_mut();
                        this.environment = Some((name, environment.clone()));
                        this.player.relight(Some(environment))
                    };
                    Page::build(
                        &self.page,
                        Pending {
                            request,
                            source: None,
                            settle: ends,
                        },
                    );
                }
                Err(why) => {
                    let why = why.in_origin(&name).to_string();
                    self.fail(why.clone());
                    settle(ends, Err(why));
                }
            };
        }
        let mut options = ModelOptions::default();
        if raypipe::scene::is_model_file(std::path::Path::new(&name)) {
            options.floor = self.page.borrow().floor;
        }
        let loaded = Scene::from_bytes_with(&name, &bytes, &options).map_err(|e| e.to_string());
        Page::open_scene(&self.page, name.clone(), loaded, Some((name, bytes)), ends);
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

    /// Turns the camera about its target by `yaw_degrees` about the up axis and `pitch_degrees`
    /// about the view's right axis (the element's auto-rotate and arrow keys).
    pub fn turn(&self, yaw_degrees: f32, pitch_degrees: f32) {
        if yaw_degrees.is_finite() && pitch_degrees.is_finite() {
            let camera = &mut self.page.borrow_mut().player.camera;
            camera.turn(yaw_degrees.to_radians(), pitch_degrees.to_radians());
        }
    }

    /// Puts the eye on a sphere about the target, as model-viewer's `camera-orbit`: `theta_degrees`
    /// about the up axis from the front (+z), `phi_degrees` down from the up axis, at `radius`
    /// (times the scene's own camera distance where `relative`; `None`: as far as now). Returns
    /// the message where a number is not finite or the radius not positive.
    pub fn place_camera(
        &self,
        theta_degrees: f32,
        phi_degrees: f32,
        radius: Option<f32>,
        relative: bool,
    ) -> Option<String> {
        if !(theta_degrees.is_finite() && phi_degrees.is_finite() && radius.is_none_or(|r| r > 0.0 && r.is_finite())) {
            return self.fail(format!(
                "camera-orbit: angles must be finite and the radius positive (got {theta_degrees}, {phi_degrees}, {radius:?})"
            ));
        }
        let camera = &mut self.page.borrow_mut().player.camera;
        let distance = radius.map(|r| if relative { r * camera.home_distance() } else { r });
        camera.place(theta_degrees.to_radians(), phi_degrees.to_radians(), distance);
        None
    }

    /// The vertical field of view, in degrees (above 0, below 180; `None`: the scene's own);
    /// returns the message where it is not.
    pub fn set_field_of_view(&self, degrees: Option<f32>) -> Option<String> {
        if degrees.is_some_and(|d| !(d > 0.0 && d < 180.0)) {
            return self.fail(format!("field-of-view: {degrees:?} degrees is not in (0, 180)"));
        }
        let camera = &mut self.page.borrow_mut().player.camera;
        camera.camera.fov_degrees = degrees.unwrap_or(camera.home.fov_degrees);
        None
    }

    /// The camera now: `{ eye, target, up, fov }` (points and the up vector as arrays of three
    /// numbers, the vertical field of view in degrees).
    #[wasm_bindgen(getter)]
    pub fn camera(&self) -> JsValue {
        js_value(StatusCamera::of(&self.page.borrow().player.camera.camera).value())
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

    /// The last status published: `{ frames, backend, adapter, scene, error, lost, busy, samples,
    /// spp, fps, ... }`.
    #[wasm_bindgen(getter)]
    pub fn status(&self) -> JsValue {
        self.page.borrow().status.clone()
    }

    /// The frames drawn so far, at any moment: a status publishes its count four times a second.
    #[wasm_bindgen(getter)]
    pub fn frames(&self) -> u32 {
        self.page.borrow().player.frames
    }

    /// Calls `listener` with each status published from now on (after the call that published
    /// it returns); `null` stops it.
    pub fn on_status(&self, listener: Option<js_sys::Function>) {
        self.page.borrow_mut().listener = listener;
    }

    /// The frame shown as a PNG (colour exposed, tone-mapped and sRGB-encoded as on the canvas;
    /// the other views as `raypipe render --aov` writes them), read back from the GPU.
    pub async fn screenshot(&self) -> Result<js_sys::Uint8Array, JsError> {
        // The frame is read back without holding the page across awaits: the tracer is taken
        // nowhere, so a frame drawn meanwhile only adds a sample.
        let (ctx, generation) = {
            let this = self.page.borrow();
            if this.disposed {
                return Err(JsError::new("the viewer was disposed"));
            }
            if this.gpu != GpuState::Live {
                return Err(JsError::new("the GPU is lost: no frame to read until it is back"));
            }
            (this.screen.ctx.clone(), this.generation)
        };
        let read = self.page.borrow_mut().player.read_frame_detached(&ctx);
        let frame = read.await.map_err(|e| JsError::new(&e.to_string()))?;
        let this = self.page.borrow();
        if this.generation != generation {
            return Err(JsError::new("the GPU was lost while the frame was read"));
        }
        let modes = &this.player.modes;
        let png = frame
            .aov_image(modes.view, false, &modes.display)
            .to_png()
            .map_err(|e| JsError::new(&e))?;
        Ok(js_sys::Uint8Array::from(png.as_slice()))
    }

    /// Stops drawing, removes the viewer's listeners and frees its GPU resources (its device is
    /// destroyed); every later call but `status` does nothing or fails. Other viewers go on.
    pub fn dispose(&self) {
        let mut this = self.page.borrow_mut();
        if this.disposed {
            return;
        }
        this.disposed = true;
        if let (Some(window), Some(id)) = (web_sys::window(), this.frame_request.take()) {
            let _ = window.cancel_animation_frame(id);
        }
        let this = &mut *this;
        for (name, listener) in this.canvas_listeners.drain(..) {
            let _ = this
                .canvas
                .remove_event_listener_with_callback(name, listener.as_ref().unchecked_ref());
        }
        if let Some(pending) = this.waiting.take() {
            settle(pending.settle, Err("the viewer was disposed".into()));
        }
        this.listener = None;
        // The frame callback may be the caller (a status listener that disposes): it is dropped
        // after the current task.
        let frames = this.frames.clone();
        wasm_bindgen_futures::spawn_local(async move {
            frames.borrow_mut().take();
        });
        this.screen.ctx.device.destroy();
    }
}
