// The tools of a result played back: each tool's force as an arrow at the
// tool's frame, a marker where a tool has no surface of its own (its shaped
// parts and jaws are scene objects, posed by the frames' object poses), a
// readout of each tool's force and closure, and the list of grasps and
// releases (click one to seek to it).
import * as THREE from 'three';
import { makeArrows, placeArrow } from './force_arrows.js';

export class ResultTools {
  // scene3: the three.js scene; meta: the scene message; objects: its object meshes;
  // table, events: the page's readout table and event list; seek(t): sends a seek.
  constructor({ scene3, meta, objects, table, events, seek }) {
    const arrows = makeArrows(scene3, meta.tools.length, 0xff4060);
    this.views = meta.tools.map((tool, t) => {
      const arrow = arrows[t];
      let marker = null;
      if (!(tool.object >= 0 && objects[tool.object])) {
        // No surface: a 5 mm sphere with the tool frame's axes (3 cm).
        marker = new THREE.Group();
        marker.add(new THREE.Mesh(new THREE.SphereGeometry(0.005, 16, 12),
                                  new THREE.MeshStandardMaterial({ color: 0xe0a040, roughness: 0.5 })));
        marker.add(new THREE.AxesHelper(0.03));
        marker.matrixAutoUpdate = false;
        scene3.add(marker);
      }
      const row = table.insertRow();
      row.insertCell().textContent = tool.name;
      const force = row.insertCell();
      force.className = 'n';
      const closure = row.insertCell();
      closure.className = 'n';
      return { arrow, marker, force, closure };
    });
    this.items = (meta.tool_events || []).map((e) => {
      const li = document.createElement('li');
      li.textContent = `${e.time.toFixed(3)} s · ${e.tool} ${e.kind}s ${e.body} (${e.points} points)`;
      li.title = 'seek here';
      li.onclick = () => seek(e.time);
      events.appendChild(li);
      return { li, time: e.time };
    });
    if (!this.items.length) events.appendChild(Object.assign(document.createElement('li'), { textContent: 'none' }));
  }

  // Poses the markers and arrows from a frame's info.tools (3-D view, every frame).
  show(tools) {
    const p = new THREE.Vector3(), q = new THREE.Quaternion(), one = new THREE.Vector3(1, 1, 1);
    for (let t = 0; t < this.views.length && t < tools.length; ++t) {
      const v = this.views[t], s = tools[t];
      p.set(s.pose[0], s.pose[1], s.pose[2]);
      q.set(s.pose[4], s.pose[5], s.pose[6], s.pose[3]);
      if (v.marker) v.marker.matrix.compose(p, q, one);
      placeArrow(v.arrow, p, s.force);
    }
  }

  // The panel: each tool's |F| and closure, the events up to time t marked (at most 5 times a second).
  panel(tools, t) {
    for (let k = 0; k < this.views.length && k < tools.length; ++k) {
      this.views[k].force.textContent = `${Math.hypot(...tools[k].force).toFixed(2)} N`;
      this.views[k].closure.textContent = `${tools[k].closure.toFixed(2)} rad`;
    }
    for (const item of this.items) item.li.classList.toggle('past', item.time <= t + 1e-9);
  }
}
