// The map: the azimuthal equidistant projection centred on the station, drawn into #map.
//
// Rules:
// 1. The map is the unit disc in the SVG's own units (viewBox -1.1..1.1): the station at (0, 0),
//    north up, the antipode on the rim. A point at great-circle bearing b and distance d km lies
//    at radius d / (pi * EARTH_RADIUS_KM), x = r sin b, y = -r cos b (SVG's y runs down).
//    EARTH_RADIUS_KM is bridge/core/geo.py's, so a click and the bridge agree on the point.
// 2. The base (land, distance rings, the bearing ring) is drawn once per configuration; the
//    rotator's fixed marks (sectors, presets, park) once per tab switch; a status only moves
//    attributes (update), so a status costs no rebuild.
// 3. Without a station the map is a dial: no land, no distance rings, the same ring.
// 4. DX cluster spots (the feed's `spots`, B/spots' document) are dots labelled with the call at
//    their short-path bearing and distance as the bridge worked them out; a spot without them
//    (no station, no position) or beyond the rim is not drawn. Each list replaces the last.

export const EARTH_RADIUS_KM = 6371.0;
export const RIM_KM = Math.PI * EARTH_RADIUS_KM;
const NS = 'http://www.w3.org/2000/svg';
const RAD = Math.PI / 180;

export const norm360 = (d) => ((d % 360) + 360) % 360;
const f = (v) => (Math.abs(v) < 1e-9 ? '0' : v.toFixed(4));

/** Map coordinates of bearing b (degrees) at radius r. */
export function polar(b, r) {
  return [r * Math.sin(b * RAD), -r * Math.cos(b * RAD)];
}
const pt = (b, r) => polar(b, r).map(f).join(' ');

function unit(lat, lon) {
  const p = lat * RAD, l = lon * RAD;
  return [Math.cos(p) * Math.cos(l), Math.cos(p) * Math.sin(l), Math.sin(p)];
}

/** Short-path bearing (deg) and distance (km) from the station to (lat, lon). */
export function greatCircle(lat0, lon0, lat, lon) {
  const a = unit(lat0, lon0), b = unit(lat, lon);
  const c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const angle = Math.atan2(Math.hypot(...c), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
  const p1 = lat0 * RAD, p2 = lat * RAD, dl = (lon - lon0) * RAD;
  const y = Math.sin(dl) * Math.cos(p2);
  const x = Math.cos(p1) * Math.sin(p2) - Math.sin(p1) * Math.cos(p2) * Math.cos(dl);
  const bearing = Math.hypot(x, y) < 1e-12 ? 0 : norm360(Math.atan2(y, x) / RAD);
  return { bearing, distance_km: angle * EARTH_RADIUS_KM };
}

/** The point reached from (lat, lon) along bearing after distance_km (bridge/core/geo.py). */
export function destination(lat, lon, bearing, distanceKm) {
  const phi = lat * RAD, lam = lon * RAD, th = bearing * RAD, ang = distanceKm / EARTH_RADIUS_KM;
  const here = [Math.cos(phi) * Math.cos(lam), Math.cos(phi) * Math.sin(lam), Math.sin(phi)];
  const east = [-Math.sin(lam), Math.cos(lam), 0];
  const north = [-Math.sin(phi) * Math.cos(lam), -Math.sin(phi) * Math.sin(lam), Math.cos(phi)];
  const c = Math.cos(ang), s = Math.sin(ang);
  const [px, py, pz] = here.map((h, i) => c * h + s * (Math.cos(th) * north[i] + Math.sin(th) * east[i]));
  return [Math.atan2(pz, Math.hypot(px, py)) / RAD, Math.atan2(py, px) / RAD];
}

/** The path of a sector clockwise from..to between radii r0 and r1 (r0 = 0: a wedge). */
export function sectorPath(from, to, r1 = 1, r0 = 0) {
  let span = norm360(to - from);
  if (span === 0) span = 360;
  if (span > 359.99) {
    const ring = (r) => `M0 ${f(-r)}A${r} ${r} 0 1 1 0 ${f(r)}A${r} ${r} 0 1 1 0 ${f(-r)}Z`;
    return ring(r1) + (r0 > 0 ? ring(r0) : '');
  }
  const large = span > 180 ? 1 : 0;
  const outer = `${pt(from, r1)}A${r1} ${r1} 0 ${large} 1 ${pt(to, r1)}`;
  if (r0 <= 0) return `M0 0L${outer}Z`;
  return `M${outer}L${pt(to, r0)}A${r0} ${r0} 0 ${large} 0 ${pt(from, r0)}Z`;
}

export function svg(tag, attrs, parent) {
  const node = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, String(v));
  if (parent) parent.appendChild(node);
  return node;
}

function label(text, attrs, parent) {
  const node = svg('text', attrs, parent);
  node.textContent = text;
  return node;
}

const tip = (node, text) => { svg('title', {}, node).textContent = text; };
const show = (node, on) => node.classList.toggle('off', !on);
const set = (node, name, value) => {
  const text = String(value);
  if (node.getAttribute(name) !== text) node.setAttribute(name, text);
};
const CARDINAL = { 0: 'N', 90: 'E', 180: 'S', 270: 'W' };
const PRESET_GAP_DEG = 14; // labels closer than this on one ring would overlap
const PRESET_LANES = 3;
const BODY_GLYPH = { sun: '\u2600', moon: '\u263E' };

/** The bearing ring with its ticks and labels, on any polar SVG (the map and the sky plot). */
export function drawRing(parent, labels = 'all') {
  svg('circle', { class: 'rim', r: 1 }, parent);
  let ticks = '';
  for (let b = 0; b < 360; b += 10) ticks += `M${pt(b, 1)}L${pt(b, b % 30 ? 1.025 : 1.045)}`;
  svg('path', { class: 'tick', d: ticks }, parent);
  for (let b = 0; b < 360; b += labels === 'all' ? 30 : 90) {
    const [x, y] = polar(b, 1.072);
    label(CARDINAL[b] || String(b), { class: b % 90 ? 'ring-label' : 'ring-label cardinal', x: f(x), y: f(y) }, parent);
  }
}

export class MapView {
  constructor(root) {
    this.root = root;
    this.station = null;
    root.replaceChildren();
    const defs = svg('defs', {}, root);
    for (const [id, cls] of [['hatch-keepout', 'hatch-keepout'], ['hatch-unreach', 'hatch-unreach']]) {
      const p = svg('pattern', { id, width: 0.03, height: 0.03, patternUnits: 'userSpaceOnUse', patternTransform: 'rotate(45)' }, defs);
      svg('line', { class: cls, x1: 0, y1: 0, x2: 0, y2: 0.03 }, p);
    }
    svg('circle', { class: 'sea', r: 1 }, root);
    this.landLayer = svg('g', { class: 'land-layer' }, root);
    this.gridLayer = svg('g', { class: 'grid' }, root);
    this.sectorLayer = svg('g', {}, root);
    this.ringLayer = svg('g', { class: 'ring' }, root);
    drawRing(this.ringLayer);
    this.fixedLayer = svg('g', {}, root);
    this.wedge = svg('path', { class: 'beam-wedge' }, root);
    this.beam = svg('line', { class: 'beam', x1: 0, y1: 0 }, root);
    this.beamTip = svg('circle', { class: 'beam-tip', r: 0.018 }, root);
    this.targetMark = svg('g', { class: 'target-mark off' }, root);
    svg('line', { x1: 0, y1: 0, x2: 0, y2: -1 }, this.targetMark);
    svg('path', { d: 'M0 -1.0L-0.03 -1.06L0.03 -1.06Z' }, this.targetMark);
    this.gcPath = svg('path', { class: 'gc-path off' }, root);
    this.targetPoint = svg('circle', { class: 'target-point off', r: 0.02 }, root);
    this.gcLabel = label('', { class: 'gc-label off' }, root);
    this.bodyMark = svg('g', { class: 'body-mark off' }, root);
    svg('circle', { class: 'body-dot', r: 0.035 }, this.bodyMark);
    this.bodyGlyph = label('', { class: 'body-glyph', y: 0.002 }, this.bodyMark);
    this.bodyName = label('', { class: 'body-name' }, this.bodyMark);
    this.spotLayer = svg('g', { class: 'spots' }, root);
    this.hoverPath = svg('path', { class: 'hover-path off' }, root);
    this.hoverLabel = label('', { class: 'hover-label off' }, root);
    this.clickMark = svg('circle', { class: 'click-mark off', r: 0.022 }, root);
    svg('circle', { class: 'station', r: 0.014 }, root);
  }

  /** The base: land and distance rings with a station, a bare dial without (rule 3). */
  setStation(station, land) {
    this.station = station;
    this.landLayer.replaceChildren();
    this.gridLayer.replaceChildren();
    this.root.classList.toggle('dial', !station);
    if (!station) return;
    if (land && Array.isArray(land.rings)) {
      const s = 1 / (land.scale || 1);
      const g = svg('g', { transform: `scale(${s} ${-s})` }, this.landLayer);
      land.rings.forEach((ring, i) => {
        if (ring.length < 4) return;
        let d = `M${ring[0]} ${ring[1]}`;
        for (let k = 2; k < ring.length; k += 2) d += `L${ring[k]} ${ring[k + 1]}`;
        const closed = land.closed ? Boolean(land.closed[i]) : false;
        svg('path', { class: closed ? 'land closed' : 'land', d: closed ? d + 'Z' : d }, g);
      });
    }
    if (station.locator) label(station.locator, { class: 'station-label', x: 0, y: 0.05 }, this.gridLayer);
    for (let km = 5000; km < RIM_KM - 2000; km += 5000) {
      const r = km / RIM_KM;
      svg('circle', { class: 'dist-ring', r: f(r) }, this.gridLayer);
      const [x, y] = polar(180, r);
      label(`${km.toLocaleString('en-US')} km`, { class: 'dist-label', x: f(x + 0.012), y: f(y - 0.012) }, this.gridLayer);
    }
  }

  /** The rotator's fixed marks: keep-out and unreachable sectors, presets, park (rule 2). */
  setRotator(cfg, onPreset) {
    this.cfg = cfg;
    this.sectorLayer.replaceChildren();
    this.fixedLayer.replaceChildren();
    for (const [from, to] of cfg.unreachable_deg || []) {
      const p = svg('path', { class: 'unreachable', d: sectorPath(from, to), 'data-from': from, 'data-to': to }, this.sectorLayer);
      tip(p, `beyond the rotator's limits: ${from}\u00B0\u2013${to}\u00B0`);
    }
    for (const [from, to] of cfg.keep_out_deg || []) {
      const p = svg('path', { class: 'keepout', d: sectorPath(from, to), 'data-from': from, 'data-to': to }, this.sectorLayer);
      tip(p, `keep-out sector ${from}\u00B0\u2013${to}\u00B0: targets here are refused`);
      svg('path', { class: 'keepout-band', d: sectorPath(from, to, 1.045, 1) }, this.sectorLayer);
    }
    if (cfg.park) {
      const g = svg('g', { class: 'park-mark', 'data-bearing': cfg.park[0], transform: `rotate(${cfg.park[0]})` }, this.fixedLayer);
      svg('path', { d: 'M0 -1L-0.032 -0.95L0.032 -0.95Z' }, g);
      label('P', { x: 0, y: -0.905, transform: `rotate(${-cfg.park[0]} 0 -0.905)` }, g);
    }
    const lanes = []; // the bearing of the last label in each ring of labels, inward
    const presets = Object.entries(cfg.presets || {}).sort((a, b) => norm360(a[1][0]) - norm360(b[1][0]));
    for (const [name, [az]] of presets) {
      // a label too close to the last one in its ring moves one ring inward
      let lane = lanes.findIndex((last) => Math.abs(norm360(az - last + 180) - 180) >= PRESET_GAP_DEG);
      if (lane < 0) lane = Math.min(lanes.length, PRESET_LANES - 1);
      lanes[lane] = az;
      const inner = 0.85 - lane * 0.075;
      const g = svg('g', { class: 'preset', 'data-preset': name, 'data-bearing': az }, this.fixedLayer);
      tip(g, `preset ${name}: ${az}\u00B0 (click to turn there)`);
      svg('path', { class: 'preset-hit', d: sectorPath(az - 2.5, az + 2.5, 1.05, inner - 0.04) }, g);
      svg('path', { class: 'preset-tick', d: `M${pt(az, inner + 0.045)}L${pt(az, 1.045)}` }, g);
      const [x, y] = polar(az, inner);
      label(name, { x: f(x), y: f(y) }, g);
      g.addEventListener('click', (e) => { e.stopPropagation(); onPreset(name); });
    }
  }

  /** Everything a status moves: beam, target, point target and path, body (rule 2). */
  update(st, tracking) {
    const cfg = this.cfg || {};
    const b = st.bearing;
    const known = typeof b === 'number';
    show(this.beam, known); show(this.wedge, known); show(this.beamTip, known);
    if (known) {
      const [x, y] = polar(b, 1);
      set(this.beam, 'x2', f(x)); set(this.beam, 'y2', f(y));
      set(this.beam, 'data-bearing', b);
      set(this.beamTip, 'cx', f(x)); set(this.beamTip, 'cy', f(y));
      const w = (cfg.beamwidth_deg || 60) / 2;
      set(this.wedge, 'd', sectorPath(b - w, b + w));
    }
    const t = st.target;
    const turning = st.state === 'moving' || st.state === 'braking';
    const away = typeof t === 'number' && (!known || Math.abs(norm360(t - b + 180) - 180) > 1.5);
    show(this.targetMark, typeof t === 'number' && (turning || away));
    if (typeof t === 'number') {
      set(this.targetMark, 'transform', `rotate(${norm360(t)})`);
      set(this.targetMark, 'data-bearing', t);
    }
    this.updatePoint(st.target_info);
    const az = tracking ? tracking.az : null;
    show(this.bodyMark, typeof az === 'number');
    if (typeof az === 'number') {
      const [x, y] = polar(az, 0.93);
      set(this.bodyMark, 'transform', `translate(${f(x)} ${f(y)})`);
      set(this.bodyMark, 'data-body', tracking.body);
      set(this.bodyMark, 'data-bearing', az);
      this.bodyMark.classList.toggle('below', typeof tracking.el === 'number' && tracking.el < 0);
      const kind = tracking.body === 'sun' || tracking.body === 'moon' ? tracking.body : 'satellite';
      set(this.bodyMark, 'data-kind', kind);
      if (this.bodyName.textContent !== tracking.body) {
        this.bodyGlyph.textContent = BODY_GLYPH[kind] || '\u2726';
        this.bodyName.textContent = tracking.body;
      }
      const [nx, ny] = polar(az, -0.085); // the name on the centre's side, clear of the ring
      set(this.bodyName, 'x', f(nx));
      set(this.bodyName, 'y', f(ny));
    }
  }

  updatePoint(info) {
    const lat = info ? info.latitude ?? info.latitude_deg : null;
    const lon = info ? info.longitude ?? info.longitude_deg : null;
    const on = Boolean(this.station) && typeof lat === 'number' && typeof lon === 'number';
    for (const n of [this.gcPath, this.targetPoint, this.gcLabel]) show(n, on);
    if (!on) return;
    const key = `${lat},${lon},${info.path}`;
    if (key === this.pointKey) return;
    this.pointKey = key;
    const gc = greatCircle(this.station.latitude_deg, this.station.longitude_deg, lat, lon);
    const r = Math.min(gc.distance_km / RIM_KM, 1);
    const [x, y] = polar(gc.bearing, r);
    const long = info.path === 'long';
    set(this.gcPath, 'd', long
      ? `M0 0L${pt(gc.bearing + 180, 1)}M${pt(gc.bearing, 1)}L${f(x)} ${f(y)}`
      : `M0 0L${f(x)} ${f(y)}`);
    this.gcPath.classList.toggle('long', long);
    set(this.gcPath, 'data-path', long ? 'long' : 'short');
    set(this.targetPoint, 'cx', f(x)); set(this.targetPoint, 'cy', f(y));
    const km = typeof info.distance_km === 'number' ? info.distance_km : long ? 2 * RIM_KM - gc.distance_km : gc.distance_km;
    this.gcLabel.textContent = `${info.locator ? info.locator + ' ' : ''}${Math.round(km).toLocaleString('en-US')} km${long ? ' long' : ''}`;
    const right = x < 0.45;
    set(this.gcLabel, 'x', f(x + (right ? 0.035 : -0.035)));
    set(this.gcLabel, 'y', f(y - 0.03));
    set(this.gcLabel, 'text-anchor', right ? 'start' : 'end');
  }

  /** The DX cluster's spots (rule 4); onSpot(spot, shiftKey) on a click on one. */
  setSpots(spots, onSpot) {
    this.spotLayer.replaceChildren();
    for (const s of Array.isArray(spots) ? spots : []) {
      const b = s.bearing_deg, km = s.distance_km;
      if (typeof b !== 'number' || typeof km !== 'number' || km > RIM_KM) continue;
      const [x, y] = polar(b, km / RIM_KM);
      const g = svg('g', { class: 'spot', 'data-call': s.call, 'data-bearing': b, transform: `translate(${f(x)} ${f(y)})` }, this.spotLayer);
      const where = s.locator || s.entity || '';
      tip(g, `${s.call} ${s.frequency_khz} kHz ${s.time || ''} de ${s.spotter}${where ? ' \u00B7 ' + where : ''}` +
        ` \u00B7 ${Math.round(b)}\u00B0 ${Math.round(km).toLocaleString('en-US')} km (click to turn there, shift: long path)`);
      svg('circle', { class: 'spot-hit', r: 0.03 }, g); // a finger's worth round the dot
      label(s.call, { class: 'spot-call', x: 0.022, y: 0 }, g);
      svg('circle', { class: 'spot-dot', r: 0.012 }, g); // over the label: Chrome's text hit box is wide
      g.addEventListener('click', (e) => { e.stopPropagation(); onSpot(s, e.shiftKey); });
    }
  }

  /** The map point under a pointer event: bearing, radius, and with a station the place. */
  pick(event) {
    const m = this.root.getScreenCTM();
    if (!m) return null;
    const p = new DOMPoint(event.clientX, event.clientY).matrixTransform(m.inverse());
    const r = Math.hypot(p.x, p.y);
    const bearing = r > 0 ? norm360(Math.atan2(p.x, -p.y) / RAD) : 0;
    const out = { x: p.x, y: p.y, r, bearing };
    if (this.station && r <= 1) {
      out.distance_km = r * RIM_KM;
      [out.lat, out.lon] = destination(this.station.latitude_deg, this.station.longitude_deg, bearing, out.distance_km);
    }
    return out;
  }

  /** The path to the point under the pointer and what it is, beside the pointer; null hides. */
  hover(p, long, text) {
    show(this.hoverPath, Boolean(p)); show(this.hoverLabel, Boolean(p));
    if (!p) return;
    const r = Math.min(p.r, 1);
    const [x, y] = polar(p.bearing, r);
    this.hoverPath.setAttribute('d', long
      ? `M0 0L${pt(p.bearing + 180, 1)}M${pt(p.bearing, 1)}L${f(x)} ${f(y)}`
      : `M0 0L${f(x)} ${f(y)}`);
    const left = p.x > 0.35;
    this.hoverLabel.textContent = text;
    this.hoverLabel.setAttribute('x', f(p.x + (left ? -0.04 : 0.04)));
    this.hoverLabel.setAttribute('y', f(Math.max(-1.06, Math.min(1.06, p.y - 0.045))));
    this.hoverLabel.setAttribute('text-anchor', left ? 'end' : 'start');
  }

  markClick(p) {
    this.clickMark.setAttribute('cx', f(p.x)); this.clickMark.setAttribute('cy', f(p.y));
    show(this.clickMark, true);
    this.clickMark.classList.remove('fade');
    void this.clickMark.getBoundingClientRect();
    this.clickMark.classList.add('fade');
  }
}
