// Measures the page in headless Chromium: time to the first frame and frames per second on each
// backend, for docs/BENCHMARKS.md. Build the page first (scripts/build-web.sh target/web).
//
//   node web/bench.mjs [--scene S | --model FILE] [--integrator whitted|path] [--width W]
//                      [--height H] [--frames N] [--screenshot F.png]
//
// Each backend loads the page with spp=4096, so that every frame traces a new sample (a still frame
// with its samples gathered is only shown again); the frames per second are those of N frames
// presented after the first two (which pay for compiling the tracer), by the page's clock. Prints
// one JSON line per backend. --model serves a model file's folder beside the page and opens it
// (a glTF's own integrator unless --integrator says). The screenshot is the WebGPU page's, whole, with 16 samples gathered.
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { parseArgs } from "node:util";
import { launch, serve } from "./harness.mjs";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const { values: options } = parseArgs({
  options: {
    scene: { type: "string", default: "random:20000" },
    width: { type: "string", default: "320" },
    height: { type: "string", default: "240" },
    frames: { type: "string", default: "10" },
    accel: { type: "string", default: "threaded" },
    model: { type: "string" },
    integrator: { type: "string" },
    screenshot: { type: "string" },
    site: { type: "string", default: path.join(root, "target/web") },
  },
});

const mounts = { "/": options.site };
if (options.model) mounts["/bench-model/"] = path.dirname(path.resolve(options.model));
const server = await serve(mounts);
const origin = server.origin;
const browser = await launch();
const wasmBytes = fs.statSync(path.join(options.site, "raypipe_web_bg.wasm")).size;

for (const backend of ["webgpu", "webgl2"]) {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 }, deviceScaleFactor: 1 });
  const model = options.model ? `&model=bench-model/${encodeURIComponent(path.basename(options.model))}` : "";
  const integrator = options.integrator ? `&integrator=${options.integrator}` : "";
  const query = `scene=${options.scene}&accel=${options.accel}&width=${options.width}&height=${options.height}` +
    `&backend=${backend}&spp=4096${model}${integrator}`;
  const loaded = Date.now();
  await page.goto(`${origin}/index.html?${query}`);
  // With a model, the frames that count are the model's: the built-in scene shows first.
  const shown = options.model ? path.basename(options.model) : null;
  await page.waitForFunction(
    (shown) => {
      const status = window.raypipeStatus;
      if (status?.error) return true;
      return shown ? status?.scene === shown && status.samples >= 2 : status?.frames >= 2;
    },
    shown,
    { timeout: 600_000, polling: 50 },
  );
  const firstFrames = Date.now() - loaded;
  // The viewer's live frame count, not the status's (published four times a second).
  const sample = () => page.evaluate(() => ({ ...window.raypipeStatus, frames: window.raypipeViewer.frames, now: performance.now() }));
  const start = await sample();
  if (start.error) throw new Error(`${backend}: ${start.error}`);
  await page.waitForFunction((frames) => window.raypipeViewer.frames >= frames, start.frames + Number(options.frames), {
    timeout: 600_000,
    polling: 20,
  });
  const end = await sample();
  const fps = ((end.frames - start.frames) * 1000) / (end.now - start.now);
  console.log(JSON.stringify({
    backend,
    adapter: end.adapter,
    scene: end.scene,
    integrator: end.integrator,
    accel: end.accel,
    memory: end.memory,
    size: `${end.width}x${end.height}`,
    wasm_bytes: wasmBytes,
    load_to_second_frame_ms: firstFrames,
    fps: Number(fps.toFixed(2)),
    ms_per_frame: Number((1000 / fps).toFixed(2)),
  }));
  if (options.screenshot && backend === "webgpu") {
    await page.evaluate(() => window.raypipeViewer.set({ spp: 16 }));
    await page.waitForFunction(() => window.raypipeStatus.samples >= 16, null, { timeout: 600_000 });
    await page.locator("main").screenshot({ path: options.screenshot, timeout: 120_000 });
  }
  await page.close();
}
await browser.close();
server.close();
