// The link to the bridge: the session token, the login form, and the live event stream.
//
// Rules:
// 1. Every URL is relative (the page runs behind a path prefix and in an iframe); every api/
//    request but hello/session/login carries X-Rotor-Token. A 401 drops the token: without a
//    password a new one is fetched at once, with one the login form is shown. A page that had
//    a session keeps STOP (and the line saying what became of it) on screen beside the form:
//    the token it dropped still carries a STOP or a lock ON (an attack pass: the form hid the
//    whole console, STOP with it, and a phone or a wall display left open past its token's
//    life had no way to stop a turning rotor). The tab keeps that token (sessionStorage) and
//    console.js the rotator it showed, so a reload keeps STOP too (a review: a phone's browser
//    reloads a tab it put away, and the page came back with the form alone).
// 2. The live feed is api/live, a WebSocket (a browser keeps a few HTTP connections per host,
//    six over HTTP/1.1: an event stream per tab held one each, and six tabs left none for a
//    STOP; WebSockets are counted apart), its token a subprotocol of its opening request
//    ('token.<token>' beside 'rotor-bridge': live.py rule 4). When it closes, fails,
//    or is silent for 25 s, the page is told at once (onOnline(false)) and it reconnects: every
//    1 s, then backing off to 5 s; each connect reads api/config first (onConfig), since the
//    bridge may have restarted with another one.
// 3. The bridge's clock (live.py rule 8): each 'clock' and 'ping' message says the bridge's
//    steady clock as it left; bridgeNow() is the largest (bridge's clock - this page's
//    performance.now()) heard since the feed last said hello (its 'clock'), plus performance.now(): never
//    later than the bridge's clock (a message arrives after it left), whatever the phone's own
//    clock says. null before the first hello. Each move carries it as its send time
//    (commands.py rule 6); a new hello starts the reckoning again (the bridge may be another).
//    A page that slept (a phone put away, a laptop's lid shut) finds its steady clock stood
//    still meanwhile (Chromium's does, on Linux, Android and macOS) while the bridge's went on:
//    the reckoning was as far behind as the sleep was long, and every click until the next
//    ping was refused, 'sent 60 s ago' (a review). When the page's steady clock has fallen
//    SLEPT_MS behind its wall clock since it last heard the bridge's (the wall clock only
//    tells that it slept, never the time), the reckoning is dropped and the feed opened anew;
//    bridgeClock() waits for its clock (AGAIN_MS at most) before a move is stamped.

const TOKEN_KEY = 'rotor-bridge-token';
const HALT_KEY = 'rotor-bridge-halt-token'; // rule 1: the token dropped, for a STOP after a reload
const SILENCE_MS = 25000;
const ASK_MS = 15000; // a request the bridge has not answered by then is lost
const RETRY_MS = [1000, 1000, 1000, 1000, 1000, 2000, 3000, 4000, 5000];
const $ = (id) => document.getElementById(id);
const delay = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// sessionStorage may be refused in a third-party iframe: the token then lives in this page only
const kept = (key) => ({
  get: () => { try { return sessionStorage.getItem(key); } catch { return null; } },
  set: (v) => { try { sessionStorage.setItem(key, v); } catch { /* this page only */ } },
  drop: () => { try { sessionStorage.removeItem(key); } catch { /* this page only */ } },
});
const store = kept(TOKEN_KEY);
const haltStore = kept(HALT_KEY);

export const session = { token: store.get(), password: false, lastToken: haltStore.get() };

export function dropToken() {
  // kept for a STOP or lock ON only: the bridge still takes those with a token whose life has
  // ended (a page left open for days must be able to stop the rotor before anyone logs in)
  session.lastToken = session.token || session.lastToken;
  session.token = null;
  store.drop();
  if (session.lastToken) haltStore.set(session.lastToken); // rule 1: a reload keeps it
}

let openSocket = null; // the live feed's WebSocket once the bridge said hello
let clockOffset = null; // rule 3: the bridge's clock minus performance.now(), in seconds
const SLEPT_MS = 1000; // rule 3: the steady clock this far behind the wall clock: the page slept
const AGAIN_MS = 4000; // rule 3: how long a move waits for the clock heard anew after a sleep
let clockWall = null; // rule 3: Date.now() - performance.now() when the clock was last heard
let again = null; // rule 3: the clock heard anew after a sleep (a promise), while awaited
let heardAgain = null;
let endFeed = null; // ends the live feed that is open (it reconnects)

/** Rule 3: the bridge's steady clock now, as this page reckons it (seconds), or null. */
export function bridgeNow() {
  return clockOffset === null ? null : clockOffset + performance.now() / 1000;
}

/** Rule 3: bridgeNow(), the clock heard anew first if the page slept since it was heard. */
export async function bridgeClock() {
  if (slept()) forgetClock();
  if (again) await Promise.race([again, delay(AGAIN_MS)]);
  return bridgeNow();
}

function slept() {
  return clockWall !== null && Date.now() - performance.now() - clockWall > SLEPT_MS;
}

function forgetClock() {
  clockOffset = null;
  clockWall = null;
  if (!again) again = new Promise((resolve) => { heardAgain = resolve; });
  if (endFeed) endFeed(); // a new feed says the clock right after its hello
}

function heardClock(now, fresh) {
  if (typeof now !== 'number' || !Number.isFinite(now)) return;
  if (!fresh && slept()) { forgetClock(); return; } // (a ping sent while it slept lags too)
  const offset = now - performance.now() / 1000;
  clockOffset = fresh || clockOffset === null ? offset : Math.max(clockOffset, offset);
  clockWall = Date.now() - performance.now();
  if (heardAgain) { heardAgain(); heardAgain = null; again = null; }
}

setInterval(() => { if (slept()) forgetClock(); }, SLEPT_MS); // rule 3: at once on waking

/** A STOP or lock ON over the live feed too (the bridge takes nothing else there): when a
 *  flood holds every connection a POST could take, the socket the page has still carries it. */
export function sendLive(doc) {
  if (!openSocket || openSocket.readyState !== WebSocket.OPEN) return false;
  openSocket.send(JSON.stringify(doc));
  return true;
}

let tokenPending = null;
export function getToken() {
  if (session.token) return Promise.resolve(session.token);
  if (!tokenPending) tokenPending = newToken().finally(() => { tokenPending = null; });
  return tokenPending;
}

async function newToken() {
  const hello = await (await fetch('api/hello', { cache: 'no-store', signal: AbortSignal.timeout(ASK_MS) })).json();
  session.password = Boolean(hello.password);
  const token = session.password ? await askPassword() : await sessionToken();
  session.token = token;
  store.set(token);
  return token;
}

async function sessionToken() {
  const res = await postJSON('api/session', {});
  if (!res.ok) throw new Error(`api/session: HTTP ${res.status}`);
  return (await res.json()).token;
}

let loginWaiters = [];
function askPassword() {
  document.body.classList.add('login-needed');
  document.body.classList.toggle('keeps-stop', Boolean(session.lastToken)); // rule 1
  $('login').hidden = false;
  $('connection').textContent = 'log in to control the rotators';
  $('connection').className = 'connection asks-login';
  $('password').focus();
  return new Promise((resolve) => loginWaiters.push(resolve));
}

$('login').addEventListener('submit', async (e) => {
  e.preventDefault();
  const error = $('login-error');
  error.textContent = '';
  let res;
  try {
    res = await postJSON('api/login', { password: $('password').value });
  } catch {
    error.textContent = 'the bridge is not reachable';
    return;
  }
  const body = await res.json().catch(() => ({}));
  if (!res.ok) {
    error.textContent = body.error || `HTTP ${res.status}`;
    if (res.status === 429 && body.retry_after_s) holdLogin(body.retry_after_s);
    return;
  }
  $('password').value = '';
  $('login').hidden = true;
  document.body.classList.remove('login-needed', 'keeps-stop');
  const waiters = loginWaiters;
  loginWaiters = [];
  waiters.forEach((resolve) => resolve(body.token));
});

function holdLogin(seconds) {
  const go = $('login-go');
  go.disabled = true;
  setTimeout(() => { go.disabled = false; }, seconds * 1000);
}

export function postJSON(url, body, headers = {}) {
  return fetch(url, {
    method: 'POST',
    cache: 'no-store',
    headers: { 'Content-Type': 'application/json', ...headers },
    body: JSON.stringify(body),
  });
}

export const authHeaders = (halts = false) => ({
  'X-Rotor-Token': session.token || (halts ? session.lastToken : '') || '',
});

/** Connect, and stay connected, forever (rule 2). */
export async function connect({ onConfig, onEvent, onOnline }) {
  let configured = false;
  let attempt = 0;
  let quickRetry = true; // one 401 in a row retries at once with a new token
  for (;;) {
    try {
      await getToken();
      const cfg = await fetch('api/config', { cache: 'no-store', headers: authHeaders(), signal: AbortSignal.timeout(ASK_MS) });
      if (cfg.status === 401) {
        dropToken();
        if (quickRetry) { quickRetry = false; continue; }
      }
      if (!cfg.ok) throw new Error(`api/config: HTTP ${cfg.status}`);
      await onConfig(await cfg.json());
      configured = true;
      const ended = await readLive(onEvent, () => {
        quickRetry = true;
        attempt = 0;
        onOnline(true);
      });
      if (ended === 4401) {
        dropToken(); // the token's life ended, or the bridge restarted: ask for a new one
        if (quickRetry) { quickRetry = false; continue; }
      }
    } catch (err) {
      if (!configured) console.warn(err);
    }
    onOnline(false, configured);
    await delay(RETRY_MS[Math.min(attempt++, RETRY_MS.length - 1)]);
  }
}

/** api/live until it ends; resolves with the close code. The token goes with the opening
 *  request as a subprotocol (a WebSocket cannot carry a header; live.py rule 4: a socket that
 *  gives it so never waits for room); "hello" says the bridge took it (then onOpen). */
function readLive(onEvent, onOpen) {
  return new Promise((resolve) => {
    const url = new URL('api/live', location.href);
    url.protocol = url.protocol === 'https:' ? 'wss:' : 'ws:';
    const ws = new WebSocket(url, ['rotor-bridge', 'token.' + (session.token || 'none')]);
    let watchdog = 0;
    let ended = false;
    const end = (code) => {
      if (ended) return;
      ended = true;
      if (openSocket === ws) { openSocket = null; endFeed = null; }
      clearTimeout(watchdog);
      resolve(code);
    };
    const kick = (ms) => {
      clearTimeout(watchdog);
      // rule 2: lost at once, not when the close is answered: a bridge or a network that went
      // silent never answers it, and the browser waits a minute for it (an attack pass: the
      // page said "live" over a hung bridge's last bearing for 85 s, not 25)
      watchdog = setTimeout(() => { end(1006); ws.close(); }, ms);
    };
    kick(ASK_MS); // an opening the bridge never answers is lost
    ws.onmessage = (m) => {
      if (ended) return; // (a socket given up for silence tells nothing more)
      kick(SILENCE_MS);
      let doc;
      try {
        doc = JSON.parse(m.data);
      } catch {
        return; // not ours to judge: the next message is independent
      }
      if (doc.event === 'hello') {
        openSocket = ws;
        endFeed = () => { end(1000); ws.close(); }; // rule 3
        onOpen();
      }
      else if (doc.event === 'clock' || doc.event === 'ping') {
        heardClock(doc.now, doc.event === 'clock'); // rule 3: the clock right after hello
      }
      else onEvent(doc.event, doc.data);
    };
    ws.onclose = (e) => end(e.code);
  });
}
