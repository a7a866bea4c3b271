// The sky plot of an az/el rotator (#sky): azimuth around (north up), elevation inward.
//
// Rules:
// 1. Elevation e lies at radius (90 - e) / 90: the zenith at the centre, the horizon on the rim;
//    a body below the horizon is not drawn (its AOS mark says where it will rise).
// 2. The trail is every body position seen since the page opened, per rotator, for the body
//    tracked now (a new body starts a new trail), bounded so a long session stays cheap.
// 3. A click sends a target at the clicked azimuth and elevation (the caller's onPick).
// 4. The pass ahead, as the bridge predicts it (tracking.pass_track: AOS to LOS), is drawn
//    dashed under the trail, above the horizon only.

import { drawRing, polar, svg, norm360 } from './map.js';

const TRAIL_MAX = 3000;
const f = (v) => v.toFixed(4);
const radius = (el) => (90 - el) / 90;
const show = (node, on) => node.classList.toggle('off', !on);

export class SkyView {
  constructor(root, onPick) {
    this.root = root;
    this.trails = new Map(); // rotator id -> {body, points: []}
    root.replaceChildren();
    svg('circle', { class: 'sky-bg', r: 1 }, root);
    for (const el of [30, 60]) svg('circle', { class: 'sky-grid', r: f(radius(el)) }, root);
    let spokes = '';
    for (let b = 0; b < 360; b += 45) spokes += `M0 0L${polar(b, 1).map(f).join(' ')}`;
    svg('path', { class: 'sky-grid', d: spokes }, root);
    drawRing(root, 'cardinal');
    for (const el of [30, 60]) {
      const t = svg('text', { class: 'sky-el-label', x: 0.01, y: f(-radius(el) + 0.05) }, root);
      t.textContent = `${el}\u00B0`;
    }
    this.pass = svg('polyline', { class: 'sky-pass' }, root);
    this.trail = svg('polyline', { class: 'sky-trail' }, root);
    this.aos = svg('path', { class: 'sky-aos off', d: 'M0 -1L-0.05 -1.09L0.05 -1.09Z' }, root);
    this.next = svg('circle', { class: 'sky-next off', r: 0.03 }, root);
    this.body = svg('circle', { class: 'sky-body off', r: 0.045 }, root);
    this.antenna = svg('circle', { class: 'sky-antenna off', r: 0.06 }, root);
    this.targetMark = svg('circle', { class: 'sky-target off', r: 0.085 }, root);
    root.addEventListener('click', (e) => {
      const m = root.getScreenCTM();
      if (!m) return;
      const p = new DOMPoint(e.clientX, e.clientY).matrixTransform(m.inverse());
      const r = Math.hypot(p.x, p.y);
      if (r > 1.02) return;
      const az = r > 0 ? norm360((Math.atan2(p.x, -p.y) * 180) / Math.PI) : 0;
      onPick(az, Math.max(0, Math.min(90, 90 - r * 90)));
    });
  }

  /** Remember where the tracked body was (rule 2); called for every rotator's status. */
  record(id, tracking) {
    if (!tracking || typeof tracking.az !== 'number' || typeof tracking.el !== 'number') return;
    let trail = this.trails.get(id);
    if (!trail || trail.body !== tracking.body) {
      trail = { body: tracking.body, points: [] };
      this.trails.set(id, trail);
    }
    if (tracking.el < 0) return;
    const p = polar(tracking.az, radius(tracking.el)).map(f).join(',');
    if (trail.points[trail.points.length - 1] === p) return;
    trail.points.push(p);
    if (trail.points.length > TRAIL_MAX) trail.points.splice(0, trail.points.length - TRAIL_MAX);
    trail.version = (trail.version || 0) + 1;
  }

  update(id, st, tracking) {
    const put = (node, az, el) => {
      const on = typeof az === 'number' && typeof el === 'number' && el >= 0;
      show(node, on);
      if (!on) return;
      const [x, y] = polar(az, radius(Math.min(el, 90)));
      if (node.getAttribute('cx') !== f(x)) node.setAttribute('cx', f(x));
      if (node.getAttribute('cy') !== f(y)) node.setAttribute('cy', f(y));
    };
    put(this.antenna, st.bearing, st.elevation);
    const moving = st.state === 'moving' || st.state === 'braking';
    put(this.targetMark, moving ? st.target : null, st.target_elevation ?? st.elevation);
    put(this.body, tracking && tracking.az, tracking && tracking.el);
    put(this.next, tracking && tracking.nextAz, tracking && tracking.nextEl);
    const aos = tracking ? tracking.aosAz : null;
    show(this.aos, typeof aos === 'number');
    if (typeof aos === 'number') this.aos.setAttribute('transform', `rotate(${aos})`);
    const pass = tracking && tracking.pass.length ? tracking.pass : [];
    const passKey = `${id}:${pass.length}:${pass.length ? pass[0].join() + pass[pass.length - 1].join() : ''}`;
    if (passKey !== this.passKey) {
      this.passKey = passKey;
      const above = pass.filter(([, el]) => el >= 0);
      this.pass.setAttribute('points', above.map(([az, el]) => polar(az, radius(Math.min(el, 90))).map(f).join(',')).join(' '));
    }
    const trail = tracking ? this.trails.get(id) : null;
    const key = trail && trail.body === tracking.body ? `${id}:${trail.body}:${trail.version}` : '';
    if (key !== this.trailKey) {
      this.trailKey = key;
      this.trail.setAttribute('points', key ? trail.points.join(' ') : '');
    }
  }
}
