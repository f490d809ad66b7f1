// The demo page: one viewer of the npm package (raypipe.js), its settings from the URL, and
// controls that pass the user's input to it and show what its status says. The status is also
// window.raypipeStatus and the viewer window.raypipeViewer, for the page's tests.
import { choices, createViewer } from "./raypipe.js";

const canvas = document.getElementById("frame");
const message = document.getElementById("message");
const controls = document.getElementById("controls");

function show(error) {
  message.hidden = !error;
  message.textContent = error ?? "";
}

function describe(status) {
  document.getElementById("adapter").textContent =
    `${status.scene} · ${status.primitives} primitives · ${status.width}x${status.height} · ` +
    `${status.backend}: ${status.adapter}`;
  const build = status.buildMs == null ? "" : ` · BVH build ${status.buildMs.toFixed(2)} ms`;
  document.getElementById("speed").textContent =
    `${status.fps.toFixed(1)} fps · ${status.frameMs.toFixed(2)} ms per frame (wall clock)${build}`;
  const done = status.samples >= status.spp ? " (done)" : "";
  const busy = status.busy ? " · building the tracer…" : "";
  document.getElementById("samples").textContent =
    `${status.samples} of ${status.spp} samples per pixel${done}${busy}`;
  for (const input of controls.querySelectorAll("[data-key]")) {
    if (input === document.activeElement) continue;
    const value = status[input.dataset.key];
    if (input.type === "checkbox") input.checked = Boolean(value);
    else if (value != null && input.dataset.key !== "scene") input.value = String(value);
  }
  for (const option of controls.querySelectorAll("[data-key=memory] option")) {
    option.disabled = !status.memories.includes(option.value);
  }
  for (const option of controls.querySelectorAll("[data-key=pipeline] option")) {
    option.disabled = option.value === "compute" && status.backend !== "webgpu";
  }
  show(status.error);
}

/// Opens a file the user gave; a broken one shows its line (the viewer's status), and the scene stays.
function open(viewer, file) {
  viewer.load(file).catch(() => {});
}

function wire(viewer) {
  controls.addEventListener("change", (event) => {
    const input = event.target;
    if (input.id === "file") {
      if (input.files.length) open(viewer, input.files[0]);
      input.value = "";
    } else if (input.id === "scene-name") {
      if (input.value.trim()) change(viewer, { scene: input.value.trim() });
    } else if (input.dataset.key) {
      change(viewer, { [input.dataset.key]: input.type === "checkbox" ? input.checked : input.value });
    }
  });
  controls.addEventListener("submit", (event) => event.preventDefault());

  // The canvas takes keys while it has the focus (the package's input); the rest of the page too,
  // but for its form fields.
  const elsewhere = (event) => !["INPUT", "SELECT", "CANVAS"].includes(event.target?.tagName);
  document.addEventListener("keydown", (event) => {
    if (elsewhere(event) && !event.repeat && viewer.key(event.code, true)) event.preventDefault();
  });
  document.addEventListener("keyup", (event) => {
    if (elsewhere(event)) viewer.key(event.code, false);
  });

  document.addEventListener("dragover", (event) => event.preventDefault());
  document.addEventListener("drop", (event) => {
    event.preventDefault();
    const file = event.dataTransfer?.files?.[0];
    if (file) open(viewer, file);
  });
}

/// A change from the controls: a refused one shows its line through the status.
function change(viewer, settings) {
  try {
    viewer.set(settings);
  } catch {}
}

/// The controls' lists, limits and file types, as the wasm module (Rust) has them.
async function fill() {
  const { choices: lists, accept, maxDepth, maxSpp } = await choices();
  for (const [key, names] of Object.entries(lists)) {
    const select = controls.querySelector(`select[data-key=${key}]`);
    for (const name of names) select.add(new Option(name));
  }
  document.getElementById("file").accept = accept;
  controls.querySelector("[data-key=depth]").max = String(maxDepth);
  controls.querySelector("[data-key=spp]").max = String(maxSpp);
}

async function main() {
  await fill();
  const query = Object.fromEntries(new URLSearchParams(window.location.search));
  const { model, environment, ...options } = query;
  // Not strict: a bad setting in the address is shown, and the page starts without it.
  const viewer = await createViewer(canvas, { ...options, strict: false });
  window.raypipeViewer = viewer;
  viewer.addEventListener("status", (event) => {
    window.raypipeStatus = event.detail;
    describe(event.detail);
  });
  window.raypipeStatus = viewer.status;
  describe(viewer.status);
  const scene = query.scene;
  if (scene) {
    const select = document.getElementById("scene");
    if (![...select.options].some((o) => o.value === scene)) select.add(new Option(scene), 0);
    select.value = scene;
  }
  wire(viewer);
  // The environment first: it lights the model opened after it. A failure shows its line.
  if (environment) await viewer.load(environment).catch(() => {});
  if (model) await viewer.load(model).catch(() => {});
}

main().catch((error) => {
  const line = String(error?.message ?? error);
  window.raypipeStatus = { frames: 0, backend: null, adapter: null, scene: null, error: line };
  show(line);
});
