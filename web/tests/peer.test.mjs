// The peer benchmark (web/peer/run.mjs) on a small generated sphere: its validation must stop a run
// whose images differ before any time is printed (WebGL2), and pass a run whose images agree (both
// backends, both peers).
// Times are not checked here (docs/BENCHMARKS.md has them); only that they are printed or not.
import { test } from "node:test";
import assert from "node:assert/strict";
import { spawnSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const TIMEOUT_MS = 900_000;

/// A UV sphere as an OBJ: `rings` x `segments` quads, each two triangles.
function sphereObj(rings, segments) {
  const lines = [];
  for (let i = 0; i <= rings; i++) {
    const theta = (Math.PI * i) / rings;
    for (let j = 0; j < segments; j++) {
      const phi = (2 * Math.PI * j) / segments;
      lines.push(`v ${Math.sin(theta) * Math.cos(phi)} ${Math.cos(theta)} ${Math.sin(theta) * Math.sin(phi)}`);
    }
  }
  const at = (i, j) => i * segments + (j % segments) + 1;
  for (let i = 0; i < rings; i++) {
    for (let j = 0; j < segments; j++) {
      lines.push(`f ${at(i, j)} ${at(i + 1, j)} ${at(i + 1, j + 1)}`, `f ${at(i, j)} ${at(i + 1, j + 1)} ${at(i, j + 1)}`);
    }
  }
  return lines.join("\n") + "\n";
}

function benchmark(backends, ...extra) {
  const folder = fs.mkdtempSync(path.join(os.tmpdir(), "raypipe-peer-test-"));
  const model = path.join(folder, "sphere.obj");
  fs.writeFileSync(model, sphereObj(16, 24));
  const run = spawnSync("node", [path.join(web, "peer/run.mjs"), "--model", model, "--width", "64", "--height", "48",
    "--backends", backends, "--rounds", "1", ...extra], { encoding: "utf8", timeout: TIMEOUT_MS });
  fs.rmSync(folder, { recursive: true, force: true });
  return { status: run.status, output: `${run.stdout}${run.stderr}` };
}

test("the peer benchmark refuses to time images that differ (the peer's camera turned by 8 degrees)", { timeout: TIMEOUT_MS }, () => {
  const { status, output } = benchmark("webgl2", "--skew-peer", "8");
  assert.equal(status, 1, output);
  assert.match(output, /the images differ: raypipe \(webgl2, threaded\) hits \d+, three-mesh-bvh \(webgl2\) \d+/);
  assert.doesNotMatch(output, /ms per frame/);
});

test("the peer benchmark times both tracers on both backends where their images agree", { timeout: TIMEOUT_MS }, () => {
  const { status, output } = benchmark("webgl2,webgpu");
  assert.equal(status, 0, output);
  assert.match(output, /three-mesh-bvh [\d.]+ \(three [\d.]+\) webgl2 texture: [\d.]+ ms per frame/);
  assert.match(output, /three-mesh-bvh [\d.]+ \(three [\d.]+\) webgpu storage: [\d.]+ ms per frame/);
  for (const walk of ["threaded", "stack"]) {
    assert.match(output, new RegExp(`raypipe webgl2 texture ${walk} lbvh: [\\d.]+ ms per frame .*, \\d+ rays .*x three-mesh-bvh's on webgl2`));
    assert.match(output, new RegExp(`raypipe webgpu (storage|texture) ${walk} lbvh: [\\d.]+ ms per frame .*x three-mesh-bvh's on webgpu .*x raypipe webgl2's`));
  }
});

test("the peer benchmark times raypipe's page with each tree builder", { timeout: TIMEOUT_MS }, () => {
  const { status, output } = benchmark("webgl2", "--accel", "stack", "--builder", "lbvh,sah");
  assert.equal(status, 0, output);
  for (const builder of ["lbvh", "sah"]) {
    assert.match(output, new RegExp(`raypipe webgl2 texture stack ${builder}: [\\d.]+ ms per frame .*x three-mesh-bvh's on webgl2`));
  }
});
