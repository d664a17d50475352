// The tool's pose source in the page: the mouse (Shift + drag moves the tool in
// the view plane, Shift + wheel along the view direction), the keyboard
// (W A S D in the view plane, Q E in depth, G opens/closes the gripper) and a
// gamepad (Gamepad API: left stick in the view plane, right stick vertical in
// depth, right trigger closes the gripper). Poses go to the server as "tool"
// control messages at most every 16 ms, each at most MAX_SPEED·dt from the
// previous one (the server rejects faster jumps).
import * as THREE from 'three';

const MAX_SPEED = 3.0;       // m/s, below the server's 5 m/s jump limit
const KEY_STEP = 0.003;      // m per key press
const WHEEL_STEP = 0.004;    // m per wheel notch
const PAD_SPEED = 0.15;      // m/s at full stick
const SEND_PERIOD = 16;      // ms

export class ToolInput {
  constructor({ camera, dom, orbit, send, toolMesh, toolModeBox }) {
    Object.assign(this, { camera, dom, orbit, send, toolMesh, toolModeBox });
    this.pos = null;             // the pose last sent (or the server's before any)
    this.target = null;          // where the user wants the tool
    this.quat = [1, 0, 0, 0];
    this.closure = 0; this.open = 0; this.closureTarget = 0;
    this.dragging = false; this.lastSend = 0; this.lastTick = 0; this.driver = false;
    this.plane = new THREE.Plane(); this.offset = new THREE.Vector3(); this.ray = new THREE.Raycaster();
    dom.addEventListener('pointerdown', (e) => this.down(e), { capture: true });
    window.addEventListener('pointermove', (e) => this.move(e));
    window.addEventListener('pointerup', () => this.up());
    dom.addEventListener('wheel', (e) => this.wheel(e), { capture: true, passive: false });
    window.addEventListener('keydown', (e) => this.key(e));
  }

  toolMode(e) { return e.shiftKey || this.toolModeBox.checked; }
  viewAxes() {
    const dir = new THREE.Vector3(), up = this.camera.up.clone().applyQuaternion(this.camera.quaternion);
    this.camera.getWorldDirection(dir);
    const right = new THREE.Vector3().crossVectors(dir, up).normalize();
    return { dir, up: new THREE.Vector3().crossVectors(right, dir).normalize(), right };
  }
  hit(e) {
    const r = this.dom.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    this.ray.setFromCamera(ndc, this.camera);
    return this.ray.ray.intersectPlane(this.plane, new THREE.Vector3());
  }
  down(e) {
    if (!this.target || e.button !== 0 || !this.toolMode(e)) return;
    e.stopImmediatePropagation();
    this.plane.setFromNormalAndCoplanarPoint(this.viewAxes().dir, this.target);
    const h = this.hit(e);
    if (!h) return;
    this.offset.subVectors(h, this.target);
    this.dragging = true;
    this.dom.setPointerCapture?.(e.pointerId);
  }
  move(e) {
    if (!this.dragging) return;
    const h = this.hit(e);
    if (h) this.target.subVectors(h, this.offset);
  }
  up() { this.dragging = false; }
  wheel(e) {
    if (!this.target || !this.toolMode(e)) return;
    e.preventDefault();
    e.stopImmediatePropagation();
    this.target.addScaledVector(this.viewAxes().dir, -Math.sign(e.deltaY) * WHEEL_STEP);
  }
  key(e) {
    if (!this.target || e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT') return;
    const { dir, up, right } = this.viewAxes();
    const k = e.key.toLowerCase();
    const moves = { w: [up, 1], s: [up, -1], a: [right, -1], d: [right, 1], q: [dir, -1], e: [dir, 1] };
    if (moves[k]) this.target.addScaledVector(moves[k][0], moves[k][1] * KEY_STEP);
    else if (k === 'g') this.closureTarget = this.closureTarget > 0 ? 0 : Math.max(this.open, 0.5);
  }

  // A reset was sent: stop sending until the server's frames show it (resync).
  hold() { this.held = true; this.pos = this.target = null; this.dragging = false; }
  // The server reset the scene: start again from its tool pose.
  resync() { this.held = false; this.pos = this.target = null; this.dragging = false; }

  // The server's view of the tool (frame info): the starting pose, and the pose to follow while watching.
  serverPose(tool, driver) {
    this.driver = driver;
    if (this.held) return;
    if (!this.pos || (!driver && !this.dragging)) {
      this.pos = new THREE.Vector3(...tool.device);
      this.target = this.pos.clone();
      this.quat = tool.quat;
      if (!this.open) this.open = tool.closure;
      this.closure = this.closureTarget = tool.closure;
    }
  }

  tick(now) {
    const dt = Math.min((now - (this.lastTick || now)) / 1000, 0.1);
    this.lastTick = now;
    if (!this.target) return;
    const pads = navigator.getGamepads ? navigator.getGamepads() : [];
    const pad = pads && [...pads].find((p) => p);
    if (pad) {
      const dz = (v) => (Math.abs(v) < 0.12 ? 0 : v);
      const { dir, up, right } = this.viewAxes();
      this.target.addScaledVector(right, dz(pad.axes[0] ?? 0) * PAD_SPEED * dt);
      this.target.addScaledVector(up, -dz(pad.axes[1] ?? 0) * PAD_SPEED * dt);
      this.target.addScaledVector(dir, -dz(pad.axes[3] ?? 0) * PAD_SPEED * dt);
      const trigger = pad.buttons[7] ? pad.buttons[7].value : 0;
      this.closureTarget = Math.max(this.open, 0) * (1 - trigger);
    }
    if (!this.driver || now - this.lastSend < SEND_PERIOD) return;
    const step = new THREE.Vector3().subVectors(this.target, this.pos);
    if (step.length() < 1e-6 && Math.abs(this.closureTarget - this.closure) < 1e-6) return;
    const sinceLast = Math.min(Math.max((now - this.lastSend) / 1000, SEND_PERIOD / 1000), 0.1);
    step.clampLength(0, MAX_SPEED * sinceLast);
    this.pos.add(step);
    this.closure = this.closureTarget;
    this.lastSend = now;
    this.send({ type: 'tool', tool: 0, t: now / 1000, pos: this.pos.toArray(), quat: this.quat, closure: this.closure });
  }
}
