// raypipe's page against three-mesh-bvh in the same headless Chromium, on each backend: on WebGL2
// its GLSL walk from a full-screen quad (web/peer/peer.js), on WebGPU its `three-mesh-bvh/webgpu`
// walk from a compute kernel (web/peer/webgpu.js). The same scene and workload everywhere: a model
// framed by a pinhole camera, one point light, no floor, a primary ray per pixel and a shadow ray per
// hit whose normal faces the light.
//
//   node web/peer/run.mjs [--model FILE.ply] [--width 320] [--height 240] [--frames 20] [--rounds 3]
//                         [--backends webgl2,webgpu] [--accel threaded,stack] [--builder lbvh,sah]
//                         [--webgpu-memory MODE]
//                         [--json OUT.json]
//
// Needs the page built (scripts/build-web.sh target/web), the native binary (target/release/raypipe,
// which counts raypipe's rays) and `npm ci --prefix web` (three, three-mesh-bvh, pngjs).
//
// Before any time is printed the images are checked: the hit counts (raypipe's from its normal view,
// the peers' from a counting pass) and the shadow-ray counts (raypipe's from `raypipe render
// --stats`, the peers' from the counting pass) must agree within 1 %, or the run fails (exit 1).
// Times: the median interval between the page's frames by its own clock (requestAnimationFrame's
// timestamps) over --frames frames after warm-up, and the mean over them; rays per frame are pixels
// plus shadow rays, and the ratio is of rays per second, against the peer on the same backend (and,
// for raypipe on WebGPU, against raypipe on WebGL2 with the same walk and tree). Each of --rounds
// rounds loads every page anew (the peers, then raypipe on each backend) and takes its ratios within
// itself; the report gives the medians over the rounds, and each round's figures.
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { parseArgs } from "node:util";
import { PNG } from "pngjs";
import { launch, serve } from "../harness.mjs";
import { readTriangles, sceneGlb } from "./scene.mjs";

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const root = path.resolve(web, "..");
const { values: options } = parseArgs({
  options: {
    model: { type: "string", default: path.join(root, "../shared/models/bunny.ply") },
    width: { type: "string", default: "320" },
    height: { type: "string", default: "240" },
    frames: { type: "string", default: "20" },
    rounds: { type: "string", default: "3" },
    backends: { type: "string", default: "webgl2,webgpu" },
    // Each walk is timed on each backend.
    accel: { type: "string", default: "threaded,stack" },
    // And with each way of building raypipe's tree (the page's `builder`): the LBVH, binned SAH.
    builder: { type: "string", default: "lbvh" },
    // WebGL2 reads the scene from textures only; WebGPU from storage buffers or textures, by
    // default the page's choice for the adapter.
    "webgpu-memory": { type: "string" },
    json: { type: "string" },
    site: { type: "string", default: path.join(root, "target/web") },
    raypipe: { type: "string", default: process.env.RAYPIPE_BIN ?? path.join(root, "target/release/raypipe") },
    // The benchmark's own test: turn the peer's camera by this many degrees, so that validation must fail.
    "skew-peer": { type: "string", default: "0" },
  },
});

/// Frames before timing starts: the first pays for compiling, the next for settling.
const WARM_UP = 3;
/// The most that hit and shadow-ray counts may differ, relative.
const AGREE = 0.01;
const TIMEOUT_MS = 600_000;

// The scratch folder for the scenes and the reference image, once made; fail() removes it.
let scratch = null;
const width = Number(options.width);
const height = Number(options.height);
const frames = Number(options.frames);
if (!(width > 0 && height > 0 && frames >= 20 && Number(options.rounds) >= 1)) {
  fail("--width and --height must be positive, --frames at least 20, --rounds at least 1");
}
const backends = options.backends.split(",");
for (const b of backends) if (!["webgl2", "webgpu"].includes(b)) fail(`--backends: unknown ${b} (webgl2, webgpu)`);
if (![undefined, "storage", "texture"].includes(options["webgpu-memory"])) fail("--webgpu-memory: storage or texture");
const walks = options.accel.split(",");
const WALKS = ["brute", "stack", "stackless", "threaded", "wide"];
for (const a of walks) if (!WALKS.includes(a)) fail(`--accel: unknown ${a} (${WALKS.join(", ")})`);
// What each round measures of raypipe's page, in this order.
const builders = options.builder.split(",");
for (const b of builders) if (!["lbvh", "sah"].includes(b)) fail(`--builder: unknown ${b} (lbvh, sah)`);
const configs = backends.flatMap((backend) =>
  walks.flatMap((accel) => builders.map((builder) => ({ backend, accel, builder }))));

/// One line and exit 1, with the scratch folder (if made) gone.
function fail(line) {
  console.error(`peer benchmark: ${line}`);
  if (scratch) fs.rmSync(scratch, { recursive: true, force: true });
  process.exit(1);
}

/// What `step` returns, or its error as one line.
function attempt(what, step) {
  try {
    return step();
  } catch (error) {
    const line = String(error.stderr || error.message).trim().split("\n")[0];
    return fail(line.startsWith(what) ? line : `${what}: ${line}`);
  }
}

// One scene for both tracers; the peer's may be turned (--skew-peer) to prove validation bites.
const triangles = attempt(options.model, () => readTriangles(options.model));
scratch = fs.mkdtempSync(path.join(os.tmpdir(), "raypipe-peer-"));
const sceneFile = path.join(scratch, "scene.glb");
fs.writeFileSync(sceneFile, sceneGlb(triangles, width, height));
fs.writeFileSync(path.join(scratch, "peer.glb"), sceneGlb(triangles, width, height, Number(options["skew-peer"])));
const pixels = width * height;
const version = (name) => JSON.parse(fs.readFileSync(path.join(web, "node_modules", name, "package.json"), "utf8")).version;
const peerName = `three-mesh-bvh ${version("three-mesh-bvh")} (three ${version("three")})`;

// raypipe's rays for this scene, counted by the native tracer (the page's image equals it; web/tests);
// every walk traces the same rays.
const stats = attempt(options.raypipe, () => execFileSync(options.raypipe, [
  "render", sceneFile, "--device", "cpu", "--width", `${width}`, "--height", `${height}`, "--depth", "1",
  // The peer casts camera and shadow rays: Whitted's light, one sample.
  "--integrator", "whitted", "--spp", "1",
  "--accel", walks[0], "--stats", "-o", path.join(scratch, "reference.png"),
], { encoding: "utf8", stdio: ["ignore", "pipe", "pipe"] }));
const nativeRays = Number(/(\d+) rays/.exec(stats)?.[1]);
if (!Number.isFinite(nativeRays)) fail(`no ray count in raypipe render --stats: ${stats}`);

const server = await serve({ "/": options.site, "/peer/": path.join(web, "peer"), "/scene/": scratch, "/node_modules/": path.join(web, "node_modules") });
const browser = await launch();
// Per round, each tracer's figures; the machine's speed drifts between rounds, so each round's
// ratio is taken within it and the report gives their median.
const rounds = [];
try {
  for (let round = 0; round < Number(options.rounds); round++) {
    const peers = {};
    for (const backend of backends) peers[backend] = await measurePeer(backend);
    const raypipe = [];
    for (const { backend, accel, builder } of configs) {
      const result = await measureRaypipe(backend, accel, builder);
      const peer = peers[backend];
      validate(result, peer);
      raypipe.push({ ...result, ratio: rate(result, "ms") / rate(peer, "ms"), meanRatio: rate(result, "meanMs") / rate(peer, "meanMs") });
    }
    rounds.push({ peers, raypipe });
  }
  report();
} catch (error) {
  process.exitCode = 1;
  console.error(`peer benchmark: ${error.message}`);
} finally {
  await browser.close();
  server.close();
  fs.rmSync(scratch, { recursive: true, force: true });
}

/// A page's frame time from the intervals between its frames: the median, and the mean over the whole
/// run (`span` ms for `count` frames), which pipelined frames (an interval of 17 ms after one of 117)
/// disturb less.
function frameTimes(intervals, span, count) {
  return { ms: median(intervals), meanMs: span / count };
}

async function newPage() {
  const page = await browser.newPage({ viewport: { width: Math.max(1280, width + 400), height: Math.max(800, height + 300) }, deviceScaleFactor: 1 });
  page.errors = [];
  page.on("pageerror", (error) => page.errors.push(error.message));
  return page;
}

/// The peer on `backend`: its WebGL2 page (textures) or its WebGPU page (storage buffers).
async function measurePeer(backend) {
  const page = await newPage();
  await page.goto(`${server.origin}/peer/index.html?backend=${backend}&model=/scene/peer.glb&width=${width}&height=${height}`);
  await page.waitForFunction((n) => window.peerStatus?.error || window.peerStatus?.frames >= n, WARM_UP + frames + 1, { timeout: TIMEOUT_MS, polling: 50 });
  const status = await page.evaluate(() => window.peerStatus);
  if (status.error) throw new Error(`three-mesh-bvh on ${backend}: ${status.error} ${page.errors}`);
  const times = status.times.slice(WARM_UP, WARM_UP + frames + 1);
  const timing = frameTimes(times.slice(1).map((t, i) => t - times[i]), times.at(-1) - times[0], frames);
  const counts = await page.evaluate(() => window.peerCount());
  await page.close();
  const memory = backend === "webgl2" ? "texture" : "storage";
  return { tracer: peerName, backend, memory, ...timing, rays: pixels + counts.shadowRays, ...counts, adapter: status.renderer, buildMs: status.buildMs };
}

async function measureRaypipe(backend, accel, builder) {
  const name = `raypipe ${backend} ${accel} ${builder}`;
  const page = await newPage();
  // Every animation frame's timestamp with the viewer's frame count then (live, where the status
  // is published four times a second): a frame's time is the interval to the next frame that
  // traced.
  await page.addInitScript(() => {
    window.frameLog = [];
    const watch = (time) => {
      const frames = window.raypipeViewer?.frames;
      const last = window.frameLog.at(-1);
      if (frames != null && (!last || last[1] !== frames)) window.frameLog.push([time, frames]);
      requestAnimationFrame(watch);
    };
    requestAnimationFrame(watch);
  });
  const memory = backend === "webgl2" ? "texture" : options["webgpu-memory"];
  const query = `model=/scene/scene.glb&backend=${backend}${memory ? `&memory=${memory}` : ""}&accel=${accel}&builder=${builder}&depth=1&integrator=whitted` +
    `&width=${width}&height=${height}&spp=4096`;
  await page.goto(`${server.origin}/index.html?${query}`);
  const until = (condition, arg) => page.waitForFunction(condition, arg, { timeout: TIMEOUT_MS, polling: 50 });
  await until(() => window.raypipeStatus?.error || (window.raypipeStatus?.primitives > 0 && !window.raypipeStatus.busy));
  const opened = await page.evaluate(() => ({ ...window.raypipeStatus }));
  if (opened.error) throw new Error(`${name}: ${opened.error}`);
  const start = opened.frames;
  await until((n) => window.raypipeStatus.error || window.raypipeStatus.frames >= n, start + WARM_UP + frames + 1);
  const log = await page.evaluate(() => window.frameLog);
  const status = await page.evaluate(() => ({ ...window.raypipeStatus }));
  if (status.error) throw new Error(`${name}: ${status.error}`);
  if (status.builder !== builder) throw new Error(`${name}: the page built its tree by ${status.builder}`);
  // Only consecutive frames: an interval that spans two frames (a missed observation) is left out.
  const timed = log.filter(([, n]) => n > start + WARM_UP && n <= start + WARM_UP + frames + 1);
  const intervals = timed.slice(1).flatMap(([t, n], i) => (n === timed[i][1] + 1 ? [t - timed[i][0]] : []));
  if (intervals.length < frames / 2) throw new Error(`${name}: only ${intervals.length} frames observed`);
  const timing = frameTimes(intervals, timed.at(-1)[0] - timed[0][0], timed.at(-1)[1] - timed[0][1]);

  // Hits: the pixels the normal view does not leave black.
  await page.evaluate(() => window.raypipeViewer.set({ aov: "normal" }));
  await until((n) => window.raypipeStatus.aov === "normal" && window.raypipeStatus.frames >= n, status.frames + 2);
  const png = PNG.sync.read(await page.locator("#frame").screenshot());
  if (png.width !== width || png.height !== height) throw new Error(`${name}: canvas is ${png.width}x${png.height}`);
  let hits = 0;
  for (let i = 0; i < png.data.length; i += 4) hits += png.data[i] + png.data[i + 1] + png.data[i + 2] > 0;
  await page.close();
  return {
    tracer: "raypipe", backend, memory: status.memory, accel: status.accel, builder: status.builder, ...timing, rays: nativeRays,
    hits, shadowRays: nativeRays - pixels, adapter: status.adapter,
  };
}

/// Both images must show the same model the same way before any time means anything.
function validate(raypipe, peer) {
  for (const key of ["hits", "shadowRays"]) {
    const [a, b] = [raypipe[key], peer[key]];
    if (Math.abs(a - b) > AGREE * Math.max(a, b, 1)) {
      throw new Error(`the images differ: raypipe (${raypipe.backend}, ${raypipe.accel}) ${key} ${a}, three-mesh-bvh (${peer.backend}) ${b} ` +
        `(more than ${AGREE * 100} % apart); no time is printed`);
    }
  }
}

/// Rays per millisecond by a frame time (`ms`, the median, or `meanMs`).
function rate(result, time) {
  return result.rays / result[time];
}

/// The median of numbers: the middle one; for an even count the mean of the middle two.
function median(values) {
  const sorted = [...values].sort((a, b) => a - b);
  const half = Math.floor(sorted.length / 2);
  return sorted.length % 2 ? sorted[half] : (sorted[half - 1] + sorted[half]) / 2;
}

function report() {
  const mrays = (r) => (rate(r, "ms") / 1e3).toFixed(3);
  const times = (list) => `${median(list.map((r) => r.ms)).toFixed(1)} ms per frame (rounds: ` +
    `${list.map((r) => r.ms.toFixed(0)).join(", ")}; means ${list.map((r) => r.meanMs.toFixed(0)).join(", ")})`;
  const rounded = (list) => list.map((x) => x.toFixed(2)).join(", ");
  console.log(`scene: ${path.basename(options.model)}, ${triangles.indices.length / 3} triangles, ${width}x${height}, ` +
    `1 light, depth 1; each round the median of ${frames} frames after ${WARM_UP}; ${rounds.length} rounds`);
  for (const backend of backends) {
    const peers = rounds.map((r) => r.peers[backend]);
    const peer = peers[0];
    console.log(`${peerName} ${backend} ${peer.memory}: ${times(peers)}, ${peer.rays} rays (${peer.hits} hits), ` +
      `${mrays({ ...peer, ms: median(peers.map((r) => r.ms)) })} Mrays/s`);
  }
  configs.forEach(({ backend, accel, builder }, i) => {
    const list = rounds.map((r) => r.raypipe[i]);
    const r = list[0];
    // WebGPU against WebGL2 per ray, same walk, within each round.
    const onWebgl2 = configs.findIndex((c) => c.backend === "webgl2" && c.accel === accel && c.builder === builder);
    let againstWebgl2 = "";
    if (backend === "webgpu" && onWebgl2 >= 0) {
      const perRay = rounds.map((round) => rate(round.raypipe[i], "ms") / rate(round.raypipe[onWebgl2], "ms"));
      againstWebgl2 = `; ${median(perRay).toFixed(2)}x raypipe webgl2's (rounds ${rounded(perRay)})`;
    }
    console.log(`raypipe ${backend} ${r.memory} ${accel} ${builder}: ${times(list)}, ${r.rays} rays (${r.hits} hits), ` +
      `${mrays({ ...r, ms: median(list.map((x) => x.ms)) })} Mrays/s; rays per second ` +
      `${median(list.map((x) => x.ratio)).toFixed(2)}x three-mesh-bvh's on ${backend} ` +
      `(rounds ${rounded(list.map((x) => x.ratio))}; by the means ${median(list.map((x) => x.meanRatio)).toFixed(2)}x)${againstWebgl2}`);
  });
  if (options.json) {
    fs.writeFileSync(options.json, JSON.stringify({ width, height, frames, model: path.basename(options.model), peer: peerName, rounds }, null, 2));
  }
}
