// End-to-end check of the viewer page in headless Debian chromium (puppeteer-core;
// no browser download). Run by tests/viewer/browser_e2e_test.cpp and by
// scripts/viewer_figures.sh:
//   node apps/viewer/test/e2e.mjs --url http://127.0.0.1:PORT/ --mode live|playback
//        [--screenshot out.png] [--seconds S] [--drag DX,DY,DZ] [--wheel N] [--query ?aa=0]
//        [--controls 1] [--gl swiftshader|angle-swiftshader|in-process|egl]
// live: waits for frames, Shift-drags the tool by DX,DY,DZ metres (default 0,-0.03,0)
// in the view plane, holds, and reports what the server sent (contact, max |u|);
// with --controls, then moves the stiffness slider to 10^0.5 ≈ 3.16×, pauses, steps, resets
// and resumes with the page's controls and reports what the frames said;
// playback: presses play and checks the time advances, and reports the result's tools; then
// seeks to the last frame and reports the contact arrows drawn.
// Always: display fps, bandwidth, input-to-photon latencies, pixel statistics of the rendered image.
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
const waitInfo = (page, fn, arg) =>
  page.waitForFunction(fn, { timeout: 10000 }, arg).then(() => true, () => false);

// The live panel's controls, as a user clicks them; what the frames report after each.
async function controls(page, info) {
  const c = {};
  await page.evaluate(() => {
    const s = document.getElementById('stiffness');
    s.value = '0.5';  // 10^0.5 = 3.16×
    s.dispatchEvent(new Event('change'));
  });
  await waitInfo(page, () => Math.abs(window.sflshViewer.lastInfo.stiffness - Math.sqrt(10)) < 1e-9);
  c.stiffness = (await info()).stiffness;
  await page.click('#pause');
  c.paused = await waitInfo(page, () => window.sflshViewer.lastInfo.paused);
  await sleep(300);
  const p0 = await info();
  await sleep(500);
  const p1 = await info();
  c.held = p1.t === p0.t && p1.steps === p0.steps;
  await page.click('#step');
  await waitInfo(page, (n) => window.sflshViewer.lastInfo.steps > n, p1.steps);
  await sleep(300);
  const p2 = await info();
  Object.assign(c, { step_count: p2.steps - p1.steps, step_dt: p2.t - p1.t });
  await page.click('#reset');
  await waitInfo(page, () => window.sflshViewer.lastInfo.resets >= 1);
  await sleep(300);
  const r = await info();
  Object.assign(c, { resets: r.resets, reset_t: r.t, reset_max_u_mm: r.max_u_mm, reset_device: r.tool.device,
                     reset_stiffness: r.stiffness });
  await page.click('#pause');
  await waitInfo(page, () => !window.sflshViewer.lastInfo.paused);
  await sleep(500);
  c.resumed_t = (await info()).t;
  return c;
}

const fail = (msg, extra = {}) => { console.log(JSON.stringify({ ok: false, error: msg, ...extra })); process.exit(1); };

const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'sflsh-chromium-'));
// GPU-less WebGL back ends of chromium to compare (scripts/viewer_figures.sh):
//   swiftshader (default): --disable-gpu, WebGL on SwiftShader through ANGLE in the GPU process;
//   angle-swiftshader: --use-gl=angle --use-angle=swiftshader, GPU not disabled;
//   in-process: the same as swiftshader with the GPU thread in the browser process (no GPU-process IPC);
//   egl: --use-gl=egl (Mesa's llvmpipe when present).
const GL = {
  swiftshader: ['--disable-gpu', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
  'angle-swiftshader': ['--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  'in-process': ['--disable-gpu', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--in-process-gpu'],
  egl: ['--use-gl=egl', '--ignore-gpu-blocklist'],
};
const gl = args.gl || 'swiftshader';
if (!GL[gl]) { console.log(JSON.stringify({ ok: false, error: `--gl ${gl}: expected one of ${Object.keys(GL)}` })); process.exit(1); }
const browser = await puppeteer.launch({
  executablePath: chromium, headless: true, userDataDir,
  args: ['--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync', ...GL[gl], '--window-size=1280,800'],
});
const result = { ok: true, mode, gl };
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
    const counts = () => page.evaluate(() => [performance.now(), window.sflshViewer.rendered, window.sflshViewer.frames,
                                              window.sflshViewer.bytes]);
    const h0 = await counts();
    await sleep(seconds * 1000);
    const h1 = await counts(), dt = (h1[0] - h0[0]) / 1000;
    result.hold = { seconds: +dt.toFixed(2), drawn_fps: +((h1[1] - h0[1]) / dt).toFixed(2),
                    received_fps: +((h1[2] - h0[2]) / dt).toFixed(2), mb_per_s: +((h1[3] - h0[3]) / dt / 1e6).toFixed(4) };
    const last = await info();
    const seen = await page.evaluate(() => [window.sflshViewer.contactFrames, window.sflshViewer.maxU]);
    Object.assign(result, { contact: seen[0] > 0, contact_frames: seen[0], max_u_mm_after: seen[1], device_before: from, device_after: last.tool.device,
                            force_after: last.tool.force, rtf: last.rtf, step_ms: last.step_ms, driver: last.driver });
    if (args.controls) result.controls = await controls(page, info);
  } else {
    await page.click('#play');
    await sleep(seconds * 1000);
    const last = await info();
    Object.assign(result, { t_before: first.t, t_after: last.t, frame_after: last.frame });
    // The result's tools: in the frames, and in the page's tool panel.
    const panel = await page.evaluate(() => ({ rows: document.querySelectorAll('#tooltable tr').length,
                                               shown: !document.getElementById('resulttools').classList.contains('hidden') }));
    Object.assign(result, { tools_in_frame: (last.tools || []).length, tool_rows: panel.rows, tools_panel: panel.shown,
                            tool_pose: last.tools && last.tools.length ? last.tools[0].pose : null });
    // The result's contacts: seek to the last frame (the probe pressed in) and count the arrows drawn.
    await page.evaluate(() => {
      const tl = document.getElementById('timeline');
      tl.value = tl.max;
      tl.dispatchEvent(new Event('input'));
    });
    await page.waitForFunction(() => window.sflshViewer.maxContactArrows > 0, { timeout: 5000 }).catch(() => {});
    Object.assign(result, await page.evaluate(() => ({
      contacts_in_scene: (window.sflshViewer.scene.contacts || []).length,
      contact_arrows: window.sflshViewer.maxContactArrows,
      contact_force: ((window.sflshViewer.lastInfo.contacts || [])[0] || {}).force || null })));
  }
  const s = await page.evaluate(() => {
    const v = window.sflshViewer, l = v.latencies.slice().sort((a, b) => a - b);
    const t = v.timing, per = (x, n) => (n ? +(x / n).toFixed(3) : null);
    return { fps: v.fps, received_fps: v.receivedFps, bandwidth: v.bandwidth, frames: v.frames, rendered: v.rendered, errors: v.errors,
             latency_median_ms: l.length ? l[l.length >> 1] : null, latency_count: l.length,
             page_ms: { decode_per_frame: per(t.decode_ms, v.frames), apply_per_frame: per(t.apply_ms, v.frames),
                        normals_per_draw: per(t.normals_ms, t.draws), render_call_per_draw: per(t.render_ms, t.draws) },
             renderer: (() => { const g = document.createElement('canvas').getContext('webgl2');
                                const d = g && g.getExtension('WEBGL_debug_renderer_info');
                                return d ? g.getParameter(d.UNMASKED_RENDERER_WEBGL) : null; })(),
             pixels: v.pixelStats() };
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
