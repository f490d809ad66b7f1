// The page's controls: they pass the user's input to the viewer (wasm) and show what
// window.raypipeStatus, which the viewer publishes every frame, says.
import init, { controls as offered, start } from "./raypipe_web.js";

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

function watch() {
  const status = window.raypipeStatus;
  if (status && status.backend) describe(status);
  else if (status) show(status.error);
  requestAnimationFrame(watch);
}

async function open(viewer, file) {
  const bytes = new Uint8Array(await file.arrayBuffer());
  viewer.open_file(file.name, bytes);
}

function wire(viewer) {
  controls.addEventListener("change", (event) => {
    const input = event.target;
    if (input.id === "file") {
      if (input.files.length) open(viewer, input.files[0]);
      input.value = "";
    } else if (input.id === "scene-name") {
      if (input.value.trim()) viewer.set("scene", input.value.trim());
    } else if (input.dataset.key) {
      const value = input.type === "checkbox" ? String(input.checked) : input.value;
      viewer.set(input.dataset.key, value);
    }
  });
  controls.addEventListener("submit", (event) => event.preventDefault());

  let last = null;
  canvas.addEventListener("pointerdown", (event) => {
    last = { x: event.clientX, y: event.clientY, pan: event.button !== 0 };
    canvas.setPointerCapture(event.pointerId);
    canvas.focus();
  });
  canvas.addEventListener("pointermove", (event) => {
    if (!last) return;
    viewer.drag(event.clientX - last.x, event.clientY - last.y, last.pan);
    last = { ...last, x: event.clientX, y: event.clientY };
  });
  canvas.addEventListener("pointerup", () => { last = null; });
  canvas.addEventListener("contextmenu", (event) => event.preventDefault());
  canvas.addEventListener("wheel", (event) => {
    event.preventDefault();
    viewer.dolly(-event.deltaY / (event.deltaMode === 0 ? 100 : 1));
  }, { passive: false });

  const typing = () => ["INPUT", "SELECT"].includes(document.activeElement?.tagName);
  document.addEventListener("keydown", (event) => {
    if (!typing() && !event.repeat && viewer.key(event.code, true)) event.preventDefault();
  });
  document.addEventListener("keyup", (event) => viewer.key(event.code, false));

  document.addEventListener("dragover", (event) => event.preventDefault());
  document.addEventListener("drop", (event) => {
    event.preventDefault();
    const file = event.dataTransfer?.files?.[0];
    if (file) open(viewer, file);
  });
}

/// The controls' lists, limits and file types, as the wasm module (Rust) has them.
function fill() {
  const { choices, accept, maxDepth, maxSpp } = offered();
  for (const [key, names] of Object.entries(choices)) {
    const select = controls.querySelector(`select[data-key=${key}]`);
    for (const name of names) select.add(new Option(name));
  }
  document.getElementById("file").accept = accept;
  controls.querySelector("[data-key=depth]").max = String(maxDepth);
  controls.querySelector("[data-key=spp]").max = String(maxSpp);
}

async function main() {
  await init();
  fill();
  const viewer = await start(canvas, window.location.search);
  window.raypipeViewer = viewer;
  const scene = new URLSearchParams(window.location.search).get("scene");
  if (scene) {
    const select = document.getElementById("scene");
    if (![...select.options].some((o) => o.value === scene)) select.add(new Option(scene), 0);
    select.value = scene;
  }
  wire(viewer);
  // The environment first: it lights the model opened after it.
  const environment = new URLSearchParams(window.location.search).get("environment");
  if (environment) await fetchModel(viewer, environment);
  const model = new URLSearchParams(window.location.search).get("model");
  if (model) await fetchModel(viewer, model);
}

/// Opens `?model=URL` or `?environment=URL`, fetched relative to the page: the file's name (the
/// URL's last segment) picks its format. A failed fetch shows its line, as a broken file does, and
/// the scene stays.
async function fetchModel(viewer, url) {
  let response;
  try {
    response = await fetch(new URL(url, window.location.href));
  } catch (error) {
    viewer.report(`${url}: cannot fetch: ${error.message}`);
    return;
  }
  if (!response.ok) {
    viewer.report(`${url}: cannot fetch: HTTP ${response.status} ${response.statusText}`.trimEnd());
    return;
  }
  const name = decodeURIComponent(new URL(response.url).pathname.split("/").pop() || url);
  viewer.open_file(name, new Uint8Array(await response.arrayBuffer()));
}

watch();
main().catch((error) => {
  // start() has already published the reason in window.raypipeStatus.error; a failure to load the
  // module itself has not.
  const line = String(error?.message ?? error);
  if (!window.raypipeStatus) {
    window.raypipeStatus = { frames: 0, backend: null, adapter: null, scene: null, error: line };
  }
  show(window.raypipeStatus.error ?? line);
});
