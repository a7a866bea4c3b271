// The link to the bridge: the session token, the login form, and the live event stream.
//
// Rules:
// 1. Every URL is relative (the page runs behind a path prefix and in an iframe); every api/
//    request but hello/session/login carries X-Rotor-Token. A 401 drops the token: without a
//    password a new one is fetched at once, with one the login form is shown.
// 2. The live feed is api/live, a WebSocket (a browser keeps a few HTTP connections per host,
//    six over HTTP/1.1: an event stream per tab held one each, and six tabs left none for a
//    STOP; WebSockets are counted apart), its token a subprotocol of its opening request
//    ('token.<token>' beside 'rotor-bridge': live.py rule 4). When it closes, fails,
//    or is silent for 25 s, the page is told at once (onOnline(false)) and it reconnects: every
//    1 s, then backing off to 5 s; each connect reads api/config first (onConfig), since the
//    bridge may have restarted with another one.

const TOKEN_KEY = 'rotor-bridge-token';
const SILENCE_MS = 25000;
const ASK_MS = 15000; // a request the bridge has not answered by then is lost
const RETRY_MS = [1000, 1000, 1000, 1000, 1000, 2000, 3000, 4000, 5000];
const $ = (id) => document.getElementById(id);
const delay = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// sessionStorage may be refused in a third-party iframe: the token then lives in this page only
const store = {
  get: () => { try { return sessionStorage.getItem(TOKEN_KEY); } catch { return null; } },
  set: (v) => { try { sessionStorage.setItem(TOKEN_KEY, v); } catch { /* this page only */ } },
  drop: () => { try { sessionStorage.removeItem(TOKEN_KEY); } catch { /* this page only */ } },
};

export const session = { token: store.get(), password: false };

export function dropToken() {
  // kept for a STOP or lock ON only: the bridge still takes those with a token whose life has
  // ended (a page left open for days must be able to stop the rotor before anyone logs in)
  session.lastToken = session.token || session.lastToken;
  session.token = null;
  store.drop();
}

let openSocket = null; // the live feed's WebSocket once the bridge said hello

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
  document.body.classList.remove('login-needed');
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
    const kick = (ms) => {
      clearTimeout(watchdog);
      watchdog = setTimeout(() => ws.close(), ms);
    };
    kick(ASK_MS); // an opening the bridge never answers is lost
    ws.onmessage = (m) => {
      kick(SILENCE_MS);
      let doc;
      try {
        doc = JSON.parse(m.data);
      } catch {
        return; // not ours to judge: the next message is independent
      }
      if (doc.event === 'hello') {
        openSocket = ws;
        onOpen();
      }
      else if (doc.event !== 'ping') onEvent(doc.event, doc.data);
    };
    ws.onclose = (e) => {
      if (openSocket === ws) openSocket = null;
      clearTimeout(watchdog);
      resolve(e.code);
    };
  });
}
