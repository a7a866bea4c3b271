// The operator console: what the bridge says, drawn (map, panel, sky), and what the user asks, sent.
//
// Rules:
// 1. The link (token, login, stream, reconnecting) is live.js's; this module draws what it
//    brings and sends what the user asks. Every URL is relative.
// 2. A lost link greys the page at once (body.offline) and says so in #connection.
// 3. A status only updates text and attributes (the map is not rebuilt), and records the
//    latency from the bridge's t to the render in window.rotorConsole.latencies_ms (the last
//    10000) for the benchmark.
// 4. STOP is the #stop button, Escape anywhere, and Space anywhere outside a text box. Space
//    never activates the focused button: whoever presses Space to stop must not park.
//    A key held down is one press: Enter's repeats activate nothing (an attack pass: Enter held
//    on the focused Lock button toggled the lock at each repeat, and it ended OFF as often as
//    ON; held on a nudge, 30 nudges a second).
// 5. A refusal (409/400 to a POST, or an error event) goes to #message; the same text for the
//    same rotator within 2 s is one refusal, shown once, unless a command went through in
//    between (then the same refusal is news again, not the first one's copy). Only the answer
//    to the newest command sent to a rotator clears its message, and only the newest click on
//    the map writes its outcome under the map: on a slow network an older click's late "ok"
//    wiped the refusal of the click after it.
// 6. A control shows what the bridge's status says, never only what the user asked: the Track
//    select, whose choice a browser shows at once, goes back to the status's when its command
//    was refused or not sent at all (the bridge unreachable, the session ended).
// 7. A STOP or lock ON sent over the live feed is never said to be unsent when its request
//    fails: the feed's copy is carried out (live.py rule 5), and the page says it went that way.
// 8. A key on the Track select chooses without sending: Chromium on Linux and Windows changes
//    a closed select's choice at each arrow or letter key, and each change was a track command
//    (an attack pass: arrowing from "off" to "Moon" tracked the sun on the way, the rotor
//    turned). Enter sends the choice shown; a choice left unsent goes back to the status's
//    when the select loses the focus. A choice picked from its list (a click, or Enter in the
//    open list) is sent at once, as before.
// 9. Every move (anything but a STOP, a lock ON and tracking off) carries its send time on the
//    bridge's clock as the live feed lets the page reckon it (live.js rule 3; commands.py
//    rule 6), and the bridge refuses one that took too long on its way ("not carried out:
//    sent 12 s ago"), shown as any refusal (rule 5). A page that never heard the bridge's clock
//    sends no move (it says so); one woken from sleep hears it anew first (live.js rule 3);
//    a STOP and a lock ON go unstamped, always.
// 10. Releasing the lock is a deliberate act: a click on Lock while it is ON sends nothing, it
//    shows a Release button beside it, usable only after RELEASE_AFTER_MS and gone after
//    RELEASE_FOR_MS (or once the lock is OFF, or another rotator is chosen). An attack pass:
//    Lock toggled, so a double click (two clicks 300 ms apart) locked and at once released.
// 11. Offline, the page is greyed but STOP is not: it stays as it is and where it is (a POST may
//    still get through while the live feed is lost). An attack pass: the filter that greys
//    the console greyed STOP with it, as if it could not be used. (The filter sits on STOP's
//    neighbours, not on an element around it: a filter is the containing block of the fixed
//    STOP bar a phone pins to the bottom of the screen.)

import { MapView, RIM_KM, norm360 } from './map.js';
import { SkyView } from './sky.js';
import { authHeaders, bridgeClock, connect, dropToken, getToken, postJSON, sendLive, session } from './live.js';

const LATENCIES_MAX = 10000;
const SELECTED_KEY = 'rotor-bridge-rotator'; // the rotator shown, for STOP after a reload (live.js rule 1)
// before any configuration, the rotator this tab showed before a reload (live.js rule 1)
const shownBefore = (() => { try { return sessionStorage.getItem(SELECTED_KEY); } catch { return null; } })();
const SAME_REFUSAL_MS = 2000;
const RELEASE_AFTER_MS = 1000; // rule 10: the Release button is usable this long after Lock's click
const RELEASE_FOR_MS = 8000; // rule 10: and shown this long

const $ = (id) => document.getElementById(id);
const metrics = { latencies_ms: [], answered: 0 }; // answered: commands whose answer was read
window.rotorConsole = metrics;

const app = {
  config: null,
  rotators: new Map(),
  status: new Map(),
  messages: new Map(),
  selected: null,
  landKey: null,
  land: null,
  lastShown: null,
  tabs: new Map(), // rotator id -> its tab button
};

let trackKey = null; // the key down on the Track select in the task now running (rule 8)
let trackKeyed = false; // a Track choice the keys made, not sent yet (rule 8)

const map = new MapView($('map'));
const sky = new SkyView($('sky'), (az, el) => send({ command: 'target', az: round1(az), el: round1(el) }));

const shown = () => app.selected || shownBefore; // the rotator STOP and the message line are for
const round1 = (v) => Math.round(v * 10) / 10;
const fmtDeg = (v) => (typeof v === 'number' && Number.isFinite(v) ? `${round1(v)}\u00B0` : '\u2014');
const fmtKm = (v) => `${Math.round(v).toLocaleString('en-US')} km`;
const fmtTime = (iso) => {
  const d = new Date(iso);
  return Number.isNaN(d.getTime()) ? '' : d.toLocaleTimeString([], { hour: '2-digit', minute: '2-digit', hour12: false });
};
const isTextBox = (el) =>
  el instanceof HTMLElement &&
  (el.isContentEditable || el.tagName === 'TEXTAREA' ||
    (el.tagName === 'INPUT' && !['button', 'checkbox', 'radio', 'submit', 'reset', 'range', 'color'].includes(el.type)));

// a status rewrites only what changed: an unchanged text or attribute costs no style work
const put = (id, text) => {
  const el = $(id);
  if (el.textContent !== text) el.textContent = text;
};
const mark = (el, name, value) => {
  if (el.getAttribute(name) !== value) el.setAttribute(name, value);
};
const flag = (el, name, on) => {
  if (el.classList.contains(name) !== on) el.classList.toggle(name, on);
};
const hide = (id, hidden) => {
  const el = $(id);
  if (el.hidden !== hidden) el.hidden = hidden;
};

// ---- the configuration ------------------------------------------------------------------
async function applyConfig(config) {
  app.config = config;
  app.rotators = new Map(config.rotators.map((r) => [r.id, r]));
  const key = config.station ? JSON.stringify(config.station) : null;
  if (key !== app.landKey) {
    app.land = null;
    if (key) {
      try {
        const res = await fetch('api/land', { headers: authHeaders(), signal: AbortSignal.timeout(30000) });
        if (res.ok) app.land = await res.json();
      } catch (err) {
        console.warn('no coastlines this time:', err); // the map works without them
      }
    }
    if (app.land || !key) app.landKey = key; // else try again on the next connect
  }
  map.setStation(config.station, app.land);
  $('no-station').hidden = Boolean(config.station);
  document.body.classList.toggle('dial-mode', !config.station);
  $('locator-form').hidden = !config.station;
  buildTabs(config.rotators);
  let wanted = '';
  try {
    wanted = decodeURIComponent(location.hash.slice(1));
  } catch { /* a hash that is no rotator's id */ }
  const id = app.rotators.has(app.selected) ? app.selected : app.rotators.has(wanted) ? wanted : config.rotators[0]?.id;
  if (id) selectRotator(id);
}

function buildTabs(rotators) {
  const tabs = $('tabs');
  tabs.replaceChildren();
  app.tabs.clear();
  tabs.hidden = rotators.length < 2;
  document.body.classList.toggle('multi', rotators.length > 1);
  for (const r of rotators) {
    const b = document.createElement('button');
    b.type = 'button';
    b.className = 'tab';
    b.dataset.rotator = r.id;
    b.setAttribute('role', 'tab');
    const name = document.createElement('span');
    name.textContent = r.name || r.id;
    const bearing = document.createElement('span');
    bearing.className = 'tab-bearing';
    b.append(name, bearing);
    b.addEventListener('click', () => selectRotator(r.id));
    tabs.appendChild(b);
    app.tabs.set(r.id, b);
    const st = app.status.get(r.id);
    if (st) updateTab(r.id, st);
  }
}

function updateTab(id, st) {
  const tab = app.tabs.get(id);
  if (!tab) return;
  const bearing = fmtDeg(st.bearing);
  if (tab.lastChild.textContent !== bearing) tab.lastChild.textContent = bearing;
  mark(tab, 'data-state', st.state || '');
  flag(tab, 'locked', Boolean(st.locked || st.lock_unknown));
}

function selectRotator(id) {
  const cfg = app.rotators.get(id);
  if (!cfg) return;
  if (app.selected !== id) disarmRelease(); // rule 10: a Release offered for another rotator
  app.selected = id;
  try { sessionStorage.setItem(SELECTED_KEY, id); } catch { /* this page only */ }
  if (app.rotators.size > 1 && location.hash.slice(1) !== id) history.replaceState(null, '', `#${encodeURIComponent(id)}`);
  for (const tab of document.querySelectorAll('.tab')) tab.setAttribute('aria-selected', String(tab.dataset.rotator === id));
  $('title').textContent = cfg.name || cfg.id;
  $('model').textContent = cfg.model || '';
  map.setRotator(cfg, (name) => send({ command: 'preset', name }));
  buildPresets(cfg);
  $('park').hidden = !cfg.park;
  const step = cfg.nudge_step_deg || 5;
  $('nudge-ccw').textContent = `\u27F2 \u2212${step}\u00B0`;
  $('nudge-cw').textContent = `+${step}\u00B0 \u27F3`;
  $('nudge-up').hidden = $('nudge-down').hidden = !cfg.has_elevation;
  $('nudge-up').textContent = `el +${step}\u00B0`;
  $('nudge-down').textContent = `el \u2212${step}\u00B0`;
  $('elevation').hidden = !cfg.has_elevation;
  $('sky-box').hidden = !cfg.has_elevation;
  $('track-row').hidden = !cfg.can_track;
  buildTrackOptions(cfg);
  document.body.classList.toggle('azel', Boolean(cfg.has_elevation));
  const msg = app.messages.get(id);
  renderMessage(msg);
  renderStatus(id, app.status.get(id) || { bearing: null, target: null, state: 'unknown' });
}

function buildPresets(cfg) {
  const box = $('presets');
  box.replaceChildren();
  for (const [name, [az, el]] of Object.entries(cfg.presets || {})) {
    const b = document.createElement('button');
    b.type = 'button';
    b.className = 'preset-button';
    b.dataset.preset = name;
    const label = document.createElement('span');
    label.textContent = name;
    const where = document.createElement('small');
    where.textContent = el == null ? fmtDeg(az) : `${fmtDeg(az)} / ${fmtDeg(el)}`;
    b.append(label, where);
    b.addEventListener('click', () => send({ command: 'preset', name }));
    box.appendChild(b);
  }
}

function buildTrackOptions(cfg) {
  const select = $('track');
  select.replaceChildren();
  const add = (value, text, parent = select) => {
    const o = document.createElement('option');
    o.value = value;
    o.textContent = text;
    parent.appendChild(o);
  };
  add('off', 'off');
  add('sun', 'Sun');
  add('moon', 'Moon');
  if ((cfg.satellites || []).length) {
    const group = document.createElement('optgroup');
    group.label = 'Satellites';
    for (const name of cfg.satellites) add(name, name, group);
    select.appendChild(group);
  }
}

// ---- status (rule 3) --------------------------------------------------------------------
function trackingOf(st) {
  const t = st.tracking;
  if (!t) return null;
  const next = t.next || {};
  return {
    body: t.body,
    phase: t.phase,
    az: t.azimuth ?? t.azimuth_deg ?? null,
    el: t.elevation ?? t.elevation_deg ?? null,
    nextAz: next.azimuth ?? t.next_azimuth_deg ?? null,
    nextEl: next.elevation ?? t.next_elevation_deg ?? null,
    aosAz: t.aos_azimuth ?? t.aos_azimuth_deg ?? null,
    maxEl: t.max_elevation ?? t.max_elevation_deg ?? null,
    aos: t.aos,
    los: t.los,
    pass: Array.isArray(t.pass_track) ? t.pass_track : [],
    // a satellite's elements older than two weeks (session/tracking.py rule 11)
    staleSince: t.elements_stale === true && typeof t.elements_epoch === 'string' ? t.elements_epoch.slice(0, 10) : null,
    // ... or dated days after this station's clock: the clock is wrong (the same rule)
    aheadOf: t.elements_ahead === true && typeof t.elements_epoch === 'string' ? t.elements_epoch.slice(0, 10) : null,
  };
}

function onStatus(doc) {
  const id = doc.rotator;
  const st = doc.status;
  if (!st || !app.rotators.has(id)) return;
  app.status.set(id, st);
  const tracking = trackingOf(st);
  sky.record(id, tracking);
  updateTab(id, st);
  if (id === app.selected) renderStatus(id, st, tracking);
  if (typeof doc.t === 'number') {
    const list = metrics.latencies_ms;
    list.push(performance.timeOrigin + performance.now() - doc.t * 1000);
    if (list.length > LATENCIES_MAX) list.splice(0, list.length - LATENCIES_MAX);
  }
}

function renderStatus(id, st, tracking = trackingOf(st)) {
  const cfg = app.rotators.get(id);
  put('bearing', fmtDeg(st.bearing));
  if (cfg.has_elevation) put('elevation', `el ${fmtDeg(st.elevation)}`);
  const state = st.state || 'unknown';
  // the same at a glance in the map's corner, for a phone or a card where the panel is below
  put('corner-bearing', cfg.has_elevation ? `${fmtDeg(st.bearing)} ${fmtDeg(st.elevation)}` : fmtDeg(st.bearing));
  put('corner-state', state);
  put('state', st.estimated ? `${state} (estimate)` : state);
  mark($('state'), 'data-state', state);
  mark(document.body, 'data-state', state);
  let target = '\u2014';
  if (typeof st.target === 'number') {
    target = fmtDeg(st.target);
    if (typeof st.target_elevation === 'number') target += ` / el ${fmtDeg(st.target_elevation)}`;
  }
  const info = st.target_info;
  if (info) {
    const where = info.locator || `${round1(info.latitude ?? info.latitude_deg)}, ${round1(info.longitude ?? info.longitude_deg)}`;
    target += ` \u00B7 ${where} \u00B7 ${fmtKm(info.distance_km || 0)} ${info.path || 'short'} path`;
  }
  put('target', target);
  const who = st.last_operator && st.last_operator !== st.last_command_source ? ` \u00B7 ${st.last_operator}` : '';
  put('source', st.last_command_source ? `${st.last_command_source}${who}` : '\u2014');
  // the control lease: who holds the rotator, and until when (UTC, as the refusals say it)
  const control = st.control;
  hide('control-label', !control);
  hide('control', !control);
  if (control) put('control', `${control.holder} until ${String(control.until).slice(11, 16)} UTC`);
  // not known yet (the state file does not say it, the broker's R/lock/state not read): motion
  // is refused as if locked, and the button says neither ON nor OFF; a click locks (the safe side)
  const locked = Boolean(st.locked);
  const unknown = !locked && Boolean(st.lock_unknown);
  mark($('lock'), 'aria-pressed', unknown ? 'mixed' : String(locked));
  put('lock', unknown ? 'Lock ?' : locked ? 'Lock ON' : 'Lock OFF');
  mark($('lock'), 'title', unknown ? 'Lock not known yet (the broker not read): motion is refused; a click locks' : '');
  flag(document.body, 'locked', locked || unknown);
  if (!locked && !$('unlock').hidden) disarmRelease(); // rule 10: nothing left to release
  flag(document.body, 'rotor-down', st.available === false);
  hide('path-row', !info);
  if (info) {
    mark($('path-long'), 'aria-pressed', String(info.path === 'long'));
    mark($('path-short'), 'aria-pressed', String(info.path !== 'long'));
    put('path-short', `Short ${fmtDeg(info.short_path_deg)}`);
    put('path-long', `Long ${fmtDeg(info.long_path_deg)}`);
  }
  const body = tracking ? tracking.body : 'off';
  const select = $('track');
  if (select.value !== body && !trackKeyed) { // rule 8: not over a choice the keys made
    if (![...select.options].some((o) => o.value === body)) {
      select.add(new Option(body, body)); // a satellite the TLE file no longer names
    }
    select.value = body;
  }
  hide('tracking-label', !tracking);
  hide('tracking-info', !tracking);
  if (tracking) {
    let text = `${tracking.body} \u00B7 ${tracking.phase || ''}`;
    if (typeof tracking.az === 'number') text += ` \u00B7 az ${fmtDeg(tracking.az)} el ${fmtDeg(tracking.el)}`;
    if (tracking.aos) text += ` \u00B7 AOS ${fmtTime(tracking.aos)} LOS ${fmtTime(tracking.los)}`;
    if (typeof tracking.maxEl === 'number') text += ` max ${fmtDeg(tracking.maxEl)}`;
    if (tracking.staleSince) text += ` \u00B7 elements of ${tracking.staleSince}: stale, is the TLE file refreshed?`;
    if (tracking.aheadOf) text += ` \u00B7 elements of ${tracking.aheadOf}, after the bridge's clock: is its clock set?`;
    put('tracking-info', text);
  }
  renderHealth(st.health);
  renderBadges(st, tracking);
  map.update(st, tracking);
  if (cfg.has_elevation) sky.update(id, st, tracking);
}

// rotor health (R/health, in the status): speeds each way, start delay, moves, and the warnings
function renderHealth(h) {
  const shown = Boolean(h && h.measured);
  hide('health-label', !shown);
  hide('health-info', !shown);
  if (!shown) return;
  const speed = (v) => (typeof v === 'number' ? `${round1(v)}°/s` : '—');
  let text = `cw ${speed(h.speed_cw_deg_s)} · ccw ${speed(h.speed_ccw_deg_s)}`;
  if (typeof h.start_delay_s === 'number') text += ` · start ${round1(h.start_delay_s)} s`;
  text += ` · ${h.moves} moves, ${h.stalls} stalls`;
  if (h.baseline && h.baseline.from === 'learning') text += ` · learning (${h.baseline.moves_to_learn} to go)`;
  const warnings = h.warnings || [];
  if (warnings.length) text += ` — ${warnings.join('; ')}`;
  put('health-info', text);
  flag($('health-info'), 'warn', warnings.length > 0);
}

let badgeKey = '';
function renderBadges(st, tracking) {
  const badges = [];
  if (st.available === false) badges.push(['down', 'ROTATOR OFFLINE']);
  if (st.locked) badges.push(['locked', 'LOCKED']);
  else if (st.lock_unknown) badges.push(['locked', 'LOCK NOT KNOWN YET']);
  if (st.parked) badges.push(['parked', 'PARKED']);
  if (tracking) badges.push(['tracking', `TRACKING ${tracking.body.toUpperCase()}`]);
  const key = badges.map((b) => b[1]).join('|');
  if (key === badgeKey) return;
  badgeKey = key;
  $('badges').replaceChildren(...badges.map(([cls, text]) => {
    const s = document.createElement('span');
    s.className = `badge ${cls}`;
    s.textContent = text;
    return s;
  }));
}

// ---- messages (rule 5) ------------------------------------------------------------------
function showMessage(id, text, kind) {
  const now = performance.now();
  const last = app.lastShown;
  if (last && last.id === id && last.text === text && now - last.at < SAME_REFUSAL_MS) return;
  app.lastShown = { id, text, at: now };
  const msg = { text, kind, time: new Date() };
  app.messages.set(id, msg);
  if (id === shown()) renderMessage(msg);
  else app.tabs.get(id)?.classList.add('has-message');
}

function renderMessage(msg) {
  const el = $('message');
  el.className = `message ${msg ? msg.kind : ''}`;
  if (!msg) {
    el.textContent = '';
    return;
  }
  const when = document.createElement('time');
  when.textContent = msg.time.toLocaleTimeString([], { hour12: false });
  el.replaceChildren(when, ` ${msg.text}`);
  app.tabs.get(app.selected)?.classList.remove('has-message');
}

function clearMessage(id) {
  app.messages.delete(id);
  if (app.lastShown && app.lastShown.id === id) app.lastShown = null; // the next is news again
  if (id === shown()) renderMessage(null);
}

function onErrorEvent(doc) {
  if (!doc || !doc.rotator) return;
  const text = doc.kind === 'refused' || !doc.kind ? doc.message : `${doc.kind}: ${doc.message}`;
  showMessage(doc.rotator, text, doc.kind === 'refused' ? 'refusal' : 'error');
}

// ---- commands ---------------------------------------------------------------------------
// Each command is numbered in this page's order: the bridge carries out nothing this page
// numbered before a STOP or lock ON it already carried out, whichever arrives first.
const PAGE_ID = Array.from(crypto.getRandomValues(new Uint8Array(8)), (b) => b.toString(16).padStart(2, '0')).join('');
let sequence = 0;
const newestSent = new Map(); // rotator id -> the seq of the newest command sent to it (rule 5)

async function send(command, id = app.selected) {
  if (!id) return false;
  const body = { ...command, page: PAGE_ID, seq: ++sequence };
  newestSent.set(id, body.seq);
  const halts = body.command === 'stop' || (body.command === 'lock' && body.on);
  if (!halts && !(body.command === 'track' && body.body === 'off')) {
    const now = await bridgeClock(); // rule 9 (heard anew first after a sleep: live.js rule 3)
    if (now === null) {
      showMessage(id, 'not sent: the live connection has not told the bridge\'s clock yet', 'error');
      return false;
    }
    body.sent = Math.round(now * 1000) / 1000;
  }
  const live = halts && sendLive({ ...body, rotator: id }); // and by POST: either will do
  // rule 7: a halt the live feed carried was sent, whatever becomes of its request
  const unsent = (why) => (live ? `${why}: sent over the live connection only` : `${why}: nothing was sent`);
  const url = `api/rotators/${encodeURIComponent(id)}/command`;
  for (let attempt = 0; attempt < 2; attempt++) {
    let res;
    try {
      res = await postJSON(url, body, authHeaders(halts));
    } catch {
      // a STOP or lock ON is sent once more at once: the connection it went on may have been
      // closing just then (the bridge closes idle ones), and carrying either out twice is safe
      if (halts && attempt === 0) continue;
      showMessage(id, unsent('the bridge is not reachable'), 'error');
      return live;
    }
    metrics.answered += 1;
    if (res.ok) {
      if (newestSent.get(id) === body.seq) clearMessage(id); // rule 5: not a newer one's refusal
      return true;
    }
    if (res.status === 401 && attempt === 0) {
      dropToken();
      if (session.password) {
        showMessage(id, 'the session ended: log in again (nothing was sent)', 'error');
        getToken();
        return false;
      }
      try {
        await getToken();
      } catch {
        break;
      }
      continue;
    }
    const answer = await res.json().catch(() => ({}));
    showMessage(id, answer.error || `refused (HTTP ${res.status})`, 'refusal');
    return false;
  }
  showMessage(id, unsent('no session'), 'error');
  return live;
}

const stop = () => send({ command: 'stop' }, shown());

$('stop').addEventListener('click', stop);
$('park').addEventListener('click', () => send({ command: 'park' }));
// rule 10: Lock locks (from OFF or not known yet); while ON it only offers Release
let releaseTimers = [];
function disarmRelease() {
  releaseTimers.forEach(clearTimeout);
  releaseTimers = [];
  hide('unlock', true);
}
$('lock').addEventListener('click', () => {
  if ($('lock').getAttribute('aria-pressed') !== 'true') {
    disarmRelease();
    send({ command: 'lock', on: true });
    return;
  }
  if (!$('unlock').hidden) return; // offered already: another click on Lock does nothing more
  $('unlock').disabled = true;
  hide('unlock', false);
  releaseTimers = [
    setTimeout(() => { $('unlock').disabled = false; }, RELEASE_AFTER_MS),
    setTimeout(disarmRelease, RELEASE_FOR_MS),
  ];
});
$('unlock').addEventListener('click', () => {
  disarmRelease();
  send({ command: 'lock', on: false });
});
const step = () => app.rotators.get(app.selected)?.nudge_step_deg || 5;
$('nudge-ccw').addEventListener('click', () => send({ command: 'nudge', d_az: -step(), d_el: 0 }));
$('nudge-cw').addEventListener('click', () => send({ command: 'nudge', d_az: step(), d_el: 0 }));
$('nudge-down').addEventListener('click', () => send({ command: 'nudge', d_az: 0, d_el: -step() }));
$('nudge-up').addEventListener('click', () => send({ command: 'nudge', d_az: 0, d_el: step() }));
$('path-long').addEventListener('click', () => send({ command: 'path', long_path: true }));
$('path-short').addEventListener('click', () => send({ command: 'path', long_path: false }));
// rule 6: a choice not carried out (refused, or never sent) goes back to what the bridge tracks
function sendTrack() {
  const id = app.selected;
  trackKeyed = false;
  send({ command: 'track', body: $('track').value }, id).then((ok) => {
    if (!ok && id === app.selected) renderStatus(id, app.status.get(id) || {});
  });
}
// rule 8: a change in the same task as a key (not Enter) on the select is that key's doing (the
// key's default action changes it); a choice committed in the open list comes in a later task
$('track').addEventListener('keydown', (e) => {
  trackKey = e.key;
  setTimeout(() => { trackKey = null; }, 0); // (a task after the key's own)
  if (e.key === 'Enter' && trackKeyed) {
    e.preventDefault();
    sendTrack();
  }
});
$('track').addEventListener('change', () => {
  if (trackKey === null || trackKey === 'Enter') {
    sendTrack();
    return;
  }
  trackKeyed = true;
  const msg = { text: `Enter tracks ${$('track').value}; nothing is sent before`, kind: 'note', time: new Date() };
  renderMessage(msg);
});
$('track').addEventListener('blur', () => {
  if (!trackKeyed) return;
  trackKeyed = false;
  const id = app.selected;
  if (id) renderStatus(id, app.status.get(id) || {});
  renderMessage(app.messages.get(id));
});
$('locator-form').addEventListener('submit', (e) => {
  e.preventDefault();
  const locator = $('locator').value.replace(/\s+/g, '');
  if (locator) send({ command: 'toward', locator, long_path: false });
  $('locator').blur(); // the rotor may be turning now: Space must stop it, not type a blank
});

// rule 4: capture phase, before any focused control sees the key
window.addEventListener('keydown', (e) => {
  if (e.key === 'Escape') {
    if (!e.repeat) stop();
  } else if ((e.key === ' ' || e.code === 'Space') && !isTextBox(e.target)) {
    e.preventDefault();
    e.stopPropagation();
    if (!e.repeat) stop();
  } else if (e.key === 'Enter' && e.repeat) {
    e.preventDefault(); // one press, one command
  }
}, true);
window.addEventListener('keyup', (e) => {
  if ((e.key === ' ' || e.code === 'Space') && !isTextBox(e.target)) {
    e.preventDefault();
    e.stopPropagation();
  }
}, true);

// ---- the map: hover says where, a click turns there --------------------------------------
const pointer = $('pointer');
let pointerNote = pointer.textContent;

function describe(p, long) {
  if (p.distance_km === undefined) {
    const b = long ? norm360(p.bearing + 180) : p.bearing;
    return `${fmtDeg(b)}${app.config && app.config.station ? ' (bearing ring)' : ''}`;
  }
  const ns = p.lat >= 0 ? 'N' : 'S';
  const ew = p.lon >= 0 ? 'E' : 'W';
  const place = `${Math.abs(p.lat).toFixed(2)}\u00B0${ns} ${Math.abs(p.lon).toFixed(2)}\u00B0${ew}`;
  if (long) return `${fmtDeg(norm360(p.bearing + 180))} \u00B7 ${fmtKm(2 * RIM_KM - p.distance_km)} long path \u00B7 ${place}`;
  return `${fmtDeg(p.bearing)} \u00B7 ${fmtKm(p.distance_km)} \u00B7 ${place}`;
}

function short(p, long) {
  const b = fmtDeg(long ? norm360(p.bearing + 180) : p.bearing);
  if (p.distance_km === undefined) return b;
  return `${b} ${fmtKm(long ? 2 * RIM_KM - p.distance_km : p.distance_km)}`;
}

$('map').addEventListener('pointermove', (e) => {
  const p = map.pick(e);
  if (!p || p.r > 1.1 || e.pointerType === 'touch') return map.hover(null);
  pointer.textContent = describe(p, e.shiftKey);
  map.hover(p, e.shiftKey && p.distance_km !== undefined, short(p, e.shiftKey));
});
$('map').addEventListener('pointerleave', () => {
  pointer.textContent = pointerNote;
  map.hover(null);
});
$('map').addEventListener('click', (e) => {
  const p = map.pick(e);
  if (!p || p.r > 1.1 || !app.selected) return;
  const long = e.shiftKey;
  map.markClick(p);
  aim(p.distance_km !== undefined && p.r > 1e-6
    ? { command: 'toward', latitude_deg: +p.lat.toFixed(5), longitude_deg: +p.lon.toFixed(5), long_path: long }
    : { command: 'target', az: round1(long ? norm360(p.bearing + 180) : p.bearing) }, describe(p, long));
});

let clicks = 0; // clicks on the map (rule 5)

/** A command from the map (a click on it or on a spot), what it was said beside the map. */
function aim(command, said) {
  pointerNote = `sending: ${said}`;
  pointer.textContent = pointerNote;
  const click = ++clicks;
  send(command).then((ok) => {
    if (click !== clicks) return; // rule 5: a late answer to an older click says nothing now
    pointerNote = `${ok ? 'sent' : 'refused'}: ${said}`;
    pointer.textContent = pointerNote;
  });
}

/** A click on a DX cluster spot turns toward its place, as a click on the map does. */
function aimAtSpot(s, long) {
  if (!app.selected || typeof s.latitude !== 'number' || typeof s.longitude !== 'number') return;
  const b = long ? s.long_path_deg : s.bearing_deg;
  const said = `${s.call} ${fmtDeg(b)}${long ? ' long path' : ''}`;
  aim({ command: 'toward', latitude_deg: s.latitude, longitude_deg: s.longitude, long_path: long }, said);
}

connect({
  onConfig: applyConfig,
  onEvent: (type, doc) => {
    if (type === 'status') onStatus(doc);
    else if (type === 'error') onErrorEvent(doc);
    else if (type === 'spots') map.setSpots(doc.spots, aimAtSpot);
  },
  onOnline: (online, configured) => {
    document.body.classList.toggle('offline', !online);
    document.body.classList.remove('starting');
    const why = configured ? 'connection lost \u2014 reconnecting' : 'bridge not reachable \u2014 retrying';
    $('connection').textContent = online ? 'live' : why;
    $('connection').className = online ? 'connection' : 'connection lost';
  },
});
