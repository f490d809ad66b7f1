// raypipe in a web page: a Whitted ray tracer in the fragment shader (WebGPU or WebGL2), over a
// linear BVH rebuilt every frame, as an ES module that needs no bundler.
//
//   import { createViewer } from "raypipe";
//   const viewer = await createViewer(document.getElementById("view"), { scene: "whitted", spp: 16 });
//   await viewer.load("models/bunny.glb");
//
// The tracer is the wasm module beside this file (raypipe_web.js, raypipe_web_bg.wasm); each viewer
// has its own adapter and device. Types: raypipe.d.ts.
import { RaypipeViewerElement } from "./element.js";
import { fetchFile } from "./fetch.js";
import { Gestures } from "./gestures.js";
import init, { controls, start } from "./raypipe_web.js";

export { RaypipeViewerElement };

let module = null;

/// Loads the wasm module, once: createViewer() calls it; call it earlier to start the download.
export function ready() {
  module ??= init({ module_or_path: new URL("./raypipe_web_bg.wasm", import.meta.url) });
  return module;
}

/// What the settings take: `{ choices: { accel, builder, memory, pipeline, aov, tonemap, integrator }, accept,
/// maxDepth, maxSpp }` (lists of names, the file types `load` opens, limits).
export async function choices() {
  await ready();
  return controls();
}

// Options of the package itself, not of the tracer.
const OWN_OPTIONS = ["model", "environment", "input", "strict"];

/// A viewer on `element`: a canvas, or a container that gets one. `options` are the page's URL
/// settings (`backend`, `scene`, `accel`, `spp`, `width`, ...) plus `model` and `environment` (URLs
/// to load once it runs), `input` (false: no orbit, pan, dolly or keys on the canvas) and `strict`
/// (false: a bad option is shown in `status.error` and skipped). Rejects with the one-line reason
/// where it cannot start (a bad option, no WebGPU and no WebGL2).
export async function createViewer(element, options = {}) {
  if (!(element instanceof HTMLElement)) throw new TypeError("createViewer: give a canvas or a container element");
  await ready();
  const query = new URLSearchParams();
  for (const [key, value] of Object.entries(options)) {
    if (!OWN_OPTIONS.includes(key) && value !== undefined && value !== null) query.set(key, String(value));
  }
  const made = !(element instanceof HTMLCanvasElement);
  const canvas = made ? element.appendChild(document.createElement("canvas")) : element;
  let inner;
  try {
    inner = await start(canvas, query.toString(), options.strict !== false);
  } catch (error) {
    if (made) canvas.remove();
    throw new Error(error?.message ?? String(error));
  }
  const viewer = new Viewer(inner, canvas, { made, input: options.input !== false });
  if (options.environment) await viewer.load(options.environment);
  if (options.model) await viewer.load(options.model);
  return viewer;
}

/// A viewer: `status` and its `status` event say what runs; `set`, `load`, `screenshot` and
/// `dispose` change it.
export class Viewer extends EventTarget {
  #inner;
  #made;
  #listeners = [];
  #reading = new Set();
  #input = false;
  #listening = false;

  constructor(inner, canvas, { made, input }) {
    super();
    this.#inner = inner;
    this.#made = made;
    /// The canvas it draws on (made here where `createViewer` was given a container).
    this.canvas = canvas;
    inner.on_status((status) => this.dispatchEvent(new CustomEvent("status", { detail: status })));
    this.input = input;
  }

  /// Whether pointers, the wheel and keys on the canvas move the camera (`createViewer`'s `input`).
  get input() {
    return this.#input;
  }

  set input(on) {
    this.#input = Boolean(on);
    if (this.#input && !this.#listening) this.#listen();
    // A finger's drag turns the camera where input is on, and scrolls the page where it is off.
    if (this.#listening) this.canvas.style.touchAction = this.#input ? "none" : "";
  }

  /// The camera now: `{ eye, target, up, fov }` (arrays of three numbers; degrees).
  get camera() {
    return this.#alive().camera;
  }

  /// Turns the camera about its target: `yaw` degrees about the up axis, `pitch` about the view's
  /// right axis.
  turn(yaw, pitch = 0) {
    this.#alive().turn(yaw, pitch);
  }

  /// Puts the eye on a sphere about the target, as model-viewer's camera-orbit: `theta` degrees
  /// about the up axis from the front (+z), `phi` degrees down from the up axis, at `radius`
  /// (times the scene's own distance where `relative`; omitted: as far as now). Throws the line
  /// of a refused value.
  placeCamera(theta, phi, radius, relative = false) {
    const why = this.#alive().place_camera(theta, phi, radius ?? undefined, relative);
    if (why !== undefined) throw new Error(why);
  }

  /// The vertical field of view in degrees; `null`: the scene's own. Throws the line of a refused one.
  setFieldOfView(degrees) {
    const why = this.#alive().set_field_of_view(degrees ?? undefined);
    if (why !== undefined) throw new Error(why);
  }

  /// Draws at `width` x `height` pixels from the next frame on (the canvas's drawing buffer; its
  /// size on the page is the page's); throws the line where the adapter refuses the size, which
  /// leaves the previous one.
  resize(width, height) {
    const why = this.#alive().resize(width, height);
    if (why !== undefined) throw new Error(why);
  }

  /// What runs: `{ frames, backend, adapter, scene, error, lost, busy, samples, spp, fps, ... }`.
  get status() {
    return this.#inner ? this.#inner.status : null;
  }

  /// The frames drawn so far, at any moment (the status's `frames` is published four times a
  /// second); 0 once disposed.
  get frames() {
    return this.#inner ? this.#inner.frames : 0;
  }

  /// Changes settings by the URL's names: `{ accel: "stack", spp: 16 }`. Each one taken lands at
  /// once or a few frames later; a refused one throws its line after the others are applied.
  set(settings) {
    const refused = [];
    for (const [key, value] of Object.entries(settings)) {
      const why = this.#alive().set(key, String(value));
      if (why !== undefined) refused.push(why);
    }
    if (refused.length) throw new Error(refused.join("; "));
  }

  /// Opens a model, scene or environment: a URL (relative to the document), a File, or an
  /// ArrayBuffer or typed array with its `name` (the name's extension says the format). Resolves once
  /// it is shown; rejects with the one-line message (the current scene stays).
  async load(source, name) {
    const inner = this.#alive();
    let bytes;
    if (typeof source === "string" || source instanceof URL) {
      let file;
      try {
        file = await fetchFile(source);
      } catch (error) {
        return this.#refuse(error.message);
      }
      name ??= file.name;
      bytes = file.bytes;
    } else if (typeof Blob !== "undefined" && source instanceof Blob) {
      name ??= source.name;
      bytes = new Uint8Array(await source.arrayBuffer());
    } else if (source instanceof ArrayBuffer || ArrayBuffer.isView(source)) {
      bytes = source instanceof ArrayBuffer
        ? new Uint8Array(source)
        : new Uint8Array(source.buffer, source.byteOffset, source.byteLength);
    } else {
      return this.#refuse("load: give a URL, a File or an ArrayBuffer");
    }
    if (!name) return this.#refuse("load: name the bytes (its extension says the format: model.glb, scene.toml, sky.hdr)");
    await inner.load(name, bytes).catch((error) => {
      throw new Error(error?.message ?? String(error));
    });
  }

  /// The frame shown, as a PNG Blob (as on the canvas: exposed, tone-mapped, sRGB).
  async screenshot() {
    const reading = this.#alive().screenshot();
    this.#reading.add(reading);
    try {
      return new Blob([await reading], { type: "image/png" });
    } catch (error) {
      throw new Error(error?.message ?? String(error));
    } finally {
      this.#reading.delete(reading);
    }
  }

  /// A key by its `KeyboardEvent.code` (the viewer's keys: R, B, G, M, V, [ ], Space; W A S D Q E
  /// held to fly); returns whether the viewer used it.
  key(code, pressed) {
    return this.#alive().key(code, pressed);
  }

  /// Stops drawing and frees the viewer's GPU resources and listeners; other viewers go on.
  dispose() {
    const inner = this.#inner;
    if (!inner) return;
    this.#inner = null;
    for (const [target, type, listener, options] of this.#listeners) target.removeEventListener(type, listener, options);
    this.#listeners = [];
    inner.dispose();
    if (this.#made) this.canvas.remove();
    // Its memory in the module goes once no screenshot is being read.
    Promise.allSettled([...this.#reading]).then(() => inner.free());
  }

  #alive() {
    if (!this.#inner) throw new Error("the viewer was disposed");
    return this.#inner;
  }

  #refuse(line) {
    this.#inner?.report(line);
    throw new Error(line);
  }

  #on(target, type, listener, options) {
    target.addEventListener(type, listener, options);
    this.#listeners.push([target, type, listener, options]);
  }

  /// One pointer drags (the primary button orbits, the others pan); two pinch to dolly and move
  /// together to pan; the wheel dollies; keys act while the canvas has the focus. Pointers are
  /// told apart by id and captured, a cancelled one is let go, and the canvas takes touches itself
  /// (`touch-action: none`), so that a finger's drag does not scroll the page.
  #listen() {
    this.#listening = true;
    const canvas = this.canvas;
    if (!canvas.hasAttribute("tabindex")) canvas.tabIndex = 0;
    canvas.style.touchAction = "none";
    const gestures = new Gestures();
    const release = (event) => gestures.release(event.pointerId);
    this.#on(canvas, "pointerdown", (event) => {
      if (!this.#input) return;
      gestures.down(event.pointerId, event.clientX, event.clientY, event.button);
      canvas.setPointerCapture(event.pointerId);
      canvas.focus();
    });
    this.#on(canvas, "pointermove", (event) => {
      const actions = gestures.move(event.pointerId, event.clientX, event.clientY);
      for (const action of this.#inner ? actions : []) {
        if (action.drag) this.#inner.drag(...action.drag);
        else this.#inner.dolly(action.dolly);
      }
    });
    for (const type of ["pointerup", "pointercancel", "lostpointercapture"]) this.#on(canvas, type, release);
    this.#on(canvas, "contextmenu", (event) => event.preventDefault());
    this.#on(canvas, "wheel", (event) => {
      if (!this.#input) return;
      event.preventDefault();
      this.#inner?.dolly(-event.deltaY / (event.deltaMode === 0 ? 100 : 1));
    }, { passive: false });
    this.#on(canvas, "keydown", (event) => {
      if (!this.#input) return;
      if (!event.repeat && this.#inner?.key(event.code, true)) event.preventDefault();
    });
    this.#on(canvas, "keyup", (event) => this.#input && this.#inner?.key(event.code, false));
  }
}

// After the module's own bindings exist: an element already on the page starts at once.
if (typeof customElements !== "undefined" && !customElements.get("raypipe-viewer")) {
  customElements.define("raypipe-viewer", RaypipeViewerElement);
}
