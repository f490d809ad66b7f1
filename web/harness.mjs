// What every script that drives the page in headless Chromium shares: the browser's flags, a
// static server for the built page (and whatever else a script mounts), and the launch.
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { chromium } from "playwright-core";

// WebGPU on SwiftShader's Vulkan and WebGL2 on ANGLE over SwiftShader, without a GPU or a sandbox.
export const FLAGS = [
  "--no-sandbox", "--disable-quic", "--no-first-run", "--disable-background-networking",
  "--disable-component-update", "--disable-sync", "--enable-unsafe-webgpu", "--enable-unsafe-swiftshader",
  "--use-angle=swiftshader", "--enable-features=Vulkan", "--use-vulkan=swiftshader",
  // More, for a diagnosis (say, "--enable-dawn-features=disable_robustness"): never in a published run.
  ...(process.env.CHROMIUM_FLAGS ?? "").split(" ").filter(Boolean),
];

const TYPES = {
  ".html": "text/html",
  ".js": "text/javascript",
  ".mjs": "text/javascript",
  ".css": "text/css",
  ".wasm": "application/wasm",
  ".glb": "model/gltf-binary",
};

/// Serves files from folders by URL prefix (`{ "/": site, "/peer/": folder }`, the longest prefix
/// first) on a free port of 127.0.0.1; anything outside them, or not a regular file, is a 404.
/// Returns `{ origin, close }`.
export async function serve(mounts) {
  const prefixes = Object.keys(mounts).sort((a, b) => b.length - a.length);
  const server = http.createServer((request, response) => {
    const name = decodeURIComponent(new URL(request.url, "http://x").pathname);
    const prefix = prefixes.find((p) => name.startsWith(p));
    const folder = prefix && path.resolve(mounts[prefix]);
    const rest = prefix ? name.slice(prefix.length) : "";
    const file = folder && path.join(folder, rest === "" ? "index.html" : rest);
    if (!file || !file.startsWith(folder) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      response.writeHead(404).end();
      return;
    }
    response.writeHead(200, { "content-type": TYPES[path.extname(file)] ?? "application/octet-stream" });
    fs.createReadStream(file).pipe(response);
  });
  await new Promise((resolve) => server.listen(0, "127.0.0.1", resolve));
  return { origin: `http://127.0.0.1:${server.address().port}`, close: () => server.close() };
}

/// Debian's Chromium (or $CHROMIUM), headless, with FLAGS.
export function launch() {
  return chromium.launch({ executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium", args: FLAGS });
}
