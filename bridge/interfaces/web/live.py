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
4. The WebSocket's token is its first message (a browser cannot give a WebSocket a header),
   within TOKEN_WAIT_S; its Origin was checked with the opening request (server.py). Until the
   token is in it counts as a page (MAX_PAGES) and shows no token (connections.py rule 1).
5. A page sends its STOP and lock ON over its WebSocket as well as by POST: when a flood holds
   every connection a new POST could take, the socket the page already has still carries them.
   Nothing else is taken over it.
6. ``on_spots`` runs on the DX cluster's thread (the spot list as ``B/spots`` carries it): it
   keeps the newest and hands it to the event loop while a page is open, as rule 1; a page that
   joins gets it (feed.py rule 6). ``with_console`` puts it beside the MQTT publish, contained.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Callable

from aiohttp import WSMsgType, web

from bridge.core.model import ErrorEvent, RotatorStatus
from bridge.interfaces.web.auth import Tokens
from bridge.interfaces.web.feed import Feed, Page, sse, websocket
from bridge.runtime.listeners import contained

log = logging.getLogger(__name__)

PING_S = 10.0
TOKEN_WAIT_S = 3.0  # the WebSocket's token (its first message) comes within this
MAX_PAGES = 100  # open streams; more are refused (503), not queued
TOKEN_HEADER = "X-Rotor-Token"


class Live:
    def __init__(
        self,
        feed: Feed,
        tokens: Tokens,
        wall: Callable[[], float],
        headers: dict[str, str],
        *,
        trust: Callable[[asyncio.BaseTransport | None], None],
        halt: Callable[[str, bytes, str | None], None],
        client: Callable[[web.Request], str | None] = lambda request: request.remote,
    ) -> None:
        self.feed, self._tokens, self._wall = feed, tokens, wall
        self._client = client  # who a request is from (auth.py rule 6)
        self._headers = headers  # the console's safety headers (server.py rule 3)
        self._trust = trust  # connections.py rule 1
        # a STOP or lock ON that came over the WebSocket (rule 5), with the page's address
        self._halt = halt
        self._opening = 0  # WebSockets upgraded, their token not in yet (they count as pages)
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
        if self.feed.pages >= MAX_PAGES:  # each holds a connection: a flood is not served
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
        STOP). The token comes as the first message; then the same messages as api/events."""
        if self.feed.pages + self._opening >= MAX_PAGES:
            return web.json_response({"error": f"{MAX_PAGES} pages are open already"}, status=503)
        ws = web.WebSocketResponse(max_msg_size=4096)
        self._opening += 1
        try:
            await ws.prepare(request)
            first = await asyncio.wait_for(ws.receive(), TOKEN_WAIT_S)
            token = json.loads(first.data).get("token") if first.type == WSMsgType.TEXT else None
        except (TimeoutError, ValueError, AttributeError, RecursionError, TypeError):
            token = None
        finally:
            self._opening -= 1
        if not isinstance(token, str) or not self._tokens.valid(token, self._wall()):
            await ws.close(code=4401, message=b"no valid token")
            return ws
        self._trust(request.transport)
        page = self.join(token)
        reader = asyncio.get_running_loop().create_task(self._read(ws, page, self._client(request)))
        try:
            await ws.send_str('{"event":"hello"}')
            while await _next(page):
                messages = list(page.take())
                if page.ping:
                    page.ping = False
                    await ws.send_str('{"event":"ping"}')
                for message in messages:
                    await ws.send_str(websocket(message))
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            self.feed.leave(page)
            reader.cancel()
            await ws.close(code=4401 if page.expired else 1001)  # 4401: the token's life ended
        return ws

    async def _read(self, ws: web.WebSocketResponse, page: Page, peer: str | None) -> None:
        """What the page sends: a STOP or a lock ON, sent here as well as by POST (rule 5);
        anything else is ignored. Its close is seen at once."""
        async for message in ws:
            if message.type == WSMsgType.TEXT:
                self._halt_from(message.data, peer)
        page.closed = True
        page.wake.set()

    def _halt_from(self, text: str, peer: str | None) -> None:
        try:
            doc = json.loads(text)
        except (ValueError, RecursionError):
            return
        rid = doc.pop("rotator", None) if isinstance(doc, dict) else None
        if isinstance(rid, str):
            try:
                self._halt(rid, json.dumps(doc).encode(), peer)
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
