// <raypipe-viewer>: raypipe as one element of a page, defined when the package's module
// (raypipe.js) is imported. Its attributes follow model-viewer's where they mean the same (src, environment-image,
// exposure, tone-mapping, camera-controls, alt, poster, loading), with raypipe's own beside them
// (accel, integrator, backend, render-scale). The canvas inside draws at the element's size on the page times
// the device pixel ratio times render-scale, and follows it as it changes.
import { fetchFile } from "./fetch.js";
import { createViewer } from "./raypipe.js";

/// model-viewer's tone-mapping names, as raypipe's tone maps (`tonemap`).
const TONE_MAPS = { auto: "neutral", neutral: "neutral", aces: "aces", linear: "none", none: "none" };

/// A side shrinks by this, and is tried again, where the adapter refuses a size.
const SHRINK = 0.75;

/// auto-rotate's speed and its wait after the user's last touch of the camera, as model-viewer's
/// defaults (rotation-per-second, auto-rotate-delay).
const ROTATION_DEGREES_PER_SECOND = 32;
const ROTATION_DELAY_MS = 3000;

/// render-scale="auto": the frame time it holds by default (frame-budget), how often it looks,
/// how far it may lower the scale, and the share of the budget below which it raises it again.
const FRAME_BUDGET_MS = 33;
const GOVERNOR_PERIOD_MS = 500;
const MIN_AUTO_SCALE = 0.25;
const RAISE_BELOW = 0.6;

/// An arrow key's turn of the camera, in degrees.
const ARROW_DEGREES = 10;

/// camera-orbit's terms where it says `auto`: model-viewer's defaults, the radius as the scene's
/// own camera distance.
const ORBIT_DEFAULTS = ["0deg", "75deg", "100%"];

const STYLE = `
:host { display: block; position: relative; width: 300px; height: 150px; overflow: hidden; }
:host([hidden]) { display: none; }
canvas { position: absolute; inset: 0; width: 100%; height: 100%; display: block; outline: none; }
canvas.waiting { visibility: hidden; }
img { position: absolute; inset: 0; width: 100%; height: 100%; object-fit: contain; pointer-events: none; }
`;

export class RaypipeViewerElement extends HTMLElement {
  static observedAttributes = [
    "src", "environment-image", "exposure", "tone-mapping", "camera-controls", "alt", "poster", "loading",
    "accel", "integrator", "backend", "render-scale", "frame-budget", "auto-rotate", "camera-orbit", "field-of-view",
  ];

  #viewer = null;
  #canvas;
  #poster;
  #starting = null;
  #resizes = null;
  #sight = null;
  #frame = 0;
  /// The model shown, and the one asked for last (a later `src` wins over an earlier load).
  #shown = null;
  #asked = null;
  #turning = 0;
  #touched = -Infinity;
  /// render-scale="auto": the scale it holds now, and its clock.
  #autoScale = 1;
  #governor = 0;

  constructor() {
    super();
    const root = this.attachShadow({ mode: "open" });
    root.innerHTML = `<style>${STYLE}</style><canvas part="canvas"></canvas><img part="poster" alt="" hidden>`;
    this.#canvas = root.querySelector("canvas");
    this.#poster = root.querySelector("img");
    // The user's touch of the camera holds auto-rotate off for a while; the arrow keys orbit.
    for (const type of ["pointerdown", "wheel", "keydown"]) {
      this.addEventListener(type, () => { this.#touched = performance.now(); }, { passive: true });
    }
    this.addEventListener("keydown", (event) => this.#arrow(event));
  }

  /// The viewer (`Viewer` of `createViewer`), once the element has started; `null` before and
  /// once it left the page.
  get viewer() {
    return this.#viewer;
  }

  /// The viewer's status, as its `status` event says it; `null` before it starts.
  get status() {
    return this.#viewer?.status ?? null;
  }

  connectedCallback() {
    if (!this.hasAttribute("role")) this.setAttribute("role", "img");
    this.#label();
    this.#showPoster();
    // `auto` (the default) is `lazy`, as model-viewer's: the viewer starts once the element is in
    // view; `eager` starts it at once.
    if (this.getAttribute("loading") !== "eager" && typeof IntersectionObserver !== "undefined") {
      this.#sight = new IntersectionObserver((entries) => {
        if (entries.some((entry) => entry.isIntersecting)) {
          this.#sight?.disconnect();
          this.#sight = null;
          this.#start();
        }
      });
      this.#sight.observe(this);
    } else {
      this.#start();
    }
  }

  disconnectedCallback() {
    this.#sight?.disconnect();
    this.#sight = null;
    this.#stop();
  }

  attributeChangedCallback(name, before, now) {
    if (before === now) return;
    if (name === "alt") return this.#label();
    if (name === "poster") return this.#showPoster();
    if (!this.#viewer) return;
    switch (name) {
      case "src":
        return this.#loadModel();
      case "environment-image":
        return this.#loadEnvironment();
      case "render-scale":
        this.#govern();
        return this.#fit();
      case "frame-budget":
        return this.#govern();
      case "auto-rotate":
        return this.#rotate();
      case "camera-orbit":
        return this.#orbit();
      case "field-of-view":
        return this.#fieldOfView();
      case "backend":
        // A backend is chosen when a viewer starts: a new one, with the same model.
        this.#stop();
        return this.#start();
      default:
        return this.#apply(name);
    }
  }

  // ---- src, environment-image and the others as attributes and properties of the same names.

  get src() { return this.getAttribute("src"); }
  set src(value) { this.#reflect("src", value); }
  get environmentImage() { return this.getAttribute("environment-image"); }
  set environmentImage(value) { this.#reflect("environment-image", value); }
  get exposure() { return Number(this.getAttribute("exposure") ?? 1); }
  set exposure(value) { this.#reflect("exposure", value); }
  get toneMapping() { return this.getAttribute("tone-mapping"); }
  set toneMapping(value) { this.#reflect("tone-mapping", value); }
  get cameraControls() { return this.hasAttribute("camera-controls"); }
  set cameraControls(value) { this.toggleAttribute("camera-controls", Boolean(value)); }
  get alt() { return this.getAttribute("alt"); }
  set alt(value) { this.#reflect("alt", value); }
  get poster() { return this.getAttribute("poster"); }
  set poster(value) { this.#reflect("poster", value); }
  get loading() { return this.getAttribute("loading") ?? "auto"; }
  set loading(value) { this.#reflect("loading", value); }
  get accel() { return this.getAttribute("accel"); }
  set accel(value) { this.#reflect("accel", value); }
  get integrator() { return this.getAttribute("integrator"); }
  set integrator(value) { this.#reflect("integrator", value); }
  get backend() { return this.getAttribute("backend") ?? "auto"; }
  set backend(value) { this.#reflect("backend", value); }
  /// A number, or "auto"; reading it gives the scale drawn at now.
  get renderScale() { return this.#auto() ? this.#autoScale : Number(this.getAttribute("render-scale") ?? 1); }
  set renderScale(value) { this.#reflect("render-scale", value); }
  get frameBudget() { return Number(this.getAttribute("frame-budget") ?? FRAME_BUDGET_MS); }
  set frameBudget(value) { this.#reflect("frame-budget", value); }
  get autoRotate() { return this.hasAttribute("auto-rotate"); }
  set autoRotate(value) { this.toggleAttribute("auto-rotate", Boolean(value)); }
  get cameraOrbit() { return this.getAttribute("camera-orbit"); }
  set cameraOrbit(value) { this.#reflect("camera-orbit", value); }
  get fieldOfView() { return this.getAttribute("field-of-view"); }
  set fieldOfView(value) { this.#reflect("field-of-view", value); }

  #reflect(name, value) {
    if (value === null || value === undefined) this.removeAttribute(name);
    else this.setAttribute(name, String(value));
  }

  #label() {
    const alt = this.getAttribute("alt");
    if (alt) this.setAttribute("aria-label", alt);
    else this.removeAttribute("aria-label");
  }

  #showPoster() {
    const poster = this.getAttribute("poster");
    if (poster) this.#poster.src = new URL(poster, document.baseURI).href;
    this.#poster.hidden = !poster || this.#shown !== null;
  }

  /// The drawing buffer's size: the element's on the page, in device pixels, times render-scale.
  #wanted(scale = this.#scale()) {
    const box = this.getBoundingClientRect();
    const ratio = window.devicePixelRatio || 1;
    return [box.width, box.height].map((side) => Math.max(1, Math.round(side * ratio * scale)));
  }

  #auto() {
    return this.getAttribute("render-scale")?.trim() === "auto";
  }

  #scale() {
    if (this.#auto()) return this.#autoScale;
    const scale = Number(this.getAttribute("render-scale") ?? 1);
    return Number.isFinite(scale) && scale > 0 ? Math.min(scale, 1) : 1;
  }

  async #start() {
    if (this.#viewer || this.#starting || !this.isConnected) return;
    const backend = this.getAttribute("backend") ?? "auto";
    const [width, height] = this.#wanted();
    this.#canvas.classList.toggle("waiting", this.hasAttribute("src"));
    const starting = createViewer(this.#canvas, { backend, width, height, input: this.hasAttribute("camera-controls") });
    this.#starting = starting;
    let viewer;
    try {
      viewer = await starting;
    } catch (error) {
      if (this.#starting === starting) this.#starting = null;
      return this.#fail(error.message);
    }
    if (this.#starting !== starting || !this.isConnected) return viewer.dispose();
    this.#starting = null;
    this.#viewer = viewer;
    // The canvas fills the element; the viewer sized its drawing buffer.
    this.#canvas.style.width = "100%";
    this.#canvas.style.height = "100%";
    viewer.addEventListener("status", (event) => this.dispatchEvent(new CustomEvent("status", { detail: event.detail })));
    this.#resizes = new ResizeObserver(() => {
      cancelAnimationFrame(this.#frame);
      this.#frame = requestAnimationFrame(() => this.#fit());
    });
    this.#resizes.observe(this);
    for (const name of ["exposure", "tone-mapping", "camera-controls", "accel", "integrator"]) this.#apply(name);
    this.#camera();
    this.#rotate();
    this.#govern();
    if (this.hasAttribute("environment-image")) await this.#loadEnvironment();
    if (this.hasAttribute("src")) await this.#loadModel();
  }

  /// camera-orbit and field-of-view, where given, over the scene's own camera.
  #camera() {
    if (this.hasAttribute("camera-orbit")) this.#orbit();
    if (this.hasAttribute("field-of-view")) this.#fieldOfView();
  }

  #orbit() {
    const value = this.getAttribute("camera-orbit");
    if (!this.#viewer || value === null) return;
    try {
      const terms = value.trim().split(/\s+/);
      if (terms.length > 3 || terms[0] === "") throw new Error("expected up to three terms: theta phi radius");
      const [theta, phi, radius] = ORBIT_DEFAULTS.map((fallback, i) => (terms[i] && terms[i] !== "auto" ? terms[i] : fallback));
      const distance = parseLength(radius);
      this.#viewer.placeCamera(parseAngle(theta), parseAngle(phi), distance.value, distance.relative);
    } catch (error) {
      this.#fail(error.message.startsWith("camera-orbit") ? error.message : `camera-orbit=${value}: ${error.message}`);
    }
  }

  #fieldOfView() {
    const value = this.getAttribute("field-of-view");
    if (!this.#viewer) return;
    try {
      this.#viewer.setFieldOfView(value === null || value.trim() === "auto" ? null : parseAngle(value.trim()));
    } catch (error) {
      this.#fail(error.message.startsWith("field-of-view") ? error.message : `field-of-view=${value}: ${error.message}`);
    }
  }

  /// Turns the camera while auto-rotate is on, the element on the page and the user not at it.
  #rotate() {
    cancelAnimationFrame(this.#turning);
    if (!this.#viewer || !this.hasAttribute("auto-rotate")) return;
    let last = performance.now();
    const step = (now) => {
      if (!this.#viewer || !this.hasAttribute("auto-rotate")) return;
      if (now - this.#touched > ROTATION_DELAY_MS) this.#viewer.turn(ROTATION_DEGREES_PER_SECOND * (now - last) / 1000, 0);
      last = now;
      this.#turning = requestAnimationFrame(step);
    };
    this.#turning = requestAnimationFrame(step);
  }

  #arrow(event) {
    const turns = { ArrowLeft: [ARROW_DEGREES, 0], ArrowRight: [-ARROW_DEGREES, 0], ArrowUp: [0, ARROW_DEGREES], ArrowDown: [0, -ARROW_DEGREES] };
    const turn = turns[event.key];
    if (!turn || !this.#viewer || !this.hasAttribute("camera-controls")) return;
    event.preventDefault();
    this.#viewer.turn(...turn);
  }

  #stop() {
    this.#starting = null;
    this.#resizes?.disconnect();
    this.#resizes = null;
    cancelAnimationFrame(this.#frame);
    cancelAnimationFrame(this.#turning);
    clearInterval(this.#governor);
    this.#viewer?.dispose();
    this.#viewer = null;
    this.#shown = null;
    this.#showPoster();
  }

  /// render-scale="auto": every half second, the frame time over it against frame-budget. Frames
  /// cost about their pixels, so a scale s that took t ms wants s * sqrt(budget / t); it is
  /// lowered at once where frames run over the budget, raised (a tenth at a time) where they run
  /// under RAISE_BELOW of it, and looked at only while the viewer traces (samples to gather, or
  /// motion): a still, finished frame costs nothing to show.
  #govern() {
    clearInterval(this.#governor);
    if (!this.#viewer || !this.#auto()) {
      this.#autoScale = 1;
      return;
    }
    let frames = this.#viewer.frames;
    let since = performance.now();
    this.#governor = setInterval(() => {
      const viewer = this.#viewer;
      const status = viewer?.status;
      if (!viewer || !status) return;
      const now = performance.now();
      const drawn = viewer.frames - frames;
      const elapsed = now - since;
      [frames, since] = [viewer.frames, now];
      const tracing = status.samples < status.spp || status.moving || this.hasAttribute("auto-rotate");
      if (drawn < 2 || status.busy || !tracing) return;
      const frameMs = elapsed / drawn;
      const budget = this.frameBudget > 0 ? this.frameBudget : FRAME_BUDGET_MS;
      const wanted = this.#autoScale * Math.sqrt(budget / frameMs);
      let scale = this.#autoScale;
      if (frameMs > budget) scale = Math.max(MIN_AUTO_SCALE, Math.min(wanted, scale * 0.95));
      else if (frameMs < budget * RAISE_BELOW && scale < 1) scale = Math.min(1, wanted, scale * 1.1);
      // Each new size starts the samples again: only a change of a twentieth or more.
      if (Math.abs(scale - this.#autoScale) >= 0.05 * this.#autoScale || (scale === 1 && this.#autoScale !== 1)) {
        this.#autoScale = scale;
        this.#fit();
        this.dispatchEvent(new CustomEvent("render-scale", { detail: { scale, frameMs } }));
      }
    }, GOVERNOR_PERIOD_MS);
  }

  /// Follows the element's size: the largest the adapter takes, at most the size wanted.
  #fit() {
    const viewer = this.#viewer;
    if (!viewer) return;
    let scale = this.#scale();
    for (;;) {
      const [width, height] = this.#wanted(scale);
      try {
        return viewer.resize(width, height);
      } catch (error) {
        if (Math.max(width, height) * SHRINK < 64) return this.#fail(error.message);
        scale *= SHRINK;
      }
    }
  }

  #apply(name) {
    const viewer = this.#viewer;
    const value = this.getAttribute(name);
    try {
      if (name === "camera-controls") {
        viewer.input = this.hasAttribute("camera-controls");
      } else if (name === "exposure" && value !== null) {
        // model-viewer's exposure multiplies; raypipe's is in stops.
        const factor = Number(value);
        if (!(factor > 0 && Number.isFinite(factor))) throw new Error(`exposure=${value}: expected a positive number`);
        viewer.set({ exposure: Math.log2(factor) });
      } else if (name === "tone-mapping" && value !== null) {
        // Without the attribute, the scene's own tone map.
        const tonemap = TONE_MAPS[value];
        if (!tonemap) throw new Error(`tone-mapping=${value}: expected one of ${Object.keys(TONE_MAPS).join(", ")}`);
        viewer.set({ tonemap });
      } else if (name === "accel" && value !== null) {
        viewer.set({ accel: value });
      } else if (name === "integrator" && value !== null) {
        // Without the attribute, the scene's own: path for a glTF file.
        viewer.set({ integrator: value });
      }
    } catch (error) {
      this.#fail(error.message);
    }
  }

  async #loadModel() {
    const src = this.getAttribute("src");
    this.#asked = src;
    if (!src) return;
    let bytes, name;
    try {
      ({ bytes, name } = await fetchFile(src, (loaded, total) => this.#progress("fetch", loaded, total)));
    } catch (error) {
      return this.#asked === src && this.#fail(error.message);
    }
    if (this.#asked !== src || !this.#viewer) return;
    this.#progress("build", 0, 1);
    try {
      await this.#viewer.load(bytes, name);
    } catch (error) {
      return this.#asked === src && this.#fail(error.message);
    }
    if (this.#asked !== src) return;
    this.#progress("build", 1, 1);
    // A new scene brings its own camera: the element's orbit and field of view apply over it.
    this.#camera();
    this.#shown = src;
    this.#canvas.classList.remove("waiting");
    this.#showPoster();
    this.dispatchEvent(new CustomEvent("load", { detail: { url: src } }));
  }

  async #loadEnvironment() {
    const url = this.getAttribute("environment-image");
    if (!url || !this.#viewer) return;
    try {
      await this.#viewer.load(url);
    } catch (error) {
      this.#fail(error.message);
    }
  }

  #progress(phase, loaded, total) {
    this.dispatchEvent(new CustomEvent("progress", { detail: { phase, loaded, total } }));
  }

  #fail(message) {
    this.dispatchEvent(new CustomEvent("error", { detail: { message } }));
  }
}

/// An angle of camera-orbit or field-of-view (`30deg`, `0.5rad`, a bare number in degrees), in
/// degrees.
function parseAngle(term) {
  const match = /^(-?[\d.]+(?:e-?\d+)?)(deg|rad)?$/.exec(term);
  const number = match ? Number(match[1]) : NaN;
  if (!Number.isFinite(number)) throw new Error(`${term} is not an angle (30deg, 0.5rad)`);
  return match[2] === "rad" ? (number * 180) / Math.PI : number;
}

/// camera-orbit's radius: `105%` of the scene's own distance, or `2m` (`cm`, `mm`, a bare number
/// in metres).
function parseLength(term) {
  const match = /^([\d.]+(?:e-?\d+)?)(%|m|cm|mm)?$/.exec(term);
  const number = match ? Number(match[1]) : NaN;
  if (!(number > 0 && Number.isFinite(number))) throw new Error(`${term} is not a positive length (105%, 2m)`);
  const scale = { "%": 0.01, m: 1, cm: 0.01, mm: 0.001 }[match[2] ?? "m"];
  return { value: number * scale, relative: match[2] === "%" };
}
