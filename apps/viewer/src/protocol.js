// The viewer's frame format (include/sflsh/viewer/frame_codec.hpp): decodes a
// binary frame onto the page's skin state (positions and |u| per vertex).
export const FRAME_MAGIC = 0x46564653;
export const FULL = 1, DELTA = 2;

// state: { pos: Float32Array(3V) metres, mag: Float32Array(V) metres, ready: bool }
export function makeState(V) {
  return { pos: new Float32Array(3 * V), mag: new Float32Array(V), ready: false };
}

// Decodes `buf` (ArrayBuffer) for `scene` (the JSON scene message) onto `state`.
// Returns { kind, number, time, changed (vertex indices or null = all), poses (Float32Array 7O),
//           joints (Float32Array 3J), info (object) } or throws Error.
export function decodeFrame(buf, scene, state) {
  const dv = new DataView(buf);
  if (buf.byteLength < 48 || dv.getUint32(0, true) !== FRAME_MAGIC) throw new Error('bad frame magic');
  if (dv.getUint16(4, true) !== 1) throw new Error('unknown frame version');
  const kind = dv.getUint16(6, true), number = dv.getUint32(8, true);
  const V = dv.getUint32(12, true), N = dv.getUint32(16, true), O = dv.getUint32(20, true);
  const J = dv.getUint32(24, true), L = dv.getUint32(28, true);
  const time = dv.getFloat64(32, true), legend = dv.getFloat32(40, true);
  if (V * 3 !== state.pos.length) throw new Error(`frame has ${V} vertices, scene ${state.pos.length / 3}`);
  if (kind === DELTA && !state.ready) throw new Error('delta frame before a full frame');
  let at = 48;
  let index = null;
  // Views, not copies: every section starts aligned to its element size (header 48 bytes, padding to 4).
  if (kind === DELTA) { index = new Uint32Array(buf, at, N); at += 4 * N; }
  const q = new Uint16Array(buf, at, 3 * N); at += 6 * N;
  const m = new Uint8Array(buf, at, N); at += N;
  at = (at + 3) & ~3;
  const lo = scene.box_min, hi = scene.box_max;
  const s0 = (hi[0] - lo[0]) / 65535, s1 = (hi[1] - lo[1]) / 65535, s2 = (hi[2] - lo[2]) / 65535;
  const um = legend / 255;
  for (let e = 0; e < N; ++e) {
    const i = index ? index[e] : e;
    state.pos[3 * i] = lo[0] + q[3 * e] * s0;
    state.pos[3 * i + 1] = lo[1] + q[3 * e + 1] * s1;
    state.pos[3 * i + 2] = lo[2] + q[3 * e + 2] * s2;
    state.mag[i] = m[e] * um;
  }
  state.ready = true;
  if (at + 28 * O + 12 * J + L > buf.byteLength) throw new Error('truncated frame');
  const poses = new Float32Array(buf, at, 7 * O); at += 28 * O;
  const joints = new Float32Array(buf, at, 3 * J); at += 12 * J;
  const info = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, at, L)));
  return { kind, number, time, changed: index, poses, joints, info, bytes: buf.byteLength };
}
