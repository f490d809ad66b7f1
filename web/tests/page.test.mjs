// The page in headless Chromium, on WebGPU (SwiftShader's Vulkan) and on WebGL2 (ANGLE on
// SwiftShader), or in Firefox (RAYPIPE_BROWSER=firefox, under xvfb-run: WebGPU on its wgpu over
// lavapipe, WebGL2 on llvmpipe): its canvas against the native CPU reference (`raypipe render --device cpu`) of the
// same scene and size, compared by `raypipe diff --tolerance color`, the GPU-against-CPU colour
// tolerance of the Rust tests (Tolerance::COLOR in src/image/diff.rs); switches, motion, broken
// files and a browser without either API. On a failure the screenshot and the difference image stay
// in target/web-test/.
//
// Needs the page built (scripts/build-web.sh target/web, or RAYPIPE_WEB_DIR), the native binary
// (target/release/raypipe, or RAYPIPE_BIN) and the browser (/usr/bin/chromium, or CHROMIUM;
// /usr/bin/firefox-esr, or FIREFOX).
import { test, before, after, describe } from "node:test";
import assert from "node:assert/strict";
import { execFileSync, spawnSync } from "node:child_process";
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { BROWSER, launch, serve } from "../harness.mjs";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../..");
const site = process.env.RAYPIPE_WEB_DIR ?? path.join(root, "target/web");
const raypipe = process.env.RAYPIPE_BIN ?? path.join(root, "target/release/raypipe");
const output = path.join(root, "target/web-test");
const references = path.join(output, "references");

// SwiftShader compiles the tracer on two cores: minutes, not seconds, for a new pipeline.
const COMPILE_MS = 240_000;

let server;
let origin;
let browser;

before(async () => {
  for (const needed of [path.join(site, "index.html"), raypipe]) {
    assert.ok(fs.existsSync(needed), `${needed} is missing: run scripts/build-web.sh target/web and cargo build --release`);
  }
  // References and screenshots of an earlier run (or build) must not satisfy this one.
  fs.rmSync(output, { recursive: true, force: true });
  fs.mkdirSync(references, { recursive: true });
  server = await serve({ "/": site });
  origin = server.origin;
  browser = await launch();
});

after(async () => {
  await browser?.close();
  server?.close();
});

/// A page at `query`, with what reaches its console as errors collected in `page.errors`.
async function open(query, { init, device = { viewport: { width: 1280, height: 800 }, deviceScaleFactor: 1 } } = {}) {
  const page = await browser.newPage(device);
  page.errors = [];
  page.on("pageerror", (error) => page.errors.push(`uncaught: ${error.message}`));
  page.on("console", (message) => {
    if (message.type() === "error") page.errors.push(`console: ${message.text()}`);
  });
  if (init) await page.addInitScript(init);
  await page.goto(`${origin}/index.html?${query}`);
  return page;
}

/// Waits until `window.raypipeStatus` satisfies `condition` (a function of it and `arg`), failing at once
/// where the page shows an error the condition does not wait for; says what the status was.
async function until(page, condition, what, { arg = null, timeout = COMPILE_MS } = {}) {
  const source = condition.toString();
  const expectsError = source.includes("error");
  let status;
  try {
    // The status that met the condition (or showed the error), not one read after it.
    const met = await page.waitForFunction(
      ([source, expectsError, arg]) => {
        const status = window.raypipeStatus;
        if (status == null) return false;
        const done = (status.error != null && !expectsError) || new Function("s", "arg", `return (${source})(s, arg)`)(status, arg);
        return done && JSON.stringify(status);
      },
      [source, expectsError, arg],
      { timeout, polling: 100 },
    );
    status = JSON.parse(await met.jsonValue());
  } catch (error) {
    const now = await page.evaluate(() => JSON.stringify(window.raypipeStatus));
    throw new Error(`waiting for ${what}: ${error.message.split("\n")[0]}; status ${now}; errors ${page.errors}`);
  }
  if (status.error != null && !expectsError) {
    throw new Error(`waiting for ${what}, the page says: ${status.error}; errors ${page.errors}`);
  }
  return status;
}

/// A frame traced with every sample asked for, no tracer pending, and a frame presented after.
const SETTLED = (s) => s.frames >= 2 && !s.busy && s.samples >= s.spp;

/// Waits until the page's message line shows `text`: the page's script copies it from the status.
async function shows(page, text) {
  await page.waitForFunction((text) => document.getElementById("message").textContent === text, text, { timeout: 10_000 });
  assert.ok(await page.locator("#message").isVisible());
}

async function screenshot(page, name) {
  const file = path.join(output, `${name}-actual.png`);
  await page.locator("#frame").screenshot({ path: file });
  return file;
}

/// `raypipe render SPEC --device cpu`, once per scene and size.
function reference(spec, width, height) {
  const file = path.join(references, `${spec.replaceAll(":", "_")}-${width}x${height}.png`);
  if (!fs.existsSync(file)) {
    execFileSync(raypipe, ["render", spec, "--device", "cpu", "--width", `${width}`, "--height", `${height}`, "-q", "-o", file]);
  }
  return file;
}

/// `raypipe render FILE --device cpu` at a size: the reference of a file the page opens.
function fileReference(file, width, height, flags = []) {
  const named = flags.map((flag) => path.basename(flag)).join("");
  const out = path.join(references, `${path.basename(file)}-${width}x${height}${named}.png`);
  // One sample, as the page tests trace (a glTF file's render takes more by default).
  execFileSync(raypipe, ["render", file, "--device", "cpu", "--width", `${width}`, "--height", `${height}`, "--spp", "1", ...flags, "-q", "-o", out]);
  return out;
}

/// An environment in `dir`: `raypipe render SPEC` at `width` x `height` written as EXR (2:1, a colour
/// for every direction, unless the size says otherwise).
function environmentFile(dir, name, spec = "random:40:3", width = 64, height = 32) {
  const file = path.join(dir, name);
  execFileSync(raypipe, ["render", spec, "--device", "cpu", "--width", `${width}`, "--height", `${height}`, "-q", "-o", file]);
  return file;
}

/// `raypipe diff --tolerance color` of `actual` against `expected`: the GPU-against-CPU colour
/// tolerance of the Rust tests (Tolerance::COLOR, by name: no copy of its numbers here), or the
/// difference image is written beside the screenshot and the test fails. Passing screenshots are
/// removed.
function assertSimilar(actual, expected) {
  const difference = actual.replace(/-actual\.png$/, "-difference.png");
  const run = spawnSync(raypipe, ["diff", actual, expected, "--tolerance", "color", "--out", difference], { encoding: "utf8" });
  if (run.status !== 0) {
    assert.fail(`${path.basename(actual)} against ${path.basename(expected)}: ${run.stdout}${run.stderr}` +
      ` (kept ${actual} and ${difference})`);
  }
  fs.rmSync(difference, { force: true });
  fs.rmSync(actual, { force: true });
}

/// Whether two screenshots differ anywhere.
function differ(a, b) {
  const run = spawnSync(raypipe, ["diff", a, b, "--metric", "mean", "--threshold", "0"], { encoding: "utf8" });
  assert.ok(run.status === 0 || run.status === 1, `raypipe diff ${a} ${b}: ${run.stderr}`);
  return run.status === 1;
}

const BROKEN_PLY = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n" +
  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 oops\n0 1 0\n3 0 1 2\n";
const TETRAHEDRON_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

// A textured glTF from the shared models (beside the repository): skipped, visibly, where they are
// missing, unless RAYPIPE_REQUIRE_MODELS=1 makes that a failure.
const BOX_TEXTURED = path.join(root, "../shared/models/gltf/BoxTextured.gltf");
const MODELS_SKIP = fs.existsSync(BOX_TEXTURED) || process.env.RAYPIPE_REQUIRE_MODELS === "1"
  ? false : `${BOX_TEXTURED} is missing (the shared models)`;

for (const backend of ["webgpu", "webgl2"]) {
  const memories = backend === "webgpu" ? ["storage", "texture"] : ["texture"];
  const size = { width: 160, height: 120 };

  describe(`the page on ${backend}`, () => {
    for (const memory of memories) {
      test(`whitted and random:2000 (threaded and wide, ${memory} memory) equal the CPU reference`, async () => {
        for (const [scene, accel] of [["whitted", "threaded"], ["random:2000", "threaded"], ["random:2000", "wide"]]) {
          const page = await open(
            `scene=${scene}&accel=${accel}&memory=${memory}&width=${size.width}&height=${size.height}&backend=${backend}&spp=1`,
          );
          const status = await until(page, SETTLED, `${scene} on ${backend}`);
          assert.equal(status.backend, backend);
          assert.equal(status.memory, memory);
          assert.equal(status.error, null);
          assert.deepEqual(await page.locator("#frame").evaluate((c) => [c.width, c.height, c.clientWidth, c.clientHeight]),
            [size.width, size.height, size.width, size.height]);
          assert.equal(status.accel, accel);
          const shot = await screenshot(page, `${backend}-${memory}-${accel}-${scene.replace(":", "_")}`);
          assertSimilar(shot, reference(scene, size.width, size.height));
          assert.deepEqual(page.errors, []);
          await page.close();
        }
      });
    }

    if (backend === "webgpu") {
      test("the compute pipeline gives the CPU reference's image", async () => {
        const page = await open(`scene=whitted&pipeline=compute&width=${size.width}&height=${size.height}&backend=webgpu&spp=1`);
        const status = await until(page, SETTLED, "whitted through compute");
        assert.equal(status.pipeline, "compute");
        const shot = await screenshot(page, "webgpu-compute-whitted");
        assertSimilar(shot, reference("whitted", size.width, size.height));
        assert.deepEqual(page.errors, []);
        await page.close();
      });
    } else {
      test("the compute pipeline is refused with its reason and the fragment pipeline stays", async () => {
        const page = await open(`scene=whitted&width=64&height=48&backend=webgl2&spp=1`);
        await until(page, SETTLED, "whitted");
        // The page's script disables what the backend lacks, from the status, at its next frame.
        await page.waitForFunction(() =>
          [...document.querySelectorAll("select[data-key=pipeline] option")].some((o) => o.value === "compute" && o.disabled),
          null, { timeout: 10_000 });
        await page.evaluate(() => window.raypipeViewer.set({ pipeline: "compute" }));
        const refused = await until(page, (s) => s.error != null && !s.busy, "the refusal");
        assert.match(refused.error, /compute/);
        assert.equal(refused.pipeline, "fragment");
        await shows(page, refused.error);
        await page.close();
      });
    }

    test("switching the acceleration keeps the image; a broken file shows its error and the image stays", async () => {
      const page = await open(`scene=whitted&width=${size.width}&height=${size.height}&backend=${backend}&spp=1`);
      await until(page, SETTLED, "whitted");
      await page.selectOption("select[data-key=accel]", "brute");
      const brute = await until(page, (s) => s.accel === "brute" && !s.busy && s.samples >= 1, "the brute-force tracer");
      assert.equal(brute.error, null);
      const before = await screenshot(page, `${backend}-brute-whitted`);
      assertSimilar(before, reference("whitted", size.width, size.height));

      const shown = await screenshot(page, `${backend}-before-broken`);
      await page.setInputFiles("#file", { name: "broken.ply", mimeType: "application/octet-stream", buffer: Buffer.from(BROKEN_PLY) });
      const broken = await until(page, (s) => s.error != null, "the broken file's error", { timeout: 30_000 });
      assert.match(broken.error, /^broken\.ply:11: /);
      assert.ok(!broken.error.includes("\n"), broken.error);
      assert.equal(broken.scene, "whitted");
      await shows(page, broken.error);
      await until(page, (s, frames) => s.error != null && s.frames >= frames, "frames after the error", { arg: broken.frames + 2 });
      const after = await screenshot(page, `${backend}-after-broken`);
      assert.ok(!differ(after, shown), "the image changed after a broken file");
      fs.rmSync(shown);
      fs.rmSync(after);

      // A scene beyond the mode's limits: refused with its reason, and the current one stays.
      await page.selectOption("select[data-key=memory]", "uniform");
      await until(page, (s) => s.memory === "uniform" && !s.busy && s.samples >= 1, "uniform memory");
      await page.selectOption("#scene", "sphere-8k");
      const refused = await until(page, (s) => s.error != null && !s.busy, "the refusal");
      assert.match(refused.error, /^sphere-8k: .*uniform/);
      assert.equal(refused.scene, "whitted");
      await shows(page, refused.error);

      await page.setInputFiles("#file", { name: "tetrahedron.obj", mimeType: "text/plain", buffer: Buffer.from(TETRAHEDRON_OBJ) });
      const opened = await until(page, (s) => s.scene === "tetrahedron.obj" && s.error == null && !s.busy && s.samples >= 1, "the opened model");
      assert.equal(opened.error, null);
      assert.equal(opened.primitives, 4);
      assert.deepEqual(page.errors, []);
      await page.close();
    });

    test("a glTF file opens with its texture as the CPU renders it; a cut .glb shows its error and the scene stays", { skip: MODELS_SKIP }, async () => {
      const page = await open(`scene=whitted&width=${size.width}&height=${size.height}&backend=${backend}&spp=1`);
      await until(page, SETTLED, "whitted");
      const gltf = fs.readFileSync(BOX_TEXTURED);
      await page.setInputFiles("#file", { name: "BoxTextured.gltf", mimeType: "model/gltf+json", buffer: gltf });
      const opened = await until(page, (s) => s.scene === "BoxTextured.gltf" && !s.busy && s.samples >= s.spp, "the glTF");
      assert.equal(opened.primitives, 12);
      await until(page, (s, frames) => s.frames >= frames, "a frame of the glTF", { arg: opened.frames + 2 });
      const shot = await screenshot(page, `${backend}-box-textured`);
      assertSimilar(shot, fileReference(BOX_TEXTURED, size.width, size.height));

      // The tone map and exposure controls: the display pass shows what `render --tonemap
      // --exposure` writes, without tracing again.
      await page.selectOption("select[data-key=tonemap]", "aces");
      const exposure = page.locator("input[data-key=exposure]");
      await exposure.fill("1");
      await exposure.dispatchEvent("change");
      const toned = await until(page, (s) => s.tonemap === "aces" && s.exposure === 1, "the tone map and exposure");
      await until(page, (s, frames) => s.frames >= frames, "a tone-mapped frame", { arg: toned.frames + 2 });
      const tonedShot = await screenshot(page, `${backend}-box-textured-aces`);
      assertSimilar(tonedShot, fileReference(BOX_TEXTURED, size.width, size.height, ["--tonemap", "aces", "--exposure", "1"]));

      // An environment file lights the model as `render --environment` does; one that is not 2:1
      // shows its error, and the environment stays.
      const sky = environmentFile(output, "sky.exr");
      await page.setInputFiles("#file", { name: "sky.exr", mimeType: "image/x-exr", buffer: fs.readFileSync(sky) });
      const lit = await until(page, (s) => s.environment === "sky.exr" && !s.busy && s.samples >= s.spp, "the environment");
      await until(page, (s, frames) => s.frames >= frames, "a frame in the environment", { arg: lit.frames + 2 });
      const litShot = await screenshot(page, `${backend}-box-textured-sky`);
      assertSimilar(litShot, fileReference(BOX_TEXTURED, size.width, size.height, ["--tonemap", "aces", "--exposure", "1", "--environment", sky]));
      const square = environmentFile(output, "square.exr", "whitted", 32, 32);
      await page.setInputFiles("#file", { name: "square.exr", mimeType: "image/x-exr", buffer: fs.readFileSync(square) });
      const refused = await until(page, (s) => s.error != null, "the square environment's error", { timeout: 30_000 });
      assert.match(refused.error, /^square\.exr: 32x32: an equirectangular environment is twice as wide as it is high$/);
      assert.equal(refused.environment, "sky.exr");
      await shows(page, refused.error);

      const glb = Buffer.from("glTF\x02\x00\x00\x00\xff\x00\x00\x00", "latin1");
      await page.setInputFiles("#file", { name: "cut.glb", mimeType: "model/gltf-binary", buffer: glb });
      // The environment's error stands until the cut file's replaces it.
      const broken = await until(page, (s) => s.error?.startsWith("cut.glb") === true, "the cut file's error", { timeout: 30_000 });
      assert.match(broken.error, /^cut\.glb: GLB header: total length 255, where the file has 12 bytes/);
      assert.equal(broken.scene, "BoxTextured.gltf");
      await shows(page, broken.error);
      assert.deepEqual(page.errors, []);
      await page.close();
    });

    test("an animated glTF by URL, held at ?time=, equals raypipe render --time; played, it moves", { skip: MODELS_SKIP }, async () => {
      const models = path.join(site, "test-models");
      fs.mkdirSync(models, { recursive: true });
      const rigged = path.join(models, "RiggedSimple.gltf");
      fs.copyFileSync(path.join(root, "../shared/models/gltf/RiggedSimple.gltf"), rigged);
      const query = `width=${size.width}&height=${size.height}&backend=${backend}&spp=1&paused=true&time=1.25`;
      const page = await open(`model=test-models/RiggedSimple.gltf&${query}`);
      const held = await until(page, (s) => s.scene === "RiggedSimple.gltf" && !s.busy && s.samples >= s.spp, "the animated model");
      assert.ok(held.moving && Math.abs(held.time - 1.25) < 1e-6, `time ${held.time}`);
      assert.ok(Math.abs(held.duration - 2.083) < 0.01, `duration ${held.duration}`);
      await until(page, (s, frames) => s.frames >= frames, "a frame of the model", { arg: held.frames + 2 });
      const reference = path.join(references, `RiggedSimple-t1.25-${size.width}x${size.height}.png`);
      execFileSync(raypipe, ["render", rigged, "--device", "cpu", "--time", "1.25", "--width", `${size.width}`, "--height", `${size.height}`, "--spp", "1", "-q", "-o", reference]);
      const still = await screenshot(page, `${backend}-animated-held`);
      assertSimilar(still, reference);
      const stillAgain = await screenshot(page, `${backend}-animated-held-again`);
      await page.locator("input[data-key=paused]").uncheck();
      await until(page, (s) => !s.paused && Math.abs(s.time - 1.25) > 0.2 && s.samples >= 1, "the animation playing");
      const played = await screenshot(page, `${backend}-animated-played`);
      assert.ok(differ(played, stillAgain), "the model did not move");
      fs.rmSync(played);
      fs.rmSync(stillAgain);
      assert.deepEqual(page.errors, []);
      await page.close();
    });

    test("?model=URL opens a file fetched beside the page as raypipe render shows it; a 404 and a broken file show their line and the scene stays", async () => {
      const models = path.join(site, "test-models");
      fs.mkdirSync(models, { recursive: true });
      const tetrahedron = path.join(models, "tetrahedron.obj");
      fs.writeFileSync(tetrahedron, TETRAHEDRON_OBJ);
      fs.writeFileSync(path.join(models, "broken.ply"), BROKEN_PLY);
      fs.rmSync(path.join(models, "missing.ply"), { force: true });
      const query = `width=${size.width}&height=${size.height}&backend=${backend}&spp=1`;

      const page = await open(`model=test-models/tetrahedron.obj&${query}`);
      const opened = await until(page, (s) => s.scene === "tetrahedron.obj" && !s.busy && s.samples >= s.spp, "the model");
      assert.equal(opened.primitives, 4);
      // No memory asked for: textures on WebGL2 and on a browser's software WebGPU adapter, storage
      // buffers on a GPU's WebGPU.
      assert.equal(opened.memory, backend === "webgl2" || /, Cpu,/.test(opened.adapter) ? "texture" : "storage");
      await until(page, (s, frames) => s.frames >= frames, "a frame of the model", { arg: opened.frames + 2 });
      assertSimilar(await screenshot(page, `${backend}-model-url`), fileReference(tetrahedron, size.width, size.height));
      assert.deepEqual(page.errors, []);
      await page.close();

      // floor=0: the model as `raypipe render --floor none` shows it.
      const floating = await open(`model=test-models/tetrahedron.obj&floor=0&${query}`);
      const shown = await until(floating, (s) => s.scene === "tetrahedron.obj" && !s.busy && s.samples >= s.spp, "the model without its floor");
      assert.equal(shown.floor, false);
      await until(floating, (s, frames) => s.frames >= frames, "a frame of the model", { arg: shown.frames + 2 });
      assertSimilar(await screenshot(floating, `${backend}-model-url-no-floor`),
        fileReference(tetrahedron, size.width, size.height, ["--floor", "none"]));
      assert.deepEqual(floating.errors, []);
      await floating.close();

      // ?environment=: fetched before the model, it lights the model as `render --environment` does.
      const sky = environmentFile(models, "sky.exr");
      const lit = await open(`environment=test-models/sky.exr&model=test-models/tetrahedron.obj&${query}`);
      const shownLit = await until(lit, (s) => s.scene === "tetrahedron.obj" && s.environment === "sky.exr" && !s.busy && s.samples >= s.spp, "the model in the environment");
      await until(lit, (s, frames) => s.frames >= frames, "a frame of the model", { arg: shownLit.frames + 2 });
      assertSimilar(await screenshot(lit, `${backend}-model-url-environment`),
        fileReference(tetrahedron, size.width, size.height, ["--environment", sky]));
      assert.deepEqual(lit.errors, []);
      await lit.close();

      for (const [file, line] of [["missing.ply", /^test-models\/missing\.ply: cannot fetch: HTTP 404/], ["broken.ply", /^broken\.ply:11: /]]) {
        const failing = await open(`model=test-models/${file}&${query}`);
        const failed = await until(failing, (s) => s.error != null && s.frames >= 1, `the error of ${file}`);
        assert.match(failed.error, line);
        assert.ok(!failed.error.includes("\n"), failed.error);
        assert.equal(failed.scene, "whitted");
        await shows(failing, failed.error);
        await failing.close();
      }
    });

    test("?builder=sah traces random:2000 as the CPU renders it; a moving scene is refused with its reason and the scene stays", async () => {
      const query = `scene=random:2000&accel=stack&builder=sah&width=${size.width}&height=${size.height}&backend=${backend}&spp=1`;
      const page = await open(query);
      const opened = await until(page, (s) => s.primitives === 2000 && !s.busy && s.samples >= s.spp, "random:2000");
      assert.equal(opened.builder, "sah");
      await until(page, (s, frames) => s.frames >= frames, "a frame of random:2000", { arg: opened.frames + 2 });
      assertSimilar(await screenshot(page, `${backend}-builder-sah`), reference("random:2000", size.width, size.height));
      assert.deepEqual(page.errors, []);
      await page.evaluate(() => window.raypipeViewer.set({ scene: "bounce:40" }));
      const refused = await until(page, (s) => s.error != null && !s.busy, "the refusal of bounce:40");
      assert.match(refused.error, /sah builder builds a still scene's tree once/);
      assert.equal(refused.scene, "random:2000");
      assert.equal(refused.builder, "sah");
      await shows(page, refused.error);
      await page.close();
    });

    test("bounce:N stands still when paused, equal to the CPU's first frame, and moves between frames", async () => {
      const spec = "bounce:300";
      const small = { width: 96, height: 72 };
      // WebGPU rebuilds in compute passes from storage memory, asked for here (a software adapter's
      // default is texture memory, rebuilt on the CPU as on WebGL2).
      const memory = backend === "webgpu" ? "&memory=storage" : "";
      const page = await open(`scene=${spec}&paused=true&width=${small.width}&height=${small.height}&backend=${backend}&spp=1${memory}`);
      const still = await until(page, SETTLED, spec);
      assert.equal(still.time, 0);
      assert.equal(still.memory, backend === "webgpu" ? "storage" : "texture");
      const first = await screenshot(page, `${backend}-bounce-0`);
      assertSimilar(first, reference(spec, small.width, small.height));
      const firstAgain = await screenshot(page, `${backend}-bounce-first`);
      await page.locator("input[data-key=paused]").uncheck();
      const moved = await until(page, (s) => !s.paused && s.time > 0.1 && s.samples >= 1, "motion");
      // WebGL2 rebuilds on the CPU and reports its time; WebGPU rebuilds in compute passes, untimed.
      // (The browser's clock is coarse: a small build may read as 0 ms.)
      if (backend === "webgl2") assert.equal(typeof moved.buildMs, "number", "a CPU rebuild reports its time");
      else assert.equal(moved.buildMs, null, "a GPU rebuild reports no CPU time");
      const later = await screenshot(page, `${backend}-bounce-later`);
      assert.ok(differ(later, firstAgain), "the spheres did not move");
      fs.rmSync(later);
      fs.rmSync(firstAgain);
      assert.deepEqual(page.errors, []);
      await page.close();
    });
  });
}

test("on a phone (390x844 CSS pixels, 3 device pixels to one, touch) the page fits the screen, draws, and turns and pinches by touch", { skip: BROWSER !== "chromium" && "Firefox's driver sends no touches" }, async () => {
  const page = await open("scene=whitted&width=960&height=540&spp=1", {
    device: { viewport: { width: 390, height: 844 }, deviceScaleFactor: 3, isMobile: true, hasTouch: true },
  });
  const first = await until(page, (s) => s.frames >= 2 && !s.busy && s.samples >= 1, "a frame on the phone");
  const [wide, screen] = await page.evaluate(() => [document.documentElement.scrollWidth, window.innerWidth]);
  assert.ok(wide <= screen, `the page is ${wide} CSS pixels wide on a screen of ${screen}`);
  const box = await page.locator("#frame").boundingBox();
  assert.ok(box.x >= 0 && box.x + box.width <= screen && box.height > 100, `the canvas at ${JSON.stringify(box)}`);
  for (const control of await page.locator("#controls select, #controls input").all()) {
    const place = await control.boundingBox();
    if (place) assert.ok(place.x >= 0 && place.x + place.width <= screen, `a control at ${JSON.stringify(place)} leaves the screen`);
  }

  const cdp = await page.context().newCDPSession(page);
  const centre = { x: box.x + box.width / 2, y: box.y + box.height / 2 };
  const touch = (type, points) => cdp.send("Input.dispatchTouchEvent", {
    type,
    touchPoints: points.map(([x, y], id) => ({ x: centre.x + x, y: centre.y + y, id })),
  });
  const distance = (c) => Math.hypot(...c.eye.map((x, i) => x - c.target[i]));
  await touch("touchStart", [[0, 0]]);
  for (const x of [10, 20, 30]) await touch("touchMove", [[x, 0]]);
  await touch("touchEnd", []);
  const turned = await until(page, (s, eye) => s.camera.eye.some((x, i) => Math.abs(x - eye[i]) > 1e-3), "the camera turned by a finger", { arg: first.camera.eye });
  assert.ok(Math.abs(distance(turned.camera) - distance(first.camera)) < 1e-3 * distance(first.camera), "an orbit keeps the distance");
  await touch("touchStart", [[-10, 0], [10, 0]]);
  for (const d of [15, 20, 25, 30]) await touch("touchMove", [[-d, 0], [d, 0]]);
  await touch("touchEnd", []);
  await until(page, (s, d) => Math.hypot(...s.camera.eye.map((x, i) => x - s.camera.target[i])) < 0.9 * d, "the camera dollied in by a pinch", { arg: distance(turned.camera) });
  await until(page, (s) => s.frames >= 2 && !s.busy && s.samples >= 1, "a frame after the touches");
  // The whole screen, as docs/images/phone.png shows it.
  await page.screenshot({ path: path.join(output, "phone-screen.png") });
  assert.deepEqual(page.errors, []);
  await page.close();
});

test("a browser with neither WebGPU nor WebGL2 gets one line on the page", async () => {
  const page = await open("scene=whitted&width=64&height=48", {
    init: () => {
      Object.defineProperty(navigator, "gpu", { value: undefined });
      const getContext = HTMLCanvasElement.prototype.getContext;
      HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
        return kind === "webgl2" ? null : getContext.call(this, kind, ...rest);
      };
    },
  });
  const status = await until(page, (s) => s.error != null, "the error", { timeout: 60_000 });
  assert.match(status.error, /^raypipe cannot trace here: this browser has no WebGPU; this browser has no WebGL2/);
  assert.ok(!status.error.includes("\n"), status.error);
  assert.equal(status.frames, 0);
  await shows(page, status.error);
  await page.close();
});

test("a bad URL setting is reported and the rest applies", async () => {
  const page = await open("scene=whitted&accel=bvh&width=64&height=48&backend=webgl2&spp=1");
  const status = await until(page, (s) => s.frames >= 1 && s.error != null, "a frame");
  assert.equal(status.error, "accel=bvh: expected one of brute, stack, stackless, threaded, wide");
  assert.equal(status.width, 64);
  // The walk the page takes where the URL names none: the stack walk on a software adapter, as
  // Chromium's SwiftShader and Firefox's llvmpipe are here.
  assert.equal(status.accel, "stack");
  await shows(page, status.error);
  await page.close();
});
