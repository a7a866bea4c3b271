"""The console's live side: the newest status of each rotator from the serial-lines thread, and
the two ways a page reads them: ``api/live`` (a WebSocket: the page's own) and ``api/events`` (an
event stream: scripts, curl). Both carry the same messages (feed.py).

Rules:
1. ``on_status`` and ``on_event`` run on the serial-lines thread and only keep the newest or
   hand it to the event loop (``call_soon_threadsafe``), and that only while a page is open: a
   console nobody looks at costs the lines thread a dict write per status.
2. A page that joins gets every rotator's newest first (``join``), then changes.
3. A stream ends when its token's life does (the page then asks for a new one while nothing is
   urgent, rather than when its STOP is answered 401), and when the bridge stops.
4. The page gives the WebSocket's token with its opening request, as a subprotocol beside
   TOKEN_PROTOCOL (``token.<token>``: a browser cannot give a WebSocket a header, and a token's
   characters are a subprotocol's), so it is a page the moment it is open and never waits;
   its Origin was checked with that request (server.py). A client that does not (a script)
   gives it as its first message, within TOKEN_WAIT_S; until then it shows no token
   (connections.py rule 1) and holds a place among MAX_PAGES, but never keeps a page out: a
   page with its token is refused (503) only when MAX_PAGES pages are open, and when pages and
   sockets waiting for their token fill MAX_PAGES, the oldest one still waiting is closed
   (1013, try again later) to make room for it; a socket without its token makes room for
   none, and is refused instead (attack passes: a host with no password opened tokenless
   sockets again as they were closed, and every new tab of the operator's was answered 503;
   then, with any newcomer making room, closed 1013 whenever its token took 50 ms to come). A
   token that came is taken, even when its socket was chosen to give way in the same turn,
   while fewer than MAX_PAGES pages are open. A token offered that is not one is closed 4401
   and takes no place; an offer whose first header line does not name TOKEN_PROTOCOL is
   refused (400) before the handshake, where aiohttp would log every offer, the token with
   them (a review).
5. A page sends its STOP and lock ON over its WebSocket as well as by POST: when a flood holds
   every connection a new POST could take, the socket the page already has still carries them.
   Nothing else is taken over it.
6. ``on_spots`` runs on the DX cluster's thread (the spot list as ``B/spots`` carries it): it
   keeps the newest and hands it to the event loop while a page is open, as rule 1; a page that
   joins gets it (feed.py rule 6). ``with_console`` puts it beside the MQTT publish, contained.
7. What a page's WebSocket sends is read within a budget of its own (``ratelimit.Budget``,
   READ_BYTES_S, each message charged MESSAGE_COST on top of its bytes), one message a turn of
   the event loop: over its budget the socket is not read (its bytes wait in aiohttp's buffer,
   then TCP's, and hold the sender back), as a TCP port's client is not (docs/architecture.md,
   "Why no front end can starve a stop"). A page sends a STOP or a lock ON a click, far below
   it. An attack pass: one socket sent STOPs back to back, the console carried out every
   message a read brought (thousands) before it served anything else, and the operator's STOP
   of another rotator waited 3 to 8 s while that rotor turned on.
8. The page's WebSocket tells it the bridge's clock: ``{"event":"clock","now":...}`` right after
   ``hello``, and ``now`` in every ping (every PING_S), the bridge's steady clock
   (commands.py ``feed_clock``, seconds; not the host's uptime) as the message leaves. The
   page reckons from them when it sends each move, on the bridge's clock (commands.py rule
   6): never later than the truth, since a message arrives after it left. The steady clock,
   not the wall clock: neither a time server stepping the bridge's clock nor the phone's own
   clock (often wrong) can make a held-up click look young.
9. An event stream ends as soon as its connection goes (connections.py rule 5: its client's
   close read from the socket), not at the next write that fails: it sleeps on its page's
   wake-up and writes only a status or a ping (PING_S), so a closed stream held its place among
   MAX_PAGES up to 10 s, and a script opening and closing ``api/events`` MAX_PAGES times in
   that kept every page out, the operator's and the STOP its WebSocket carries (rule 5) among
   them, with 503 (attack 31). A WebSocket's close is its reader's (``_read``). MAX_PAGES
   stays a limit of pages whose connections are open.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time
from collections import OrderedDict
from collections.abc import Callable

from aiohttp import WSMsgType, web

from bridge.core.model import ErrorEvent, RotatorStatus
from bridge.core.ratelimit import Budget
from bridge.interfaces.web.auth import Tokens
from bridge.interfaces.web.commands import feed_clock
from bridge.interfaces.web.feed import Feed, Page, sse, websocket
from bridge.runtime.listeners import contained

log = logging.getLogger(__name__)

PING_S = 10.0
TOKEN_WAIT_S = 3.0  # the WebSocket's token (its first message) comes within this
MAX_PAGES = 100  # open streams; more are refused (503), not queued
TOKEN_HEADER = "X-Rotor-Token"
ROOM_MADE = 1013  # rule 4: a socket still waiting for its token, closed for one (try again later)
TOKEN_PROTOCOL = "rotor-bridge"  # rule 4: the subprotocol echoed to a page giving its token so
TOKEN_OFFER = "token."  # rule 4: the subprotocol that carries the token
READ_BYTES_S = 1024.0  # rule 7: what one page's socket may send a second, a burst of as many
MESSAGE_COST = 64  # rule 7: each message costs this many bytes of it besides its own


class Live:
    def __init__(
        self,
        feed: Feed,
        tokens: Tokens,
        wall: Callable[[], float],
        headers: dict[str, str],
        *,
        trust: Callable[[asyncio.BaseTransport | None], None],
        on_gone: Callable[[asyncio.BaseTransport | None, Callable[[], None]], bool],
        halt: Callable[[str, bytes, str | None, str], None],
        client: Callable[[web.Request], str | None] = lambda request: request.remote,
    ) -> None:
        self.feed, self._tokens, self._wall = feed, tokens, wall
        self._client = client  # who a request is from (auth.py rule 6)
        self._headers = headers  # the console's safety headers (server.py rule 3)
        self._trust = trust  # connections.py rule 1
        self._on_gone = on_gone  # rule 9 (connections.py rule 5)
        # a STOP or lock ON that came over the WebSocket (rule 5), with the page's address and
        # its token
        self._halt = halt
        # rule 4: the WebSockets whose token is not in yet, oldest first; each one's future is
        # set when it is to make room
        self._waiting: OrderedDict[asyncio.Future[None], None] = OrderedDict()
        self._newest: dict[str, tuple[RotatorStatus, float]] = {}  # written by the lines thread
        self._spots: str | None = None  # written by the DX cluster's thread (rule 6)

    def on_status(
        self, rotator_id: str, status: RotatorStatus, loop: asyncio.AbstractEventLoop | None
    ) -> None:
        """The newest is kept; it is handed over (and rendered) only while a page is open: a
        page that joins takes what it missed from ``_newest`` (``join``)."""
        t = self._wall()
        self._newest[rotator_id] = (status, t)
        if loop is not None and self.feed.pages:
            loop.call_soon_threadsafe(self.feed.status, rotator_id, status, t)

    def on_event(
        self, rotator_id: str, event: ErrorEvent, loop: asyncio.AbstractEventLoop | None
    ) -> None:
        if loop is not None and self.feed.pages:
            loop.call_soon_threadsafe(self.feed.event, rotator_id, event)

    def on_spots(self, doc: str, loop: asyncio.AbstractEventLoop | None) -> None:
        """Rule 6."""
        self._spots = doc
        if loop is not None and self.feed.pages:
            loop.call_soon_threadsafe(self.feed.spots, doc)

    async def events(self, request: web.Request) -> web.StreamResponse:
        """``api/events``, an event stream (scripts; the caller checked its token)."""
        if not self._room():  # each holds a connection: a flood is not served
            return web.json_response({"error": f"{MAX_PAGES} pages are open already"}, status=503)
        response = web.StreamResponse(
            headers={
                "Content-Type": "text/event-stream",
                "Cache-Control": "no-store",
                "X-Accel-Buffering": "no",  # nginx: pass each event on at once
                **self._headers,
            }
        )
        await response.prepare(request)
        page = self.join(request.headers.get(TOKEN_HEADER))

        def gone() -> None:  # rule 9: its client went
            page.closed = True
            page.wake.set()

        if not self._on_gone(request.transport, gone):
            gone()  # (gone already)
        try:
            await response.write(b": hello\n\n")
            while await _next(page):
                if page.ping:
                    page.ping = False
                    await response.write(b": ping\n\n")
                chunks = "".join(sse(m) for m in page.take())
                if chunks:
                    await response.write(chunks.encode())
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            self.feed.leave(page)
        return response

    def _room(self, page: bool = True) -> bool:
        """Rule 4: room for one more stream, made for a ``page`` (one with its token) if need be
        by closing the oldest socket still waiting for its token; False when MAX_PAGES pages are
        open, or, for a socket without its token, when there is no room without that."""
        if self.feed.pages >= MAX_PAGES:
            return False
        if not page and self.feed.pages + len(self._waiting) >= MAX_PAGES:
            return False
        while self.feed.pages + len(self._waiting) >= MAX_PAGES:
            oldest, _ = self._waiting.popitem(last=False)
            oldest.set_result(None)
        return True

    def join(self, token: str | None) -> Page:
        """A page joins, then takes every newest status not rendered yet (the lines thread
        hands statuses over only while a page is open: on_status); it ends with its token
        (rule 3)."""
        page = self.feed.join()
        page.expires = self._tokens.expires(token) or 0.0
        for rid, (status, t) in list(self._newest.items()):
            if self.feed.rendered.get(rid) != t:
                self.feed.status(rid, status, t)
        spots = self._spots
        if spots is not None and spots is not self.feed.newest_spots:  # rule 6
            self.feed.spots(spots)
        return page

    async def websocket(self, request: web.Request) -> web.StreamResponse:
        """The page's feed: a WebSocket (a browser's own connections to a host are few, six
        over HTTP/1.1, and a page's event stream held one of them: six tabs left none for a
        STOP). The token comes with the opening request, or as the first message (rule 4); then
        the same messages as api/events."""
        first_line = request.headers.get("Sec-WebSocket-Protocol")  # (all aiohttp reads)
        if first_line is not None and TOKEN_PROTOCOL not in (
            o.strip() for o in first_line.split(",")
        ):  # aiohttp would log every offer, the token with them
            return web.json_response({"error": f"offer {TOKEN_PROTOCOL} first"}, status=400)
        offered = _offered_token(request)
        if offered is not None and not self._tokens.valid(offered, self._wall()):
            ws = web.WebSocketResponse(max_msg_size=4096, protocols=(TOKEN_PROTOCOL,))
            await ws.prepare(request)
            await ws.close(code=4401, message=b"no valid token")
            return ws
        if not self._room(page=offered is not None):
            return web.json_response({"error": f"{MAX_PAGES} pages are open already"}, status=503)
        if offered is not None:
            ws = web.WebSocketResponse(max_msg_size=4096, protocols=(TOKEN_PROTOCOL,))
            await ws.prepare(request)
            token: object = offered
        else:
            ws = web.WebSocketResponse(max_msg_size=4096, protocols=(TOKEN_PROTOCOL,))
            room = asyncio.get_running_loop().create_future()
            self._waiting[room] = None
            try:
                await ws.prepare(request)
                token = await self._token(ws, room)
            finally:
                self._waiting.pop(room, None)
            if room.done() and (token is None or self.feed.pages >= MAX_PAGES):
                await ws.close(code=ROOM_MADE, message=b"room made for a page with its token")
                return ws
        if not isinstance(token, str) or not self._tokens.valid(token, self._wall()):
            await ws.close(code=4401, message=b"no valid token")
            return ws
        self._trust(request.transport)
        page = self.join(token)
        reader = asyncio.get_running_loop().create_task(
            self._read(ws, page, self._client(request), token)
        )
        try:
            await ws.send_str('{"event":"hello"}')
            await ws.send_str(_clock("clock"))  # rule 8
            while await _next(page):
                messages = list(page.take())
                if page.ping:
                    page.ping = False
                    await ws.send_str(_clock("ping"))
                for message in messages:
                    await ws.send_str(websocket(message))
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            self.feed.leave(page)
            reader.cancel()
            await ws.close(code=4401 if page.expired else 1001)  # 4401: the token's life ended
        return ws

    async def _token(self, ws: web.WebSocketResponse, room: asyncio.Future[None]) -> object:
        """What the socket's first message gives as its token (rule 4); None when nothing came
        within TOKEN_WAIT_S, or ``room`` was set before it came (a page needs the place)."""
        receiving = asyncio.ensure_future(ws.receive())
        try:
            await asyncio.wait(
                (receiving, room), timeout=TOKEN_WAIT_S, return_when=asyncio.FIRST_COMPLETED
            )
        finally:
            if not receiving.done():  # (its close, next, waits for it to end)
                receiving.cancel()
        if not receiving.done() or receiving.cancelled():  # (a token that came is taken)
            return None
        first = receiving.result()
        try:
            return json.loads(first.data).get("token") if first.type == WSMsgType.TEXT else None
        except (ValueError, AttributeError, RecursionError, TypeError):
            return None

    async def _read(
        self, ws: web.WebSocketResponse, page: Page, peer: str | None, token: str
    ) -> None:
        """What the page sends: a STOP or a lock ON, sent here as well as by POST (rule 5);
        anything else is ignored. Its close is seen at once; what it sends, within its budget
        (rule 7)."""
        budget = Budget(READ_BYTES_S, time.monotonic())
        async for message in ws:
            if message.type == WSMsgType.TEXT:
                self._halt_from(message.data, peer, token)
            size = len(message.data) if isinstance(message.data, str | bytes) else 0
            budget.spend(MESSAGE_COST + size, time.monotonic())
            await asyncio.sleep(budget.wait_s(time.monotonic()))  # (0: the loop's next turn)
        page.closed = True
        page.wake.set()

    def _halt_from(self, text: str, peer: str | None, token: str) -> None:
        try:
            doc = json.loads(text)
        except (ValueError, RecursionError):
            return
        rid = doc.pop("rotator", None) if isinstance(doc, dict) else None
        if isinstance(rid, str):
            try:
                self._halt(rid, json.dumps(doc).encode(), peer, token)
            except Exception:  # the page's socket goes on: its POST carries the same STOP
                log.exception("web console: a STOP over the live feed failed")

    async def ticking(self) -> None:
        """One timer for every page (feed.py rule 5)."""
        while True:
            await asyncio.sleep(PING_S)
            self.feed.tick(self._wall())


async def _next(page: Page) -> bool:
    """Wait until something is owed to the page; False when its stream ends."""
    await page.wake.wait()
    return not (page.closed or page.expired)


def with_console(
    publish: Callable[[str], None], on_spots: Callable[[str], None]
) -> Callable[[str], None]:
    """``B/spots``' publish with the console's map given each list first (rule 6): a failing
    console never costs MQTT its spots (docs/architecture.md rule 8)."""
    console = contained(on_spots, "web console: spots")

    def both(doc: str) -> None:
        console(doc)
        publish(doc)

    return both


def _clock(event: str) -> str:
    """Rule 8: the bridge's steady clock as the message leaves, for the page's send times."""
    return f'{{"event":"{event}","now":{feed_clock():.3f}}}'


def _offered_token(request: web.Request) -> str | None:
    """Rule 4: the token a page gives with its opening request, as a subprotocol."""
    for header in request.headers.getall("Sec-WebSocket-Protocol", ()):
        for offer in header.split(","):
            offer = offer.strip()
            if offer.startswith(TOKEN_OFFER):
                return offer[len(TOKEN_OFFER) :]
    return None
