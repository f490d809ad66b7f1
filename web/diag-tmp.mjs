import { launch, serve } from "./harness.mjs";
const server = await serve({ "/": "../target/web", "/scene/": "/tmp/pscene" });
const browser = await launch();
for (const q of process.argv.slice(2)) {
  const page = await browser.newPage();
  await page.addInitScript(() => {
    window.frameLog = [];
    const watch = (time) => { const f = window.raypipeStatus?.frames; const last = window.frameLog.at(-1);
      if (f != null && (!last || last[1] !== f)) window.frameLog.push([time, f]); requestAnimationFrame(watch); };
    requestAnimationFrame(watch);
  });
  await page.goto(`${server.origin}/index.html?${q}`);
  await page.waitForFunction(() => window.raypipeStatus?.error || window.raypipeStatus?.frames >= 25, null, {timeout: 600000});
  const log = await page.evaluate(() => window.frameLog.slice(-16));
  const s = await page.evaluate(() => window.raypipeStatus);
  const mean = (log.at(-1)[0] - log[0][0]) / (log.at(-1)[1] - log[0][1]);
  console.log(q, "mean", mean.toFixed(1), "ms", s.error ?? "", s.samples);
  await page.close();
}
await browser.close(); server.close();
