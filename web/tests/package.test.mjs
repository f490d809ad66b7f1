// The npm package (scripts/build-web.sh --package), as a user gets it: packed by `npm pack`,
// installed into a scratch folder, imported by its bare name through an import map (no bundler),
// on a page with two viewers (WebGL2 and WebGPU) in headless Chromium, or in Firefox
// (RAYPIPE_BROWSER=firefox, under xvfb-run). Both draw the CPU reference's image (their
// screenshots, compared by `raypipe diff --tolerance color`); a lost WebGL2 context
// (WEBGL_lose_context) and a destroyed WebGPU device are reported and recovered, the same image
// again; dispose() of one leaves the other drawing; both canvases take touches themselves
// (touch-action: none; the gestures are tests/gestures.test.mjs's). The declarations type-check a usage file
// (tsc --noEmit) and name the lists the module offers. The <raypipe-viewer> element: defined on
// import, both backends draw the CPU reference's image at the element's size, it follows a resize
// and render-scale, loads src (progress, load), keeps its scene on a missing one (error), places
// its camera (camera-orbit, field-of-view, auto-rotate, the arrow keys; render-scale="auto"
// under budgets no frame meets and every frame meets; in Chromium, the browser's
// own touches: a finger orbits, two pinch and pan), waits out of view, and lets go of its GPU when
// removed.
//
// Needs the package built (scripts/build-web.sh --package target/web-package, or
// RAYPIPE_PACKAGE_DIR), the native binary (target/release/raypipe, or RAYPIPE_BIN) and the browser.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { execFileSync, spawnSync } from "node:child_process";
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { BROWSER, launch, serve } from "../harness.mjs";

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const root = path.resolve(web, "..");
const built = process.env.RAYPIPE_PACKAGE_DIR ?? path.join(root, "target/web-package");
const raypipe = process.env.RAYPIPE_BIN ?? path.join(root, "target/release/raypipe");
const scratch = path.join(root, "target/package-test");
const COMPILE_MS = 240_000;
const SIZE = { width: 96, height: 72 };

let server;
let browser;
let page;

const PAGE = `<!doctype html>
<meta charset="utf-8">
<link rel="icon" href="data:,">
<script type="importmap">{ "imports": { "raypipe": "./node_modules/raypipe/raypipe.js" } }</script>
<div id="left"></div><canvas id="right"></canvas><div id="spare"></div>
<script type="module">
  import { createViewer } from "raypipe";
  window.createViewer = createViewer;
</script>
`;

// Two elements, one per backend, at the size of the CPU reference image, and a third far below
// them; the package imported after them, so that defining the element starts those in view.
const ELEMENT_PAGE = `<!doctype html>
<meta charset="utf-8">
<link rel="icon" href="data:,">
<script type="importmap">{ "imports": { "raypipe": "./node_modules/raypipe/raypipe.js" } }</script>
<raypipe-viewer id="gl" backend="webgl2" alt="The paper's Whitted scene" camera-controls style="width: 96px; height: 72px"></raypipe-viewer>
<raypipe-viewer id="gpu" backend="webgpu" style="width: 96px; height: 72px"></raypipe-viewer>
<raypipe-viewer id="far" backend="webgl2" style="margin-top: 3000px; width: 40px; height: 30px"></raypipe-viewer>
<script type="module">
  import "raypipe";
  window.heard = { gl: [], gpu: [] };
  window.statuses = { gl: 0, gpu: 0 };
  for (const id of ["gl", "gpu"]) {
    const element = document.getElementById(id);
    element.addEventListener("status", (event) => { if (event.detail.frames != null) window.statuses[id] += 1; });
    for (const type of ["load", "error", "progress"]) {
      element.addEventListener(type, (event) => window.heard[id].push({ type, ...event.detail }));
    }
  }
</script>
`;

before(async () => {
  for (const needed of [path.join(built, "package.json"), raypipe]) {
    assert.ok(fs.existsSync(needed), `${needed} is missing: run scripts/build-web.sh --package target/web-package and cargo build --release`);
  }
  fs.rmSync(scratch, { recursive: true, force: true });
  fs.mkdirSync(scratch, { recursive: true });
  const packed = execFileSync("npm", ["pack", built, "--pack-destination", scratch, "--json", "--loglevel=error"], { encoding: "utf8" });
  const tarball = path.join(scratch, JSON.parse(packed)[0].filename);
  fs.writeFileSync(path.join(scratch, "package.json"), JSON.stringify({ name: "scratch", private: true, type: "module" }));
  execFileSync("npm", ["install", "--no-audit", "--no-fund", "--loglevel=error", tarball], { cwd: scratch });
  fs.writeFileSync(path.join(scratch, "index.html"), PAGE);
  fs.writeFileSync(path.join(scratch, "element.html"), ELEMENT_PAGE);
  fs.writeFileSync(path.join(scratch, "tetrahedron.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  server = await serve({ "/": scratch });
  browser = await launch();
  await openPage();
});

/// A fresh page (the last one closed) with the package imported and the devices it opens listed.
async function openPage() {
  await page?.close();
  page = await browser.newPage({ viewport: { width: 800, height: 600 }, deviceScaleFactor: 1 });
  page.errors = [];
  page.on("pageerror", (error) => page.errors.push(`uncaught: ${error.message}`));
  page.on("console", (message) => {
    if (message.type() === "error") page.errors.push(`console: ${message.text()}`);
  });
  // The devices the page opens, so that the test can destroy one as a driver reset would.
  await page.addInitScript(() => {
    window.gpuDevices = [];
    if (navigator.gpu) {
      const requestDevice = GPUAdapter.prototype.requestDevice;
      GPUAdapter.prototype.requestDevice = async function (...args) {
        const device = await requestDevice.apply(this, args);
        window.gpuDevices.push(device);
        return device;
      };
    }
  });
  await page.goto(`${server.origin}/index.html`);
  await page.waitForFunction(() => window.createViewer, null, { timeout: 30_000 });
}

after(async () => {
  await browser?.close();
  server?.close();
});

/// Waits until viewer `name`'s status satisfies `condition`, failing at once on an error it does not expect.
async function until(name, condition, what, { arg = null, timeout = COMPILE_MS } = {}) {
  const source = condition.toString();
  let met;
  try {
    // The status that met the condition, not one read after it: a lost device may be restored
    // between the two.
    met = await page.waitForFunction(([name, source, arg]) => {
      const status = window.viewers[name].status;
      if (status == null) return false;
      if (status.error != null && !source.includes("error")) throw new Error(status.error);
      return new Function("s", "arg", `return (${source})(s, arg)`)(status, arg) && JSON.stringify(status);
    }, [name, source, arg], { timeout, polling: 100 });
  } catch (error) {
    const now = await page.evaluate((name) => JSON.stringify(window.viewers[name].status), name);
    throw new Error(`waiting for ${what}: ${error.message.split("\n")[0]}; status ${now}; errors ${page.errors}`);
  }
  return JSON.parse(await met.jsonValue());
}

const SETTLED = (s) => s.frames >= 2 && !s.busy && s.samples >= s.spp && !s.lost;

/// Viewer `name`'s screenshot() against the CPU reference of whitted at `spp` samples a pixel.
async function assertShowsWhitted(name, label, spp = 1) {
  const png = await page.evaluate(async (name) => {
    const blob = await window.viewers[name].screenshot();
    if (blob.type !== "image/png") throw new Error(`screenshot() gave ${blob.type}`);
    return [...new Uint8Array(await blob.arrayBuffer())];
  }, name);
  const actual = path.join(scratch, `${label}-actual.png`);
  fs.writeFileSync(actual, Buffer.from(png));
  const expected = path.join(scratch, `whitted-reference-${spp}spp.png`);
  if (!fs.existsSync(expected)) {
    execFileSync(raypipe, ["render", "whitted", "--device", "cpu", "--width", `${SIZE.width}`, "--height", `${SIZE.height}`, "--spp", `${spp}`, "-q", "-o", expected]);
  }
  const difference = path.join(scratch, `${label}-difference.png`);
  const run = spawnSync(raypipe, ["diff", actual, expected, "--tolerance", "color", "--out", difference], { encoding: "utf8" });
  assert.equal(run.status, 0, `${label}: ${run.stdout}${run.stderr} (kept ${actual} and ${difference})`);
}

test("two viewers (WebGL2 in a container, WebGPU on a canvas) draw, survive a lost GPU, and dispose alone", async () => {
  await page.evaluate(async (size) => {
    const options = { scene: "whitted", spp: 1, ...size };
    window.viewers = {
      webgl2: await window.createViewer(document.getElementById("left"), { ...options, backend: "webgl2" }),
      webgpu: await window.createViewer(document.getElementById("right"), { ...options, backend: "webgpu" }),
    };
    window.heard = { webgl2: 0, webgpu: 0 };
    for (const [name, viewer] of Object.entries(window.viewers)) {
      viewer.addEventListener("status", (event) => {
        if (event.detail.frames != null) window.heard[name] += 1;
      });
    }
  }, SIZE);
  for (const name of ["webgl2", "webgpu"]) {
    const status = await until(name, SETTLED, `the ${name} viewer's first frame`);
    assert.equal(status.backend, name);
    assert.equal(status.lost, false);
    await assertShowsWhitted(name, `${name}-first`);
  }
  assert.ok(await page.evaluate(() => window.heard.webgl2 > 0 && window.heard.webgpu > 0), "no status event");
  assert.equal(await page.evaluate(() => document.querySelectorAll("#left > canvas").length), 1);
  // The canvases take touches themselves: a finger's drag turns the camera, not the page.
  assert.deepEqual(
    await page.evaluate(() => [...document.querySelectorAll("canvas")].map((c) => getComputedStyle(c).touchAction)),
    ["none", "none"],
  );

  // WebGL2: the context lost, then restored.
  await page.evaluate(() => {
    window.loseContext = window.viewers.webgl2.canvas.getContext("webgl2").getExtension("WEBGL_lose_context");
    window.loseContext.loseContext();
  });
  const lostGl = await until("webgl2", (s) => s.lost && s.error != null, "the lost WebGL2 context");
  assert.match(lostGl.error, /GPU was lost/);
  await page.evaluate(() => window.loseContext.restoreContext());
  const back = await until("webgl2", (s, frames) => !s.lost && s.error == null && s.frames > frames && s.samples >= 1, "the WebGL2 viewer again", { arg: lostGl.frames });
  assert.equal(back.scene, "whitted");
  await assertShowsWhitted("webgl2", "webgl2-restored");

  // dispose(): the container's canvas goes, the other viewer draws on.
  await page.evaluate(() => window.viewers.webgl2.dispose());
  assert.equal(await page.evaluate(() => document.querySelectorAll("#left > canvas").length), 0);
  assert.equal(await page.evaluate(() => window.viewers.webgl2.status), null);
  const before = await page.evaluate(() => window.viewers.webgpu.status.frames);
  await until("webgpu", (s, frames) => s.frames >= frames + 5, "frames after the other's dispose()", { arg: before, timeout: 60_000 });
  await assert.rejects(() => page.evaluate(() => window.viewers.webgl2.screenshot()), /disposed/);

  // WebGPU: the device destroyed, as a driver reset loses it; a new one is opened and the
  // viewer draws again at once. Last on this page: Firefox (ESR 153) gives a page no animation
  // frame again once a device that presented to one of its canvases is destroyed (a plain
  // WebGPU page too), so there the viewer draws that one frame and no more.
  await page.evaluate(() => window.gpuDevices.at(-1).destroy());
  const lostGpu = await until("webgpu", (s) => s.lost && s.error != null, "the lost WebGPU device");
  assert.match(lostGpu.error, /GPU was lost/);
  await until("webgpu", (s, frames) => !s.lost && s.error == null && s.frames > frames && s.samples >= 1, "the WebGPU viewer again", { arg: lostGpu.frames });
  assert.ok(await page.evaluate(() => window.gpuDevices.length >= 2), "no new device was asked for");
  await assertShowsWhitted("webgpu", "webgpu-restored");
  if (BROWSER !== "firefox") {
    await until("webgpu", (s, frames) => s.frames >= frames + 5, "frames on the new device", { arg: lostGpu.frames + 1, timeout: 60_000 });
  }
  assert.deepEqual(page.errors, []);
});

test("load() resolves when the file is shown and rejects with its line; bad options reject createViewer", async () => {
  await openPage();
  await page.evaluate(async (size) => {
    window.viewers = { webgpu: await window.createViewer(document.getElementById("right"), { scene: "whitted", spp: 1, ...size, backend: "webgpu" }) };
  }, SIZE);
  await until("webgpu", SETTLED, "the viewer's first frame");
  const broken = await page.evaluate(async () => {
    try {
      const ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n" +
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 oops\n0 1 0\n3 0 1 2\n";
      await window.viewers.webgpu.load(new TextEncoder().encode(ply), "broken.ply");
      return null;
    } catch (error) {
      return error.message;
    }
  });
  assert.match(broken ?? "", /^broken\.ply:11: /);
  assert.ok(!broken.includes("\n"));
  const opened = await page.evaluate(async () => {
    const obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    await window.viewers.webgpu.load(new Blob([obj]), "tetrahedron.obj");
    return { ...window.viewers.webgpu.status };
  });
  assert.equal(opened.scene, "tetrahedron.obj");
  assert.equal(opened.primitives, 4);
  const refused = await page.evaluate(async () => {
    try {
      await window.createViewer(document.getElementById("spare"), { scene: "whitted", accel: "fastest" });
      return null;
    } catch (error) {
      return error.message;
    }
  });
  assert.match(refused ?? "", /^accel=fastest: expected one of /);
  assert.equal(await page.evaluate(() => document.querySelectorAll("#spare > canvas").length), 0);
  const setRefused = await page.evaluate(() => {
    try {
      window.viewers.webgpu.set({ depth: 1000 });
      return null;
    } catch (error) {
      return error.message;
    }
  });
  assert.match(setRefused ?? "", /^depth=1000: /);
  assert.deepEqual(page.errors, []);
});

test("the declarations type-check a usage file and name the lists the module offers", async () => {
  fs.writeFileSync(path.join(scratch, "usage.ts"), `import { createViewer, choices, type ViewerStatus } from "raypipe";
const viewer = await createViewer(document.body, { backend: "webgl2", scene: "whitted", spp: 4, input: false });
viewer.addEventListener("status", (event) => { const s: ViewerStatus = event.detail; console.log(s.fps, s.lost); });
viewer.set({ accel: "stack", exposure: 1, tonemap: "aces", integrator: "path" });
await viewer.load("model.glb");
const png: Blob = await viewer.screenshot();
const { maxSpp } = await choices();
console.log(png.size, maxSpp);
viewer.dispose();
const element = document.querySelector("raypipe-viewer")!;
element.renderScale = 0.5;
element.toneMapping = "aces";
element.integrator = "whitted";
element.addEventListener("error", (event) => console.log(event.detail.message));
element.addEventListener("progress", (event) => console.log(event.detail.phase, event.detail.loaded));
console.log(element.viewer?.status?.width);
`);
  fs.writeFileSync(path.join(scratch, "tsconfig.json"), JSON.stringify({
    compilerOptions: { target: "es2022", module: "es2022", moduleResolution: "bundler", strict: true, noEmit: true, lib: ["es2022", "dom"] },
    files: ["usage.ts"],
  }));
  const tsc = spawnSync(path.join(web, "node_modules/.bin/tsc"), ["-p", scratch], { encoding: "utf8" });
  assert.equal(tsc.status, 0, `tsc: ${tsc.stdout}${tsc.stderr}`);
  // A wrong setting must not type-check.
  fs.writeFileSync(path.join(scratch, "usage.ts"), `import { createViewer } from "raypipe";
const viewer = await createViewer(document.body);
viewer.set({ accel: "fastest" });
`);
  const wrong = spawnSync(path.join(web, "node_modules/.bin/tsc"), ["-p", scratch], { encoding: "utf8" });
  assert.notEqual(wrong.status, 0, "tsc took accel: \"fastest\"");

  // Every union of names in the declarations is the module's own list.
  const declarations = fs.readFileSync(path.join(scratch, "node_modules/raypipe/raypipe.d.ts"), "utf8");
  const offered = await page.evaluate(async () => (await import("raypipe")).choices());
  const unions = {
    accel: "Accel",
    builder: "Builder",
    memory: "Memory",
    pipeline: "Pipeline",
    aov: "View",
    tonemap: "ToneMap",
    integrator: "Integrator",
  };
  for (const [key, type] of Object.entries(unions)) {
    const line = declarations.match(new RegExp(`export type ${type} = ([^;]+);`));
    assert.ok(line, `raypipe.d.ts has no type ${type}`);
    const names = [...line[1].matchAll(/"([^"]+)"/g)].map((m) => m[1]);
    assert.deepEqual(names.sort(), [...offered.choices[key]].sort(), `${type} in raypipe.d.ts`);
  }
});

test("<raypipe-viewer> is defined on import, draws at its size, follows it and render-scale, loads src, keeps its scene on a bad one, and lets go of the GPU when removed", async () => {
  await page?.close();
  page = await browser.newPage({ viewport: { width: 800, height: 600 }, deviceScaleFactor: 1, hasTouch: true });
  page.errors = [];
  page.on("pageerror", (error) => page.errors.push(`uncaught: ${error.message}`));
  await page.goto(`${server.origin}/element.html`);
  await page.waitForFunction(() => customElements.get("raypipe-viewer") && document.getElementById("gpu").viewer, null, { timeout: 30_000 });
  await page.evaluate(() => {
    window.viewers = { gl: document.getElementById("gl").viewer, gpu: document.getElementById("gpu").viewer };
  });
  for (const name of ["gl", "gpu"]) {
    // The viewer's own sample count (no spp attribute): the reference takes as many.
    const status = await until(name, SETTLED, `the ${name} element's samples`);
    assert.deepEqual([status.width, status.height], [SIZE.width, SIZE.height], "the element's size in device pixels");
    assert.equal(status.backend, name === "gl" ? "webgl2" : "webgpu");
    await assertShowsWhitted(name, `element-${name}`, status.spp);
  }
  assert.ok(await page.evaluate(() => window.statuses.gl > 0 && window.statuses.gpu > 0), "the elements' status events");
  // alt is the element's accessible label; camera-controls alone lets the canvas take touches.
  assert.deepEqual(
    await page.evaluate(() => ["gl", "gpu"].map((id) => {
      const element = document.getElementById(id);
      return [element.getAttribute("role"), element.getAttribute("aria-label"), element.viewer.input];
    })),
    [["img", "The paper's Whitted scene", true], ["img", null, false]],
  );

  // The canvas follows the element's size, times render-scale.
  await page.evaluate(() => { document.getElementById("gl").style.width = "160px"; });
  await until("gl", (s) => s.width === 160 && s.height === 72, "the element's new width");
  await page.evaluate(() => { document.getElementById("gl").renderScale = 0.5; });
  await until("gl", (s) => s.width === 80 && s.height === 36, "half the element's pixels");

  // src: fetched with its progress, shown, then `load`; a missing one says why, and the scene stays.
  await page.evaluate(() => { document.getElementById("gl").src = "tetrahedron.obj"; });
  await page.waitForFunction(() => window.heard.gl.some((e) => e.type === "load"), null, { timeout: COMPILE_MS });
  const shown = await until("gl", (s) => s.scene === "tetrahedron.obj" && !s.busy, "the element's model");
  assert.equal(shown.primitives, 4);
  const phases = await page.evaluate(() => window.heard.gl.filter((e) => e.type === "progress").map((e) => e.phase));
  assert.ok(phases.includes("fetch") && phases.at(-1) === "build", `progress phases ${phases}`);
  await page.evaluate(() => { document.getElementById("gl").src = "missing.glb"; });
  await page.waitForFunction(() => window.heard.gl.some((e) => e.type === "error"), null, { timeout: 60_000 });
  const error = await page.evaluate(() => window.heard.gl.find((e) => e.type === "error").message);
  assert.match(error, /^missing\.glb: cannot fetch: HTTP 404/);
  assert.equal((await page.evaluate(() => ({ ...window.viewers.gl.status }))).scene, "tetrahedron.obj");

  // camera-orbit, field-of-view, auto-rotate; the arrow keys where camera-controls is on.
  const offset = (c) => c.eye.map((x, i) => x - c.target[i]);
  const near = (a, b) => a.every((x, i) => Math.abs(x - b[i]) < 1e-3);
  await page.evaluate(() => { document.getElementById("gpu").cameraOrbit = "90deg 90deg 2m"; });
  const placed = await page.evaluate(() => window.viewers.gpu.camera);
  assert.ok(near(offset(placed), [2, 0, 0]), `camera-orbit 90deg 90deg 2m put the eye at ${offset(placed)} from the target`);
  await until("gpu", (s, eye) => s.camera.eye.every((x, i) => Math.abs(x - eye[i]) < 1e-3), "the camera in the status", { arg: placed.eye });
  const fovs = await page.evaluate(() => {
    const element = document.getElementById("gpu");
    element.fieldOfView = "30deg";
    const set = element.viewer.camera.fov;
    element.fieldOfView = "auto";
    return [set, element.viewer.camera.fov];
  });
  assert.equal(fovs[0], 30);
  assert.notEqual(fovs[1], 30, "field-of-view=auto is the scene's own");
  await page.evaluate(() => { document.getElementById("gpu").autoRotate = true; });
  await page.waitForFunction((eye) => window.viewers.gpu.camera.eye[2] !== eye[2], placed.eye, { timeout: 30_000 });
  // render-scale="auto" under a budget no frame meets goes down to a quarter, and back up under one
  // every frame meets.
  await page.evaluate(() => {
    const element = document.getElementById("gpu");
    element.frameBudget = 0.01;
    element.renderScale = "auto";
  });
  await until("gpu", (s, width) => s.width <= width / 2, "a lower scale", { arg: SIZE.width, timeout: 60_000 });
  await page.evaluate(() => { document.getElementById("gpu").frameBudget = 1e6; });
  await until("gpu", (s, width) => s.width === width, "the full scale again", { arg: SIZE.width, timeout: 60_000 });
  await page.evaluate(() => document.getElementById("gpu").removeAttribute("render-scale"));
  await page.evaluate(() => { document.getElementById("gpu").autoRotate = false; });
  const glBefore = await page.evaluate(() => window.viewers.gl.camera.eye);
  await page.evaluate(() => {
    const canvas = document.getElementById("gl").shadowRoot.querySelector("canvas");
    canvas.focus();
    canvas.dispatchEvent(new KeyboardEvent("keydown", { key: "ArrowLeft", code: "ArrowLeft", bubbles: true, composed: true }));
  });
  assert.notDeepEqual(await page.evaluate(() => window.viewers.gl.camera.eye), glBefore, "ArrowLeft turned the camera");
  if (BROWSER === "chromium") await assertTouchMovesCamera();
  const refusedOrbit = await page.evaluate(() => {
    document.getElementById("gpu").cameraOrbit = "sideways";
    return window.heard.gpu.find((e) => e.type === "error")?.message;
  });
  assert.match(refusedOrbit ?? "", /^camera-orbit=sideways: /);

  // Out of view, an element waits (loading="auto", as model-viewer's), and starts once in view.
  assert.equal(await page.evaluate(() => document.getElementById("far").viewer), null);
  await page.evaluate(() => document.getElementById("far").scrollIntoView());
  await page.waitForFunction(() => document.getElementById("far").status?.frames >= 1, null, { timeout: COMPILE_MS });
  await page.evaluate(() => window.scrollTo(0, 0));

  // Removed from the page: its viewer is disposed; the other draws on.
  await page.evaluate(() => document.getElementById("gl").remove());
  assert.equal(await page.evaluate(() => document.getElementById("gl")?.viewer ?? window.viewers.gl.status), null);
  const before = await page.evaluate(() => window.viewers.gpu.status.frames);
  await until("gpu", (s, frames) => s.frames >= frames + 5, "frames after the other element left", { arg: before, timeout: 60_000 });
  assert.deepEqual(page.errors, []);
});

/// The browser's own touch events (Chromium's DevTools Input.dispatchTouchEvent) on the element
/// with camera-controls: one finger orbits, two spreading dolly in, two moving together pan.
/// Firefox's driver (WebDriver BiDi through Puppeteer) sends no touches here.
async function assertTouchMovesCamera() {
  const cdp = await page.context().newCDPSession(page);
  const box = await page.evaluate(() => {
    const r = document.getElementById("gl").getBoundingClientRect();
    return { x: r.x + r.width / 2, y: r.y + r.height / 2 };
  });
  const touch = (type, points) => cdp.send("Input.dispatchTouchEvent", {
    type,
    touchPoints: points.map(([x, y], id) => ({ x: box.x + x, y: box.y + y, id })),
  });
  const camera = () => page.evaluate(() => window.viewers.gl.camera);
  const distance = (c) => Math.hypot(...c.eye.map((x, i) => x - c.target[i]));

  const before = await camera();
  await touch("touchStart", [[0, 0]]);
  for (const x of [10, 20, 30]) await touch("touchMove", [[x, 0]]);
  await touch("touchEnd", []);
  const orbited = await camera();
  assert.notDeepEqual(orbited.eye, before.eye, "a finger's drag orbits");
  assert.deepEqual(orbited.target, before.target, "about the target");
  assert.ok(Math.abs(distance(orbited) - distance(before)) < 1e-3 * distance(before));

  await touch("touchStart", [[-10, 0], [10, 0]]);
  for (const d of [15, 20, 25, 30]) await touch("touchMove", [[-d, 0], [d, 0]]);
  await touch("touchEnd", []);
  const dollied = await camera();
  assert.ok(distance(dollied) < 0.9 * distance(orbited), `spreading fingers dolly in: ${distance(orbited)} to ${distance(dollied)}`);

  await touch("touchStart", [[-10, 0], [10, 0]]);
  for (const y of [5, 10, 15]) await touch("touchMove", [[-10, y], [10, y]]);
  await touch("touchEnd", []);
  const panned = await camera();
  assert.notDeepEqual(panned.target, dollied.target, "two fingers moving together pan");
  assert.ok(Math.abs(distance(panned) - distance(dollied)) < 1e-3 * distance(dollied), "a pan keeps the distance");
  await cdp.detach();
}
