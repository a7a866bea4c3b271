"""The operator console over HTTP: the page, its token, the live feed and the commands (aiohttp
on a thread of its own; the contract the page keeps is docs/console.md).

Why aiohttp: one event loop on one thread serves every open page's stream and every command
(a page costs a coroutine, not a thread), the streams and the POSTs need nothing beyond it, and
the rest of the bridge stays threads and queues: the serial-lines thread hands statuses over
with ``call_soon_threadsafe`` and never waits for a page.

Rules:
1. Every URL is relative to the page (``api/events``, never ``/api/events``): the console
   works behind a reverse proxy under a path prefix and inside a Home Assistant card.
2. The safety rules of auth.py hold for every request: the host check (no password), the
   Origin of every POST, the token of every ``api/`` call but ``hello``, ``session`` and
   ``login``; commands are POSTs only (a GET is 405 and moves nothing). A command without a
   token is 403, one with a bad or expired token 401 (the page fetches a new one).
3. Every answer carries a strict Content-Security-Policy (scripts and styles from this origin
   only, no inline script), ``nosniff`` and no referrer; who may frame the page is the
   ``frame_ancestors`` setting (only the console itself by default: a hostile page must not
   frame it and steer clicks onto the map).
4. A command is judged by the rotator's judge (commands.py); the answer says what the judge
   said (409 with the refusal's code), and the refusal reaches every page as an error event
   too, as it reaches R/error. Who sent it is ``web`` and the client's address, as the login's
   limit counts it (auth.py rule 6): behind a reverse proxy, the proxy's, unless it is one of
   ``trusted_proxies`` (anyone can write an ``X-Forwarded-For``).
5. Slow work (projecting the coastlines, reading the TLE file's names) runs on the loop's
   executor, never on the loop: a STOP posted meanwhile is carried out at once
   (docs/architecture.md rule 12). So do the commands of a rotator whose commands wait for a
   round trip (``commands_block``: the remote's, which waits for its broker's
   acknowledgement): on one thread per such rotator (made at ``attach``), in the order they
   came (a stop never overtakes a target posted before it, nor a target the stop), so no
   page's stream or command, nor another rotator's, waits for them (their order at the broker
   is kept by the link's own send lock). A STOP or lock ON posted there waits for that
   rotator's one command under way at most: those queued before it that have not started are
   not sent (refused ``stale``: the stop came first), so it is neither overtaken nor does it
   overtake. Nor is one sent after a STOP that another front end of the rotator's (the
   remote's rotctld) sent since it was posted (port.py rule 2b), nor one whose send time
   is older than commands.py rule 6 allows when its turn comes. At most ``FAR_MOVES``
   moves wait per rotator (the one under way included); one more is refused at once (409,
   code ``busy``), never queued. A STOP or lock ON is never refused so.
6. ``stop`` closes every page's stream first (each page sees the bridge go), then the server.
7. What the HTTP server logs of a request it could not serve (``Quieter``) is the client's doing,
   not the bridge's: a malformed request is one line naming its sender and what was wrong, no
   traceback; a login or command whose client went before its body came, nothing (an attack
   pass: each was a traceback at ERROR, a login's from any client); any such line (a request's
   error too) goes at its level NOISE_BURST at once, then one every NOISE_EVERY_S, the rest at
   DEBUG (an attack pass: aiohttp logged every malformed request at ERROR with its traceback,
   22,000 lines a second from one client that needed no token, and journald's rate limit then
   drops every line of the service, its warnings too). A body is read in one place (``_body``,
   for every endpoint that reads one): one that does not come within BODY_S is a 408, one
   whose client went a 400, and one that is not the gzip or deflate its Content-Encoding
   names a 400 after which its connection is closed (a login's counts against its address's
   tries), never a 500; one left unread (sent to ``api/session``) that aiohttp finds bad so
   is one line. A login in a charset that is no text encoding is a wrong password. An answer
   begun to a client already gone (a WebSocket's opening, closed at once) is one line at
   DEBUG. No reason or header carries the client's text: a file name not served is said in
   the 404's JSON body (an attack pass: ``GET /a%0ab`` put it in the reason, which aiohttp
   refuses for its line break: a 500; a bad gzip body, a charset that is none and a
   WebSocket whose client went were each a traceback at ERROR).
8. An accept the system refuses for want of descriptors or memory (EMFILE, ENFILE, ENOBUFS,
   ENOMEM: the process is at its ``ulimit -n``, its other ports' clients hold the rest) is one
   warning per ACCEPT_SAY_S naming it and how many since, no traceback (``AcceptErrors``, the
   loop's exception handler); asyncio pauses the listener a second and tries again. An attack
   pass: asyncio said each at ERROR with its traceback, and its accept loop tries a hundred
   times a wake-up, so a flood of idle connections at the descriptor limit wrote 700 tracebacks
   a second (108,000 lines in 15 s) and journald's rate limit then drops every line of the
   service, the state file's failed save among them. Every other error of the loop goes to
   asyncio's own handler, as before.
9. A command's body longer than commands.py's MAX_BODY_BYTES is refused unread when its length
   is given, and said as a bad body is (413 with code ``invalid`` and the reason, on R/error),
   as is one without its length over the 16 KiB the server reads at most (an attack pass:
   from 16 KiB on it was a bare 413 "Request Entity Too Large", said nowhere, neither on
   R/error nor in the log).
10. A command the judge makes from the rotator's status (a nudge, the other path: commands.py
   ``from_status``) while a motion command taken before it is not in that status yet
   (runtime/rotator.py ``on_its_way``) waits for it on the loop, SHOWN_S at most, then is
   judged as it came (rule 5's look again: a STOP meanwhile, or a newer click of the page's,
   makes it stale): three quick clicks on +5 are +15 (commands.py rule 5a). The judge refuses
   one made from a status that does not show what is on its way ("send it again"), and a
   second click came within a millisecond of the first, before the lines thread took it (a
   failed CI run). Still on its way after SHOWN_S (a line that owes a long reply), the judge
   refuses it so. At most SHOWN_WAITERS wait per rotator; one more is refused at once (409,
   code ``busy``, on R/error): each waiter looks every SHOWN_POLL_S, and a client posting
   hundreds at a line that owes a long reply kept the loop, and the interpreter the serial
   lines share, busy with their looks.
11. A command is dated by when its bytes reached the bridge, not by when the loop began its
   request (rule 5's start): every rotator's halt watchers (core/haltwatch.py) have the
   console look at its connections right before each STOP or lock ON is counted, whichever
   front end brought it (looks.py, the TCP ports' construction: interfaces/tcplines.py rule
   9), and a command whose request's first byte a look counted before a halt is refused as
   stale (409, code ``stale``, on R/error), as the judge refuses one a halt overtook
   (runtime/rotator.py ``since``), however late the loop read it: a script's POST (no
   ``sent``, no numbers) that waited in the kernel while the loop was busy was dated after a
   rotctld STOP or a Home Assistant lock ON counted meanwhile, and turned the rotor or
   unlocked it (an attack pass). The halts the console carried out itself are numbered as
   they are counted (``_own_halt``, as tcplines.py ``Fence.halting``): one that came on the
   same connection, or that the same page numbered before the command (commands.py rule 5:
   its later click merely overtook its STOP), does not make it stale. On the remote the
   count is that of the remote's other front ends (port.py rule 2b), told before each
   (remote/rotator.py ``halted``).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import errno
import gzip
import ipaddress
import json
import logging
import socket
import threading
import time
from collections.abc import Awaitable, Callable, Hashable

from aiohttp import web
from aiohttp.http_exceptions import HttpProcessingError
from aiohttp.web_protocol import RequestPayloadError

from bridge import __version__
from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import ErrorEvent, Origin, RotatorStatus, Source
from bridge.core.ratelimit import TokenBucket
from bridge.interfaces.tcplines import halt_watchers
from bridge.interfaces.web import auth, view
from bridge.interfaces.web.commands import (
    MAX_BODY_BYTES,
    STALE,
    BadCommand,
    Order,
    WebCommand,
    aged,
    carry_out,
    feed_clock,
    parse,
    scoped,
)
from bridge.interfaces.web.connections import MOST_HELD, Connections
from bridge.interfaces.web.feed import Feed, Shape
from bridge.interfaces.web.files import static_files
from bridge.interfaces.web.live import TOKEN_HEADER, Live
from bridge.interfaces.web.looks import Conn, HaltLooks
from bridge.interfaces.web.port import ConsoleRotator

log = logging.getLogger(__name__)

BODY_S = 10.0  # a command's or a login's body arrives within this, or it is not waited for
WRONG_LOG_S = 10.0  # a wrong password is said at most this often, with a count
SHOWN_S = 3.0  # rule 10: a nudge waits this long at most for the command before it to show
SHOWN_POLL_S = 0.005  # rule 10: how often it looks
SHOWN_WAITERS = 8  # rule 10: commands waiting so per rotator, no more
FAR_MOVES = 4  # rule 5: moves waiting per far rotator (the one under way included), no more
OWN_KEPT = 64  # rule 11: the numbers of the console's own halts kept per rotator (the oldest go)
NOISE_BURST = 10  # rule 7: lines at their level at once, then one every NOISE_EVERY_S
NOISE_EVERY_S = 10.0
ACCEPT_SAY_S = 10.0  # rule 8: an accept refused for want of descriptors, said this often at most
_OUT_OF = (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM)  # what asyncio pauses for
Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]


class Quieter(logging.Filter):
    """Rule 7, on the logger the HTTP server is given (the event loop's thread alone logs)."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        super().__init__()
        self._clock = clock
        self._loud = TokenBucket.full(NOISE_BURST, 1.0 / NOISE_EVERY_S, clock())

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno < logging.WARNING:
            return True
        exc = record.exc_info[1] if record.exc_info else None
        if isinstance(exc, RequestPayloadError):  # a body not as its headers say (rule 7)
            exc = exc.__cause__ if isinstance(exc.__cause__, HttpProcessingError) else None
            if exc is None:  # (no words of aiohttp's to give: the console's)
                exc = HttpProcessingError(code=400, message="a body that could not be read")
        if isinstance(exc, HttpProcessingError):  # the client's bytes: what was wrong, in short
            said = (str(exc.message).splitlines() or [""])[0][:80]
            who = record.args[0] if isinstance(record.args, tuple) and record.args else "a client"
            record.msg = "web console: a malformed request from %s refused (%d: %r)"
            record.args = (who, exc.code, said)
            record.exc_info, record.exc_text = None, None
            record.levelno, record.levelname = logging.WARNING, "WARNING"
        if self._loud.take(self._clock()):
            return True
        record.levelno, record.levelname = logging.DEBUG, "DEBUG"
        return logging.getLogger(record.name).isEnabledFor(logging.DEBUG)


class AcceptErrors:
    """Rule 8, the console loop's exception handler (only that loop's thread calls it)."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self._said_s = -ACCEPT_SAY_S
        self._since = 0

    def __call__(self, loop: asyncio.AbstractEventLoop, context: dict[str, object]) -> None:
        exc = context.get("exception")
        accepting = "accept" in str(context.get("message", ""))
        if not (accepting and isinstance(exc, OSError) and exc.errno in _OUT_OF):
            loop.default_exception_handler(context)
            return
        self._since += 1
        now = self._clock()
        if now - self._said_s < ACCEPT_SAY_S:
            return
        count, self._since, self._said_s = self._since, 0, now
        log.warning(
            "web console: cannot accept a connection: %s (%d time(s) since last said); the "
            "process is out of descriptors or memory: are many connections held open to its "
            "ports? (systemd: LimitNOFILE)",
            exc.strerror or exc,
            count,
        )


http_log = logging.getLogger(__name__ + ".http")  # rule 7: the HTTP server's own
http_log.addFilter(Quieter())


def _named(exc: OSError, bind: str, port: int) -> OSError:
    """``listen``'s failure with the address and the settings to change (its errno kept: the
    start tells an address not up yet at boot by it)."""
    where = f"{bind or '(every address)'}:{port}"
    if isinstance(exc, socket.gaierror):
        why = f"web.bind {bind!r} is no address this machine can resolve ({exc.strerror or exc})"
    elif exc.errno == errno.EADDRINUSE:
        why = "the port is in use by another program: change web.port"
    else:
        why = f"{exc.strerror or exc}: check web.bind and web.port"
    return OSError(exc.errno, f"web console: cannot listen on {where}: {why}")


def _json(doc: object, status: int = 200) -> web.Response:
    return web.json_response(doc, status=status, headers={"Cache-Control": "no-store"})


class Unread(Exception):
    """Rule 7: a request's body that could not be read, the client's doing: the answer's
    ``status`` and why, in the console's own words (never the client's text), and whether its
    connection is closed after the answer (``close``: what follows the body cannot be told
    from a next request)."""

    def __init__(self, status: int, why: str, *, close: bool = False) -> None:
        super().__init__(why)
        self.status, self.why, self.close = status, why, close

    def answer(self, code: str | None = None) -> web.Response:
        response = _json({"error": self.why, **({"code": code} if code else {})}, self.status)
        if self.close:
            response.force_close()
        return response


async def _body(request: web.Request, whose: str) -> bytes:
    """Rule 7: the one place a request's body is read (``whose``: "the login's", "the
    command's"), within BODY_S, at most the server's ``client_max_size`` (over it aiohttp's
    HTTPRequestEntityTooLarge, which the caller says: rule 9). A body that did not come in
    time, whose client went, or that is not the gzip or deflate (or the chunks) its headers
    name, is Unread: no traceback, and its reason the console's words."""
    try:
        return await asyncio.wait_for(request.read(), BODY_S)
    except TimeoutError:
        raise Unread(408, f"{whose} body did not come within {BODY_S:g} s") from None
    except ConnectionError:  # the client went before its body came
        raise Unread(400, "the connection closed before the body came") from None
    except RequestPayloadError:
        # aiohttp's parser set the error and went on to what follows: for it the body is done.
        # Said so, or its lingering close reads the body again after the answer, and logs the
        # same error at ERROR with its traceback (an attack pass: a gzip body that was not)
        request.content.feed_eof()
        why = f"{whose} body could not be read as its Content-Encoding or Transfer-Encoding say"
        raise Unread(400, why, close=True) from None


class WebConsole:
    def __init__(
        self,
        bind: str,
        port: int,
        *,
        password: str | None,
        frame_ancestors: list[str],
        host_names: list[str] | None = None,
        trusted_proxies: list[str] | None = None,
        secret: bytes = b"",
        station: tuple[float, float] | None,
        locator: str | None,
        satellites: Callable[[], list[str]],
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.bind, self.port = bind, port
        self._password = password
        self._host_names = tuple(host_names or ())
        self._proxies = tuple(ipaddress.ip_network(p, strict=False) for p in trusted_proxies or ())
        self._tokens = auth.Tokens(auth.key_for(password, secret))
        self._logins = auth.LoginLimiter()
        # a wrong password is said at most once per WRONG_LOG_S, with a count (an attack pass:
        # 3,000 lines in a second, one per try)
        self._wrong_said_s, self._wrong_since = -1e18, 0
        self._station, self._locator = station, locator
        self._satellites = satellites
        self._wall = wall
        self._rotators: dict[str, ConsoleRotator] = {}
        self._facts: dict[str, view.RotatorFacts] = {}
        self._shapes: dict[str, Shape] = {}
        self._files = static_files()
        self._land: asyncio.Future[bytes] | None = None
        ancestors = " ".join(["'self'", *frame_ancestors])
        self._headers = {
            "Content-Security-Policy": "default-src 'self'; script-src 'self'; style-src 'self'; "
            "img-src 'self' data:; connect-src 'self'; base-uri 'none'; form-action 'self'; "
            f"frame-ancestors {ancestors}",
            "X-Content-Type-Options": "nosniff",
            "Referrer-Policy": "no-referrer",
        }
        if not frame_ancestors:
            self._headers["X-Frame-Options"] = "SAMEORIGIN"
        self.live = Live(
            Feed(self._shapes),
            self._tokens,
            wall,
            self._headers,
            trust=lambda transport: self._conns.trust(transport),
            on_gone=lambda transport, told: self._conns.on_gone(transport, told),
            halt=self._halt,
            client=self._client,
        )
        self._loop: asyncio.AbstractEventLoop | None = None
        self._runner: web.AppRunner | None = None
        self._conns = Connections(lambda: None)
        self._listeners: list[asyncio.Server] = []
        self._looks = HaltLooks()  # rule 11
        self._sweeper: asyncio.Task[None] | None = None
        self._ticker: asyncio.Task[None] | None = None
        self._order = Order()
        self._started: dict[int, float] = {}  # requests being served (by id): when they began
        self._thread: threading.Thread | None = None
        self._running = False
        self._far: dict[str, concurrent.futures.ThreadPoolExecutor] = {}  # rule 5, per rotator
        self._far_halts: dict[str, int] = {}  # rule 5: halts posted per rotator (the loop's)
        self._far_moves: dict[str, int] = {}  # rule 5: moves not yet done per rotator (the loop's)
        self._waiting: dict[str, int] = {}  # rule 10: commands waiting per rotator (the loop's)

    # -- wiring (the main thread) ------------------------------------------------------------
    def attach(self, rot: ConsoleRotator, facts: view.RotatorFacts) -> None:
        if rot.commands_block and rot.id not in self._far:  # rule 5: one thread each, in order
            self._far[rot.id] = concurrent.futures.ThreadPoolExecutor(1, f"console-{rot.id}")
        self._rotators[rot.id] = rot
        self._facts[rot.id] = facts
        watchers = halt_watchers(rot)
        if watchers is not None:  # rule 11: its connections looked at before each halt
            self._looks.attach(rot.id, lambda: rot.halts, watchers)
        self._shapes[rot.id] = Shape(rot.spec.has_elevation, rot.pointing.shows_raw)

    @property
    def most_held(self) -> int:
        """The descriptors its connections may hold at once, at most (connections.py rule 1:
        a burst is judged once connected, up to twice the limit; app.py rule 5)."""
        return MOST_HELD

    @property
    def url(self) -> str:
        host = self.bind if self.bind not in ("", "0.0.0.0", "::") else "127.0.0.1"
        return f"http://{f'[{host}]' if ':' in host else host}:{self.port}/"

    def listen(self) -> None:
        """Bind the port (OSError if it cannot be had) and serve on a thread of its own. The
        loop runs on that thread from the start: the caller's thread may have a loop of its own
        running (a script, a test driving a browser)."""
        loop = self._loop = asyncio.new_event_loop()
        loop.set_exception_handler(AcceptErrors())  # rule 8
        self._thread = threading.Thread(target=loop.run_forever, name="web", daemon=True)
        self._thread.start()
        try:
            asyncio.run_coroutine_threadsafe(self._start(), loop).result(timeout=30.0)
        except BaseException as exc:
            loop.call_soon_threadsafe(loop.stop)
            self._thread.join(timeout=5.0)
            loop.close()
            self._loop = self._thread = None
            # the settings to change, named (a name that does not resolve said nothing); not a
            # start that took too long (TimeoutError is an OSError: no setting is at fault)
            if isinstance(exc, OSError) and not isinstance(exc, TimeoutError):
                raise _named(exc, self.bind, self.port) from None
            raise
        self._running = True
        log.info("web console on %s", self.url)

    async def _start(self) -> None:
        app = web.Application(middlewares=[self._guard], client_max_size=16 * 1024)  # rule 9
        app.router.add_get("/", self._index)
        app.router.add_get("/api/hello", self._hello)
        app.router.add_post("/api/session", self._session)
        app.router.add_post("/api/login", self._login)
        app.router.add_get("/api/config", self._config)
        app.router.add_get("/api/land", self._land_data)
        app.router.add_get("/api/events", self._tokened(self.live.events))
        app.router.add_get("/api/live", self.live.websocket)
        app.router.add_post("/api/rotators/{rid}/command", self._command)
        app.router.add_get("/{name}", self._file)
        # the streams end themselves at stop (feed.close): nothing is worth waiting long for
        runner = self._runner = web.AppRunner(
            app, access_log=None, shutdown_timeout=1.0, logger=http_log
        )
        await runner.setup()
        # served through Connections (connections.py), not a TCPSite: what is held is counted
        server = runner.server
        assert server is not None  # set up above
        self._conns = Connections(server)
        loop = asyncio.get_running_loop()
        # rule 11: the listeners and what they accept are looks.py's, served by asyncio
        socks = self._looks.listeners(self.bind, self.port)
        self._looks.start()
        for sock in socks:
            listening = await loop.create_server(self._conns.protocol, sock=sock)
            self._listeners.append(listening)
        self._sweeper = loop.create_task(self._conns.sweeping())
        self._ticker = loop.create_task(self.live.ticking())

    def stop(self) -> None:
        """Rule 6."""
        loop, self._running = self._loop, False
        if loop is None or self._thread is None:
            return
        done = asyncio.run_coroutine_threadsafe(self._shutdown(), loop)
        try:
            done.result(timeout=5.0)
        except Exception:
            log.exception("the web console did not stop cleanly")
        loop.call_soon_threadsafe(loop.stop)
        self._thread.join(timeout=5.0)
        if not self._thread.is_alive():
            loop.close()
        for far in self._far.values():
            far.shutdown(wait=False, cancel_futures=True)
        self._looks.stop()

    async def _shutdown(self) -> None:
        self.live.feed.close()
        for task in (self._sweeper, self._ticker):
            if task is not None:
                task.cancel()
        for listener in self._listeners:
            listener.close()
        if self._runner is not None:
            await self._runner.cleanup()

    # -- the engine's listeners (the serial-lines thread: live.py rule 1) --------------------
    def on_status(self, rotator_id: str, status: RotatorStatus) -> None:
        self.live.on_status(rotator_id, status, self._loop if self._running else None)

    def on_event(self, rotator_id: str, event: ErrorEvent) -> None:
        self.live.on_event(rotator_id, event, self._loop if self._running else None)

    def on_spots(self, doc: str) -> None:
        """The DX cluster's spot list (``B/spots``' document), from its thread (live.py rule 6)."""
        self.live.on_spots(doc, self._loop if self._running else None)

    # -- every request (rules 2, 3) ----------------------------------------------------------
    @web.middleware
    async def _guard(self, request: web.Request, handler: Handler) -> web.StreamResponse:
        conn = self._looks.of(request.transport)  # rule 11: dated from its first byte
        if conn is not None:
            conn.begin()
        try:
            response = await self._guarded(request, handler)
        finally:
            if conn is not None:
                conn.end()
        response.headers.update(self._headers)
        return response

    async def _guarded(self, request: web.Request, handler: Handler) -> web.StreamResponse:
        self._started[id(request)] = time.monotonic()  # commands.py rule 5
        self._conns.started(request.transport)
        try:
            await self._conns.turn(request.transport)  # connections.py rule 4: its budget
            refusal = self._refusal(request)
            if refusal is not None:
                return _json({"error": refusal}, 403)
            try:
                return await handler(request)
            except web.HTTPException as exc:
                return _json({"error": exc.reason}, exc.status)
            except ConnectionError as exc:  # rule 7: an answer begun to a client that went
                transport = request.transport
                if transport is not None and not transport.is_closing():
                    raise  # (not the client's doing: aiohttp says it, with its traceback)
                log.debug(
                    "web console: a client at %s went before its answer (%s)", request.remote, exc
                )
                return _json({"error": "the connection closed"}, 400)  # (aiohttp writes none)
        finally:
            self._conns.finished(request.transport)
            del self._started[id(request)]

    def _refusal(self, request: web.Request) -> str | None:
        host = request.headers.get("Host")
        forwarded = request.headers.get("X-Forwarded-Host")
        if self._password is None:  # auth.py rule 5: the name asked for, through a proxy too
            for name in (host, *([forwarded.split(",")[0]] if forwarded else [])):
                if not auth.host_is_local_name(name, self._host_names):
                    return (
                        f"this console answers to IP addresses, localhost and web.host_names "
                        f"only, not {name!r}: without web.password_file a page from another "
                        "name could drive it"
                    )
        if request.method in ("GET", "HEAD") and request.headers.get("Upgrade") is None:
            return None  # a WebSocket's opening GET is checked as a POST is (its Origin)
        if not auth.origin_allowed(request.headers.get("Origin"), host, forwarded):
            return "a request from another site's page is refused"
        if request.method == "GET":
            return None
        if request.content_type != "application/json":
            return "commands are JSON (Content-Type: application/json)"
        return None

    def _tokened(self, handler: Handler) -> Handler:
        async def checked(request: web.Request) -> web.StreamResponse:
            if not self._token_ok(request):
                return _json({"error": "no valid token: ask api/session or api/login"}, 401)
            return await handler(request)

        return checked

    def _client(self, request: web.Request) -> str:
        """Who a request is from (auth.py rule 6: a trusted proxy's browser)."""
        forwarded = request.headers.get("X-Forwarded-For")
        return auth.forwarded_client(request.remote, forwarded, self._proxies)

    def _token_ok(self, request: web.Request) -> bool:
        if not self._tokens.valid(request.headers.get(TOKEN_HEADER), self._wall()):
            return False
        self._conns.trust(request.transport)  # connections.py rule 1
        return True

    # -- the page ----------------------------------------------------------------------------
    async def _index(self, request: web.Request) -> web.StreamResponse:
        return self._serve(request, "index.html")

    async def _file(self, request: web.Request) -> web.StreamResponse:
        return self._serve(request, request.match_info["name"])

    def _serve(self, request: web.Request, name: str) -> web.StreamResponse:
        found = self._files.get(name)
        if found is None:  # (rule 7: the name, the client's text, in the body alone, escaped)
            return _json({"error": f"no {name}"}, 404)
        plain, packed, kind = found
        zipped = "gzip" in request.headers.get("Accept-Encoding", "")
        response = web.Response(body=packed if zipped else plain)
        response.headers["Content-Type"] = kind
        response.headers["Cache-Control"] = "no-cache"
        response.headers["Vary"] = "Accept-Encoding"
        if zipped:
            response.headers["Content-Encoding"] = "gzip"
        return response

    # -- tokens --------------------------------------------------------------------------------
    async def _hello(self, request: web.Request) -> web.StreamResponse:
        return _json({"password": self._password is not None, "version": __version__})

    async def _session(self, request: web.Request) -> web.StreamResponse:
        if self._password is not None:
            return _json({"error": "this console asks for a password (api/login)"}, 403)
        return _json({"token": self._tokens.issue(self._wall())})

    async def _login(self, request: web.Request) -> web.StreamResponse:
        if self._password is None:
            return _json({"token": self._tokens.issue(self._wall())})
        client, now = self._client(request), time.monotonic()
        forwarded = ",".join(request.headers.getall("X-Forwarded-Host", ()))
        key = auth.login_key(
            client, request.headers.get("Host"), self._host_names, forwarded=forwarded
        )
        proxy = request.remote if client != request.remote else None  # (auth.py rule 6)
        wait_s = self._logins.wait(key, now, proxy)
        if wait_s is not None:
            message = f"too many failed logins; try again in {wait_s:.0f} s"
            return _json({"error": message, "retry_after_s": round(wait_s)}, 429)
        try:  # its body within BODY_S, as a command's (connections.py rule 2)
            body = await _body(request, "the login's")
        except Unread as exc:
            if exc.close:  # a body that is not what its headers say: a try, counted (rule 7)
                self._failed(key, now, proxy, client)
            return exc.answer()
        try:  # in the charset its client names: one that is no text encoding is no password
            doc = json.loads(body.decode(request.charset or "utf-8"))
        except (ValueError, LookupError, RecursionError):
            doc = None
        given = doc.get("password") if isinstance(doc, dict) else None
        if not isinstance(given, str) or not auth.password_matches(given, self._password):
            self._failed(key, now, proxy, client)
            return _json({"error": "wrong password"}, 401)
        return _json({"token": self._tokens.issue(self._wall())})

    def _failed(self, key: str, now: float, proxy: str | None, client: str) -> None:
        """A login that failed, counted against its address (auth.py rule 6) and said at most
        once per WRONG_LOG_S, with a count."""
        self._logins.failed(key, now, proxy)
        self._wrong_since += 1
        if now - self._wrong_said_s >= WRONG_LOG_S:
            log.warning(
                "web console: a wrong password from %s (%d since the last said)",
                client,
                self._wrong_since,
            )
            self._wrong_said_s, self._wrong_since = now, 0

    # -- what the page reads -----------------------------------------------------------------
    async def _config(self, request: web.Request) -> web.StreamResponse:
        if not self._token_ok(request):
            return _json({"error": "no valid token: ask api/session or api/login"}, 401)
        loop = asyncio.get_running_loop()
        try:  # rule 5: the TLE file is read here
            satellites = await loop.run_in_executor(None, self._satellites)
        except Exception:
            log.exception("web console: the TLE file's names could not be read")
            satellites = []
        doc = {
            "version": __version__,
            "station": view.station_doc(self._station, self._locator),
            "rotators": [
                view.rotator_doc(rot, self._facts[rid], satellites)
                for rid, rot in self._rotators.items()
            ],
        }
        return _json(doc)

    async def _land_data(self, request: web.Request) -> web.StreamResponse:
        if not self._token_ok(request):
            return _json({"error": "no valid token: ask api/session or api/login"}, 401)
        station = self._station
        if station is None:
            return _json({"error": "no [station]: the console shows a dial without a map"}, 404)
        if self._land is None:  # rule 5: projected once, on the executor
            loop = asyncio.get_running_loop()
            self._land = loop.run_in_executor(None, _land_gzip, station)
        packed = await asyncio.shield(self._land)
        zipped = "gzip" in request.headers.get("Accept-Encoding", "")
        response = web.Response(body=packed if zipped else gzip.decompress(packed))
        response.headers["Content-Type"] = "application/json"
        if zipped:
            response.headers["Content-Encoding"] = "gzip"
        response.headers["Cache-Control"] = "no-cache"
        return response

    # -- commands (rule 4) -------------------------------------------------------------------
    def _halt(self, rotator_id: str, body: bytes, peer: str | None, token: str) -> None:
        """A STOP or lock ON over a page's WebSocket (live.py rule 5), the page's ``token``
        given with it; nothing else."""
        rot = self._rotators.get(rotator_id)
        try:
            cmd = scoped(parse(body), token)  # (commands.py rule 5)
        except BadCommand:
            return
        if rot is None or not cmd.halts() or self._order.carried(rot.id, cmd):
            return  # (a halt its POST carried out: commands.py ``Order.carried``)
        far = self._far.get(rot.id)
        if far is not None and rot.commands_block:  # rule 5
            self._far_halts[rot.id] = self._far_halts.get(rot.id, 0) + 1
            done = asyncio.wrap_future(far.submit(carry_out, rot, cmd, peer))
            done.add_done_callback(lambda f: self._halted(rot.id, cmd, f))
            return
        try:  # never refused by a judge (commands.py rule 3)
            self._own_halt(rot, cmd, peer, None, by=("ws", token))
        except Refused:  # a rotator far away, its broker out of reach: its POST says so
            self._order.pressed(rot.id, cmd)
            return
        self._order.halted(rot.id, cmd, time.monotonic())

    def _far_move(
        self, rot: ConsoleRotator, cmd: WebCommand, peer: str | None, posted: int, since: int
    ) -> None:
        """Rule 5, on the commands' thread: not sent if a halt was posted since it came, nor
        (``since``, port.py rule 2b: the judge says so) if another front end's went out, nor
        if it has grown too old waiting (commands.py rule 6)."""
        if self._far_halts.get(rot.id, 0) != posted:
            why = "a STOP or lock ON posted after it was sent first: not sent (send it again)"
            rot.report_refusal(why, cmd.described(), origin=Origin(Source.WEB, None, peer))
            raise Refused(RefusalCode.STALE, why)
        old = aged(cmd, feed_clock())  # commands.py rule 6: its wait here counts too
        if old is not None:
            rot.report_refusal(old, cmd.described(), origin=Origin(Source.WEB, None, peer))
            raise Refused(RefusalCode.STALE, old)
        carry_out(rot, cmd, peer, since)

    def _far_moved(self, rotator_id: str) -> None:
        """A far move done (any thread): no longer counted against rule 5's bound."""
        loop = self._loop
        if loop is None:
            return
        try:
            loop.call_soon_threadsafe(self._far_unqueue, rotator_id)
        except RuntimeError:  # the console stopped meanwhile: nothing is counted any more
            pass

    def _far_unqueue(self, rotator_id: str) -> None:
        self._far_moves[rotator_id] = self._far_moves.get(rotator_id, 1) - 1

    def _halted(self, rotator_id: str, cmd: WebCommand, done: asyncio.Future[None]) -> None:
        """A halt carried out off the loop (rule 5), back on the loop."""
        if not done.cancelled() and done.exception() is None:
            self._order.halted(rotator_id, cmd, time.monotonic())
        else:  # (kept far away and sent first on reconnect: commands.py ``pressed``)
            self._order.pressed(rotator_id, cmd)

    async def _command(self, request: web.Request) -> web.StreamResponse:
        token = request.headers.get(TOKEN_HEADER)
        if token is None:
            return _json({"error": f"a command needs the page's token ({TOKEN_HEADER})"}, 403)
        if self._tokens.issued(token) is None:
            return _json({"error": "the token is not valid (any more): reload"}, 401)
        self._conns.trust(request.transport)  # connections.py rule 1
        rot = self._rotators.get(request.match_info["rid"])
        if rot is None:
            return _json({"error": "no such rotator"}, 404)
        by = Origin(Source.WEB, None, self._client(request))  # rule 4
        size = request.content_length or 0
        try:
            if size > MAX_BODY_BYTES:  # rule 9: refused unread
                raise web.HTTPRequestEntityTooLarge(MAX_BODY_BYTES, size)
            body = await _body(request, "the command's")
        except Unread as exc:
            if exc.close:  # a body not what its headers say: a bad body (rule 9's R/error)
                rot.report_refusal(exc.why, "console: a body that could not be read", origin=by)
                return exc.answer("invalid")
            return exc.answer()
        except web.HTTPRequestEntityTooLarge:  # rule 9 (one without its length: over 16 KiB)
            why = f"a command is at most {MAX_BODY_BYTES} bytes"
            said = f"console: a body of {size} bytes" if size else "console: a body over 16 KiB"
            rot.report_refusal(why, said, origin=by)
            return _json({"error": why, "code": "invalid"}, 413)
        try:
            cmd = scoped(parse(body), token)  # (commands.py rule 5)
        except BadCommand as exc:
            said = "console: " + body[:80].decode("utf-8", "replace")
            rot.report_refusal(str(exc), said, origin=by)
            return _json({"error": str(exc), "code": "invalid"}, 400)
        halt = cmd.halts()
        if halt and self._order.carried(rot.id, cmd):  # (its WebSocket's copy carried it out)
            return _json({"ok": True})
        if not halt and not self._tokens.valid(token, self._wall()):  # auth.py rule 2
            return _json({"error": "the token has expired: log in again"}, 401)
        far = self._far.get(rot.id)
        # rule 5's look and the halt count it goes with (port.py rules 2a, 2b): a STOP another
        # thread puts after the look refuses the command at the judge
        away = far is not None and rot.commands_block
        since = rot.halts
        stale = self._order.stale(rot.id, cmd, self._started[id(request)], rot.last_halt_s)
        stale = stale or aged(cmd, feed_clock())  # commands.py rule 6
        conn = self._looks.of(request.transport)
        stale = stale or self._looked(rot, cmd, conn, since)  # rule 11
        if stale is not None:
            rot.report_refusal(stale, cmd.described(), origin=by)
            return _json({"error": stale, "code": "stale"}, 409)
        busy = self._far_moves.get(rot.id, 0) >= FAR_MOVES
        if away and not halt and busy:  # rule 5: a bound
            why = _busy(FAR_MOVES)
            rot.report_refusal(why, cmd.described(), origin=by)
            return _json({"error": why, "code": "busy"}, 409)
        if not away and not halt and cmd.from_status() and rot.on_its_way():  # rule 10
            waiting = self._waiting.get(rot.id, 0)
            if waiting >= SHOWN_WAITERS:  # (refused at once)
                why = _busy(SHOWN_WAITERS)
                rot.report_refusal(why, cmd.described(), origin=by)
                return _json({"error": why, "code": "busy"}, 409)
            self._waiting[rot.id] = waiting + 1
            try:
                stale = await self._shown(rot, cmd, self._started[id(request)])
            finally:
                self._waiting[rot.id] -= 1
            stale = stale or self._looked(rot, cmd, conn, rot.halts)  # rule 11, again
            if stale is not None:
                rot.report_refusal(stale, cmd.described(), origin=by)
                return _json({"error": stale, "code": "stale"}, 409)
        self._order.took(rot.id, cmd)  # (commands.py rule 5a)
        try:
            if far is not None and away:  # rule 5
                if halt:
                    self._far_halts[rot.id] = self._far_halts.get(rot.id, 0) + 1
                    done = far.submit(carry_out, rot, cmd, self._client(request))
                else:
                    posted = self._far_halts.get(rot.id, 0)
                    done = far.submit(
                        self._far_move, rot, cmd, self._client(request), posted, since
                    )
                    self._far_moves[rot.id] = self._far_moves.get(rot.id, 0) + 1
                    done.add_done_callback(lambda _: self._far_moved(rot.id))
                await asyncio.wrap_future(done)
            elif halt:  # rule 11: its number the console's own
                self._own_halt(rot, cmd, self._client(request), since, by=conn)
            else:
                carry_out(rot, cmd, self._client(request), since)
        except Refused as exc:
            if halt:  # (kept far away and sent first on reconnect: commands.py ``pressed``)
                self._order.pressed(rot.id, cmd)
            return _json({"error": str(exc), "code": exc.code.value}, 409)
        if halt:
            self._order.halted(rot.id, cmd, time.monotonic())
        return _json({"ok": True})

    def _looked(
        self, rot: ConsoleRotator, cmd: WebCommand, conn: Conn | None, now: int
    ) -> str | None:
        """Rule 11: why ``cmd``, come on ``conn`` (looks.py, None: not looked at), is stale
        at the halt count ``now``: a halt was counted after its request's first byte came
        that is neither the connection's own nor one its page numbered before it."""
        arrived = conn.arrived(rot.id) if conn is not None else None
        if cmd.halts() or arrived is None or now <= arrived:
            return None
        own = self._looks.own.get(rot.id, {})
        if now - arrived > len(own):
            return STALE  # (not all of them the console's own)
        for number in range(arrived + 1, now + 1):
            made = own.get(number)
            if made is None:
                return STALE
            by, page, seq = made
            mine = by is conn or (
                page is not None
                and page == cmd.page
                and seq is not None
                and cmd.seq is not None
                and seq < cmd.seq
            )
            if not mine:
                return STALE
        return None

    def _own_halt(
        self,
        rot: ConsoleRotator,
        cmd: WebCommand,
        peer: str | None,
        since: int | None,
        by: Hashable,
    ) -> None:
        """A halt the console carries out on its loop (never refused by a judge), the numbers
        it adds to the count kept as the console's own, made ``by`` (a connection, or a page's
        WebSocket) for its page (rule 11), as a TCP port's are (tcplines.py ``Fence.halting``)."""
        watchers = halt_watchers(rot)
        own = self._looks.own.get(rot.id)
        if watchers is None or own is None:
            carry_out(rot, cmd, peer, since)
            return
        me = threading.get_ident()
        made: list[int] = []

        def mine() -> None:
            if threading.get_ident() == me:
                made.append(rot.halts + 1)

        watchers.add(mine)
        try:
            carry_out(rot, cmd, peer, since)
        finally:
            watchers.remove(mine)
        for number in made:
            own[number] = (by, cmd.page, cmd.seq)
        while len(own) > OWN_KEPT:  # (the oldest go: refusing)
            del own[next(iter(own))]

    async def _shown(self, rot: ConsoleRotator, cmd: WebCommand, started: float) -> str | None:
        """Rule 10: once what is on its way shows (or SHOWN_S went by), why ``cmd`` is stale
        now (rule 5), if it is; nothing awaits between the last look and the judge."""
        end = time.monotonic() + SHOWN_S
        while rot.on_its_way() and time.monotonic() < end:
            await asyncio.sleep(SHOWN_POLL_S)
        stale = self._order.stale(rot.id, cmd, started, rot.last_halt_s)
        return stale or aged(cmd, feed_clock())


def _busy(waiting: int) -> str:
    """Why a command is refused when ``waiting`` already wait for its rotator (rules 5, 10)."""
    return f"{waiting} commands already wait for this rotator: not sent (send it later)"


def _land_gzip(station: tuple[float, float]) -> bytes:
    doc = view.land_doc(station, view.land_rings())
    return gzip.compress(json.dumps(doc, separators=(",", ":")).encode(), mtime=0)
