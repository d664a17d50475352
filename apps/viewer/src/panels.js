// The page's 2-D panels: the colour map and its legend, the scrolling force plot.

// A perceptual blue -> teal -> yellow -> red map of x in [0, 1] (clamped), as r, g, b in [0, 1].
const STOPS = [[0.23, 0.30, 0.75], [0.20, 0.65, 0.70], [0.55, 0.80, 0.35], [0.98, 0.80, 0.20], [0.85, 0.15, 0.15]];
export function colormap(x) {
  x = Math.min(Math.max(x, 0), 1) * (STOPS.length - 1);
  const i = Math.min(Math.floor(x), STOPS.length - 2), f = x - i, a = STOPS[i], b = STOPS[i + 1];
  return [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])];
}

export function drawLegend(canvas, maxMm, midEl, maxEl) {
  const ctx = canvas.getContext('2d');
  for (let x = 0; x < canvas.width; ++x) {
    const [r, g, b] = colormap(x / (canvas.width - 1));
    ctx.fillStyle = `rgb(${255 * r},${255 * g},${255 * b})`;
    ctx.fillRect(x, 0, 1, canvas.height);
  }
  midEl.textContent = (maxMm / 2).toFixed(1);
  maxEl.textContent = `≥ ${maxMm.toFixed(1)}`;
}

// Force on the tool over the last `span` seconds: |F| and its x, y, z components (N);
// push() adds a sample, draw() paints.
export class ForcePlot {
  constructor(canvas, span) { this.canvas = canvas; this.span = span; this.samples = []; }
  push(t, f) {
    if (this.samples.length && t < this.samples[this.samples.length - 1][0]) this.samples = [];  // reset
    this.samples.push([t, f[0], f[1], f[2], Math.hypot(f[0], f[1], f[2])]);
    while (this.samples.length && this.samples[0][0] < t - this.span) this.samples.shift();
  }
  draw() {
    const c = this.canvas, ctx = c.getContext('2d'), s = this.samples;
    ctx.fillStyle = '#1c1f26';
    ctx.fillRect(0, 0, c.width, c.height);
    if (!s.length) return;
    const t1 = s[s.length - 1][0], t0 = t1 - this.span;
    let m = 1e-3;
    for (const r of s) m = Math.max(m, r[4]);
    const X = (t) => (t - t0) / this.span * c.width, Y = (v) => c.height / 2 - v / m * (c.height / 2 - 4);
    ctx.strokeStyle = '#444';
    ctx.beginPath(); ctx.moveTo(0, Y(0)); ctx.lineTo(c.width, Y(0)); ctx.stroke();
    const colors = [null, '#e66', '#6c6', '#69f', '#fff'];
    for (const k of [1, 2, 3, 4]) {
      ctx.strokeStyle = colors[k];
      ctx.beginPath();
      s.forEach((r, i) => (i ? ctx.lineTo(X(r[0]), Y(r[k])) : ctx.moveTo(X(r[0]), Y(r[k]))));
      ctx.stroke();
    }
    ctx.fillStyle = '#bbb';
    ctx.fillText(`±${m.toFixed(2)} N   |F| x y z`, 4, 12);
  }
}
