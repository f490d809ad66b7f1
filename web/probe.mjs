import { chromium } from "playwright-core";
import http from "node:http"; import fs from "node:fs"; import path from "node:path";
const site = "/work/main/target/web";
const TYPES = { ".html": "text/html", ".js": "text/javascript", ".css": "text/css", ".wasm": "application/wasm" };
const server = http.createServer((q, r) => { const n = new URL(q.url, "http://x").pathname; const f = path.join(site, n === "/" ? "index.html" : n);
  if (!fs.existsSync(f)) { r.writeHead(404).end(); return; } r.writeHead(200, {"content-type": TYPES[path.extname(f)]}); fs.createReadStream(f).pipe(r); });
await new Promise((res) => server.listen(8123, "127.0.0.1", res));
const FLAGS = ["--no-sandbox","--disable-quic","--no-first-run","--disable-background-networking","--disable-component-update","--disable-sync","--enable-unsafe-webgpu","--enable-unsafe-swiftshader","--use-angle=swiftshader","--enable-features=Vulkan","--use-vulkan=swiftshader"];
const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: FLAGS });
const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
page.on("console", (m) => console.log("console", m.type(), m.text().slice(0, 500)));
page.on("pageerror", (e) => console.log("pageerror", e.message));
const t0 = Date.now();
await page.goto(`http://127.0.0.1:8123/index.html?${process.argv[2]}`);
for (let i = 0; i < (+process.argv[3] || 30); i++) {
  await page.waitForTimeout(2000);
  const s = await page.evaluate(() => JSON.stringify(window.raypipeStatus));
  console.log(((Date.now() - t0) / 1000).toFixed(1), s);

}
await page.locator("#frame").screenshot({ path: "/tmp/probe.png" });
await browser.close(); server.close();
