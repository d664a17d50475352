// The sflsh viewer page: connects to the server's WebSocket, draws the skin
// coloured by soft displacement, the objects, tools and skeleton, the tools'
// and contacts' force arrows, and sends
// the user's tool motion and controls (control messages:
// include/sflsh/viewer/control_message.hpp).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { decodeFrame, makeState } from './protocol.js';
import { ForcePlot, colormap, drawLegend } from './panels.js';
import { ToolInput } from './tool_input.js';
import { ResultTools } from './result_tools.js';
import { ContactArrows, makeArrows, placeArrow } from './force_arrows.js';

const $ = (id) => document.getElementById(id);
// SMPL joint parents (24 joints per body).
const PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21];

// What tests and measurements read (window.sflshViewer).
const stats = { frames: 0, rendered: 0, bytes: 0, latencies: [], lastInfo: null, scene: null, errors: [],
                renderedFrame: -1, fps: 0, receivedFps: 0, bandwidth: 0, maxU: 0, contactFrames: 0,
                // Contact force arrows visible in the last frame, and the most seen in one frame.
                contactArrows: 0, maxContactArrows: 0,
                // Page time (ms, summed) per stage: decoding frames, applying them (colours, panels), normals, draws.
                timing: { decode_ms: 0, apply_ms: 0, normals_ms: 0, render_ms: 0, draws: 0 } };
window.sflshViewer = stats;
// Page pixel (client coordinates) of world point p (m): for tests that aim the mouse at the tool.
stats.project = (p) => {
  const v = new THREE.Vector3(...p).project(camera), r = renderer.domElement.getBoundingClientRect();
  return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
};
// Luminance statistics of the last rendered image: { mean, std, nonBackground } (fraction of pixels).
stats.pixelStats = () => {
  renderer.render(scene3, camera);
  const c = renderer.domElement, w = c.width, h = c.height;
  const tmp = document.createElement('canvas');
  tmp.width = w; tmp.height = h;
  const ctx = tmp.getContext('2d');
  ctx.drawImage(c, 0, 0);
  const d = ctx.getImageData(0, 0, w, h).data, bg = [0x20, 0x23, 0x2a];
  let s = 0, s2 = 0, other = 0;
  for (let i = 0; i < d.length; i += 4) {
    const l = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
    s += l; s2 += l * l;
    if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) > 30) ++other;
  }
  const n = d.length / 4, mean = s / n;
  return { mean, std: Math.sqrt(Math.max(s2 / n - mean * mean, 0)), nonBackground: other / n };
};

const view = $('view');
// ?aa=0 turns antialiasing off (software renderers such as headless chromium's SwiftShader draw much faster).
const params = new URLSearchParams(location.search);
// (No preserveDrawingBuffer: pixelStats renders and reads back in the same task.)
const renderer = new THREE.WebGLRenderer({ antialias: params.get('aa') !== '0' });
// ?res=R draws at R device pixels per CSS pixel (e.g. 0.5: a quarter of the fragments, for software renderers).
renderer.setPixelRatio(Number(params.get('res')) > 0 ? Math.min(Number(params.get('res')), 2) : Math.min(window.devicePixelRatio, 2));
view.appendChild(renderer.domElement);
const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0x20232a);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
camera.position.set(0, 1.2, 3);
const orbit = new OrbitControls(camera, renderer.domElement);
scene3.add(new THREE.HemisphereLight(0xffffff, 0x444455, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(2, 4, 3);
scene3.add(sun);

let ws = null, meta = null, skin = null, state = null, skeleton = null, dirty = false;
let faces = null, skinDirty = false;  // skinDirty: positions changed since the last draw (normals due)
const objects = [];
let toolInput = null, plot = null, arrow = null, driver = false, paused = false;
let resultTools = null;  // playback: the result's tools
let contactArrows = null;  // every contact's force on its body
let otherToolArrows = [];  // live: the force arrows of the tools after the driven one
let seq = 0;
let lastResets = 0, stiffnessSentAt = -1e9;
const sentAt = new Map();  // seq -> performance.now() at send, for input-to-photon
let pendingLatency = [];    // send times of the tool poses the latest frames answer, timed at their render

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  dirty = true;
}
window.addEventListener('resize', resize);
resize();

export function send(msg) {
  if (!ws || ws.readyState !== WebSocket.OPEN) return false;
  msg.seq = ++seq;
  if (msg.type === 'tool') {
    sentAt.set(msg.seq, performance.now());
    if (sentAt.size > 2000) sentAt.delete(sentAt.keys().next().value);
  }
  ws.send(JSON.stringify(msg));
  return true;
}

function buildScene(m) {
  meta = m;
  stats.scene = m;
  $('title').textContent = m.title || 'sflsh viewer';
  const V = m.rest.length / 3;
  state = makeState(V);
  state.pos.set(m.rest);
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(state.pos, 3));
  g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * V), 3));
  g.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(3 * V), 3));
  for (const name of ['position', 'color', 'normal']) g.attributes[name].setUsage(THREE.DynamicDrawUsage);
  faces = Uint32Array.from(m.faces);
  g.setIndex(new THREE.BufferAttribute(faces, 1));
  updateNormals(g);
  // ?mat=standard: three's PBR material (slower in software renderers); default Lambert.
  const material = params.get('mat') === 'standard'
    ? new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.7, side: THREE.DoubleSide })
    : new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide });
  skin = new THREE.Mesh(g, material);
  scene3.add(skin);
  recolor();
  for (const o of m.objects) {
    const og = new THREE.BufferGeometry();
    og.setAttribute('position', new THREE.Float32BufferAttribute(o.vertices, 3));
    og.setIndex(o.faces);
    og.computeVertexNormals();
    const color = o.kind === 'tool' ? 0xe0a040 : 0x9098a0;
    const mesh = new THREE.Mesh(og, new THREE.MeshStandardMaterial({ color, roughness: 0.5, side: THREE.DoubleSide,
      transparent: o.shape === 'plane', opacity: o.shape === 'plane' ? 0.6 : 1 }));
    mesh.matrixAutoUpdate = false;
    scene3.add(mesh);
    objects.push(mesh);
  }
  const jg = new THREE.BufferGeometry();
  jg.setAttribute('position', new THREE.BufferAttribute(new Float32Array(m.joints * 2 * 3), 3));
  skeleton = new THREE.LineSegments(jg, new THREE.LineBasicMaterial({ color: 0x40c0ff, depthTest: false }));
  skeleton.visible = $('skeleton').checked;
  skeleton.renderOrder = 1;
  scene3.add(skeleton);
  // Frame the bodies.
  g.computeBoundingSphere();
  const c = g.boundingSphere.center, r = g.boundingSphere.radius;
  orbit.target.copy(c);
  camera.position.set(c.x, c.y + 0.2 * r, c.z + 2.6 * r);
  camera.near = r / 100;
  camera.far = r * 100;
  camera.updateProjectionMatrix();
  orbit.update();
  drawLegend($('legendbar'), m.legend_max_mm, $('legendmid'), $('legendmax'));
  const live = m.mode === 'live';
  $('livebox').classList.toggle('hidden', !live);
  $('playbox').classList.toggle('hidden', live);
  $('timeline').max = String(m.duration);
  $('reset').disabled = live && m.can_reset === false;
  if ($('reset').disabled) $('reset').title = 'this run writes files along its time line (--out, --tool-log): no reset';
  if (live && m.tools.length > 0) {
    $('toolbox').classList.remove('hidden');
    $('toolname').textContent = m.tools[0].name;
    plot = new ForcePlot($('plot'), 10);
    arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 1, 0), new THREE.Vector3(), 0.1, 0xff4060);
    arrow.visible = false;
    scene3.add(arrow);
    toolInput = new ToolInput({ camera, dom: renderer.domElement, orbit, send, toolMesh: objects[m.tools[0].object],
                                toolModeBox: $('toolmode') });
  }
  if (live && m.tools.length > 1) otherToolArrows = makeArrows(scene3, m.tools.length - 1, 0xff4060);
  contactArrows = new ContactArrows(scene3, m);
  if (!live && m.tools.length > 0) {
    $('resulttools').classList.remove('hidden');
    resultTools = new ResultTools({ scene3, meta: m, objects, table: $('tooltable'), events: $('toolevents'),
                                    seek: (t) => send({ type: 'seek', time: t }) });
  }
  dirty = true;
}

// The colour map sampled at the 256 levels |u| is sent with (8 bits of the legend's range).
const LUT = new Float32Array(3 * 256);
for (let k = 0; k < 256; ++k) LUT.set(colormap(k / 255), 3 * k);
function recolor(changed) {
  const col = skin.geometry.attributes.color.array, mag = state.mag, scale = 255e3 / meta.legend_max_mm;
  const paint = (i) => {
    const k = 3 * Math.min(255, Math.round(mag[i] * scale));
    col[3 * i] = LUT[k]; col[3 * i + 1] = LUT[k + 1]; col[3 * i + 2] = LUT[k + 2];
  };
  if (changed) for (let e = 0; e < changed.length; ++e) paint(changed[e]);
  else for (let i = 0; i < mag.length; ++i) paint(i);
  skin.geometry.attributes.color.needsUpdate = true;
}

// Area-weighted vertex normals of the skin (what three's computeVertexNormals
// gives, without its per-face Vector3 work): one pass over the faces.
function updateNormals(geometry) {
  const p = geometry.attributes.position.array, out = geometry.attributes.normal.array;
  out.fill(0);
  for (let f = 0; f < faces.length; f += 3) {
    const a = 3 * faces[f], b = 3 * faces[f + 1], c = 3 * faces[f + 2];
    const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
    const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
    const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    out[a] += nx; out[a + 1] += ny; out[a + 2] += nz;
    out[b] += nx; out[b + 1] += ny; out[b + 2] += nz;
    out[c] += nx; out[c + 1] += ny; out[c + 2] += nz;
  }
  for (let i = 0; i < out.length; i += 3) {
    const l = Math.hypot(out[i], out[i + 1], out[i + 2]) || 1;
    out[i] /= l; out[i + 1] /= l; out[i + 2] /= l;
  }
  geometry.attributes.normal.needsUpdate = true;
}

const tmpQ = new THREE.Quaternion(), tmpP = new THREE.Vector3(), one = new THREE.Vector3(1, 1, 1);
function applyFrame(f) {
  skinDirty = true;  // positions and normals are uploaded once per drawn frame (loop)
  recolor(f.changed);
  for (let o = 0; o < objects.length && 7 * o < f.poses.length; ++o) {
    const p = f.poses.subarray(7 * o, 7 * o + 7);
    tmpP.set(p[0], p[1], p[2]);
    tmpQ.set(p[4], p[5], p[6], p[3]);
    objects[o].matrix.compose(tmpP, tmpQ, one);
  }
  if (f.joints.length) {
    const a = skeleton.geometry.attributes.position.array;
    const J = f.joints.length / 3;
    for (let j = 0; j < J; ++j) {
      const base = j - (j % 24), parent = PARENTS[j % 24];
      const pj = parent < 0 ? j : base + parent;
      a.set(f.joints.subarray(3 * j, 3 * j + 3), 6 * j);
      a.set(f.joints.subarray(3 * pj, 3 * pj + 3), 6 * j + 3);
    }
    skeleton.geometry.attributes.position.needsUpdate = true;
  }
  const info = f.info;
  stats.lastInfo = info;
  stats.maxU = Math.max(stats.maxU, info.max_u_mm);
  if (info.tool && info.tool.contact) ++stats.contactFrames;
  driver = info.driver;
  paused = info.paused;
  // A reset moved the tool back to its start: take the server's pose again.
  if (info.resets !== undefined && info.resets !== lastResets) {
    lastResets = info.resets;
    if (toolInput) toolInput.resync();
  }
  if (meta.mode === 'live' && document.activeElement !== $('stiffness') && performance.now() - stiffnessSentAt > 1000) {
    $('stiffness').value = String(Math.log10(info.stiffness));
    $('stiffval').textContent = info.stiffness.toFixed(2);
  }
  showInfo(info);
  // Controls this frame answers: timed when it reaches the screen.
  for (const [s, t0] of sentAt) if (s <= info.seq) { pendingLatency.push(t0); sentAt.delete(s); }
  dirty = true;
}

// Every frame: what the 3-D view shows (force arrow, the tool's pose), the
// plot's samples. The DOM panels at most 5 times a second (text and table
// updates cost style, layout and paint of the side panel).
let panelsAt = -1e9;
function showInfo(info) {
  if (resultTools && info.tools) resultTools.show(info.tools);
  if (contactArrows) {
    contactArrows.show(info.contacts);
    stats.contactArrows = contactArrows.shown;
    stats.maxContactArrows = Math.max(stats.maxContactArrows, contactArrows.shown);
  }
  // Live: the driven tool's arrow is below; every other tool's at its frame.
  for (let t = 0; t < otherToolArrows.length && info.tools && t + 1 < info.tools.length; ++t) {
    const pose = info.tools[t + 1].pose;
    placeArrow(otherToolArrows[t], new THREE.Vector3(pose[0], pose[1], pose[2]), info.tools[t + 1].force);
  }
  if (info.tool) {
    const F = new THREE.Vector3(...info.tool.force), n = F.length();
    if (plot) plot.push(info.t, info.tool.force);
    if (toolInput) toolInput.serverPose(info.tool, driver);
    if (arrow) {
      arrow.visible = n > 1e-6;
      if (arrow.visible) {
        const to = objects[meta.tools[0].object];
        arrow.position.setFromMatrixPosition(to ? to.matrix : new THREE.Matrix4().makeTranslation(...info.tool.device));
        arrow.setDirection(F.clone().normalize());
        const len = Math.min(0.02 * n, 0.5);
        arrow.setLength(len, Math.min(0.3 * len, 0.05), Math.min(0.15 * len, 0.025));
      }
    }
  }
  const now = performance.now();
  if (now - panelsAt < 200) return;
  panelsAt = now;
  showPanels(info);
}

function showPanels(info) {
  const live = meta.mode === 'live';
  $('status').textContent = `${live ? 'live' : 'playback'} · t = ${info.t.toFixed(3)} s` +
    (info.paused ? ' · paused' : '') + (live ? (info.driver ? ' · you drive' : ' · watching') : '') +
    ` · ${info.clients} client(s)`;
  $('rtf').textContent = live ? info.rtf.toFixed(2) : '–';
  $('stepms').textContent = info.step_ms.toFixed(2);
  $('maxu').textContent = info.max_u_mm.toFixed(2);
  $('pause').textContent = info.paused ? 'Run' : 'Pause';
  $('play').textContent = info.paused ? 'Play' : 'Pause';
  if (!live && document.activeElement !== $('timeline')) {
    $('timeline').value = String(info.t);
    $('ptime').textContent = `${info.t.toFixed(3)} s (frame ${info.frame})`;
  }
  const terms = $('terms');
  terms.innerHTML = '';
  const total = info.terms.reduce((s, x) => s + x[1], 0) || 1;
  for (const [name, ms] of info.terms) {
    const tr = terms.insertRow();
    tr.insertCell().textContent = name;
    const c = tr.insertCell(); c.className = 'n'; c.textContent = ms.toFixed(3);
    const b = tr.insertCell(); b.style.width = '80px';
    b.innerHTML = `<div class="bar" style="width:${(100 * ms / total).toFixed(0)}%"></div>`;
  }
  if (resultTools && info.tools) resultTools.panel(info.tools, info.t);
  if (info.tool) {
    const n = Math.hypot(...info.tool.force);
    $('force').textContent = `${n.toFixed(2)} (${info.tool.force.map((x) => x.toFixed(2)).join(', ')})`;
    $('contact').textContent = info.tool.contact ? '· contact' : '';
    if (plot) plot.draw();
  }
}

function connect() {
  ws = new WebSocket(`ws://${location.host}/ws`);
  ws.binaryType = 'arraybuffer';
  ws.onmessage = (ev) => {
    try {
      if (typeof ev.data === 'string') {
        const m = JSON.parse(ev.data);
        if (m.type === 'scene' && !meta) buildScene(m);
        return;
      }
      if (!meta) return;
      stats.bytes += ev.data.byteLength;
      const t0 = performance.now();
      const f = decodeFrame(ev.data, meta, state);
      stats.frames++;
      stats.lastFrameNumber = f.number;
      const t1 = performance.now();
      applyFrame(f);
      stats.timing.decode_ms += t1 - t0;
      stats.timing.apply_ms += performance.now() - t1;
    } catch (e) {
      stats.errors.push(String(e));
      console.error(e);
    }
  };
  ws.onclose = () => { $('status').textContent = 'disconnected (reload to reconnect)'; };
}

// Panels' controls.
$('pause').onclick = () => send({ type: 'pause', paused: !paused });
$('step').onclick = () => send({ type: 'step' });
$('reset').onclick = () => { if (send({ type: 'reset' }) && toolInput && driver) toolInput.hold(); };
// The stiffness slider is logarithmic: 10^value, 0.1 to 10 (control_message.hpp's range);
// sent at most every 100 ms while dragged (each one rebuilds the model's elastic terms), and on release.
function sendStiffness(force) {
  const k = Math.min(Math.max(Math.pow(10, Number($('stiffness').value)), 0.1), 10);
  $('stiffval').textContent = k.toFixed(2);
  const now = performance.now();
  if (!force && now - stiffnessSentAt < 100) return;
  stiffnessSentAt = now;
  send({ type: 'stiffness', scale: k });
}
$('stiffness').oninput = () => sendStiffness(false);
$('stiffness').onchange = () => sendStiffness(true);
$('play').onclick = () => send({ type: 'pause', paused: !paused });
$('pstep').onclick = () => send({ type: 'step' });
$('speed').onchange = () => send({ type: 'speed', speed: Number($('speed').value) });
$('timeline').oninput = () => {
  const t = Number($('timeline').value);
  $('ptime').textContent = `${t.toFixed(3)} s`;
  send({ type: 'seek', time: t });
};
$('skeleton').onchange = () => { if (skeleton) { skeleton.visible = $('skeleton').checked; dirty = true; } };
orbit.addEventListener('change', () => { dirty = true; });

// Render only when something changed; time input to photon at the render that shows the answer.
let fpsCount = 0, fpsT0 = performance.now(), bytes0 = 0;
function loop(now) {
  requestAnimationFrame(loop);
  if (toolInput) toolInput.tick(now);
  if (dirty) {
    const t0 = performance.now();
    if (skinDirty) {
      updateNormals(skin.geometry);
      skin.geometry.attributes.position.needsUpdate = true;
      skinDirty = false;
    }
    const t1 = performance.now();
    renderer.render(scene3, camera);
    const t2 = performance.now();
    stats.timing.normals_ms += t1 - t0;
    stats.timing.render_ms += t2 - t1;
    stats.timing.draws++;
    dirty = false;
    ++stats.rendered;
    stats.renderedFrame = stats.lastFrameNumber ?? -1;
    ++fpsCount;
    // Input to photon: from the pose's send to the end of the draw that shows its answer.
    for (const ts of pendingLatency) stats.latencies.push(t2 - ts);
    pendingLatency = [];
  }
  if (now - fpsT0 >= 1000) {
    stats.receivedFps = (stats.frames - (stats._f0 ?? 0)) * 1000 / (now - fpsT0);
    stats.fps = fpsCount * 1000 / (now - fpsT0);
    stats.bandwidth = (stats.bytes - bytes0) / ((now - fpsT0) / 1000);
    stats._f0 = stats.frames;
    bytes0 = stats.bytes;
    fpsT0 = now;
    fpsCount = 0;
    $('fps').textContent = stats.fps.toFixed(1);
    $('rfps').textContent = stats.receivedFps.toFixed(1);
    $('bw').textContent = (stats.bandwidth / 1e6).toFixed(2);
    const l = stats.latencies.slice(-100).sort((a, b) => a - b);
    if (l.length) $('lat').textContent = l[l.length >> 1].toFixed(1);
  }
}
connect();
requestAnimationFrame(loop);
