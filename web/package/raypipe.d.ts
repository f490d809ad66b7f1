// Types of raypipe's JavaScript API (raypipe.js).

/** The browser API a viewer traces through: WebGPU where the browser has it, else WebGL2 (`auto`). */
export type Backend = "auto" | "webgpu" | "webgl2";
/** The acceleration: brute force, or the LBVH walked with a stack, stacklessly, by threads, or collapsed into compressed 8-wide nodes. */
export type Accel = "brute" | "stack" | "stackless" | "threaded" | "wide";
export type Builder = "lbvh" | "sah";
export type Memory = "uniform" | "storage" | "texture";
export type Pipeline = "fragment" | "compute";
export type View = "color" | "depth" | "normal" | "cost";
export type ToneMap = "none" | "neutral" | "aces";
/** How light is carried: the paper's Whitted tracer, or a path tracer (the default for glTF files). */
export type Integrator = "whitted" | "path";

/** Settings a running viewer changes (`viewer.set`), by the page's URL names. */
export interface Settings {
  /** A built-in scene: `whitted`, `sphere-8k`, `torus-5k`, `random:N[:SEED]`, `bounce:N[:SEED]`. */
  scene?: string;
  accel?: Accel;
  builder?: Builder;
  memory?: Memory;
  pipeline?: Pipeline;
  /** Bounces per ray. */
  depth?: number;
  integrator?: Integrator;
  aov?: View;
  /** Stops: radiance times 2^EV before the tone map. */
  exposure?: number;
  tonemap?: ToneMap;
  paused?: boolean;
  /** Whether a model file stands on a checker floor. */
  floor?: boolean;
  /** Seconds into the motion. */
  time?: number;
  /** Scene seconds per second. */
  speed?: number;
  /** Samples per pixel a still frame gathers, one per frame. */
  spp?: number;
}

/** What a viewer starts with. */
export interface ViewerOptions extends Settings {
  backend?: Backend;
  /** The canvas's size in pixels (960 x 540 unless given). */
  width?: number;
  height?: number;
  /** A model or scene file to load once the viewer runs, by URL. */
  model?: string;
  /** An environment (.hdr, .exr) to light every scene with, by URL, loaded before the model. */
  environment?: string;
  /** `false`: no orbit, pan, dolly or keys on the canvas (the page drives the viewer itself). */
  input?: boolean;
  /** `false`: a bad option is shown in `status.error` and skipped, where by default it rejects. */
  strict?: boolean;
}

/**
 * What runs, as the viewer publishes it: at once when a setting, the scene, an error or the
 * samples' completion changes; four times a second while only the frame count, the clock and the
 * rates move. Its schema is the viewer's (raypipe-web's status.rs), which a test holds to this.
 */
export interface ViewerStatus {
  frames: number;
  backend: "webgpu" | "webgl2";
  adapter: string;
  scene: string;
  /** The one-line message shown, if any. */
  error: string | null;
  /** Whether the GPU is lost (until the viewer has drawn again on a new device). */
  lost: boolean;
  /** Whether a tracer is being built. */
  busy: boolean;
  width: number;
  height: number;
  primitives: number;
  pipeline: Pipeline;
  accel: Accel;
  builder: Builder;
  memory: Memory;
  /** The memory modes this adapter offers. */
  memories: Memory[];
  depth: number;
  integrator: Integrator;
  aov: View;
  exposure: number;
  tonemap: ToneMap;
  paused: boolean;
  floor: boolean;
  environment: string | null;
  moving: boolean;
  time: number;
  duration: number | null;
  speed: number;
  /** Samples per pixel in the frame shown, and the number gathered at most. */
  samples: number;
  spp: number;
  /** Frames per second and milliseconds per frame, by the wall clock. */
  fps: number;
  frameMs: number;
  buildMs: number | null;
  firstFrameMs: number | null;
  camera: ViewerCamera;
}

/** The camera: points and the up vector as arrays of three numbers, the vertical field of view in degrees. */
export interface ViewerCamera {
  eye: [number, number, number];
  target: [number, number, number];
  up: [number, number, number];
  fov: number;
}

export interface ViewerEventMap {
  status: CustomEvent<ViewerStatus>;
}

export declare class Viewer extends EventTarget {
  /** The canvas it draws on. */
  readonly canvas: HTMLCanvasElement;
  /** What runs; `null` once disposed. */
  readonly status: ViewerStatus | null;
  /** The frames drawn so far, at any moment (the status's `frames` is published four times a second); 0 once disposed. */
  readonly frames: number;
  /** Changes settings; throws the line of any refused (after applying the others). */
  set(settings: Settings): void;
  /** Opens a model, scene or environment; resolves once it is shown, rejects with the one-line message. */
  load(source: string | URL | Blob | ArrayBuffer | ArrayBufferView, name?: string): Promise<void>;
  /** The frame shown as a PNG. */
  screenshot(): Promise<Blob>;
  /** A key by its `KeyboardEvent.code`; whether the viewer used it. */
  key(code: string, pressed: boolean): boolean;
  /** Whether pointers, the wheel and keys on the canvas move the camera. */
  input: boolean;
  /** Draws at `width` x `height` pixels (the drawing buffer); throws the line where the adapter refuses it. */
  resize(width: number, height: number): void;
  /** The camera now (points as arrays of three numbers, the vertical field of view in degrees). */
  readonly camera: ViewerCamera;
  /** Turns the camera about its target: degrees about the up axis and about the view's right axis. */
  turn(yaw: number, pitch?: number): void;
  /** The eye on a sphere about the target (model-viewer's camera-orbit, in degrees); `relative`: the radius times the scene's own distance. */
  placeCamera(theta: number, phi: number, radius?: number | null, relative?: boolean): void;
  /** The vertical field of view in degrees; `null`: the scene's own. */
  setFieldOfView(degrees: number | null): void;
  /** Stops drawing and frees its GPU resources and listeners. */
  dispose(): void;
  addEventListener<K extends keyof ViewerEventMap>(
    type: K,
    listener: (this: Viewer, event: ViewerEventMap[K]) => void,
    options?: boolean | AddEventListenerOptions,
  ): void;
  addEventListener(type: string, listener: EventListenerOrEventListenerObject | null, options?: boolean | AddEventListenerOptions): void;
  removeEventListener<K extends keyof ViewerEventMap>(
    type: K,
    listener: (this: Viewer, event: ViewerEventMap[K]) => void,
    options?: boolean | EventListenerOptions,
  ): void;
  removeEventListener(type: string, listener: EventListenerOrEventListenerObject | null, options?: boolean | EventListenerOptions): void;
}

/** A viewer on a canvas, or on a canvas made inside a container. Rejects with the one-line reason. */
export declare function createViewer(element: HTMLElement, options?: ViewerOptions): Promise<Viewer>;

/** Loads the wasm module (once); createViewer calls it. */
export declare function ready(): Promise<unknown>;

/** The settings' lists and limits, and the file types `load` opens. */
export declare function choices(): Promise<{
  choices: {
    accel: Accel[];
    builder: Builder[];
    memory: Memory[];
    pipeline: Pipeline[];
    aov: View[];
    tonemap: ToneMap[];
    integrator: Integrator[];
  };
  accept: string;
  maxDepth: number;
  maxSpp: number;
}>;

/** What `<raypipe-viewer>`'s `progress` event says: bytes fetched (`total` 0 where the server gives no length), then the build. */
export interface ProgressDetail {
  phase: "fetch" | "build";
  loaded: number;
  total: number;
}

export interface RaypipeViewerEventMap {
  status: CustomEvent<ViewerStatus>;
  /** The model of `src` is shown. */
  load: CustomEvent<{ url: string }>;
  /** A file, an attribute or the GPU failed; the previous scene stays drawn. */
  error: CustomEvent<{ message: string }>;
  progress: CustomEvent<ProgressDetail>;
  /** render-scale="auto" changed the scale, after frames of `frameMs`. */
  "render-scale": CustomEvent<{ scale: number; frameMs: number }>;
}

/** `<raypipe-viewer>`, defined when this module is imported: attributes and properties of the same names (docs/web.md). */
export declare class RaypipeViewerElement extends HTMLElement {
  /** The viewer, once started; `null` before and once the element left the page. */
  readonly viewer: Viewer | null;
  /** The viewer's status; `null` before it starts. */
  readonly status: ViewerStatus | null;
  src: string | null;
  environmentImage: string | null;
  /** A factor, as model-viewer's (1: as authored). */
  exposure: number;
  /** `null`: the scene's own. */
  toneMapping: "auto" | "neutral" | "aces" | "linear" | "none" | null;
  cameraControls: boolean;
  alt: string | null;
  poster: string | null;
  loading: "auto" | "lazy" | "eager";
  accel: Accel | null;
  /** `null`: the scene's own (path for a glTF file). */
  integrator: Integrator | null;
  backend: "auto" | "webgpu" | "webgl2";
  /** The drawing buffer's share of the element's device pixels, above 0, at most 1; set `"auto"` to hold `frameBudget` (reading it then gives the scale drawn at). */
  renderScale: number | "auto";
  /** render-scale="auto"'s frame time, in milliseconds (33 by default). */
  frameBudget: number;
  autoRotate: boolean;
  /** `theta phi radius`, as model-viewer's: `"0deg 75deg 105%"`, `"auto auto 2m"`. */
  cameraOrbit: string | null;
  /** `"30deg"`, or `"auto"` (the scene's own). */
  fieldOfView: string | null;
  addEventListener<K extends keyof RaypipeViewerEventMap>(
    type: K,
    listener: (this: RaypipeViewerElement, event: RaypipeViewerEventMap[K]) => void,
    options?: boolean | AddEventListenerOptions,
  ): void;
  addEventListener(type: string, listener: EventListenerOrEventListenerObject | null, options?: boolean | AddEventListenerOptions): void;
}

declare global {
  interface HTMLElementTagNameMap {
    "raypipe-viewer": RaypipeViewerElement;
  }
}
