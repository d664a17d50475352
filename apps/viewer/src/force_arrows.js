// Force arrows in the 3-D view: one ArrowHelper per force, at a point,
// along the force, 2 cm per newton up to 0.5 m; hidden while the force is 0.
import * as THREE from 'three';

// Arrow length per newton (m/N) and its cap (m), as the live tool's arrow.
export const METRES_PER_NEWTON = 0.02, MAX_ARROW = 0.5;

// Places `arrow` at point p (THREE.Vector3) along force f ([fx, fy, fz], N); returns whether it shows.
export function placeArrow(arrow, p, f) {
  const F = new THREE.Vector3(...f), n = F.length();
  arrow.visible = n > 1e-6;
  if (arrow.visible) {
    arrow.position.copy(p);
    arrow.setDirection(F.normalize());
    const len = Math.min(METRES_PER_NEWTON * n, MAX_ARROW);
    arrow.setLength(len, Math.min(0.3 * len, 0.05), Math.min(0.15 * len, 0.025));
  }
  return arrow.visible;
}

// `count` arrows of one colour added to scene3, hidden until shown.
export function makeArrows(scene3, count, color) {
  return Array.from({ length: count }, () => {
    const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 1, 0), new THREE.Vector3(), 0.1, color);
    arrow.visible = false;
    scene3.add(arrow);
    return arrow;
  });
}

// The contacts of a scene (meta.contacts: term and body): each one's force
// on its body as a green arrow at its contact point (frame info.contacts).
export class ContactArrows {
  constructor(scene3, meta) {
    this.arrows = makeArrows(scene3, (meta.contacts || []).length, 0x30c060);
    this.shown = 0;  // arrows visible after the last show() (tests read it)
  }

  show(contacts) {
    const p = new THREE.Vector3();
    this.shown = 0;
    for (let c = 0; c < this.arrows.length; ++c) {
      const s = contacts && contacts[c];
      if (!s) { this.arrows[c].visible = false; continue; }
      p.set(...s.point);
      if (placeArrow(this.arrows[c], p, s.force)) ++this.shown;
    }
  }
}
