// Measures <raypipe-viewer render-scale="auto"> in headless Chromium, for docs/BENCHMARKS.md: the
// Bunny in a 960x540 element (one device pixel to a CSS pixel) turning (auto-rotate, so that every
// frame traces anew), at a fixed render-scale of 1 and at "auto" with a frame budget; the frames per
// second over the last seconds of each, and how long "auto" takes to settle (its last change of
// scale after the model is shown). Build the package first (scripts/build-web.sh --package
// target/web-package).
//
//   node web/render-scale.mjs [--backend webgpu|webgl2] [--budget MS] [--seconds S]
//
// Prints one JSON line per run.
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { parseArgs } from "node:util";
import { launch, serve } from "./harness.mjs";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const { values: options } = parseArgs({
  options: {
    backend: { type: "string", default: "webgpu" },
    budget: { type: "string", default: "33" },
    seconds: { type: "string", default: "30" },
    package: { type: "string", default: path.join(root, "target/web-package") },
    models: { type: "string", default: path.join(root, "../shared/models") },
  },
});
const seconds = Number(options.seconds);

const page = (scale) => `<!doctype html>
<meta charset="utf-8">
<link rel="icon" href="data:,">
<script type="importmap">{ "imports": { "raypipe": "/raypipe/raypipe.js" } }</script>
<raypipe-viewer id="v" src="/models/bunny.ply" backend="${options.backend}" auto-rotate loading="eager"
  render-scale="${scale}" frame-budget="${options.budget}" style="width: 960px; height: 540px"></raypipe-viewer>
<script type="module">
  import "raypipe";
  const element = document.getElementById("v");
  window.changes = [];
  element.addEventListener("load", () => { window.shownAt = performance.now(); });
  element.addEventListener("error", (event) => { window.failed = event.detail.message; });
  element.addEventListener("render-scale", (event) => window.changes.push({ at: performance.now(), ...event.detail }));
</script>
`;

const pages = fs.mkdtempSync(path.join(os.tmpdir(), "raypipe-render-scale-"));
for (const scale of ["1", "auto"]) fs.writeFileSync(path.join(pages, `${scale}.html`), page(scale));
const server = await serve({ "/raypipe/": options.package, "/models/": options.models, "/": pages });
const browser = await launch();
for (const scale of ["1", "auto"]) {
  const tab = await browser.newPage({ viewport: { width: 1000, height: 600 }, deviceScaleFactor: 1 });
  await tab.goto(`${server.origin}/${scale}.html`);
  await tab.waitForFunction(() => window.shownAt || window.failed, null, { timeout: 600_000 });
  const failed = await tab.evaluate(() => window.failed);
  if (failed) throw new Error(failed);
  await tab.waitForTimeout(seconds * 1000);
  // The rate over the last third of the run.
  const [frames0, t0] = await tab.evaluate(() => [document.getElementById("v").viewer.frames, performance.now()]);
  await tab.waitForTimeout((seconds * 1000) / 3);
  const result = await tab.evaluate(([frames0, t0]) => {
    const element = document.getElementById("v");
    const status = element.status;
    const last = window.changes.at(-1);
    return {
      fps: ((element.viewer.frames - frames0) * 1000) / (performance.now() - t0),
      width: status.width,
      height: status.height,
      scale: element.renderScale,
      changes: window.changes.length,
      settledSeconds: last ? (last.at - window.shownAt) / 1000 : 0,
      adapter: status.adapter,
    };
  }, [frames0, t0]);
  console.log(JSON.stringify({ backend: options.backend, renderScale: scale, budgetMs: Number(options.budget), ...result }));
  await tab.close();
}
await browser.close();
server.close();
fs.rmSync(pages, { recursive: true, force: true });
