// What every script that drives the page shares: the browsers' flags, a static server for the
// built page (and whatever else a script mounts), and the launch: headless Chromium through
// Playwright, or Firefox through Puppeteer over WebDriver BiDi (RAYPIPE_BROWSER=firefox), behind
// the same page API.
import fs from "node:fs";
import http from "node:http";
import os from "node:os";
import path from "node:path";
import { chromium } from "playwright-core";
import puppeteer from "puppeteer-core";

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

/// The browser the tests drive: `chromium` (the default) or `firefox` (RAYPIPE_BROWSER).
export const BROWSER = process.env.RAYPIPE_BROWSER ?? "chromium";

// Firefox's WebGPU (wgpu, on lavapipe here) is behind a preference on Linux; its WebGL2 runs on
// llvmpipe. Headless Firefox has no WebGL2 here: it runs on a display (Xvfb in the tests).
const FIREFOX_PREFS = { "dom.webgpu.enabled": true, "gfx.webgpu.ignore-blocklist": true };

/// BROWSER: Debian's Chromium (or $CHROMIUM), headless, with FLAGS; or Debian's Firefox ESR (or
/// $FIREFOX) on the display, its pages wrapped in the Playwright calls the tests make.
export async function launch() {
  if (BROWSER === "chromium") {
    return chromium.launch({ executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium", args: FLAGS });
  }
  if (BROWSER !== "firefox") throw new Error(`RAYPIPE_BROWSER=${BROWSER}: expected chromium or firefox`);
  if (!process.env.DISPLAY) throw new Error("Firefox runs on a display here: run the tests under xvfb-run");
  const browser = await puppeteer.launch({
    browser: "firefox",
    executablePath: process.env.FIREFOX ?? "/usr/bin/firefox-esr",
    headless: false,
    extraPrefsFirefox: FIREFOX_PREFS,
  });
  return {
    newPage: async (options = {}) => new FirefoxPage(await browser.newPage(), options),
    close: () => browser.close(),
  };
}

/// A Puppeteer page behind the Playwright calls the tests make: evaluate, waitForFunction,
/// addInitScript, locator(...).screenshot/isVisible/evaluate/fill/dispatchEvent/uncheck,
/// selectOption, setInputFiles (from a buffer), on("pageerror" | "console").
class FirefoxPage {
  constructor(page, { viewport }) {
    this.page = page;
    this.viewport = viewport;
    this.files = fs.mkdtempSync(path.join(os.tmpdir(), "raypipe-upload-"));
  }

  async goto(url) {
    if (this.viewport) await this.page.setViewport(this.viewport);
    await this.page.goto(url);
  }

  on(event, listener) {
    this.page.on(event, listener);
  }

  addInitScript(script) {
    return this.page.evaluateOnNewDocument(script);
  }

  evaluate(fn, arg) {
    return this.page.evaluate(fn, arg);
  }

  waitForFunction(fn, arg, { timeout, polling } = {}) {
    return this.page.waitForFunction(fn, { timeout, polling }, arg);
  }

  selectOption(selector, value) {
    return this.page.select(selector, value);
  }

  async setInputFiles(selector, { name, buffer }) {
    const file = path.join(this.files, name);
    fs.writeFileSync(file, buffer);
    const input = await this.page.$(selector);
    await input.uploadFile(file); // fires `input` and `change`, as a user's choice does
  }

  locator(selector) {
    const element = () => this.page.waitForSelector(selector);
    return {
      screenshot: async ({ path: file }) => (await element()).screenshot({ path: file }),
      isVisible: async () => (await element()).isVisible(),
      evaluate: async (fn, arg) => (await element()).evaluate(fn, arg),
      // As Playwright's: the field focused (the page leaves a focused field alone), its value, `input`.
      fill: async (value) => (await element()).evaluate((input, value) => {
        input.focus();
        input.value = value;
        input.dispatchEvent(new Event("input", { bubbles: true }));
      }, value),
      dispatchEvent: async (type) => (await element()).evaluate((input, type) => input.dispatchEvent(new Event(type, { bubbles: true })), type),
      uncheck: async () => (await element()).evaluate((input) => {
        if (input.checked) input.click();
      }),
    };
  }

  async close() {
    await this.page.close();
    fs.rmSync(this.files, { recursive: true, force: true });
  }
}
