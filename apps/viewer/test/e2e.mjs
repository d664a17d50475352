// End-to-end check of the viewer page in headless Debian chromium (puppeteer-core;
// no browser download). Run by tests/viewer/browser_e2e_test.cpp and by
// scripts/viewer_figures.sh:
//   node apps/viewer/test/e2e.mjs --url http://127.0.0.1:PORT/ --mode live|playback
//        [--screenshot out.png] [--seconds S] [--drag DX,DY,DZ] [--wheel N] [--query ?aa=0]
// live: waits for frames, Shift-drags the tool by DX,DY,DZ metres (default 0,-0.03,0)
// in the view plane, holds, and reports what the server sent (contact, max |u|);
// playback: presses play and checks the time advances. Always: display fps,
// bandwidth, input-to-photon latencies, pixel statistics of the rendered image.
// Prints one JSON line; exits 1 when the page shows no frames or is blank.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

const args = Object.fromEntries(process.argv.slice(2).reduce((a, x, i, all) =>
  (x.startsWith('--') ? [...a, [x.slice(2), all[i + 1]]] : a), []));
const url = args.url, mode = args.mode || 'live', seconds = Number(args.seconds || 3);
const drag = (args.drag || '0,-0.03,0').split(',').map(Number);
const wheel = Number(args.wheel || 0);  // Shift+wheel notches toward the scene after the drag (4 mm each)
const chromium = process.env.CHROMIUM || '/usr/bin/chromium';
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const fail = (msg, extra = {}) => { console.log(JSON.stringify({ ok: false, error: msg, ...extra })); process.exit(1); };

const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'sflsh-chromium-'));
const browser = await puppeteer.launch({
  executablePath: chromium, headless: true, userDataDir,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
         '--window-size=1280,800'],
});
const result = { ok: true, mode };
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 800 });
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  await page.goto(url + (args.query || ''), { waitUntil: 'load', timeout: 20000 });
  await page.waitForFunction(() => window.sflshViewer && window.sflshViewer.frames >= 5, { timeout: 20000 })
    .catch(() => fail('no frames within 20 s', { consoleErrors }));
  const info = () => page.evaluate(() => window.sflshViewer.lastInfo);
  const first = await info();
  result.vertices = await page.evaluate(() => window.sflshViewer.scene.rest.length / 3);
  result.max_u_mm_before = first.max_u_mm;
  if (mode === 'live') {
    if (!first.tool) fail('the live scene has no tool');
    const from = first.tool.device, to = from.map((x, i) => x + drag[i]);
    const [x0, y0] = await page.evaluate((p) => window.sflshViewer.project(p), from);
    const [x1, y1] = await page.evaluate((p) => window.sflshViewer.project(p), to);
    await page.keyboard.down('Shift');
    await page.mouse.move(x0, y0);
    await page.mouse.down();
    const steps = 40;
    for (let i = 1; i <= steps; ++i) {
      await page.mouse.move(x0 + (x1 - x0) * i / steps, y0 + (y1 - y0) * i / steps);
      await sleep(25);
    }
    await page.mouse.up();
    for (let i = 0; i < wheel; ++i) {
      await page.mouse.wheel({ deltaY: -100 });
      await sleep(40);
    }
    await page.keyboard.up('Shift');
    // Hold; the page accumulates what every frame from the server said (contact, max |u|).
    await sleep(seconds * 1000);
    const last = await info();
    const seen = await page.evaluate(() => [window.sflshViewer.contactFrames, window.sflshViewer.maxU]);
    Object.assign(result, { contact: seen[0] > 0, contact_frames: seen[0], max_u_mm_after: seen[1], device_before: from, device_after: last.tool.device,
                            force_after: last.tool.force, rtf: last.rtf, step_ms: last.step_ms, driver: last.driver });
  } else {
    await page.click('#play');
    await sleep(seconds * 1000);
    const last = await info();
    Object.assign(result, { t_before: first.t, t_after: last.t, frame_after: last.frame });
  }
  const s = await page.evaluate(() => {
    const v = window.sflshViewer, l = v.latencies.slice().sort((a, b) => a - b);
    return { fps: v.fps, received_fps: v.receivedFps, bandwidth: v.bandwidth, frames: v.frames, rendered: v.rendered, errors: v.errors,
             latency_median_ms: l.length ? l[l.length >> 1] : null, latency_count: l.length, pixels: v.pixelStats() };
  });
  Object.assign(result, s, { consoleErrors });
  if (args.screenshot) await page.screenshot({ path: args.screenshot });
  if (s.pixels.std < 5 || s.pixels.nonBackground < 0.01) result.ok = false, result.error = 'blank image';
  if (s.errors.length) result.ok = false, result.error = 'decode errors';
} finally {
  await browser.close();
  fs.rmSync(userDataDir, { recursive: true, force: true });
}
console.log(JSON.stringify(result));
process.exit(result.ok ? 0 : 1);
